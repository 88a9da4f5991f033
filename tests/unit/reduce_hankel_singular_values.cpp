// Tests for sysid::hankel_singular_values / stable_unstable_split
// (include/sysid/reduce/hankel_singular_values.hpp).
#include <sysid/core/frequency_response.hpp>
#include <sysid/reduce/hankel_singular_values.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "random_matrices.hpp"

namespace test_unit_reduce_hankel_singular_values {

namespace {

using Eigen::MatrixXd;

/// Random discrete system: modes at radius in [r_lo, r_hi], rotated by a random
/// similarity of moderate condition.
sysid::StateSpace random_discrete(int pairs, int m, int l, double r_lo, double r_hi, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const int n = 2 * pairs;
  MatrixXd A = MatrixXd::Zero(n, n);
  for (int k = 0; k < pairs; ++k) {
    const double r = r_lo + (r_hi - r_lo) * u(rng), th = 0.05 + 3.0 * u(rng);
    A.block(2 * k, 2 * k, 2, 2) << r * std::cos(th), r * std::sin(th), -r * std::sin(th), r * std::cos(th);
  }
  MatrixXd T = sysid::test::randn(rng, n, n) + 3.0 * MatrixXd::Identity(n, n);
  const MatrixXd Ti = T.inverse();
  return sysid::StateSpace(T * A * Ti, T * sysid::test::randn(rng, n, m), sysid::test::randn(rng, l, n) * Ti,
                           sysid::test::randn(rng, l, m), 0.001);
}

TEST(ReduceHankelSingularValues, FirstOrderAnalytic) {
  // Discrete G = b c / (z - a): Wc = b^2 / (1 - a^2), Wo = c^2 / (1 - a^2), sigma = |b c| / (1 - a^2).
  const sysid::StateSpace d(MatrixXd::Constant(1, 1, 0.8), MatrixXd::Constant(1, 1, 2.0),
                            MatrixXd::Constant(1, 1, -1.5), MatrixXd::Zero(1, 1), 0.1);
  const auto hd = sysid::hankel_singular_values(d);
  ASSERT_EQ(hd.values.size(), 1);
  EXPECT_NEAR(hd.values(0), 3.0 / 0.36, 1e-13 * 3.0 / 0.36);
  // Continuous G = b c / (s + a): sigma = |b c| / (2 a).
  const sysid::StateSpace c(MatrixXd::Constant(1, 1, -4.0), MatrixXd::Constant(1, 1, 2.0),
                            MatrixXd::Constant(1, 1, 3.0), MatrixXd::Zero(1, 1), 0.0);
  EXPECT_NEAR(sysid::hankel_singular_values(c).values(0), 6.0 / 8.0, 1e-15);
}

TEST(ReduceHankelSingularValues, ParallelFirstOrderModesAnalytic) {
  // Two decoupled first-order modes, each driven by its own input and seen by its
  // own output: the Gramians are diagonal and the HSV are the two scalar ones.
  MatrixXd A(2, 2), B(2, 2), C(2, 2);
  A << -1.0, 0, 0, -10.0;
  B << 1, 0, 0, 4;
  C << 2, 0, 0, 1;
  const auto h = sysid::hankel_singular_values(sysid::StateSpace(A, B, C, MatrixXd::Zero(2, 2), 0.0));
  ASSERT_EQ(h.values.size(), 2);
  EXPECT_NEAR(h.values(0), 1.0, 1e-14);  // 2 / 2
  EXPECT_NEAR(h.values(1), 0.2, 1e-14);  // 4 / 20
}

TEST(ReduceHankelSingularValues, InvariantUnderStateTransformationAndMatchDenseFormula) {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 10; ++trial) {
    const sysid::StateSpace s = random_discrete(3 + trial, 1 + trial % 3, 1 + (trial + 1) % 3, 0.5, 0.995, rng);
    const int n = static_cast<int>(s.order());
    const Eigen::VectorXd h = sysid::hankel_singular_values(s).values;
    ASSERT_EQ(h.size(), n);
    for (int i = 1; i < n; ++i) EXPECT_GE(h(i - 1), h(i));
    // Badly scaled similarity (column scales over 2 decades): HSV unchanged.
    MatrixXd T = sysid::test::randn(rng, n, n) + 3.0 * MatrixXd::Identity(n, n);
    for (int j = 0; j < n; ++j) T.col(j) *= std::pow(10.0, -1.0 + 2.0 * j / std::max(1, n - 1));
    const MatrixXd Ti = T.inverse();
    const sysid::StateSpace st(T * s.A * Ti, T * s.B, s.C * Ti, s.D, s.Ts);
    const Eigen::VectorXd ht = sysid::hankel_singular_values(st).values;
    // Forming T A T^-1 perturbs A by ~eps cond(T) ||A|| (cond(T) ~ 1e3), and HSV of
    // poles at |z| = 0.995 move by that times ~1/(1 - |z|)^2 ~ 4e4: ~1e-8 relative,
    // observed up to 3e-7 (the HSV algorithm itself agrees with a Jacobi SVD of
    // Lo^T Lc to < 1e-12 on these systems).
    EXPECT_LT((h - ht).cwiseAbs().maxCoeff(), 2e-6 * h(0)) << "trial " << trial;
    // sqrt(eig(Wc Wo)) from the Gramians themselves.
    const sysid::GramianFactors f = sysid::gramian_factors(s);
    const MatrixXd P = (f.controllability * f.controllability.transpose()) * (f.observability * f.observability.transpose());
    Eigen::VectorXd ev = P.eigenvalues().real().cwiseMax(0.0).cwiseSqrt();
    std::sort(ev.data(), ev.data() + n, std::greater<double>());
    // The nonsymmetric eigenproblem of Wc Wo is itself ill conditioned (error
    // ~ eps kappa(Wc) kappa(Wo)): observed up to 4e-7 relative.
    EXPECT_LT((h - ev).cwiseAbs().maxCoeff(), 2e-6 * h(0)) << "trial " << trial;
  }
}

/// Stable part (given) plus an unstable part, coupled by a random similarity.
sysid::StateSpace with_unstable_part(const sysid::StateSpace& s, const MatrixXd& Au, std::mt19937_64& rng) {
  const int ns = static_cast<int>(s.order()), nu = static_cast<int>(Au.rows());
  const int n = ns + nu, m = static_cast<int>(s.inputs()), l = static_cast<int>(s.outputs());
  MatrixXd A = MatrixXd::Zero(n, n), B(n, m), C(l, n);
  A.topLeftCorner(ns, ns) = s.A;
  A.bottomRightCorner(nu, nu) = Au;
  B << s.B, sysid::test::randn(rng, nu, m);
  C << s.C, sysid::test::randn(rng, l, nu);
  MatrixXd T = sysid::test::randn(rng, n, n) + 3.0 * MatrixXd::Identity(n, n);
  const MatrixXd Ti = T.inverse();
  return sysid::StateSpace(T * A * Ti, T * B, C * Ti, s.D, s.Ts);
}

TEST(ReduceHankelSingularValues, UnstablePartExcludedAndCounted) {
  std::mt19937_64 rng(8);
  const sysid::StateSpace s = random_discrete(4, 2, 2, 0.3, 0.9, rng);
  const Eigen::VectorXd h = sysid::hankel_singular_values(s).values;
  MatrixXd Au(3, 3);  // a pair outside the unit circle and an integrator (z = 1, marginal)
  Au << 1.02 * std::cos(0.3), 1.02 * std::sin(0.3), 0, -1.02 * std::sin(0.3), 1.02 * std::cos(0.3), 0, 0, 0, 1.0;
  const sysid::StateSpace su = with_unstable_part(s, Au, rng);
  const auto hu = sysid::hankel_singular_values(su);
  EXPECT_EQ(hu.unstable_states, 3);
  ASSERT_EQ(hu.values.size(), 8);
  // The additive stable part is unique, so its HSV are those of s (absolute error
  // ~ eps sigma_1 cond(T) ||X||).
  EXPECT_LT((hu.values - h).cwiseAbs().maxCoeff(), 1e-8 * h(0));
}

TEST(ReduceHankelSingularValues, SplitAddsUpToTheModel) {
  std::mt19937_64 rng(21);
  const sysid::StateSpace s = random_discrete(3, 2, 3, 0.4, 0.95, rng);
  MatrixXd Au(2, 2);
  Au << 1.3, 0.2, 0.0, -1.1;
  const sysid::StateSpace full = with_unstable_part(s, Au, rng);
  const sysid::StabilitySplit sp = sysid::stable_unstable_split(full);
  EXPECT_EQ(sp.stable.order(), 6);
  EXPECT_EQ(sp.unstable.order(), 2);
  for (const auto& p : sysid::poles(sp.stable)) EXPECT_LT(std::abs(p), 1.0);
  for (const auto& p : sysid::poles(sp.unstable)) EXPECT_GT(std::abs(p), 1.0);
  // G = G_s + G_u at points off the unit circle and off the poles.
  for (std::complex<double> z : {std::complex<double>(0.3, 1.7), std::complex<double>(-2.0, 0.5),
                                 std::complex<double>(0.0, 0.2)}) {
    const Eigen::MatrixXcd g = sysid::frequency_response_at(full, z);
    const Eigen::MatrixXcd g2 = sysid::frequency_response_at(sp.stable, z) + sysid::frequency_response_at(sp.unstable, z);
    EXPECT_LT((g - g2).norm(), 1e-9 * g.norm());
  }
}

TEST(ReduceHankelSingularValues, ContinuousWithIntegratorAndStaticModel) {
  MatrixXd A(2, 2), B(2, 1), C(1, 2);
  A << 0, 0, 0, -2;  // integrator + stable pole
  B << 1, 1;
  C << 1, 3;
  const auto h = sysid::hankel_singular_values(sysid::StateSpace(A, B, C, MatrixXd::Zero(1, 1), 0.0));
  EXPECT_EQ(h.unstable_states, 1);
  ASSERT_EQ(h.values.size(), 1);
  EXPECT_NEAR(h.values(0), 3.0 / 4.0, 1e-14);
  const sysid::StateSpace st(MatrixXd(0, 0), MatrixXd(0, 1), MatrixXd(1, 0), MatrixXd::Ones(1, 1), 0.0);
  EXPECT_EQ(sysid::hankel_singular_values(st).values.size(), 0);
}

}  // namespace

}  // namespace test_unit_reduce_hankel_singular_values
