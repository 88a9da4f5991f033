// Tests for sysid::simulate / simulate_states (include/sysid/core/simulate.hpp).
#include <sysid/core/simulate.hpp>

#include <sysid/core/flush_subnormals.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include "random_matrices.hpp"
#include "subnormals.hpp"

namespace test_unit_core_simulate {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

using sysid::test::randn;
/// Random discrete model with spectral radius `radius` (< 1: stable).
sysid::StateSpace random_discrete(std::mt19937_64& rng, Eigen::Index n, Eigen::Index m, Eigen::Index l, double radius) {
  MatrixXd A = randn(rng, n, n);
  const double rho = A.eigenvalues().cwiseAbs().maxCoeff();
  A *= radius / rho;
  return sysid::StateSpace(A, randn(rng, n, m), randn(rng, l, n), randn(rng, l, m), 0.01);
}

/// The textbook recursion, one sample at a time: the reference.
MatrixXd reference_output(const sysid::StateSpace& s, const MatrixXd& u, VectorXd x, MatrixXd* states = nullptr) {
  MatrixXd y(u.rows(), s.outputs());
  if (states) states->resize(u.rows(), s.order());
  for (Eigen::Index k = 0; k < u.rows(); ++k) {
    // An input-free model's u has no data (null pointer): no row of it is formed.
    const VectorXd uk = u.cols() > 0 ? VectorXd(u.row(k).transpose()) : VectorXd(0);
    if (states) states->row(k) = x.transpose();
    y.row(k) = (s.C * x + s.D * uk).transpose();
    x = s.A * x + s.B * uk;
  }
  return y;
}

// Both sides compute the same sums in different association orders; for a stable
// model the difference is a few eps times the size of the terms, so 1e-12
// relative to the output scale leaves a wide margin while catching any indexing
// slip (an off-by-one shifts y by O(1)).
double rel_diff(const MatrixXd& a, const MatrixXd& b) { return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff()); }

TEST(CoreSimulate, MatchesHandRolledRecursionSweep) {
  std::mt19937_64 rng(20240601);
  for (Eigen::Index n = 1; n <= 12; ++n)
    for (Eigen::Index m = 1; m <= 3; ++m)
      for (Eigen::Index l = 1; l <= 3; ++l) {
        const sysid::StateSpace s = random_discrete(rng, n, m, l, 0.95);
        const MatrixXd u = randn(rng, 157, m);
        const VectorXd x0 = randn(rng, n, 1);
        MatrixXd xref;
        const MatrixXd yref = reference_output(s, u, x0, &xref);
        EXPECT_LT(rel_diff(sysid::simulate(s, u, x0), yref), 1e-12) << "n=" << n << " m=" << m << " l=" << l;
        EXPECT_LT(rel_diff(sysid::simulate_states(s, u, x0), xref), 1e-12) << "n=" << n;
        // zero initial state by default
        EXPECT_LT(rel_diff(sysid::simulate(s, u), reference_output(s, u, VectorXd::Zero(n))), 1e-12);
      }
}

TEST(CoreSimulate, ImpulseResponseEqualsMarkovParameters) {
  std::mt19937_64 rng(7);
  const sysid::StateSpace s = random_discrete(rng, 6, 2, 3, 0.9);
  const Eigen::Index N = 40;
  for (Eigen::Index j = 0; j < 2; ++j) {
    MatrixXd u = MatrixXd::Zero(N, 2);
    u(0, j) = 1.0;
    const MatrixXd y = sysid::simulate(s, u);
    // h_0 = D, h_k = C A^(k-1) B
    EXPECT_LT((y.row(0).transpose() - s.D.col(j)).norm(), 1e-14);
    VectorXd Akb = s.B.col(j);
    for (Eigen::Index k = 1; k < N; ++k) {
      const VectorXd h = s.C * Akb;
      EXPECT_LT((y.row(k).transpose() - h).norm(), 1e-12 * std::max(1.0, h.norm())) << "k=" << k;
      Akb = s.A * Akb;
    }
  }
}

TEST(CoreSimulate, LongRecordCrossesBlockBoundaries) {
  // Blocks of 4096 samples: the state must carry over exactly between them.
  std::mt19937_64 rng(11);
  const sysid::StateSpace s = random_discrete(rng, 5, 2, 2, 0.99);
  const MatrixXd u = randn(rng, 3 * 4096 + 17, 2);
  const VectorXd x0 = randn(rng, 5, 1);
  const MatrixXd yref = reference_output(s, u, x0);
  const MatrixXd y = sysid::simulate(s, u, x0);
  EXPECT_LT(rel_diff(y, yref), 1e-11);
  // output = states C^T + u D^T
  const MatrixXd X = sysid::simulate_states(s, u, x0);
  EXPECT_LT(rel_diff(y, X * s.C.transpose() + u * s.D.transpose()), 1e-12);
}

TEST(CoreSimulate, AcceptsExpressionsAndRowMajorInput) {
  std::mt19937_64 rng(3);
  const sysid::StateSpace s = random_discrete(rng, 4, 2, 1, 0.8);
  const MatrixXd u = randn(rng, 300, 2);
  const MatrixXd yref = reference_output(s, 2.0 * u, VectorXd::Zero(4));
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> ur = 2.0 * u;
  EXPECT_LT(rel_diff(sysid::simulate(s, 2.0 * u), yref), 1e-12);
  EXPECT_LT(rel_diff(sysid::simulate(s, ur), yref), 1e-12);
  const MatrixXd wide = randn(rng, 300, 5);
  EXPECT_LT(rel_diff(sysid::simulate(s, wide.middleCols(1, 2)), reference_output(s, wide.middleCols(1, 2), VectorXd::Zero(4))),
            1e-12);
}

TEST(CoreSimulate, UnstableModelGrowsLikeTheRecursion) {
  const sysid::StateSpace s(MatrixXd::Constant(1, 1, 1.1), MatrixXd::Ones(1, 1), MatrixXd::Ones(1, 1), MatrixXd::Zero(1, 1), 1.0);
  const MatrixXd u = MatrixXd::Zero(50, 1);
  const MatrixXd y = sysid::simulate(s, u, VectorXd::Ones(1));
  EXPECT_NEAR(y(49, 0) / std::pow(1.1, 49), 1.0, 1e-13);
}

TEST(CoreSimulate, StaticGainAndEmptyRecord) {
  const sysid::StateSpace g(MatrixXd(0, 0), MatrixXd(0, 2), MatrixXd(3, 0), (MatrixXd(3, 2) << 1, 2, 3, 4, 5, 6).finished(), 0.1);
  std::mt19937_64 rng(5);
  const MatrixXd u = randn(rng, 20, 2);
  EXPECT_LT(rel_diff(sysid::simulate(g, u), u * g.D.transpose()), 1e-15);
  EXPECT_EQ(sysid::simulate_states(g, u).cols(), 0);
  const sysid::StateSpace s = random_discrete(rng, 3, 2, 1, 0.5);
  const MatrixXd y = sysid::simulate(s, MatrixXd(0, 2));
  EXPECT_EQ(y.rows(), 0);
  EXPECT_EQ(y.cols(), 1);
}

TEST(CoreSimulate, BlockwiseHandsOverSimulatesOutputBitForBitInOrder) {
  // 10 000 samples: two full blocks of 4096 and a partial one, from a non-zero x0.
  std::mt19937_64 rng(11);
  const sysid::StateSpace s = random_discrete(rng, 5, 2, 3, 0.9);
  const MatrixXd u = randn(rng, 10000, 2);
  const VectorXd x0 = randn(rng, 5, 1);
  const MatrixXd whole = sysid::simulate(s, u, x0);
  MatrixXd pieced = MatrixXd::Constant(10000, 3, std::numeric_limits<double>::quiet_NaN());
  Eigen::Index next = 0;
  int blocks = 0;
  sysid::simulate_blockwise(s, u, x0, [&](Eigen::Index k0, const Eigen::Ref<MatrixXd>& yb) {
    EXPECT_EQ(k0, next);
    EXPECT_LE(yb.rows(), 4096);
    pieced.middleRows(k0, yb.rows()) = yb;
    next = k0 + yb.rows();
    ++blocks;
  });
  EXPECT_EQ(next, 10000);
  EXPECT_EQ(blocks, 3);
  EXPECT_TRUE((pieced.array() == whole.array()).all());
  EXPECT_THROW(sysid::simulate_blockwise(s, MatrixXd::Zero(10, 3), VectorXd(), [](Eigen::Index, const Eigen::Ref<MatrixXd>&) {}),
               std::invalid_argument);
}

/// simulate_blockwise_modal's output, gathered.
MatrixXd simulate_modal(const sysid::StateSpace& s, const MatrixXd& u, const VectorXd& x0, double limit = 1e3) {
  MatrixXd y(u.rows(), s.outputs());
  sysid::simulate_blockwise_modal(
      s, u, x0, [&](Eigen::Index k0, const Eigen::Ref<MatrixXd>& yb) { y.middleRows(k0, yb.rows()) = yb; }, limit);
  return y;
}

TEST(CoreSimulate, ModalCoordinatesAgreeWithTheRecursionSweep) {
  // Real modal coordinates change the rounding, not the model: up to a few eps
  // cond(T) (<= 1e3 here) of the output scale. 1e-10 leaves a margin of ~100
  // and still catches a wrong block sign or a swapped pair (errors of O(1)).
  std::mt19937_64 rng(20261124);
  int modal_runs = 0;
  for (Eigen::Index n = 1; n <= 12; ++n)
    for (Eigen::Index m = 0; m <= 2; ++m)
      for (Eigen::Index l = 1; l <= 2; ++l) {
        const sysid::StateSpace s = random_discrete(rng, n, m, l, 0.97);
        const MatrixXd u = randn(rng, 4096 + 211, m);  // crosses a block boundary
        const VectorXd x0 = randn(rng, n, 1);
        const MatrixXd yref = reference_output(s, u, x0);
        EXPECT_LT(rel_diff(simulate_modal(s, u, x0), yref), 1e-10) << "n=" << n << " m=" << m << " l=" << l;
        EXPECT_LT(rel_diff(simulate_modal(s, u, VectorXd()), reference_output(s, u, VectorXd::Zero(n))), 1e-10);
        if (sysid::detail::modal_recursion(s, 1e3)) ++modal_runs;
      }
  EXPECT_GT(modal_runs, 50);  // most random models have a well-conditioned modal form: the modal path was tested
}

TEST(CoreSimulate, ModalCoordinatesFollowLightlyDampedAndUnstableModes) {
  // Two lightly damped pairs, a real pole and an unstable real pole, in a
  // rotated basis: the long record and the growth must match the recursion.
  std::mt19937_64 rng(4);
  MatrixXd Am = MatrixXd::Zero(6, 6);
  const double r1 = 0.999, t1 = 0.02, r2 = 0.995, t2 = 0.3;
  Am.block(0, 0, 2, 2) << r1 * std::cos(t1), r1 * std::sin(t1), -r1 * std::sin(t1), r1 * std::cos(t1);
  Am.block(2, 2, 2, 2) << r2 * std::cos(t2), r2 * std::sin(t2), -r2 * std::sin(t2), r2 * std::cos(t2);
  Am(4, 4) = 0.5;
  Am(5, 5) = 1.0005;
  const MatrixXd T = randn(rng, 6, 6) + 3.0 * MatrixXd::Identity(6, 6);
  const sysid::StateSpace s(T * Am * T.inverse(), randn(rng, 6, 1), randn(rng, 2, 6), randn(rng, 2, 1), 0.001);
  ASSERT_TRUE(sysid::detail::modal_recursion(s, 1e3).has_value());
  const MatrixXd u = randn(rng, 10000, 1);
  const VectorXd x0 = randn(rng, 6, 1);
  EXPECT_LT(rel_diff(simulate_modal(s, u, x0), reference_output(s, u, x0)), 1e-10);
}

TEST(CoreSimulate, ModalCoordinatesFallBackForADefectiveMatrixOrALowLimit) {
  // A Jordan block has no modal form worth the name (cond(T) ~ 1e8 or worse):
  // the dense recursion runs, bit for bit simulate()'s. So it does at limit 0.
  std::mt19937_64 rng(8);
  MatrixXd A(3, 3);
  A << 0.9, 1, 0, 0, 0.9, 1, 0, 0, 0.9;
  const sysid::StateSpace jordan(A, randn(rng, 3, 1), randn(rng, 1, 3), MatrixXd::Zero(1, 1), 0.1);
  EXPECT_FALSE(sysid::detail::modal_recursion(jordan, 1e3).has_value());
  const MatrixXd u = randn(rng, 500, 1);
  const VectorXd x0 = randn(rng, 3, 1);
  EXPECT_TRUE((simulate_modal(jordan, u, x0).array() == sysid::simulate(jordan, u, x0).array()).all());
  const sysid::StateSpace s = random_discrete(rng, 4, 1, 1, 0.9);
  const VectorXd x0s = randn(rng, 4, 1);
  EXPECT_TRUE((simulate_modal(s, u, x0s, 0.0).array() == sysid::simulate(s, u, x0s).array()).all());
  EXPECT_THROW(simulate_modal(s, MatrixXd::Zero(10, 2), VectorXd()), std::invalid_argument);
  EXPECT_THROW(simulate_modal(s, u, VectorXd::Zero(3)), std::invalid_argument);
}

TEST(CoreSimulate, AFreeResponseReachesZeroWithoutPassingThroughSubnormals) {
  // Where the input is zero for a while the state decays through the subnormal
  // range, where every operation costs ~100 cycles on Intel cores; the recursions
  // flush it to zero (core/flush_subnormals.hpp). The normal range is untouched:
  // the impulse response of x+ = 0.5 x + u is 0.5^(t-1) exactly while that is normal.
  if (!sysid::ScopedFlushSubnormals::supported()) GTEST_SKIP() << "no flush-to-zero mode on this target";
  MatrixXd A(3, 3);  // one real pole 0.5, a pair of modulus 0.5 (modal coordinates have both kinds)
  A << 0.5, 0, 0, 0, 0.3, 0.4, 0, -0.4, 0.3;
  const sysid::StateSpace s(A, MatrixXd::Ones(3, 1), (MatrixXd(1, 3) << 1, 0, 0).finished(), MatrixXd::Zero(1, 1), 0.1);
  MatrixXd u = MatrixXd::Zero(3000, 1);  // 3000 samples: the decay crosses a 4096-sample block only in the modal test below
  u(0, 0) = 1.0;
  const MatrixXd y = sysid::simulate(s, u);
  for (Eigen::Index t = 1; t <= 1023; ++t) ASSERT_EQ(y(t, 0), std::ldexp(1.0, -static_cast<int>(t - 1))) << "t = " << t;
  EXPECT_FALSE(sysid::test::has_subnormal(y));
  EXPECT_EQ(y(1100, 0), 0.0);  // 0.5^1099 is below the smallest subnormal anyway; 0.5^1030 is not:
  EXPECT_EQ(y(1031, 0), 0.0);
  MatrixXd long_u = MatrixXd::Zero(9000, 1);
  long_u(4090, 0) = 1.0;  // the decay runs across the block boundary at 4096
  MatrixXd y_modal(9000, 1);
  sysid::simulate_blockwise_modal(s, long_u, VectorXd(), [&y_modal](Eigen::Index k0, const Eigen::Ref<MatrixXd>& yb) {
    y_modal.middleRows(k0, yb.rows()) = yb;
  });
  EXPECT_FALSE(sysid::test::has_subnormal(y_modal));
  EXPECT_GT(std::abs(y_modal(4091, 0)), 0.5);
  EXPECT_EQ(y_modal.bottomRows(9000 - 4091 - 1100).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_FALSE(sysid::test::flushing_subnormals());  // the caller's mode is its own again
}

TEST(CoreSimulate, RejectsViolatedPreconditions) {
  std::mt19937_64 rng(9);
  sysid::StateSpace s = random_discrete(rng, 3, 2, 1, 0.5);
  EXPECT_THROW(sysid::simulate(s, MatrixXd::Zero(10, 3)), std::invalid_argument);
  EXPECT_THROW(sysid::simulate(s, MatrixXd::Zero(10, 2), VectorXd::Zero(2)), std::invalid_argument);
  EXPECT_THROW(sysid::simulate_states(s, MatrixXd::Zero(10, 1)), std::invalid_argument);
  s.Ts = 0.0;
  EXPECT_THROW(sysid::simulate(s, MatrixXd::Zero(10, 2)), std::invalid_argument);
  EXPECT_THROW(sysid::simulate_states(s, MatrixXd::Zero(10, 2)), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_core_simulate
