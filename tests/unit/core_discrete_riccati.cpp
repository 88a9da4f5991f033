#include <sysid/core/discrete_riccati.hpp>

#include <gtest/gtest.h>

#include "random_systems.hpp"

namespace test_unit_core_discrete_riccati {

using namespace sysid;

TEST(KalmanFilter, SolvesTheFilterRiccatiEquation) {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const StateSpace sys = test::random_modal_system(1 + static_cast<int>(seed % 4), 1, 1 + static_cast<int>(seed % 3), seed);
    const Eigen::Index n = sys.order(), l = sys.outputs();
    const Eigen::MatrixXd noise = test::white_noise(n + l + 3, n + l, seed);
    const Eigen::MatrixXd cov = noise.transpose() * noise / static_cast<double>(noise.rows());
    const Eigen::MatrixXd Q = cov.topLeftCorner(n, n), R = cov.bottomRightCorner(l, l), S = cov.topRightCorner(n, l);
    const KalmanFilterResult kf = steady_state_kalman_filter(sys.A, sys.C, Q, R, S);
    ASSERT_EQ(kf.status, KalmanFilterResult::Status::converged) << kf.message;
    const Eigen::MatrixXd& P = kf.P;
    const Eigen::MatrixXd gain = sys.A * P * sys.C.transpose() + S;
    const Eigen::MatrixXd residual =
        sys.A * P * sys.A.transpose() - gain * (sys.C * P * sys.C.transpose() + R).inverse() * gain.transpose() + Q - P;
    EXPECT_LT(residual.norm(), 1e-9 * P.norm()) << "seed " << seed;
    // The closed loop A - K C is stable (the defining property of the stabilising solution).
    EXPECT_LT((sys.A - kf.K * sys.C).eigenvalues().cwiseAbs().maxCoeff(), 1.0);
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(P).eigenvalues().minCoeff(), -1e-10 * P.norm());
  }
}

TEST(KalmanFilter, ScalarCaseMatchesClosedForm) {
  // x+ = a x + w, y = x + v: P solves P = a^2 P - a^2 P^2/(P + r) + q.
  const double a = 0.9, q = 0.5, r = 2.0;
  const KalmanFilterResult kf = steady_state_kalman_filter(Eigen::MatrixXd::Constant(1, 1, a), Eigen::MatrixXd::Ones(1, 1),
                                                           Eigen::MatrixXd::Constant(1, 1, q), Eigen::MatrixXd::Constant(1, 1, r),
                                                           Eigen::MatrixXd::Zero(1, 1));
  // P^2 + P (r - a^2 r - q) - q r = 0
  const double bq = r - a * a * r - q;
  const double p = 0.5 * (-bq + std::sqrt(bq * bq + 4 * q * r));
  EXPECT_NEAR(kf.P(0, 0), p, 1e-12);
  EXPECT_NEAR(kf.K(0, 0), a * p / (p + r), 1e-12);
}

TEST(KalmanFilter, NonPositiveMeasurementNoiseIsReported) {
  const KalmanFilterResult kf =
      steady_state_kalman_filter(Eigen::MatrixXd::Constant(1, 1, 0.5), Eigen::MatrixXd::Ones(1, 1), Eigen::MatrixXd::Ones(1, 1),
                                 Eigen::MatrixXd::Zero(1, 1), Eigen::MatrixXd::Zero(1, 1));
  EXPECT_EQ(kf.status, KalmanFilterResult::Status::failed);
  EXPECT_FALSE(kf.message.empty());
}

}  // namespace test_unit_core_discrete_riccati
