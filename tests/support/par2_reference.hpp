#pragma once
// The Par2 piezo logs of data/generate_examples.cpp and the in-band fit of the
// acceptance tests (foundation issue): measured and simulated outputs through
// the same zero-phase 5th-order Butterworth low-pass at 1.2 x the excited band
// (120 Hz), simulation from rest. Shared by every method's Par2 acceptance test.
#include <sysid/core/simulate.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/model_json.hpp>
#include <sysid/signal/butterworth.hpp>
#include <sysid/signal/sos_filter.hpp>
#include <sysid/validate/fit.hpp>

#include <string>

namespace sysid::test {

inline IoData load_par2_log(const std::string& name) {
  LogOptions o;
  o.inputs = {"u"};
  o.outputs = {"y"};
  return read_log(std::string(SYSID_TEST_DATA_DIR) + "/" + name, o);
}

inline double par2_in_band_fit(const StateSpace& g, const Eigen::VectorXd& u_offset, const Eigen::VectorXd& y_offset,
                               const IoData& val) {
  const Experiment& e = val.experiments.front();
  const Eigen::MatrixXd u = e.u.rowwise() - u_offset.transpose();
  const Eigen::MatrixXd y_hat = simulate(g, u).rowwise() + y_offset.transpose();
  const SecondOrderSections lp = butterworth(5, BandType::lowpass, 120.0, 0.0, 1.0 / val.Ts);
  return fit_percent(filtfilt(lp, e.y), filtfilt(lp, y_hat))(0);
}

struct Par2Reference {
  StateSpace truth;
  IoData estimation, validation;
  double true_fit;  ///< in-band validation fit of the true model
};

inline const Par2Reference& par2_reference() {
  static const Par2Reference r = [] {
    Par2Reference ref{read_model_json(std::string(SYSID_TEST_DATA_DIR) + "/par2_gu_true.json").model,
                      load_par2_log("par2_gu.csv"), load_par2_log("par2_gu_val.csv"), 0.0};
    ref.true_fit = par2_in_band_fit(ref.truth, Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(1), ref.validation);
    return ref;
  }();
  return r;
}

}  // namespace sysid::test
