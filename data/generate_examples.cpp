// Generates the example logs of data/README.md from the published models, so the
// data in the repository is a program, not a blob. Deterministic: fixed seeds,
// std::mt19937_64 with std::normal_distribution (libstdc++).
//
//   sysid_generate_examples OUTDIR
//
// writes into OUTDIR:
//   par2_gu.csv, par2_gu_val.csv  piezo path GU of the Par2 paper, eq. (6)
//   par2_gw.csv                   disturbance path GW, eq. (5), white-noise driven
//   avi8x8.csv, avi8x8_val.csv    8x8 lightly damped modal model (isolator-like)
//   *_true.json                   the true models, for comparisons in tests
//
// The 8x8 structure and the log writers are shared with the isolator
// experiments' generator (isolator/example_data.hpp).
#include <sysid/core/simulate.hpp>
#include <sysid/core/transfer_function.hpp>
#include <sysid/signal/excitation.hpp>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "isolator/example_data.hpp"

namespace {

using sysid::StateSpace;
using sysid::example_data::add_noise;
using sysid::example_data::avi8x8;
using sysid::example_data::gaussian;
using sysid::example_data::write_log;
using sysid::example_data::write_model;

Eigen::VectorXd quadratic(double a1, double a0) {
  Eigen::VectorXd p(3);
  p << 1.0, a1, a0;
  return p;
}
Eigen::VectorXd linear(double root) {
  Eigen::VectorXd p(2);
  p << 1.0, -root;
  return p;
}
Eigen::VectorXd product(const std::vector<Eigen::VectorXd>& factors) {
  Eigen::VectorXd p = Eigen::VectorXd::Ones(1);
  for (const auto& f : factors) p = sysid::poly_multiply(p, f);
  return p;
}

constexpr double kPar2Fs = 2000.0;

/// GU(z) of the Par2 paper, eq. (6): piezo actuator voltage to sensor output.
StateSpace par2_gu() {
  sysid::TransferFunction tf;
  tf.Ts = 1.0 / kPar2Fs;
  tf.num = -0.055 * product({linear(1.003), linear(1.15), quadratic(-1.993, 1.002), linear(-1.0), linear(-1.0),
                             quadratic(-1.947, 0.985), quadratic(-1.914, 0.989)});
  tf.den = product({quadratic(-1.985, 0.993), quadratic(-1.561, 0.641), quadratic(-1.947, 0.988), quadratic(-1.901, 0.976),
                    quadratic(-1.586, 0.97)});
  StateSpace g = sysid::to_state_space(tf);
  g.input_names = {"u"};
  g.output_names = {"y"};
  return g;
}

/// GW(z) of the Par2 paper, eq. (5): disturbance path.
StateSpace par2_gw() {
  sysid::TransferFunction tf;
  tf.Ts = 1.0 / kPar2Fs;
  tf.num = Eigen::VectorXd::Constant(1, 0.0005);
  tf.den = product({quadratic(-1.992, 0.9986), quadratic(-1.963, 0.9729)});
  StateSpace g = sysid::to_state_space(tf);
  g.input_names = {"e"};
  g.output_names = {"y"};
  return g;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: sysid_generate_examples OUTDIR\n";
    return 1;
  }
  try {
    const std::filesystem::path out = argv[1];
    std::filesystem::create_directories(out);

    // Par2 piezo path: linear chirp 0-100 Hz over 20 s at +-10 V, 2 kHz, 1 % noise.
    const StateSpace gu = par2_gu();
    if (gu.A.eigenvalues().cwiseAbs().maxCoeff() >= 1.0) throw std::runtime_error("GU of eq. (6) is not stable");
    sysid::ChirpOptions chirp;
    chirp.fs_hz = kPar2Fs;
    chirp.f0_hz = 0.0;
    chirp.f1_hz = 100.0;
    chirp.duration_s = 20.0;
    chirp.amplitude = 10.0;
    const Eigen::MatrixXd u = sysid::chirp(chirp);
    Eigen::MatrixXd y = sysid::simulate(gu, u);
    add_noise(y, 0.01, 101);
    write_log(out / "par2_gu.csv", 1.0 / kPar2Fs, {"u", "y"}, {&u, &y});
    // Validation record: random-phase multisine 0-100 Hz, 10 s, same noise level.
    sysid::MultisineOptions ms;
    ms.fs_hz = kPar2Fs;
    ms.f_min_hz = 0.0;
    ms.f_max_hz = 100.0;
    ms.samples = 20000;
    ms.period = 20000;
    ms.rms = 10.0 / std::sqrt(2.0);
    ms.seed = 7;
    const Eigen::MatrixXd u_val = sysid::multisine(ms);
    Eigen::MatrixXd y_val = sysid::simulate(gu, u_val);
    add_noise(y_val, 0.01, 102);
    write_log(out / "par2_gu_val.csv", 1.0 / kPar2Fs, {"u", "y"}, {&u_val, &y_val});
    write_model(out / "par2_gu_true.json", gu, "Par2 paper eq. (6), GU");

    // Par2 disturbance path: unit white noise e through GW, 20 s, 1 % measurement noise.
    const StateSpace gw = par2_gw();
    const Eigen::MatrixXd e = gaussian(40000, 1, 201);
    Eigen::MatrixXd w = sysid::simulate(gw, e);
    add_noise(w, 0.01, 202);
    write_log(out / "par2_gw.csv", 1.0 / kPar2Fs, {"e", "y"}, {&e, &w});
    write_model(out / "par2_gw_true.json", gw, "Par2 paper eq. (5), GW");

    // 8x8 isolator-like structure: one independent random-phase multisine per input, 2-450 Hz.
    const StateSpace avi = avi8x8();
    for (auto [name, seed] : {std::pair{"avi8x8", 11}, std::pair{"avi8x8_val", 12}}) {
      sysid::MultisineOptions m8;
      m8.fs_hz = 1024.0;
      m8.f_min_hz = 2.0;
      m8.f_max_hz = 450.0;
      m8.samples = 16384;
      m8.period = 16384;
      m8.inputs = 8;
      m8.rms = 1.0;
      m8.seed = static_cast<std::uint64_t>(seed);
      const Eigen::MatrixXd u8 = sysid::multisine(m8);
      Eigen::MatrixXd y8 = sysid::simulate(avi, u8);
      add_noise(y8, 0.01, 300 + static_cast<std::uint64_t>(seed));
      std::vector<std::string> names = avi.input_names;
      names.insert(names.end(), avi.output_names.begin(), avi.output_names.end());
      write_log(out / (std::string(name) + ".csv"), 1.0 / 1024.0, names, {&u8, &y8});
    }
    write_model(out / "avi8x8_true.json", avi, "8x8 modal model, data/generate_examples.cpp");
  } catch (const std::exception& ex) {
    std::cerr << "sysid_generate_examples: " << ex.what() << "\n";
    return 1;
  }
  return 0;
}
