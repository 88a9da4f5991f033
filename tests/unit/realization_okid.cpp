// Tests for sysid::okid (include/sysid/realization/okid.hpp).
#include <sysid/core/discrete_riccati.hpp>
#include <sysid/core/modal_table.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/realization/era.hpp>
#include <sysid/realization/markov_parameters.hpp>
#include <sysid/realization/okid.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <string>
#include <vector>
#include "checks.hpp"
#include "random_systems.hpp"

namespace test_unit_realization_okid {

namespace {

using Eigen::MatrixXd;
using sysid::test::has_warning;
using sysid::test::relative_error;
using sysid::test::rotated_modal_system;
using sysid::test::white_noise;

TEST(RealizationOkid, NoiseFreeDataGiveExactMarkovParameters) {
  // Noise-free data from an order-6 system with 2 outputs: a deadbeat observer
  // exists for p l >= 6, the regression is then consistent and the recovered
  // system Markov parameters are exact to rounding, also when p l > n makes the
  // regression rank-deficient (every exact solution is a valid observer).
  const sysid::StateSpace sys = rotated_modal_system({0.05, 0.12, 0.25}, {0.02, 0.01, 0.02}, 2, 2, 11);
  const MatrixXd u = white_noise(3000, 2, 1);
  const MatrixXd y = sysid::simulate(sys, u);
  for (int p : {3, 6}) {
    sysid::OkidOptions o;
    o.observer_order = p;
    o.markov_count = 50;
    const sysid::OkidResult r = sysid::okid(sysid::IoData(u, y, 1.0), o);
    ASSERT_EQ(r.markov.count(), 51);
    const sysid::MarkovParameters truth = sysid::markov_parameters(sys, 50);
    EXPECT_LT(relative_error(r.markov.h, truth.h, 51), 1e-9) << "p=" << p;
    EXPECT_EQ(r.rank_deficient, p * 2 > 6) << "p=" << p;
    if (r.rank_deficient) {
      EXPECT_TRUE(has_warning(r.warnings, "rank-deficient"));
    }
    EXPECT_LT(r.residual_rms, 1e-10 * std::sqrt(y.squaredNorm() / static_cast<double>(y.size())));
  }
}

TEST(RealizationOkid, LightlyDampedNoisyDataPolesWithinOnePercent) {
  // zeta = 1-2 %, 2x2, white inputs, 5 % (26 dB) white noise on every output,
  // two records. Such a system's impulse response needs ~500 samples to decay,
  // but the identified observer's only p = 40. With output noise the
  // least-squares observer is biased (equation-error model), a bias that shrinks
  // as p grows (Juang et al. 1993, sec. 4); measured Markov error ~0.5 %, ERA
  // frequencies within 1e-4 and damping within ~3 %. Asserted: the required 1 %
  // on frequency, 25 % on damping (the least determined modal quantity).
  const sysid::StateSpace sys = rotated_modal_system({0.05, 0.12, 0.25}, {0.02, 0.01, 0.02}, 2, 2, 11);
  sysid::IoData data;
  data.Ts = 1.0;
  for (std::uint64_t rec = 0; rec < 2; ++rec) {
    const MatrixXd u = white_noise(10000, 2, 10 + rec);
    MatrixXd y = sysid::simulate(sys, u);
    const MatrixXd v = white_noise(y.rows(), y.cols(), 20 + rec);
    for (Eigen::Index c = 0; c < y.cols(); ++c)
      y.col(c) += 0.05 * std::sqrt(y.col(c).squaredNorm() / static_cast<double>(y.rows())) * v.col(c);
    data.add_experiment({u, y, "record" + std::to_string(rec)});
  }
  sysid::OkidOptions o;
  o.observer_order = 40;
  const sysid::OkidResult r = sysid::okid(data, o);
  EXPECT_EQ(r.markov.count(), 161);  // default markov_count = 4 p
  EXPECT_EQ(r.equations, 2 * (10000 - 40));
  const sysid::MarkovParameters truth = sysid::markov_parameters(sys, 160);
  EXPECT_LT(relative_error(r.markov.h, truth.h, 161), 0.02);
  EXPECT_LT(r.condition, 1e3);  // white inputs, output noise: well conditioned

  sysid::EraOptions eo;
  eo.order = 6;
  const sysid::EraResult era = sysid::era(r.markov, eo);
  const auto me = sysid::modal_table(era.model), mt = sysid::modal_table(sys);
  ASSERT_EQ(me.size(), mt.size());
  for (std::size_t i = 0; i < mt.size(); ++i) {
    EXPECT_NEAR(me[i].freq_hz / mt[i].freq_hz, 1.0, 0.01) << "mode " << i;
    EXPECT_NEAR(me[i].damping / mt[i].damping, 1.0, 0.25) << "mode " << i;
  }
  // The automatic order choice finds the 6 modes too, given a search range
  // below p l = 80: beyond h[p] OKID's Markov parameters follow a recursion of
  // order p l, so H(0) has a (genuine) rank gap at p l as well.
  sysid::EraOptions auto_order;
  auto_order.max_order = 20;
  EXPECT_EQ(sysid::era(r.markov, auto_order).order, 6);
}

TEST(RealizationOkid, RecoversKalmanGainMarkovParametersOfAnInnovationModel) {
  // Data from the innovation model x(k+1) = A x + B u + K e, y = C x + D u + e
  // of process noise Q = 0.01 I and sensor noise R = 0.01 I: K is the
  // steady-state Kalman predictor gain, which OKID's observer estimates. A - K C
  // has its poles well inside the unit circle (asserted below 0.9), so p = 40
  // observer parameters capture the predictor (0.9^40 ~ 1.5 %). Measured error
  // of C A^(k-1) K over k = 1..10: a few %; asserted 15 %.
  const sysid::StateSpace sys = rotated_modal_system({0.05, 0.12, 0.25}, {0.02, 0.01, 0.02}, 2, 2, 11);
  const sysid::KalmanFilterResult kf = sysid::steady_state_kalman_filter(
      sys.A, sys.C, 0.01 * MatrixXd::Identity(6, 6), 0.01 * MatrixXd::Identity(2, 2), MatrixXd::Zero(6, 2));
  ASSERT_EQ(kf.status, sysid::KalmanFilterResult::Status::converged);
  const MatrixXd K = kf.K;
  const Eigen::VectorXcd obs = sysid::poles(sysid::StateSpace(sys.A - K * sys.C, sys.B, sys.C, sys.D, 1.0));
  ASSERT_LT(obs.cwiseAbs().maxCoeff(), 0.9);  // guard the premise
  const MatrixXd Le = kf.innovation_covariance.llt().matrixL();
  MatrixXd Bk(6, 4), Dk(2, 4);
  Bk << sys.B, K * Le;
  Dk << sys.D, Le;
  const sysid::StateSpace innovation(sys.A, Bk, sys.C, Dk, 1.0);
  MatrixXd ue(20000, 4);
  ue.leftCols(2) = white_noise(20000, 2, 6);
  ue.rightCols(2) = white_noise(20000, 2, 7);  // e = Le * unit white noise
  const MatrixXd y = sysid::simulate(innovation, ue);
  sysid::OkidOptions o;
  o.observer_order = 40;
  const sysid::OkidResult r = sysid::okid(sysid::IoData(ue.leftCols(2), y, 1.0), o);
  std::vector<MatrixXd> gain_truth;
  MatrixXd X = K;
  for (int k = 0; k < 10; ++k) {
    gain_truth.push_back(sys.C * X);
    X = sys.A * X;
  }
  ASSERT_GE(r.gain_markov.size(), 10u);
  EXPECT_LT(relative_error(r.gain_markov, gain_truth, 10), 0.15);
  EXPECT_LT(relative_error(r.markov.h, sysid::markov_parameters(sys, 160).h, 161), 0.02);
  // The residual is the innovation e: RMS within 5 % of sqrt(trace(cov e) / l).
  EXPECT_NEAR(r.residual_rms / std::sqrt(kf.innovation_covariance.trace() / 2.0), 1.0, 0.05);
  ASSERT_EQ(r.observer_markov.size(), 40u);
  EXPECT_EQ(r.observer_markov.front().rows(), 2);
  EXPECT_EQ(r.observer_markov.front().cols(), 4);
}

TEST(RealizationOkid, WarnsWhenTheObserverOrderIsTooSmall) {
  // Output noise and p = 5: the least-squares observer's parameters have not
  // decayed at lag p.
  const sysid::StateSpace sys = rotated_modal_system({0.05, 0.12, 0.25}, {0.02, 0.01, 0.02}, 2, 2, 11);
  const MatrixXd u = white_noise(5000, 2, 30);
  MatrixXd y = sysid::simulate(sys, u);
  y += 0.2 * white_noise(y.rows(), y.cols(), 31);
  sysid::OkidOptions o;
  o.observer_order = 5;
  const sysid::OkidResult r = sysid::okid(sysid::IoData(u, y, 1.0), o);
  EXPECT_TRUE(has_warning(r.warnings, "increase observer_order"));
}

TEST(RealizationOkid, BadOptionsThrow) {
  const MatrixXd u = white_noise(100, 1, 1), y = white_noise(100, 2, 2);
  const sysid::IoData data(u, y, 1.0);
  auto expect_throw = [&](const sysid::OkidOptions& o, const std::string& text) {
    try {
      sysid::okid(data, o);
      ADD_FAILURE() << "no exception for " << text;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  sysid::OkidOptions o;
  o.observer_order = 0;
  expect_throw(o, "observer_order p >= 1");
  o = {};
  o.markov_count = -1;
  expect_throw(o, "markov_count >= 0");
  o = {};
  o.observer_order = 30;  // 70 equations for 1 + 30 * 3 = 91 unknowns
  expect_throw(o, "more equations than unknowns");
}

}  // namespace

}  // namespace test_unit_realization_okid
