// The covariance-based innovation model (subspace/innovation_model.hpp): it
// recovers K and the innovation covariance of a known noise model from its
// output, gives K ~ 0 for white residuals, and rejects bad arguments.
#include <sysid/subspace/innovation_model.hpp>

#include <gtest/gtest.h>

#include "random_systems.hpp"

namespace test_unit_subspace_innovation_model {

using namespace sysid;

namespace {

/// v = C x + e, x[k+1] = A x[k] + K e[k], cov(e) = R.
Eigen::MatrixXd innovation_output(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, const Eigen::MatrixXd& K,
                                  const Eigen::MatrixXd& R, Eigen::Index samples, std::uint64_t seed) {
  const Eigen::MatrixXd e = test::white_noise(samples, C.rows(), seed) * Eigen::LLT<Eigen::MatrixXd>(R).matrixU().toDenseMatrix();
  Eigen::MatrixXd v(samples, C.rows());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(A.rows());
  for (Eigen::Index t = 0; t < samples; ++t) {
    v.row(t) = (C * x + e.row(t).transpose()).transpose();
    x = A * x + K * e.row(t).transpose();
  }
  return v;
}

}  // namespace

TEST(InnovationModel, RecoversKnownGainAndCovariance) {
  Eigen::MatrixXd A(2, 2), C(2, 2), K(2, 2), R(2, 2);
  A << 0.9, 0.2, -0.2, 0.9;
  C << 1.0, 0.0, 0.5, 1.0;
  K << 0.5, 0.1, -0.3, 0.4;
  R << 1.0, 0.3, 0.3, 0.5;
  // Two experiments pooled, as n4sid passes them.
  const std::vector<Eigen::MatrixXd> v = {innovation_output(A, C, K, R, 150000, 11), innovation_output(A, C, K, R, 150000, 12)};
  const InnovationModelResult r = innovation_model(A, C, v);
  ASSERT_EQ(r.status, InnovationModelResult::Status::converged) << r.message;
  // Sampling error of covariances from 3e5 samples is a few 1e-3.
  EXPECT_LT((r.K - K).norm() / K.norm(), 0.03) << "K =\n" << r.K;
  EXPECT_LT((r.innovation_covariance - R).norm() / R.norm(), 0.02) << r.innovation_covariance;
  // The innovation model is stable (minimum phase noise model): rho(A - K C) < 1.
  EXPECT_LT((A - r.K * C).eigenvalues().cwiseAbs().maxCoeff(), 1.0);
}

TEST(InnovationModel, WhiteResidualsGiveNearZeroGain) {
  Eigen::MatrixXd A(2, 2), C(1, 2);
  A << 1.6, -0.8, 1.0, 0.0;  // lightly damped pair
  C << 0.3, 0.7;
  const std::vector<Eigen::MatrixXd> v = {test::white_noise(200000, 1, 5, 2.0)};
  const InnovationModelResult r = innovation_model(A, C, v);
  // Either the Riccati iteration converges to a gain that only carries the
  // sampling error of the lag covariances (~ 1 / sqrt(N)), or the sample
  // covariances miss positive realness and the whiteness fallback gives K = 0.
  ASSERT_EQ(r.status, InnovationModelResult::Status::converged) << r.message;
  EXPECT_LT((r.K * C).norm(), 0.05);
  EXPECT_NEAR(r.innovation_covariance(0, 0), 4.0, 0.1);
}

TEST(InnovationModel, ColouredResidualsAreNotCalledWhite) {
  // An MA(1) residual e(t) + 0.9 e(t-1) is strongly correlated at lag 1.
  const Eigen::MatrixXd e = test::white_noise(50000, 1, 21);
  Eigen::MatrixXd v = e;
  v.bottomRows(49999) += 0.9 * e.topRows(49999);
  const InnovationModelResult r = innovation_model(Eigen::MatrixXd::Constant(1, 1, 0.5), Eigen::MatrixXd::Ones(1, 1), {v});
  // A first-order model with pole 0.5 cannot reproduce an MA(1); whatever the
  // outcome, a converged gain must not be the white-residual K = 0.
  if (r.status == InnovationModelResult::Status::converged) {
    EXPECT_GT(r.K.norm(), 0.1) << r.message;
  }
}

TEST(InnovationModel, RejectsInconsistentArguments) {
  const Eigen::MatrixXd A = Eigen::MatrixXd::Identity(2, 2) * 0.5, C = Eigen::MatrixXd::Ones(1, 2);
  EXPECT_THROW(innovation_model(A, Eigen::MatrixXd::Ones(1, 3), {Eigen::MatrixXd::Ones(100, 1)}), std::invalid_argument);
  EXPECT_THROW(innovation_model(A, C, {}), std::invalid_argument);
  EXPECT_THROW(innovation_model(A, C, {Eigen::MatrixXd::Ones(5, 1)}), std::invalid_argument);  // fewer rows than lags
  EXPECT_THROW(innovation_model(A, C, {Eigen::MatrixXd::Ones(100, 2)}), std::invalid_argument);
}

}  // namespace test_unit_subspace_innovation_model
