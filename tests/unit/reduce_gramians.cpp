// Tests for sysid::controllability_gramian_factor / observability_gramian_factor /
// gramian_factors (include/sysid/reduce/gramians.hpp).
#include <sysid/reduce/gramians.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <random>

#include "random_matrices.hpp"

namespace test_unit_reduce_gramians {

namespace {

using Eigen::MatrixXd;

/// Random stable A (n x n): a random matrix shifted/scaled so its spectral abscissa
/// (continuous) or radius (discrete) is `margin` inside the boundary.
MatrixXd random_stable(int n, bool discrete, double margin, std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  MatrixXd A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = g(rng);
  const Eigen::VectorXcd ev = A.eigenvalues();
  if (discrete) A /= ev.cwiseAbs().maxCoeff() / (1.0 - margin);
  else A.diagonal().array() -= ev.real().maxCoeff() + margin;
  return A;
}

double residual(const MatrixXd& A, const MatrixXd& W, const MatrixXd& BBt, bool discrete) {
  const MatrixXd R = discrete ? MatrixXd(A * W * A.transpose() - W + BBt) : MatrixXd(A * W + W * A.transpose() + BBt);
  // Backward-error scale: a backward stable solver leaves a residual of
  // O(n eps (||A||^2 ||W|| + ||B B^T||)) (discrete) or O(n eps (||A|| ||W|| + ...)).
  const double scale = discrete ? A.norm() * A.norm() * W.norm() + BBt.norm() : 2 * A.norm() * W.norm() + BBt.norm();
  return R.norm() / scale;
}

TEST(ReduceGramians, ResidualsSmallOnRandomStableSystems) {
  std::mt19937_64 rng(11);
  for (bool discrete : {false, true})
    for (int n : {1, 2, 3, 7, 20, 40})
      for (int m : {1, 3, 9}) {  // m = 9 > n for small n exercises the column compression
        for (double margin : {0.3, 1e-3}) {  // 1e-3: lightly damped / near the unit circle
          const MatrixXd A = random_stable(n, discrete, margin, rng);
          const MatrixXd B = sysid::test::randn(rng, n, m), C = sysid::test::randn(rng, m, n);
          const MatrixXd Lc = sysid::controllability_gramian_factor(A, B, discrete);
          const MatrixXd Lo = sysid::observability_gramian_factor(A, C, discrete);
          ASSERT_EQ(Lc.rows(), n);
          ASSERT_EQ(Lc.cols(), n);
          // Lower triangular, as documented.
          EXPECT_EQ(Lc.triangularView<Eigen::StrictlyUpper>().toDenseMatrix().norm(), 0.0);
          EXPECT_LT(residual(A, Lc * Lc.transpose(), B * B.transpose(), discrete), 1e-13 * n)
              << "n=" << n << " m=" << m << " discrete=" << discrete;
          EXPECT_LT(residual(A.transpose(), Lo * Lo.transpose(), C.transpose() * C, discrete), 1e-13 * n)
              << "n=" << n << " m=" << m << " discrete=" << discrete;
        }
      }
}

TEST(ReduceGramians, ScalarAnalytic) {
  // Discrete x+ = a x + b u: Wc = b^2 / (1 - a^2). Continuous: Wc = b^2 / (-2 a).
  MatrixXd a(1, 1), b(1, 1);
  a << 0.9;
  b << 2.0;
  EXPECT_NEAR(sysid::gramian_from_factor(sysid::controllability_gramian_factor(a, b, true))(0, 0),
              4.0 / (1.0 - 0.81), 1e-13 * 4.0 / 0.19);
  a << -3.0;
  EXPECT_NEAR(sysid::gramian_from_factor(sysid::controllability_gramian_factor(a, b, false))(0, 0), 4.0 / 6.0,
              1e-15);
}

TEST(ReduceGramians, LightlyDampedOscillatorAnalytic) {
  // x = [q, dq/dt], ddq + 2 zeta w dq + w^2 q = u: Wc = diag(1 / (4 zeta w^3), 1 / (4 zeta w))
  // (solve the 2x2 Lyapunov equation by hand). zeta = 1e-4 gives a Gramian of
  // condition w^2 and entries ~ 1/zeta: the factor must stay accurate anyway.
  const double w = 2 * std::numbers::pi * 50.0, zeta = 1e-4;
  MatrixXd A(2, 2), B(2, 1);
  A << 0, 1, -w * w, -2 * zeta * w;
  B << 0, 1;
  const MatrixXd W = sysid::gramian_from_factor(sysid::controllability_gramian_factor(A, B, false));
  const double w11 = 1 / (4 * zeta * w * w * w), w22 = 1 / (4 * zeta * w);
  // Relative accuracy ~ eps cond(A) / (distance to the boundary) ~ 1e-16 * w^2 / (zeta w) here.
  EXPECT_NEAR(W(0, 0) / w11, 1.0, 1e-9);
  EXPECT_NEAR(W(1, 1) / w22, 1.0, 1e-9);
  EXPECT_LT(std::abs(W(0, 1)), 1e-9 * std::sqrt(w11 * w22));
}

TEST(ReduceGramians, BothFactorsFromOneSchurMatchSeparateCalls) {
  std::mt19937_64 rng(5);
  const MatrixXd A = random_stable(12, true, 0.05, rng);
  const MatrixXd B = sysid::test::randn(rng, 12, 2), C = sysid::test::randn(rng, 3, 12);
  const sysid::StateSpace s(A, B, C, MatrixXd::Zero(3, 2), 0.01);
  const sysid::GramianFactors f = sysid::gramian_factors(s);
  const MatrixXd Wc = f.controllability * f.controllability.transpose();
  const MatrixXd Wo = f.observability * f.observability.transpose();
  const MatrixXd Wc2 = sysid::gramian_from_factor(sysid::controllability_gramian_factor(A, B, true));
  const MatrixXd Wo2 = sysid::gramian_from_factor(sysid::observability_gramian_factor(A, C, true));
  EXPECT_LT((Wc - Wc2).norm(), 1e-12 * Wc.norm());
  EXPECT_LT((Wo - Wo2).norm(), 1e-12 * Wo.norm());
}

TEST(ReduceGramians, UnstableOrBadShapesThrow) {
  MatrixXd A(2, 2), B(2, 1), C(1, 2);
  A << 1.01, 0, 0, 0.5;
  B << 1, 1;
  C << 1, 1;
  EXPECT_THROW(sysid::controllability_gramian_factor(A, B, true), std::invalid_argument);
  A << 0.1, 0, 0, -1.0;
  EXPECT_THROW(sysid::observability_gramian_factor(A, C, false), std::invalid_argument);
  EXPECT_THROW(sysid::controllability_gramian_factor(A, C, false), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_reduce_gramians
