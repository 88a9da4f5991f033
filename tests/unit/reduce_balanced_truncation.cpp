// Tests for sysid::balanced_truncation (include/sysid/reduce/balanced_truncation.hpp).
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/reduce/balanced_truncation.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "random_matrices.hpp"

namespace test_unit_reduce_balanced_truncation {

namespace {

using Eigen::MatrixXd;
using sysid::test::kPi;

/// Random stable MIMO system of order n: complex pairs with damping log-uniform in
/// [zeta_lo, 0.7] and natural frequencies log-uniform over two decades, plus real
/// poles, in modal form rotated by a random similarity. Discrete: poles mapped by
/// z = exp(s Ts), Ts chosen so the highest frequency stays below Nyquist.
sysid::StateSpace random_stable_system(int n, int m, int l, bool discrete, double zeta_lo, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double Ts = discrete ? 1e-3 : 0.0;
  MatrixXd A = MatrixXd::Zero(n, n);
  int k = 0;
  while (k < n) {
    const double wn = 2 * kPi * std::pow(10.0, 0.5 + 2.0 * u(rng));  // 3 .. 316 Hz
    if (k + 1 < n && u(rng) < 0.8) {
      const double zeta = std::exp(std::log(zeta_lo) + (std::log(0.7) - std::log(zeta_lo)) * u(rng));
      std::complex<double> p(-zeta * wn, wn * std::sqrt(1 - zeta * zeta));
      if (discrete) p = std::exp(p * Ts);
      A.block(k, k, 2, 2) << p.real(), p.imag(), -p.imag(), p.real();
      k += 2;
    } else {
      A(k, k) = discrete ? std::exp(-wn * Ts) : -wn;
      k += 1;
    }
  }
  MatrixXd T = sysid::test::randn(rng, n, n) + 3.0 * MatrixXd::Identity(n, n);
  const MatrixXd Ti = T.inverse();
  return sysid::StateSpace(T * A * Ti, T * sysid::test::randn(rng, n, m), sysid::test::randn(rng, l, n) * Ti,
                           sysid::test::randn(rng, l, m), Ts);
}

TEST(ReduceBalancedTruncation, HinfErrorWithinBoundOnRandomSweep) {
  // Issue requirement: on 200 seeded random stable MIMO systems (orders 4..40,
  // 1..4 inputs/outputs, discrete and continuous, some lightly damped) the measured
  // H-inf error never exceeds 2 sum(discarded HSV), for truncation and singular
  // perturbation. The grid maximum is a lower estimate of the true norm, so only
  // rounding can push it above the bound: relative 1e-6 covers the HSV's absolute
  // error (~n eps sigma_1 cond) for the cut positions used (discarded sum >= 1e-6 sigma_1).
  // The other side checks the grid: ||G - G_r||_inf >= sigma_{r+1} (Glover 1984),
  // so a grid that missed the peak by more than its documented resolution fails.
  std::mt19937_64 rng(2024);
  std::uniform_int_distribution<int> order(4, 40), io(1, 4);
  int checked = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const bool discrete = trial % 2 == 0;
    const double zeta_lo = trial % 3 == 0 ? 0.002 : 0.05;
    const int n = order(rng), m = io(rng), l = io(rng);
    const sysid::StateSpace s = random_stable_system(n, m, l, discrete, zeta_lo, rng);
    const Eigen::VectorXd h = sysid::hankel_singular_values(s).values;
    int r_max = 1;
    while (r_max < n - 1 && h(r_max) > 1e-6 * h(0)) ++r_max;
    const int r = 1 + static_cast<int>(rng() % static_cast<unsigned>(r_max));
    for (sysid::BalancedMethod method : {sysid::BalancedMethod::truncation, sysid::BalancedMethod::singular_perturbation}) {
      sysid::BalancedTruncationOptions o;
      o.order = r;
      o.method = method;
      const sysid::ReductionResult res = sysid::balanced_truncation(s, o);
      ASSERT_EQ(res.order, r) << "trial " << trial;
      ASSERT_EQ(res.unstable_states, 0);
      const double sigma_next = res.hsv(r);
      EXPECT_LE(res.hinf_error, res.hinf_bound * (1 + 1e-6))
          << "trial " << trial << " n=" << n << " r=" << r << " " << res.method;
      EXPECT_GE(res.hinf_error, sigma_next * (1 - 0.01))
          << "trial " << trial << " n=" << n << " r=" << r << " " << res.method;
      for (const auto& p : sysid::poles(res.model))
        EXPECT_TRUE(discrete ? std::abs(p) < 1.0 : p.real() < 0.0) << "trial " << trial;  // balanced truncation preserves stability
      ++checked;
    }
  }
  EXPECT_EQ(checked, 400);
}

TEST(ReduceBalancedTruncation, SingularPerturbationKeepsDcGainExactly) {
  std::mt19937_64 rng(7);
  for (bool discrete : {true, false}) {
    const sysid::StateSpace s = random_stable_system(16, 2, 3, discrete, 0.01, rng);
    sysid::BalancedTruncationOptions o;
    o.order = 5;
    o.method = sysid::BalancedMethod::singular_perturbation;
    const sysid::ReductionResult spa = sysid::balanced_truncation(s, o);
    o.method = sysid::BalancedMethod::truncation;
    const sysid::ReductionResult bt = sysid::balanced_truncation(s, o);
    const Eigen::VectorXd f0 = Eigen::VectorXd::Zero(1);
    const Eigen::MatrixXcd g = sysid::frequency_response(s, f0)[0];
    const Eigen::MatrixXcd gs = sysid::frequency_response(spa.model, f0)[0];
    const Eigen::MatrixXcd gb = sysid::frequency_response(bt.model, f0)[0];
    // Exact up to rounding (relative to the HSV scale, i.e. the size of G).
    EXPECT_LT((g - gs).norm(), 1e-9 * spa.hsv(0)) << "discrete=" << discrete;
    EXPECT_LT(spa.dc_error, 1e-9 * spa.hsv(0));
    // Truncation generally does not (guards against a test that cannot fail).
    EXPECT_GT((g - gb).norm(), 1e-6 * bt.hsv(0));
  }
}

TEST(ReduceBalancedTruncation, UnstablePartKeptWhole) {
  std::mt19937_64 rng(9);
  const sysid::StateSpace s = random_stable_system(12, 2, 2, true, 0.02, rng);
  // Add an unstable pair and an integrator, coupled by a random similarity.
  const int n = 15;
  MatrixXd A = MatrixXd::Zero(n, n), B(n, 2), C(2, n);
  A.topLeftCorner(12, 12) = s.A;
  A.block(12, 12, 2, 2) << 1.05 * std::cos(0.2), 1.05 * std::sin(0.2), -1.05 * std::sin(0.2), 1.05 * std::cos(0.2);
  A(14, 14) = 1.0;
  B << s.B, sysid::test::randn(rng, 3, 2);
  C << s.C, sysid::test::randn(rng, 2, 3);
  MatrixXd T = sysid::test::randn(rng, n, n) + 3.0 * MatrixXd::Identity(n, n);
  const MatrixXd Ti = T.inverse();
  const sysid::StateSpace su(T * A * Ti, T * B, C * Ti, s.D, s.Ts);
  sysid::BalancedTruncationOptions o;
  o.order = 8;
  const sysid::ReductionResult res = sysid::balanced_truncation(su, o);
  EXPECT_EQ(res.unstable_states, 3);
  EXPECT_EQ(res.order, 8);
  EXPECT_EQ(res.hsv.size(), 12);
  // The three unstable/marginal poles are poles of the reduced model.
  const Eigen::VectorXcd pr = sysid::poles(res.model);
  for (std::complex<double> p : {std::polar(1.05, 0.2), std::polar(1.05, -0.2), std::complex<double>(1.0, 0.0)}) {
    double best = 1e300;
    for (Eigen::Index i = 0; i < pr.size(); ++i) best = std::min(best, std::abs(pr(i) - p));
    EXPECT_LT(best, 1e-9) << p;
  }
  // G - G_r is the stable-part error: bounded as for a stable model.
  EXPECT_LE(res.hinf_error, res.hinf_bound * (1 + 1e-6));
  // And checked independently off the unit circle (where the integrator is finite).
  const std::complex<double> z(0.2, 1.3);
  const double d = (sysid::frequency_response_at(su, z) - sysid::frequency_response_at(res.model, z)).norm();
  EXPECT_LT(d, 2.0 * res.hinf_bound);
  o.order = 2;
  EXPECT_THROW(sysid::balanced_truncation(su, o), std::invalid_argument);
}

TEST(ReduceBalancedTruncation, OrderFromErrorRatioOrBound) {
  std::mt19937_64 rng(13);
  const sysid::StateSpace s = random_stable_system(20, 3, 2, true, 0.01, rng);
  const Eigen::VectorXd h = sysid::hankel_singular_values(s).values;
  const double total = h.sum();
  sysid::BalancedTruncationOptions o;
  o.max_error_ratio = 0.1;
  const sysid::ReductionResult a = sysid::balanced_truncation(s, o);
  const Eigen::Index r = a.order;
  ASSERT_GT(r, 0);
  EXPECT_LE(h.tail(20 - r).sum() / total, 0.1 + 1e-12);
  EXPECT_GT(h.tail(20 - r + 1).sum() / total, 0.1);  // minimal: one fewer state is not enough
  EXPECT_NEAR(a.error_ratio, h.tail(20 - r).sum() / total, 1e-12);
  sysid::BalancedTruncationOptions ob;
  ob.max_hinf_bound = 2.0 * h.tail(10).sum() * 1.0000001;
  const sysid::ReductionResult b = sysid::balanced_truncation(s, ob);
  EXPECT_EQ(b.order, 10);
  EXPECT_LE(b.hinf_bound, ob.max_hinf_bound);
  EXPECT_THROW(sysid::balanced_truncation(s, sysid::BalancedTruncationOptions{}), std::invalid_argument);
}

TEST(ReduceBalancedTruncation, WarnsWhenCutSplitsALightlyDampedPair) {
  // One very lightly damped mode dominating: its two HSV are nearly equal, and
  // order 1 splits them.
  const double Ts = 1e-3, w = 2 * kPi * 40, zeta = 0.001;
  const std::complex<double> p = std::exp(std::complex<double>(-zeta * w, w * std::sqrt(1 - zeta * zeta)) * Ts);
  MatrixXd A = MatrixXd::Zero(4, 4), B(4, 1), C(1, 4);
  A.block(0, 0, 2, 2) << p.real(), p.imag(), -p.imag(), p.real();
  A.block(2, 2, 2, 2) << 0.5, 0.3, -0.3, 0.5;
  B << 1, 0.5, 1, 0.2;
  C << 0.3, 1, 0.5, 0.5;
  const sysid::StateSpace s(A, B, C, MatrixXd::Zero(1, 1), Ts);
  sysid::BalancedTruncationOptions o;
  o.order = 1;
  EXPECT_FALSE(sysid::balanced_truncation(s, o).warnings.empty());
  o.order = 2;
  EXPECT_TRUE(sysid::balanced_truncation(s, o).warnings.empty());
}

TEST(ReduceBalancedTruncation, NonMinimalModelOrderCapped) {
  std::mt19937_64 rng(17);
  const sysid::StateSpace s = random_stable_system(6, 1, 1, false, 0.1, rng);
  // Append 4 uncontrollable states (B rows zero): the minimal order is 6.
  const int n = 10;
  MatrixXd A = MatrixXd::Zero(n, n), B = MatrixXd::Zero(n, 1), C(1, n);
  A.topLeftCorner(6, 6) = s.A;
  A.bottomRightCorner(4, 4) = -5.0 * MatrixXd::Identity(4, 4) + 0.1 * sysid::test::randn(rng, 4, 4);
  B.topRows(6) = s.B;
  C << s.C, sysid::test::randn(rng, 1, 4);
  sysid::BalancedTruncationOptions o;
  o.order = 9;
  const sysid::ReductionResult res = sysid::balanced_truncation(sysid::StateSpace(A, B, C, s.D, 0.0), o);
  EXPECT_EQ(res.order, 6);
  EXPECT_FALSE(res.warnings.empty());
  EXPECT_LT(res.hinf_error, 1e-8 * res.hsv(0));
}

}  // namespace

}  // namespace test_unit_reduce_balanced_truncation
