/// @file
/// Purpose: the performance target of the reduce layer: balanced truncation of an
/// order-112, 8-input 8-output, lightly damped discrete model (the size of the
/// active vibration isolator model: eight SIMO order-14 models side by side) to
/// order 30, timed (median of --repeats runs), to be compared with SLICOT AB09AD
/// through slycot / python-control in the same run (bench/balred_control.py drives both).
///
/// Usage:
///   sysid_bench_balred [--order 30] [--repeats 9] [--seed 1] [--dense 0|1] [--write-json PATH]
///
/// Model (reproducible, std::mt19937_64 seeded): 56 modes with natural frequencies
/// log-uniform in [5, 400] Hz and damping ratios uniform in [0.005, 0.03], mapped
/// exactly to z = exp(s Ts), Ts = 1/1024 s, as 2x2 real blocks
/// [Re z, Im z; -Im z, Re z]; B (112 x 8) and C (8 x 112) standard normal, D = 0.
/// --dense 1 applies a random orthogonal similarity (Q of a QR of a Gaussian
/// matrix) so A is full, as an ERA realisation would be (then the Schur
/// decomposition does real work).
/// Timed: sysid::balanced_truncation with measure_error = false (what AB09AD does:
/// Gramian factors, SVD, projection). Printed: `balred_seconds <median>`, then the
/// same with the error measurement on the grid (`balred_with_error_seconds`), the
/// first HSV, the bound and the measured H-infinity error.
/// --write-json: the model, the HSV and the reduced model (state-space JSON layout
/// of DESIGN.md plus "hsv", "reduced" and "order"), for the Python peer.
#include <sysid/reduce/balanced_truncation.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace {

sysid::StateSpace isolator_like_model(std::uint64_t seed, bool dense) {
  constexpr int modes = 56, m = 8, l = 8, n = 2 * modes;
  const double Ts = 1.0 / 1024.0;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> logf(std::log(5.0), std::log(400.0)), zeta(0.005, 0.03);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n), B(n, m), C(l, n);
  for (int k = 0; k < modes; ++k) {
    const double wn = 2.0 * std::numbers::pi * std::exp(logf(rng)), z = zeta(rng);
    const std::complex<double> s(-z * wn, wn * std::sqrt(1.0 - z * z));
    const std::complex<double> p = std::exp(s * Ts);
    A(2 * k, 2 * k) = p.real();
    A(2 * k, 2 * k + 1) = p.imag();
    A(2 * k + 1, 2 * k) = -p.imag();
    A(2 * k + 1, 2 * k + 1) = p.real();
  }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) B(i, j) = g(rng);
  for (int i = 0; i < l; ++i)
    for (int j = 0; j < n; ++j) C(i, j) = g(rng);
  if (dense) {
    Eigen::MatrixXd G(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) G(i, j) = g(rng);
    const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(G).householderQ();
    A = Q * A * Q.transpose();
    B = Q * B;
    C = C * Q.transpose();
  }
  return sysid::StateSpace(A, B, C, Eigen::MatrixXd::Zero(l, m), Ts);
}

nlohmann::json matrix_json(const Eigen::MatrixXd& M) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index i = 0; i < M.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index j = 0; j < M.cols(); ++j) row.push_back(M(i, j));
    rows.push_back(row);
  }
  return rows;
}

nlohmann::json model_json(const sysid::StateSpace& s) {
  return {{"type", "state-space"}, {"Ts", s.Ts}, {"A", matrix_json(s.A)}, {"B", matrix_json(s.B)},
          {"C", matrix_json(s.C)}, {"D", matrix_json(s.D)}};
}

template <class F>
double median_seconds(int repeats, F&& f) {
  std::vector<double> t;
  for (int i = 0; i < repeats; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  Eigen::Index order = 30;
  int repeats = 9;
  std::uint64_t seed = 1;
  bool dense = false;
  std::string json_path;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--order") order = std::stol(v);
    else if (k == "--repeats") repeats = std::max(1, std::stoi(v));
    else if (k == "--seed") seed = std::stoull(v);
    else if (k == "--dense") dense = v != "0";
    else if (k == "--write-json") json_path = v;
    else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 1;
    }
  }
  const sysid::StateSpace model = isolator_like_model(seed, dense);
  sysid::BalancedTruncationOptions opt;
  opt.order = order;
  opt.measure_error = false;
  sysid::ReductionResult res;
  res = sysid::balanced_truncation(model, opt);  // warm-up (page faults, allocator)
  const double t = median_seconds(repeats, [&] { res = sysid::balanced_truncation(model, opt); });
  opt.measure_error = true;
  sysid::ReductionResult res_e;
  const double te = median_seconds(std::max(1, repeats / 3), [&] { res_e = sysid::balanced_truncation(model, opt); });
  std::printf("model: order %ld, %ld inputs, %ld outputs, Ts %.9g, %s A\n", static_cast<long>(model.order()),
              static_cast<long>(model.inputs()), static_cast<long>(model.outputs()), model.Ts,
              dense ? "dense" : "block-diagonal (modal)");
  std::printf("balred_seconds %.6g\n", t);
  std::printf("balred_with_error_seconds %.6g\n", te);
  std::printf("reduced order %ld, hsv[0] %.10g, hsv[%ld] %.10g, bound 2*sum(discarded) %.6g, "
              "measured H-inf error %.6g at %.6g Hz (grid %ld points)\n",
              static_cast<long>(res_e.order), res_e.hsv(0), static_cast<long>(order), res_e.hsv(order),
              res_e.hinf_bound, res_e.hinf_error, res_e.hinf_error_freq_hz, static_cast<long>(res_e.grid_points));
  for (const std::string& w : res_e.warnings) std::printf("warning: %s\n", w.c_str());
  if (!json_path.empty()) {
    nlohmann::json j = model_json(model);
    j["order"] = order;
    j["hsv"] = std::vector<double>(res_e.hsv.data(), res_e.hsv.data() + res_e.hsv.size());
    j["reduced"] = model_json(res_e.model);
    j["hinf_error"] = res_e.hinf_error;
    j["hinf_bound"] = res_e.hinf_bound;
    std::ofstream f(json_path);
    f << j.dump();  // nlohmann writes doubles in round-trip (shortest exact) form
    if (!f) {
      std::fprintf(stderr, "cannot write %s\n", json_path.c_str());
      return 2;
    }
  }
  return 0;
}
