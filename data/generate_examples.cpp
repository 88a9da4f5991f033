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
#include <sysid/core/discretize.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/core/transfer_function.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/model_json.hpp>
#include <sysid/signal/excitation.hpp>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace {

using sysid::StateSpace;

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

/// 8 actuators, 8 velocity sensors, 8 lightly damped modes between 18 and 330 Hz
/// (continuous modal model, then exact ZOH at 1024 Hz).
StateSpace avi8x8() {
  const int modes = 8, channels = 8;
  const double freqs[modes] = {18.0, 31.0, 47.0, 66.0, 95.0, 140.0, 210.0, 330.0};
  const double zetas[modes] = {0.010, 0.015, 0.012, 0.020, 0.018, 0.025, 0.020, 0.030};
  std::mt19937_64 rng(8088);
  std::uniform_real_distribution<double> shape(-1.0, 1.0);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * modes, 2 * modes), b = Eigen::MatrixXd::Zero(2 * modes, channels),
                  c = Eigen::MatrixXd::Zero(channels, 2 * modes);
  for (int k = 0; k < modes; ++k) {
    const double w = 2.0 * std::numbers::pi * freqs[k];
    // state [q_k; dq_k/dt]: q'' + 2 zeta w q' + w^2 q = phi_in^T f
    a(2 * k, 2 * k + 1) = 1.0;
    a(2 * k + 1, 2 * k) = -w * w;
    a(2 * k + 1, 2 * k + 1) = -2.0 * zetas[k] * w;
    for (int j = 0; j < channels; ++j) {
      b(2 * k + 1, j) = shape(rng) * 100.0;  // modal participation of actuator j
      c(j, 2 * k + 1) = shape(rng);          // sensor j measures velocity of mode k
    }
  }
  StateSpace cont(a, b, c, Eigen::MatrixXd::Zero(channels, channels), 0.0);
  StateSpace g = sysid::c2d_zoh(cont, 1.0 / 1024.0);
  for (int j = 0; j < channels; ++j) {
    g.input_names.push_back("u" + std::to_string(j + 1));
    g.output_names.push_back("y" + std::to_string(j + 1));
  }
  return g;
}

Eigen::MatrixXd gaussian(Eigen::Index rows, Eigen::Index cols, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd x(rows, cols);
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index c = 0; c < cols; ++c) x(r, c) = g(rng);
  return x;
}

/// Adds white measurement noise with the given fraction of each channel's RMS.
void add_noise(Eigen::MatrixXd& y, double fraction, std::uint64_t seed) {
  const Eigen::MatrixXd e = gaussian(y.rows(), y.cols(), seed);
  for (Eigen::Index c = 0; c < y.cols(); ++c) {
    const double rms = std::sqrt(y.col(c).squaredNorm() / static_cast<double>(y.rows()));
    y.col(c) += fraction * rms * e.col(c);
  }
}

void write_log(const std::filesystem::path& path, double ts, const std::vector<std::string>& names,
               const std::vector<const Eigen::MatrixXd*>& blocks) {
  Eigen::Index cols = 1;
  for (const auto* b : blocks) cols += b->cols();
  const Eigen::Index rows = blocks.front()->rows();
  Eigen::MatrixXd table(rows, cols);
  table.col(0) = Eigen::VectorXd::LinSpaced(rows, 0.0, static_cast<double>(rows - 1)) * ts;
  Eigen::Index at = 1;
  for (const auto* b : blocks) {
    table.middleCols(at, b->cols()) = *b;
    at += b->cols();
  }
  std::vector<std::string> all{"t"};
  all.insert(all.end(), names.begin(), names.end());
  sysid::write_csv(path.string(), all, table);
  std::cout << "wrote " << path.string() << " (" << rows << " samples)\n";
}

void write_model(const std::filesystem::path& path, const StateSpace& g, const std::string& what) {
  sysid::ModelFile file;
  file.model = g;
  file.provenance = {{"method", "true model"}, {"source", what}};
  sysid::write_model_json(path.string(), file);
  std::cout << "wrote " << path.string() << "\n";
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
