#pragma once
// Test support: seeded random stable systems and noisy simulated data.
#include <sysid/core/io_data.hpp>
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "random_matrices.hpp"

namespace sysid::test {

/// Random stable discrete-time MIMO system with lightly damped modes at given
/// frequencies (fractions of the sample rate), built in real modal form and
/// then rotated by a random similarity transform (so A is not block-diagonal).
inline StateSpace random_modal_system(int modes, int inputs, int outputs, std::uint64_t seed, double damping = 0.05,
                                      bool feedthrough = true) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> freq(0.02, 0.35), unit(-1.0, 1.0);
  const int n = 2 * modes;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < modes; ++k) {
    const double w = 2 * std::numbers::pi * freq(rng);  // rad/sample
    const double r = std::exp(-damping * w);
    a(2 * k, 2 * k) = r * std::cos(w);
    a(2 * k, 2 * k + 1) = r * std::sin(w);
    a(2 * k + 1, 2 * k) = -r * std::sin(w);
    a(2 * k + 1, 2 * k + 1) = r * std::cos(w);
  }
  Eigen::MatrixXd t(n, n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) t(r, c) = unit(rng) + (r == c ? 2.0 : 0.0);
  Eigen::MatrixXd b(n, inputs), c(outputs, n), d(outputs, inputs);
  for (auto* m : {&b, &c, &d})
    for (Eigen::Index r = 0; r < m->rows(); ++r)
      for (Eigen::Index q = 0; q < m->cols(); ++q) (*m)(r, q) = unit(rng);
  if (!feedthrough) d.setZero();
  const Eigen::MatrixXd ti = t.inverse();
  return StateSpace(t * a * ti, t * b, c * ti, d, 1.0);
}

/// blockdiag([[Re z, Im z], [-Im z, Re z]]) over the modes, z = exp(s Ts),
/// s = 2 pi f (-zeta + j sqrt(1 - zeta^2)) (f in Hz; with Ts = 1, in cycles per sample).
inline Eigen::MatrixXd modal_block_matrix(const std::vector<double>& f, const std::vector<double>& zeta, double Ts) {
  const auto n = static_cast<Eigen::Index>(2 * f.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (std::size_t k = 0; k < f.size(); ++k) {
    const std::complex<double> z =
        std::exp(2.0 * std::numbers::pi * f[k] * Ts * std::complex<double>(-zeta[k], std::sqrt(1.0 - zeta[k] * zeta[k])));
    const auto i = static_cast<Eigen::Index>(2 * k);
    A(i, i) = z.real();
    A(i, i + 1) = z.imag();
    A(i + 1, i) = -z.imag();
    A(i + 1, i + 1) = z.real();
  }
  return A;
}

/// Discrete modal system with sample time Ts: one 2x2 real block per mode with
/// poles exp(s Ts), s = 2 pi f (-zeta +/- j sqrt(1 - zeta^2)) (f in Hz; with Ts = 1,
/// in cycles per sample), B, C, D uniform in [-1, 1], then a random similarity
/// T = U + 2 I (U uniform in [-1, 1]) so A is not block-diagonal.
inline StateSpace rotated_modal_system(const std::vector<double>& f, const std::vector<double>& zeta, int m, int l,
                                       std::uint64_t seed, double Ts = 1.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const int n = 2 * static_cast<int>(f.size());
  const Eigen::MatrixXd A = modal_block_matrix(f, zeta, Ts);
  Eigen::MatrixXd B(n, m), C(l, n), D(l, m), T(n, n);
  for (Eigen::MatrixXd* M : {&B, &C, &D, &T})
    for (Eigen::Index r = 0; r < M->rows(); ++r)
      for (Eigen::Index c = 0; c < M->cols(); ++c) (*M)(r, c) = unit(rng);
  T.diagonal().array() += 2.0;
  const Eigen::MatrixXd Ti = T.inverse();
  return StateSpace(T * A * Ti, T * B, C * Ti, D, Ts);
}

}  // namespace sysid::test
