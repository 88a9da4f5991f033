// The recursions' cost where a state decays to zero (core/flush_subnormals.hpp):
// on Intel cores every operation on a subnormal number takes a microcode assist
// of ~100 cycles, so a recursion that carries a decaying state through that
// range ran 7-46x slower than the same work without it (2-core Xeon CI VM,
// bench preset, with the flush turned off: simulate 131 ms against 7.1 ms,
// sos_filter 46 ms against 1.0 ms, B/D/x0 14.4 ms against 2.1 ms). Target: each
// pair below within 1.5x of each other (minimum of the runs), which holds only
// while the recursions flush subnormals to zero (measured: 0.77-1.00).
//
//   simulate, simulate_blockwise_modal, sos_filter, filtfilt, filter_polynomial:
//     a record silent after its first 1 000 samples against a driven one (white
//     noise throughout), same length and model;
//   bdx_least_squares (n4sid's B/D/x0 step, 40 000 samples, order 10): poles of
//     modulus 0.9 (the x0 regressors C A^t pass the subnormal range after ~6 700
//     samples) against 0.9999 (they never do), same data and sizes.
//
// Usage: sysid_bench_subnormal [--repeats 5]. Exit 1 when a ratio exceeds the target.
#include <sysid/core/simulate.hpp>
#include <sysid/signal/butterworth.hpp>
#include <sysid/signal/polynomial_filter.hpp>
#include <sysid/signal/sos_filter.hpp>
#include <sysid/subspace/bdx_least_squares.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <string>

namespace {

constexpr double kTargetRatio = 1.5;

/// The fastest of `runs` calls of f, in seconds.
double fastest(int runs, const std::function<void()>& f) {
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < runs; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

/// n / 2 lightly damped modes of modulus `radius` at spread frequencies (real modal form).
Eigen::MatrixXd modal_A(Eigen::Index n, double radius) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index k = 0; k < n / 2; ++k) {
    const double angle = 0.05 + 0.25 * static_cast<double>(k);
    A(2 * k, 2 * k) = A(2 * k + 1, 2 * k + 1) = radius * std::cos(angle);
    A(2 * k, 2 * k + 1) = radius * std::sin(angle);
    A(2 * k + 1, 2 * k) = -radius * std::sin(angle);
  }
  return A;
}

Eigen::MatrixXd white(std::mt19937_64& rng, Eigen::Index rows, Eigen::Index cols) {
  std::normal_distribution<double> g;
  Eigen::MatrixXd x(rows, cols);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = g(rng);
  return x;
}

struct Pair {
  std::string name;
  double decaying = 0, reference = 0;
};

}  // namespace

int main(int argc, char** argv) {
  int repeats = 5;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--repeats") repeats = std::stoi(v);
    else {
      std::fprintf(stderr, "usage: sysid_bench_subnormal [--repeats 5]\n");
      return 2;
    }
  }
  std::mt19937_64 rng(7);
  const Eigen::Index samples = 200000, n = 10;
  const Eigen::MatrixXd driven = white(rng, samples, 1);
  Eigen::MatrixXd silent = Eigen::MatrixXd::Zero(samples, 1);
  silent.topRows(1000) = driven.topRows(1000);

  const sysid::StateSpace model(modal_A(n, 0.95), white(rng, n, 1), white(rng, 1, n), Eigen::MatrixXd::Zero(1, 1), 1e-3);
  const auto filter = sysid::butterworth(4, sysid::BandType::lowpass, 50.0, 0.0, 1000.0);
  const Eigen::VectorXd num = Eigen::VectorXd::Ones(1);
  Eigen::VectorXd den(3);
  den << 1.0, -1.8 * std::cos(0.1), 0.81;  // a resonance of modulus 0.9

  std::vector<Pair> pairs;
  auto time_pair = [&](const std::string& name, const std::function<void(const Eigen::MatrixXd&)>& run) {
    Pair p{name};
    p.decaying = fastest(repeats, [&] { run(silent); });
    p.reference = fastest(repeats, [&] { run(driven); });
    pairs.push_back(p);
  };
  double sink = 0;  // keeps the results alive
  time_pair("simulate", [&](const Eigen::MatrixXd& u) { sink += sysid::simulate(model, u)(samples - 1, 0); });
  time_pair("simulate_blockwise_modal", [&](const Eigen::MatrixXd& u) {
    sysid::simulate_blockwise_modal(model, u, Eigen::VectorXd(),
                                    [&](Eigen::Index, const Eigen::Ref<Eigen::MatrixXd>& yb) { sink += yb(0, 0); });
  });
  time_pair("sos_filter", [&](const Eigen::MatrixXd& u) { sink += sysid::sos_filter(filter, u)(samples - 1, 0); });
  time_pair("filtfilt", [&](const Eigen::MatrixXd& u) { sink += sysid::filtfilt(filter, u)(samples / 2, 0); });
  time_pair("filter_polynomial", [&](const Eigen::MatrixXd& u) { sink += sysid::filter_polynomial(num, den, u)(samples - 1, 0); });

  // B/D/x0: the same driven record of 40 000 samples, fast against slow poles.
  {
    const Eigen::Index N = 40000;
    const sysid::IoData data(driven.topRows(N), white(rng, N, 1), 1e-3);
    const Eigen::MatrixXd C = white(rng, 1, n);
    sysid::BdxLeastSquaresOptions options;
    Pair p{"bdx_least_squares"};
    const Eigen::MatrixXd fast = modal_A(n, 0.9), slow = modal_A(n, 0.9999);
    p.decaying = fastest(repeats, [&] { sink += sysid::bdx_least_squares(fast, C, data, options).B(0, 0); });
    p.reference = fastest(repeats, [&] { sink += sysid::bdx_least_squares(slow, C, data, options).B(0, 0); });
    pairs.push_back(p);
  }

  bool ok = true;
  std::printf("%-26s %14s %14s %8s\n", "recursion", "decaying [ms]", "reference [ms]", "ratio");
  for (const Pair& p : pairs) {
    const double ratio = p.decaying / p.reference;
    ok = ok && ratio <= kTargetRatio;
    std::printf("%-26s %14.3f %14.3f %8.2f%s\n", p.name.c_str(), 1e3 * p.decaying, 1e3 * p.reference, ratio,
                ratio <= kTargetRatio ? "" : "  > target");
  }
  std::printf("target: every ratio <= %.1f -> %s (checksum %g)\n", kTargetRatio, ok ? "MET" : "NOT MET", sink);
  return ok ? 0 : 1;
}
