// Tests of subspace/bdx_least_squares.hpp: exact recovery from noise-free
// data (MIMO, two experiments, one long enough to be cut in two pieces), the
// same least-squares solution as a dense Householder QR of the explicitly built
// regression on noisy data, modal and original coordinates and the Gram and QR
// routes agreeing, the QR route taken for an ill-conditioned or rank-deficient
// regression, the fallback for a defective A, and bad arguments.
#include <sysid/core/simulate.hpp>
#include <sysid/subspace/bdx_least_squares.hpp>

#include <gtest/gtest.h>

#include "random_matrices.hpp"
#include "random_systems.hpp"

namespace test_unit_subspace_bdx_least_squares {

using namespace sysid;

namespace {

double relative_error(const Eigen::MatrixXd& estimate, const Eigen::MatrixXd& truth) {
  return (estimate - truth).norm() / truth.norm();
}

/// Two experiments of `sys` from the given initial states: 12 000 samples (cut
/// in two pieces) and 3 000 (one piece); white inputs, optional output noise.
IoData two_experiments(const StateSpace& sys, const Eigen::VectorXd& x0a, const Eigen::VectorXd& x0b, double noise) {
  IoData data;
  data.Ts = sys.Ts;
  const Eigen::Index lengths[] = {12000, 3000};
  const Eigen::VectorXd* x0[] = {&x0a, &x0b};
  for (int e = 0; e < 2; ++e) {
    const Eigen::MatrixXd u = test::white_noise(lengths[e], sys.inputs(), 11 + static_cast<std::uint64_t>(e));
    Eigen::MatrixXd y = simulate(sys, u, *x0[e]);
    if (noise > 0) y += test::white_noise(lengths[e], sys.outputs(), 21 + static_cast<std::uint64_t>(e), noise);
    data.add_experiment({u, y, "experiment " + std::to_string(e)});
  }
  return data;
}

/// The regression of the header written out column by column from simulations
/// (B(p,q): the response to u_q entering state p; D(r,q): u_q on output r; x0:
/// the free responses), stacked over the experiments and solved by one dense
/// Householder QR: an independent reference for the streamed, pieced solver.
struct Reference {
  Eigen::MatrixXd B, D;
  std::vector<Eigen::VectorXd> x0;
};

Reference dense_reference(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, const IoData& data) {
  const Eigen::Index n = A.rows(), l = C.rows(), m = data.inputs();
  const Eigen::Index experiments = static_cast<Eigen::Index>(data.experiments.size());
  const Eigen::Index p = n * m + l * m + n * experiments;
  const Eigen::Index rows = data.total_samples() * l;
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(rows, p);
  Eigen::VectorXd y(rows);
  Eigen::Index offset = 0;
  for (Eigen::Index e = 0; e < experiments; ++e) {
    const Experiment& ex = data.experiments[static_cast<std::size_t>(e)];
    const Eigen::Index N = ex.samples();
    auto put = [&](Eigen::Index column, const Eigen::MatrixXd& response) {  // N x l, row-interleaved like the solver
      for (Eigen::Index t = 0; t < N; ++t) M.block(offset + t * l, column, l, 1) = response.row(t).transpose();
    };
    for (Eigen::Index q = 0; q < m; ++q)
      for (Eigen::Index i = 0; i < n; ++i) {
        Eigen::MatrixXd Bi = Eigen::MatrixXd::Zero(n, m);
        Bi(i, q) = 1;
        put(q * n + i, simulate(StateSpace(A, Bi, C, Eigen::MatrixXd::Zero(l, m), data.Ts), ex.u));
      }
    for (Eigen::Index q = 0; q < m; ++q)
      for (Eigen::Index r = 0; r < l; ++r) {
        Eigen::MatrixXd response = Eigen::MatrixXd::Zero(N, l);
        response.col(r) = ex.u.col(q);
        put(n * m + q * l + r, response);
      }
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::MatrixXd zero_input = Eigen::MatrixXd::Zero(N, m);
      put(n * m + l * m + e * n + i,
          simulate(StateSpace(A, Eigen::MatrixXd::Zero(n, m), C, Eigen::MatrixXd::Zero(l, m), data.Ts), zero_input,
                   Eigen::VectorXd::Unit(n, i)));
    }
    for (Eigen::Index t = 0; t < N; ++t) y.segment(offset + t * l, l) = ex.y.row(t).transpose();
    offset += N * l;
  }
  const Eigen::VectorXd theta = M.householderQr().solve(y);
  Reference ref;
  ref.B = Eigen::Map<const Eigen::MatrixXd>(theta.data(), n, m);
  ref.D = Eigen::Map<const Eigen::MatrixXd>(theta.data() + n * m, l, m);
  for (Eigen::Index e = 0; e < experiments; ++e) ref.x0.push_back(theta.segment(n * m + l * m + e * n, n));
  return ref;
}

}  // namespace

TEST(BdxLeastSquares, RecoversBDAndEveryInitialStateFromNoiseFreeData) {
  const StateSpace sys = test::random_modal_system(3, 2, 2, 5);
  const Eigen::VectorXd x0a = Eigen::VectorXd::LinSpaced(6, -1.0, 1.0), x0b = Eigen::VectorXd::Constant(6, 0.5);
  const IoData data = two_experiments(sys, x0a, x0b, 0.0);
  const BdxLeastSquaresResult r = bdx_least_squares(sys.A, sys.C, data);
  EXPECT_TRUE(r.modal_coordinates);
  EXPECT_LT(r.modal_condition, 1e3);
  EXPECT_EQ(r.samples_used, 15000);
  EXPECT_LT(relative_error(r.B, sys.B), 1e-9);
  EXPECT_LT(relative_error(r.D, sys.D), 1e-9);
  ASSERT_EQ(r.x0.size(), 2u);
  EXPECT_LT(relative_error(r.x0[0], x0a), 1e-8);
  EXPECT_LT(relative_error(r.x0[1], x0b), 1e-8);
  EXPECT_GT(r.rows_without_initial_response, 0);  // this A (damping 5 %) decays within the record
}

TEST(BdxLeastSquares, IsTheLeastSquaresSolutionOfTheWholeRegressionOnNoisyData) {
  // 10 % output noise: B, D, x0 are then far from the truth, and must equal
  // the dense reference's to the rounding of the regression, in both coordinates.
  const StateSpace sys = test::random_modal_system(2, 2, 2, 9);
  const Eigen::VectorXd x0a = Eigen::VectorXd::Constant(4, 1.0), x0b = Eigen::VectorXd::LinSpaced(4, 2.0, -2.0);
  const IoData data = two_experiments(sys, x0a, x0b, 0.1);
  const Reference ref = dense_reference(sys.A, sys.C, data);
  // Both coordinates, both routes (the Gram route is the default here: the
  // equilibrated regression is well conditioned).
  BdxLeastSquaresOptions original, qr, original_qr;
  original.modal_condition_limit = original_qr.modal_condition_limit = 0;
  qr.max_gram_condition = original_qr.max_gram_condition = 0;
  for (const BdxLeastSquaresOptions& options : {BdxLeastSquaresOptions{}, original, qr, original_qr}) {
    const BdxLeastSquaresResult r = bdx_least_squares(sys.A, sys.C, data, options);
    EXPECT_EQ(r.modal_coordinates, options.modal_condition_limit > 0);
    EXPECT_EQ(r.normal_equations, options.max_gram_condition > 0);
    EXPECT_LT(relative_error(r.B, ref.B), 1e-10);
    EXPECT_LT(relative_error(r.D, ref.D), 1e-10);
    for (std::size_t e = 0; e < 2; ++e) EXPECT_LT(relative_error(r.x0[e], ref.x0[e]), 1e-9) << "experiment " << e;
  }
}

TEST(BdxLeastSquares, AnIllConditionedRegressionTakesTheQrRoute) {
  // Two inputs that differ by 1e-4 of their size: the equilibrated triangle's
  // diagonal ratio is ~1.1e4, the Gram matrix's condition ~1e8 > 1e6, so the
  // normal equations are declined and the answer is the QR route's, bit for
  // bit, and the dense reference's.
  const StateSpace sys = test::random_modal_system(2, 2, 1, 3);
  IoData data;
  data.Ts = sys.Ts;
  Eigen::MatrixXd u(12000, 2);
  u.col(0) = test::white_noise(12000, 1, 5);
  u.col(1) = u.col(0) + 1e-4 * test::white_noise(12000, 1, 6);
  const Eigen::VectorXd x0 = Eigen::VectorXd::Constant(4, 1.0);
  data.add_experiment({u, simulate(sys, u, x0) + test::white_noise(12000, 1, 7, 0.01), "collinear"});
  const BdxLeastSquaresResult r = bdx_least_squares(sys.A, sys.C, data);
  EXPECT_FALSE(r.normal_equations);
  EXPECT_GT(r.condition, 1e3);
  BdxLeastSquaresOptions qr;
  qr.max_gram_condition = 0;
  const BdxLeastSquaresResult q = bdx_least_squares(sys.A, sys.C, data, qr);
  EXPECT_TRUE((r.B.array() == q.B.array()).all());
  EXPECT_TRUE((r.x0[0].array() == q.x0[0].array()).all());
  const Reference ref = dense_reference(sys.A, sys.C, data);
  // Two backward-stable solutions of a regression of condition ~1e4 agree to
  // ~eps cond^2 tan(residual angle) (measured 8e-11).
  EXPECT_LT(relative_error(r.B, ref.B), 1e-9);
  // With the limit raised past the condition the normal equations are used:
  // the estimate of cond(G) is what decides.
  BdxLeastSquaresOptions lax;
  lax.max_gram_condition = 1e14;
  EXPECT_TRUE(bdx_least_squares(sys.A, sys.C, data, lax).normal_equations);
}

TEST(BdxLeastSquares, AnInputThatIsZeroTakesTheQrRouteAndGetsNoGain) {
  // A zero column makes the Gram matrix singular: Cholesky fails, the QR
  // route's rank-revealing solve gives that input zero B and D.
  const StateSpace sys = test::random_modal_system(2, 2, 1, 4);
  IoData data;
  data.Ts = sys.Ts;
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(10000, 2);
  u.col(0) = test::white_noise(10000, 1, 8);
  data.add_experiment({u, simulate(sys, u), "second input off"});
  const BdxLeastSquaresResult r = bdx_least_squares(sys.A, sys.C, data);
  EXPECT_FALSE(r.normal_equations);
  EXPECT_EQ(r.B.col(1).norm(), 0.0);
  EXPECT_EQ(r.D.col(1).norm(), 0.0);
  EXPECT_LT(relative_error(r.B.col(0), sys.B.col(0)), 1e-9);
}

TEST(BdxLeastSquares, ADefectiveAIsSolvedInItsOwnCoordinates) {
  // A Jordan block has no eigenvector basis: its real modal form's T is
  // singular, so the recursion must run on A itself and still be exact.
  Eigen::MatrixXd A(3, 3);
  A << 0.9, 1.0, 0.0, 0.0, 0.9, 0.0, 0.0, 0.0, -0.5;
  Eigen::MatrixXd B(3, 1), C(1, 3), D(1, 1);
  B << 0.3, -1.0, 0.7;
  C << 1.0, 0.5, -0.2;
  D << 0.1;
  const StateSpace sys(A, B, C, D, 1.0);
  const IoData data = two_experiments(sys, Eigen::Vector3d(1.0, -1.0, 0.5), Eigen::Vector3d(0.0, 2.0, 1.0), 0.0);
  const BdxLeastSquaresResult r = bdx_least_squares(A, C, data);
  EXPECT_FALSE(r.modal_coordinates);
  EXPECT_GT(r.modal_condition, 1e3);
  EXPECT_LT(relative_error(r.B, B), 1e-9);
  EXPECT_LT(relative_error(r.D, D), 1e-9);
  EXPECT_LT(relative_error(r.x0[1], Eigen::Vector3d(0.0, 2.0, 1.0)), 1e-8);
}

TEST(BdxLeastSquares, MaxSamplesBoundsEachExperiment) {
  const StateSpace sys = test::random_modal_system(2, 1, 1, 3);
  const IoData data = two_experiments(sys, Eigen::VectorXd::Ones(4), Eigen::VectorXd::Zero(4), 0.0);
  BdxLeastSquaresOptions options;
  options.max_samples = 5000;
  const BdxLeastSquaresResult r = bdx_least_squares(sys.A, sys.C, data, options);
  EXPECT_EQ(r.samples_used, 5000 + 3000);
  EXPECT_LT(relative_error(r.B, sys.B), 1e-9);
}

TEST(BdxLeastSquares, RejectsMatricesThatDoNotFitTheData) {
  const StateSpace sys = test::random_modal_system(2, 1, 2, 3);
  const IoData data = two_experiments(sys, Eigen::VectorXd::Ones(4), Eigen::VectorXd::Zero(4), 0.0);
  EXPECT_THROW(bdx_least_squares(sys.A.leftCols(3), sys.C, data), std::invalid_argument);
  EXPECT_THROW(bdx_least_squares(sys.A, sys.C.topRows(1), data), std::invalid_argument);
  BdxLeastSquaresOptions options;
  options.max_samples = 0;
  EXPECT_THROW(bdx_least_squares(sys.A, sys.C, data, options), std::invalid_argument);
}

}  // namespace test_unit_subspace_bdx_least_squares
