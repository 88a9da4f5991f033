#include <sysid/core/discrete_riccati.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/validate/compare.hpp>

#include <gtest/gtest.h>

#include <array>
#include <tuple>

#include "random_systems.hpp"

namespace test_unit_validate_compare {

using namespace sysid;

namespace {

Eigen::VectorXd random_vector(Eigen::Index n, std::uint64_t seed) { return test::white_noise(n, 1, seed).col(0); }

/// Steady-state Kalman gain of `sys` for process noise Q = q I and measurement
/// noise R = I: a gain for which A - K C is stable, as an identified model's is.
Eigen::MatrixXd kalman_gain(const StateSpace& sys, double q) {
  const Eigen::Index n = sys.order(), l = sys.outputs();
  const KalmanFilterResult kf = steady_state_kalman_filter(sys.A, sys.C, q * Eigen::MatrixXd::Identity(n, n),
                                                           Eigen::MatrixXd::Identity(l, l), Eigen::MatrixXd::Zero(n, l));
  EXPECT_EQ(kf.status, KalmanFilterResult::Status::converged) << kf.message;
  return kf.K;
}

/// Data from the innovation model x+ = A x + B u + K e, y = C x + D u + e.
struct InnovationData {
  Eigen::MatrixXd u, y, e;
};

InnovationData simulate_innovation(const StateSpace& sys, const Eigen::MatrixXd& K, const Eigen::VectorXd& x0, Eigen::Index N,
                                   std::uint64_t seed, double noise) {
  InnovationData d;
  d.u = test::white_noise(N, sys.inputs(), seed);
  d.e = test::white_noise(N, sys.outputs(), seed + 1, noise);
  // Augmented input [u e] through [B K], [D I]: the library's simulate does the recursion.
  Eigen::MatrixXd Bx(sys.order(), sys.inputs() + sys.outputs()), Dx(sys.outputs(), sys.inputs() + sys.outputs());
  Bx << sys.B, K;
  Dx << sys.D, Eigen::MatrixXd::Identity(sys.outputs(), sys.outputs());
  const StateSpace aug(sys.A, Bx, sys.C, Dx, sys.Ts);
  Eigen::MatrixXd ue(N, sys.inputs() + sys.outputs());
  ue << d.u, d.e;
  d.y = simulate(aug, ue, x0);
  return d;
}

/// Reference k-step predictor written the slow, obvious way: for every t, start
/// from the filter state x^[t-k+1|t-k] (or x0 when t-k+1 <= 0) and run open loop.
Eigen::MatrixXd brute_force_predict(const StateSpace& sys, const Eigen::MatrixXd& K, const Eigen::MatrixXd& u,
                                    const Eigen::MatrixXd& y, int k, const Eigen::VectorXd& x0) {
  const Eigen::Index N = u.rows(), n = sys.order();
  std::vector<Eigen::VectorXd> xf(static_cast<std::size_t>(N), Eigen::VectorXd(n));
  Eigen::VectorXd x = x0;
  for (Eigen::Index s = 0; s < N; ++s) {
    xf[static_cast<std::size_t>(s)] = x;
    const Eigen::VectorXd innovation = y.row(s).transpose() - sys.C * x - sys.D * u.row(s).transpose();
    x = sys.A * x + sys.B * u.row(s).transpose() + K * innovation;
  }
  Eigen::MatrixXd yhat(N, sys.outputs());
  for (Eigen::Index t = 0; t < N; ++t) {
    const Eigen::Index start = std::max<Eigen::Index>(0, t - k + 1);
    Eigen::VectorXd xp = start == 0 ? x0 : xf[static_cast<std::size_t>(start)];
    for (Eigen::Index j = start; j < t; ++j) xp = sys.A * xp + sys.B * u.row(j).transpose();
    yhat.row(t) = (sys.C * xp + sys.D * u.row(t).transpose()).transpose();
  }
  return yhat;
}

}  // namespace

TEST(EstimateInitialState, RecoversX0ExactlyOnNoiseFreeData) {
  // Seeded sweep, MIMO included, lightly damped (zeta = 0.002: the free response
  // barely decays within the 2000 samples, the case normal equations handle worst).
  int case_no = 0;
  for (auto [modes, m, l, zeta] : {std::tuple{1, 1, 1, 0.05}, std::tuple{2, 1, 2, 0.002}, std::tuple{3, 2, 2, 0.01},
                                   std::tuple{4, 2, 1, 0.002}}) {
    const std::uint64_t seed = 100 + static_cast<std::uint64_t>(case_no);
    const StateSpace sys = test::random_modal_system(modes, m, l, seed, zeta);
    const Eigen::VectorXd x0 = 10.0 * random_vector(sys.order(), seed + 1);
    const Eigen::MatrixXd u = test::white_noise(3000, m, seed + 2);
    const Eigen::MatrixXd y = simulate(sys, u, x0);
    const Eigen::VectorXd est = estimate_initial_state(sys, u, y);
    // Same realisation, noise-free data: x0 is unique; the error is rounding,
    // amplified by the condition of the observability matrix (< 1e3 here).
    EXPECT_LT((est - x0).norm(), 1e-9 * x0.norm()) << "case " << case_no;
    ++case_no;
  }
}

TEST(EstimateInitialState, UnobservableDirectionGetsMinimumNormAndExactFit) {
  // A 4th-order model whose second mode is invisible at the output: x0 is not
  // unique, the estimate must still reproduce the output exactly and leave the
  // unobservable part at 0 (minimum norm).
  // Block-diagonal A, C sees only states 0 and 1.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4, 4);
  A.topLeftCorner(2, 2) << 0.9, 0.3, -0.3, 0.9;
  A.bottomRightCorner(2, 2) << 0.5, 0.6, -0.6, 0.5;
  Eigen::MatrixXd B(4, 1), C(1, 4), D(1, 1);
  B << 1, 0.5, -0.2, 0.7;
  C << 1, -0.4, 0, 0;
  D << 0.1;
  const StateSpace sys(A, B, C, D, 1.0);
  Eigen::VectorXd x0(4);
  x0 << 1.0, -2.0, 3.0, 4.0;
  const Eigen::MatrixXd u = test::white_noise(500, 1, 3);
  const Eigen::MatrixXd y = simulate(sys, u, x0);
  const Eigen::VectorXd est = estimate_initial_state(sys, u, y);
  ASSERT_TRUE(est.allFinite());
  EXPECT_LT((est.head(2) - x0.head(2)).norm(), 1e-10 * x0.norm());
  EXPECT_LT(est.tail(2).norm(), 1e-10 * x0.norm());
  EXPECT_LT((simulate(sys, u, est) - y).norm(), 1e-10 * y.norm());
}

TEST(Compare, FitIs100OnExactDataWithOffsets) {
  const StateSpace sys = test::random_modal_system(3, 2, 2, 21, 0.01);
  const Eigen::VectorXd x0 = random_vector(sys.order(), 22);
  const Eigen::MatrixXd u_dev = test::white_noise(2500, 2, 23);
  Experiment e;
  Eigen::Vector2d in_off(1.5, -2.0), out_off(10.0, 0.25);
  e.u = u_dev.rowwise() + in_off.transpose();
  e.y = simulate(sys, u_dev, x0).rowwise() + out_off.transpose();
  CompareOptions o;
  o.input_offset = in_off;
  o.output_offset = out_off;
  const CompareResult r = compare(sys, Eigen::MatrixXd(), e, o);
  ASSERT_EQ(r.fit_percent.size(), 2);
  for (Eigen::Index c = 0; c < 2; ++c) EXPECT_GT(r.fit_percent(c), 100.0 - 1e-7);
  // y_hat is returned in the units of the log.
  EXPECT_LT((r.y_hat - e.y).norm(), 1e-9 * e.y.norm());
  // Without the x0 estimate (x0 = 0) the transient is missed: fit below 100.
  o.estimate_x0 = false;
  const CompareResult z = compare(sys, Eigen::MatrixXd(), e, o);
  EXPECT_LT(z.fit_percent.minCoeff(), 100.0 - 1e-3);
}

TEST(PredictKStep, OneStepErrorEqualsTheInnovation) {
  int case_no = 0;
  for (auto [modes, m, l] : {std::tuple{1, 1, 1}, std::tuple{2, 2, 2}, std::tuple{3, 1, 2}}) {
    const std::uint64_t seed = 300 + static_cast<std::uint64_t>(10 * case_no);
    const StateSpace sys = test::random_modal_system(modes, m, l, seed, 0.02);
    const Eigen::MatrixXd K = kalman_gain(sys, 0.5);
    const Eigen::VectorXd x0 = random_vector(sys.order(), seed + 5);
    const InnovationData d = simulate_innovation(sys, K, x0, 3000, seed + 6, 0.3);
    const Eigen::MatrixXd yhat = predict_k_step(sys, K, d.u, d.y, 1, x0);
    // With the true model, K and x0, the state error obeys eps+ = (A - K C) eps from
    // eps = 0, so y - y^ = e up to rounding.
    EXPECT_LT((d.y - yhat - d.e).cwiseAbs().maxCoeff(), 1e-10 * d.y.cwiseAbs().maxCoeff()) << "case " << case_no;
    ++case_no;
  }
}

TEST(PredictKStep, MatchesBruteForceForStableAndUnstableModels) {
  // The stable path uses the superposition z[t] + A^(k-1)(xf - z); the unstable
  // one steps explicitly. Both must equal the obvious algorithm.
  const StateSpace stable = test::random_modal_system(2, 1, 2, 41, 0.03);
  StateSpace unstable = stable;
  // Spectral radius exactly 1.02; the Kalman gain below still stabilises A - K C.
  unstable.A *= 1.02 / stable.A.eigenvalues().cwiseAbs().maxCoeff();
  ASSERT_NEAR(unstable.A.eigenvalues().cwiseAbs().maxCoeff(), 1.02, 1e-12);
  for (const StateSpace* sys : std::array<const StateSpace*, 2>{&stable, &unstable}) {
    const Eigen::MatrixXd K = kalman_gain(*sys, 1.0);
    const Eigen::VectorXd x0 = random_vector(sys->order(), 42);
    const InnovationData d = simulate_innovation(*sys, K, x0, 400, 43, 0.2);
    for (int k : {1, 2, 5, 37, 399, 400, 1000}) {
      const Eigen::MatrixXd fast = predict_k_step(*sys, K, d.u, d.y, k, x0);
      const Eigen::MatrixXd slow = brute_force_predict(*sys, K, d.u, d.y, k, x0);
      // Superposition error: rounding of z (bounded, stable A) times ||A^(k-1)|| <= ~10.
      EXPECT_LT((fast - slow).cwiseAbs().maxCoeff(), 1e-9 * slow.cwiseAbs().maxCoeff())
          << "k = " << k << (sys == &stable ? " stable" : " unstable");
    }
  }
}

TEST(PredictKStep, LargeKEqualsSimulation) {
  const StateSpace sys = test::random_modal_system(3, 2, 1, 51, 0.1);
  const Eigen::MatrixXd K = kalman_gain(sys, 0.5);
  const Eigen::VectorXd x0 = random_vector(sys.order(), 52);
  const InnovationData d = simulate_innovation(sys, K, x0, 1500, 53, 0.5);
  const Eigen::MatrixXd sim = simulate(sys, d.u, x0);
  // k >= N: no measurement is old enough, the prediction is the simulation.
  EXPECT_EQ((predict_k_step(sys, K, d.u, d.y, 1500, x0) - sim).cwiseAbs().maxCoeff(), 0.0);
  // k < N but long compared with the slowest decay (zeta 0.1 at >= 0.02
  // cycles/sample: |pole| <= exp(-0.0126), |A^1400| ~ 2e-8 times the condition of
  // the modal basis): the memory of the measurements has died out, so the
  // prediction converges to the simulation.
  const Eigen::MatrixXd far = predict_k_step(sys, K, d.u, d.y, 1400, x0);
  const double gap_far = (far.bottomRows(50) - sim.bottomRows(50)).cwiseAbs().maxCoeff();
  const Eigen::MatrixXd near = predict_k_step(sys, K, d.u, d.y, 2, x0);
  const double gap_near = (near.bottomRows(50) - sim.bottomRows(50)).cwiseAbs().maxCoeff();
  EXPECT_LT(gap_far, 1e-3 * gap_near);
}

TEST(Compare, PredictionBeatsSimulationOnNoisyInnovationData) {
  const StateSpace sys = test::random_modal_system(2, 1, 1, 61, 0.02);
  const Eigen::MatrixXd K = kalman_gain(sys, 2.0);
  const InnovationData d = simulate_innovation(sys, K, Eigen::VectorXd::Zero(sys.order()), 4000, 62, 1.0);
  Experiment e{d.u, d.y, "test"};
  CompareOptions sim_opt, pred_opt;
  pred_opt.predict_steps = 1;
  const double fit_sim = compare(sys, K, e, sim_opt).fit_percent(0);
  const double fit_pred = compare(sys, K, e, pred_opt).fit_percent(0);
  // The one-step error is the innovation alone; the simulation error also
  // carries the coloured noise K e filtered by the plant.
  EXPECT_GT(fit_pred, fit_sim + 5.0);
  // Theory: 1-step fit = 100 (1 - ||e|| / ||y - mean y||), within the x0 transient.
  const double expected = 100.0 * (1.0 - d.e.norm() / (d.y.array() - d.y.mean()).matrix().norm());
  EXPECT_NEAR(fit_pred, expected, 0.5);
}

TEST(Compare, Preconditions) {
  const StateSpace sys = test::random_modal_system(1, 1, 1, 71);
  Experiment e{test::white_noise(50, 1, 1), test::white_noise(50, 1, 2), "x"};
  CompareOptions o;
  o.predict_steps = 1;
  EXPECT_THROW(compare(sys, Eigen::MatrixXd(), e, o), std::invalid_argument);
  o.predict_steps = 0;
  o.input_offset = Eigen::VectorXd::Zero(3);
  EXPECT_THROW(compare(sys, Eigen::MatrixXd(), e, o), std::invalid_argument);
  Experiment wrong{test::white_noise(50, 2, 1), test::white_noise(50, 1, 2), "x"};
  EXPECT_THROW(compare(sys, Eigen::MatrixXd(), wrong, {}), std::invalid_argument);
  EXPECT_THROW(predict_k_step(sys, Eigen::MatrixXd::Zero(2, 1), e.u, e.y, 0, Eigen::VectorXd()), std::invalid_argument);
  EXPECT_THROW(estimate_initial_state(sys, e.u, e.y, 0), std::invalid_argument);
}

}  // namespace test_unit_validate_compare
