/// @file
/// Purpose: the common scorer of the Par2 GU peer comparison (bench/run_peers.sh):
/// every tool's model is judged by the same code on the same validation log, so
/// differences in the table come from the identified models only.
///
/// Usage:
///   sysid_bench_par2_eval EST.csv VAL.csv NAME=MODEL.json [NAME=MODEL.json ...]
///
/// Method, identical for every model:
///  - offsets: the means of u and y over the estimation log. Every peer driver
///    removes exactly these means before identification, and sysid::n4sid removes
///    them itself, so each model is a model of deviations from them;
///  - simulation (DESIGN.md "Fit and validation"): yhat = simulate(model, u_val -
///    mean(u_est), x0 = 0) + mean(y_est). x0 = 0 is exact here: the validation
///    record starts from rest (the multisine is applied to a system at rest);
///  - validation fit % = 100 (1 - ||y - yhat|| / ||y - mean(y)||);
///  - in-band fit %: the same after y and yhat both pass through the same
///    zero-phase 5th-order Butterworth low-pass at 120 Hz (sysid::filtfilt), which
///    keeps the excited band 0-100 Hz and removes what the data do not determine
///    (the 202 Hz mode and the measurement noise above the band).
/// Only A, B, C, D are read from the JSON (any offsets in it are ignored, see above).
///
/// Output (one line per model, parsed by run_peers.sh):
///   EVAL name=sysid fit=93.12 inband=95.40 order=10 max_pole=0.9968
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <string>

#include "sysid/core/simulate.hpp"
#include "sysid/io/csv.hpp"
#include "sysid/io/model_json.hpp"
#include "sysid/signal/butterworth.hpp"
#include "sysid/signal/sos_filter.hpp"
#include "sysid/validate/fit.hpp"

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: sysid_bench_par2_eval EST.csv VAL.csv NAME=MODEL.json [NAME=MODEL.json ...]\n";
    return 1;
  }
  try {
    sysid::LogOptions lo;
    lo.inputs = {"u"};
    lo.outputs = {"y"};
    const sysid::IoData est = sysid::read_log(argv[1], lo);
    const sysid::IoData val = sysid::read_log(argv[2], lo);
    const Eigen::RowVectorXd mu_u = est.experiments[0].u.colwise().mean();
    const Eigen::RowVectorXd mu_y = est.experiments[0].y.colwise().mean();
    const Eigen::MatrixXd u_dev = val.experiments[0].u.rowwise() - mu_u;
    const Eigen::MatrixXd& y_val = val.experiments[0].y;

    const sysid::SecondOrderSections lp = sysid::butterworth(5, sysid::BandType::lowpass, 120.0, 0.0, 1.0 / val.Ts);
    const Eigen::MatrixXd y_val_lp = sysid::filtfilt(lp, y_val);

    int status = 0;
    for (int a = 3; a < argc; ++a) {
      const std::string arg = argv[a];
      const auto eq = arg.find('=');
      const std::string name = eq == std::string::npos ? arg : arg.substr(0, eq);
      const std::string path = eq == std::string::npos ? arg : arg.substr(eq + 1);
      try {
        sysid::StateSpace model = sysid::read_model_json(path).model;
        if (model.inputs() != 1 || model.outputs() != 1)
          throw std::invalid_argument("expected a 1-input 1-output model, found " + std::to_string(model.inputs()) + " x " +
                                      std::to_string(model.outputs()));
        if (!(model.Ts > 0)) model.Ts = val.Ts;  // a peer that did not record Ts: the log's
        Eigen::MatrixXd y_hat = sysid::simulate(model, u_dev);
        y_hat.rowwise() += mu_y;
        const double fit = sysid::fit_percent(y_val, y_hat)(0);
        const double inband = sysid::fit_percent(y_val_lp, sysid::filtfilt(lp, y_hat))(0);  // NaN for a diverging model
        const double max_pole = model.order() > 0 ? model.A.eigenvalues().cwiseAbs().maxCoeff() : 0.0;
        std::printf("EVAL name=%s fit=%.3f inband=%.3f order=%ld max_pole=%.6f\n", name.c_str(), fit, inband,
                    static_cast<long>(model.order()), max_pole);
      } catch (const std::exception& e) {
        std::cerr << "sysid_bench_par2_eval: " << name << " (" << path << "): " << e.what() << "\n";
        std::printf("EVAL name=%s fit=nan inband=nan order=0 max_pole=nan\n", name.c_str());
        status = 2;
      }
    }
    return status;
  } catch (const std::exception& e) {
    std::cerr << "sysid_bench_par2_eval: " << e.what() << "\n";
    return 2;
  }
}
