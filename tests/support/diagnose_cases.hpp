#pragma once
// Test and bench support for diagnose: a physics block from a parameter list, an
// identified model as a nominal, a two-mode collocated structure and an
// excitation with velocity reversals and a spread of amplitudes (used by tests/unit/diagnose_*.cpp,
// tests/unit/io_augmented_model_file.cpp, tests/acceptance/diagnose_*.cpp and
// bench/diagnose_bench.cpp).
#include <sysid/core/discretize.hpp>
#include <sysid/diagnose/augmented_model.hpp>
#include <sysid/diagnose/physics_block.hpp>
#include <sysid/subspace/n4sid.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <string>

#include "random_systems.hpp"

namespace sysid::test {

inline PhysicsBlock physics_block(const std::string& kind, std::map<std::string, double> params, long input = 0,
                                  long output = 0) {
  PhysicsBlock b;
  b.kind = kind;
  b.params = std::move(params);
  b.input = input;
  b.output = output;
  return b;
}

/// An identified linear model as diagnose's nominal: its x0 and offsets kept.
inline AugmentedModel nominal_from(const N4sidResult& identified) {
  AugmentedModel nominal;
  nominal.nominal = identified.model;
  nominal.x0 = identified.x0;
  nominal.input_offset = identified.input_offset;
  nominal.output_offset = identified.output_offset;
  return nominal;
}

/// Two-mode structure (f1 = 25 Hz, damping 0.02; f2 = 34 Hz, 0.015 by default)
/// sampled with a ZOH at Ts, force in (the first mode's input gain b1), collocated
/// position out, channels named u and y.
inline StateSpace two_mode_structure(double Ts, double f1_hz = 25.0, double f2_hz = 34.0, double b1 = 1.0) {
  constexpr double two_pi = 2.0 * std::numbers::pi;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4, 4), B(4, 1), C(1, 4);
  const double w1 = two_pi * f1_hz, w2 = two_pi * f2_hz;
  A(0, 1) = 1;
  A(1, 0) = -w1 * w1;
  A(1, 1) = -2 * 0.02 * w1;
  A(2, 3) = 1;
  A(3, 2) = -w2 * w2;
  A(3, 3) = -2 * 0.015 * w2;
  B << 0, b1, 0, 1;
  C << 1, 0, 0.5, 0;
  StateSpace s = c2d_zoh(StateSpace(A, B, C, Eigen::MatrixXd::Zero(1, 1), 0.0), Ts);
  s.input_names = {"u"};
  s.output_names = {"y"};
  return s;
}

/// First-order low-passed white noise (corner 60 Hz, scaled 1e4) plus a slow
/// 1.3 Hz sine of amplitude 300: velocity reversals and a spread of amplitudes.
inline Eigen::MatrixXd reversing_excitation(Eigen::Index n, double Ts, std::uint64_t seed) {
  constexpr double two_pi = 2.0 * std::numbers::pi;
  const Eigen::MatrixXd w = white_noise(n, 1, seed);
  Eigen::MatrixXd u(n, 1);
  double s = 0;
  const double a = std::exp(-two_pi * 60 * Ts);
  for (Eigen::Index k = 0; k < n; ++k) {
    s = a * s + (1 - a) * w(k, 0);
    u(k, 0) = 1e4 * s + 300.0 * std::sin(two_pi * 1.3 * static_cast<double>(k) * Ts);
  }
  return u;
}

}  // namespace sysid::test
