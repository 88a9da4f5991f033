#pragma once
// Test support: seeded random matrices and root matching, shared by the unit
// tests of the core layer (one definition, so the tests also build as one unity
// translation unit per layer).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

namespace sysid::test {

inline constexpr double kPi = std::numbers::pi;

/// r x c matrix of independent standard normal draws, filled column by column.
inline Eigen::MatrixXd randn(std::mt19937_64& rng, Eigen::Index r, Eigen::Index c) {
  std::normal_distribution<double> g;
  Eigen::MatrixXd m(r, c);
  for (Eigen::Index j = 0; j < c; ++j)
    for (Eigen::Index i = 0; i < r; ++i) m(i, j) = g(rng);
  return m;
}

/// A vector of `n` independent circular complex Gaussian entries (real and
/// imaginary parts standard normal): a noise mode's shape.
inline Eigen::VectorXcd random_complex_vector(std::mt19937_64& rng, Eigen::Index n) {
  std::normal_distribution<double> normal;
  Eigen::VectorXcd v(n);
  for (auto& e : v) e = std::complex<double>(normal(rng), normal(rng));
  return v;
}

/// n x cols Gaussian white noise of standard deviation sigma, seeded; column by
/// column, the same draws as std::normal_distribution(0, sigma) on mt19937_64(seed).
inline Eigen::MatrixXd white_noise(Eigen::Index n, Eigen::Index cols, std::uint64_t seed, double sigma = 1.0) {
  std::mt19937_64 rng(seed);
  return sigma * randn(rng, n, cols);
}

/// Random similarity with condition number <= e^1.4 ~ 4: Q1 diag(e^u) Q2 with
/// Q1, Q2 random orthogonal and u uniform in [-0.7, 0.7]. (I + noise can be nearly
/// singular for larger n and would turn a test of an algorithm into a test of an
/// ill-conditioned eigenproblem.)
inline Eigen::MatrixXd well_conditioned(std::mt19937_64& rng, Eigen::Index n) {
  std::uniform_real_distribution<double> u(-0.7, 0.7);
  const Eigen::MatrixXd Q1 = Eigen::HouseholderQR<Eigen::MatrixXd>(randn(rng, n, n)).householderQ();
  const Eigen::MatrixXd Q2 = Eigen::HouseholderQR<Eigen::MatrixXd>(randn(rng, n, n)).householderQ();
  Eigen::VectorXd d(n);
  for (Eigen::Index i = 0; i < n; ++i) d[i] = std::exp(u(rng));
  return Q1 * d.asDiagonal() * Q2;
}

/// Largest distance from an expected root to its match (greedy nearest, each
/// computed root used once); +inf if the counts differ.
inline double match_error(const Eigen::VectorXcd& expected, const Eigen::VectorXcd& computed) {
  if (expected.size() != computed.size()) return std::numeric_limits<double>::infinity();
  std::vector<bool> used(static_cast<std::size_t>(computed.size()), false);
  double worst = 0.0;
  for (Eigen::Index i = 0; i < expected.size(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t arg = 0;
    for (Eigen::Index j = 0; j < computed.size(); ++j) {
      const double d = std::abs(expected[i] - computed[j]);
      if (!used[static_cast<std::size_t>(j)] && d < best) {
        best = d;
        arg = static_cast<std::size_t>(j);
      }
    }
    used[arg] = true;
    worst = std::max(worst, best);
  }
  return worst;
}

/// Sample canonical correlations between the columns of x and y (the singular
/// values of Qx^T Qy from thin QRs), descending.
inline Eigen::VectorXd canonical_correlations(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y) {
  const Eigen::MatrixXd qx = Eigen::HouseholderQR<Eigen::MatrixXd>(x).householderQ() * Eigen::MatrixXd::Identity(x.rows(), x.cols());
  const Eigen::MatrixXd qy = Eigen::HouseholderQR<Eigen::MatrixXd>(y).householderQ() * Eigen::MatrixXd::Identity(y.rows(), y.cols());
  return Eigen::JacobiSVD<Eigen::MatrixXd>(qx.transpose() * qy).singularValues();
}

}  // namespace sysid::test
