// Tests for sysid::check_data (include/sysid/diagnose/data_check.hpp).
#include <sysid/core/discretize.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/signal/excitation.hpp>
#include <sysid/signal/polynomial_filter.hpp>
#include <sysid/diagnose/data_check.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace test_unit_diagnose_data_check {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
constexpr double kTs = 1e-3;
constexpr Eigen::Index kN = 8000;

VectorXd white(Eigen::Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  VectorXd x(n);
  for (auto& v : x) v = g(rng);
  return x;
}

/// A 40 Hz lightly damped oscillator sampled at 1 kHz.
sysid::StateSpace plant() {
  const double w = 2.0 * std::numbers::pi * 40.0;
  return sysid::c2d_zoh(sysid::StateSpace(MatrixXd{{0.0, 1.0}, {-w * w, -2.0 * 0.05 * w}}, MatrixXd{{0.0}, {w * w}},
                                          MatrixXd{{1.0, 0.0}}, MatrixXd::Zero(1, 1), 0.0),
                        kTs);
}

sysid::IoData log_of(const VectorXd& u, const VectorXd& y) {
  sysid::IoData d;
  d.Ts = kTs;
  d.input_names = {"u"};
  d.output_names = {"y"};
  d.experiments.push_back({u, y, "test"});
  return d;
}

/// y = plant(u) + white noise of `noise_std` times the clean output's std.
VectorXd respond(const VectorXd& u, double noise_std, std::uint64_t seed) {
  const VectorXd clean = sysid::simulate(plant(), MatrixXd(u)).col(0);
  const double s = std::sqrt((clean.array() - clean.mean()).square().mean());
  return clean + noise_std * s * white(u.size(), seed);
}

bool any_finding(const sysid::DataCheckResult& r, const std::string& word) {
  for (const auto& f : r.findings)
    if (f.find(word) != std::string::npos) return true;
  return false;
}

TEST(DataCheck, AGoodOpenLoopExperimentHasNoFindingsAndTheRightSnr) {
  const VectorXd u = white(kN, 1);
  const VectorXd y = respond(u, 0.1, 2);  // noise std 10 % of the signal's: SNR 20 dB
  const auto r = sysid::check_data(log_of(u, y));
  EXPECT_TRUE(r.findings.empty()) << r.report();
  EXPECT_EQ(r.inputs[0].excitation_order, 60);
  // The ARX(20,20) residual variance estimates the white noise: 20 dB within 1 dB.
  EXPECT_NEAR(r.outputs[0].snr_db, 20.0, 1.0) << r.report();
  ASSERT_EQ(r.feedback.size(), 1u);
  EXPECT_FALSE(r.feedback[0].likely);
}

TEST(DataCheck, ExcitationOrderCountsTwoPerSine) {
  VectorXd one(kN), three(kN);
  for (Eigen::Index t = 0; t < kN; ++t) {
    const double s = static_cast<double>(t) * kTs;
    one(t) = std::sin(2.0 * std::numbers::pi * 13.0 * s);
    three(t) = one(t) + 0.7 * std::sin(2.0 * std::numbers::pi * 71.0 * s + 1.0) + 0.4 * std::cos(2.0 * std::numbers::pi * 190.0 * s);
  }
  auto r = sysid::check_data(log_of(one, respond(one, 0.01, 3)));
  EXPECT_EQ(r.inputs[0].excitation_order, 2) << r.report();
  EXPECT_TRUE(any_finding(r, "persistently exciting of order 2")) << r.report();
  r = sysid::check_data(log_of(three, respond(three, 0.01, 4)));
  EXPECT_EQ(r.inputs[0].excitation_order, 6) << r.report();
  // A chirp over the lowest 10 % of the band: smoothly decaying singular values,
  // exciting every order (not a finding).
  VectorXd chirp(kN);
  for (Eigen::Index t = 0; t < kN; ++t) {
    const double s = static_cast<double>(t) * kTs, duration = static_cast<double>(kN) * kTs;
    chirp(t) = std::sin(2.0 * std::numbers::pi * (1.0 + 0.5 * 49.0 * s / duration) * s);
  }
  r = sysid::check_data(log_of(chirp, respond(chirp, 0.01, 16)));
  EXPECT_EQ(r.inputs[0].excitation_order, 60) << r.report();
  EXPECT_FALSE(any_finding(r, "persistently exciting")) << r.report();
  const VectorXd constant = VectorXd::Constant(kN, 2.5);
  r = sysid::check_data(log_of(constant, white(kN, 5)));
  EXPECT_EQ(r.inputs[0].excitation_order, 0);
  EXPECT_TRUE(any_finding(r, "constant")) << r.report();
}

TEST(DataCheck, ClippingOffsetAndTrendAreReported) {
  const VectorXd u = white(kN, 6);
  VectorXd y = respond(u, 0.05, 7);
  const double limit = 0.6 * y.cwiseAbs().maxCoeff();
  y = y.cwiseMin(limit).cwiseMax(-limit);
  auto r = sysid::check_data(log_of(u, y));
  EXPECT_GT(r.outputs[0].clipped_share, 0.002);
  EXPECT_TRUE(any_finding(r, "clipped")) << r.report();
  // A white-noise input is never "clipped": it touches each extreme once.
  EXPECT_LT(r.inputs[0].clipped_share, 0.001);

  VectorXd shifted = respond(u, 0.05, 8);
  const double s = std::sqrt((shifted.array() - shifted.mean()).square().mean());
  shifted.array() += 3.0 * s + VectorXd::LinSpaced(kN, 0.0, 2.0 * s).array();
  r = sysid::check_data(log_of(u, shifted));
  EXPECT_TRUE(any_finding(r, "offset")) << r.report();
  EXPECT_TRUE(any_finding(r, "drifts")) << r.report();
}

TEST(DataCheck, FeedbackIsFoundInClosedLoopAndNotInOpenLoopWithAColouredInput) {
  // Closed loop: u(t) = r(t) - 0.5 y(t - 1) around the plant, r white.
  const sysid::StateSpace g = plant();
  const VectorXd ref = white(kN, 9), noise = 0.05 * white(kN, 10);
  VectorXd u(kN), y(kN);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
  double y_previous = 0.0;
  for (Eigen::Index t = 0; t < kN; ++t) {
    u(t) = ref(t) - 0.5 * y_previous;
    y(t) = (g.C * x)(0) + noise(t);
    x = g.A * x + g.B * u(t);
    y_previous = y(t);
  }
  auto r = sysid::check_data(log_of(u, y));
  ASSERT_EQ(r.feedback.size(), 1u);
  EXPECT_TRUE(r.feedback[0].likely) << r.report();
  EXPECT_TRUE(any_finding(r, "closed-loop")) << r.report();
  // Open loop with a strongly coloured input (white noise through a low-pass): the
  // raw correlation of future u with y is large, the prewhitened one is not.
  const VectorXd coloured = sysid::filter_polynomial(VectorXd::Ones(1), (VectorXd(3) << 1.0, -1.6, 0.7).finished(), white(kN, 11));
  r = sysid::check_data(log_of(coloured, respond(coloured, 0.05, 12)));
  EXPECT_FALSE(r.feedback[0].likely) << r.report();
}

/// Two inputs, two outputs: the 40 Hz oscillator on each output, fed by both
/// inputs with different gains (every output sees every input).
sysid::IoData two_by_two(const MatrixXd& u, double noise_std, std::uint64_t seed) {
  MatrixXd y(u.rows(), 2);
  y.col(0) = sysid::simulate(plant(), MatrixXd(u.col(0) + 0.5 * u.col(1))).col(0);
  y.col(1) = sysid::simulate(plant(), MatrixXd(0.3 * u.col(0) - u.col(1))).col(0);
  for (Eigen::Index i = 0; i < 2; ++i) {
    const double s = std::sqrt((y.col(i).array() - y.col(i).mean()).square().mean());
    y.col(i) += noise_std * s * white(u.rows(), seed + static_cast<std::uint64_t>(i));
  }
  sysid::IoData d;
  d.Ts = kTs;
  d.input_names = {"u1", "u2"};
  d.output_names = {"y1", "y2"};
  d.experiments.push_back({u, y, "test"});
  return d;
}

TEST(DataCheck, NoFeedbackWarningOnOpenLoopMultisinesAndTheLevelIsFamilyWise) {
  // Independent random-phase multisines with a sharp band edge below Nyquist
  // (no power above 450 of 500 Hz): no AR prewhitening filter whitens them, and the
  // earlier prewhitened test called such open-loop logs closed-loop. One period and
  // eight periods of the same signal.
  for (const Eigen::Index period : {kN, kN / 8}) {
    sysid::MultisineOptions ms;
    ms.fs_hz = 1.0 / kTs;
    ms.f_min_hz = 2.0;
    ms.f_max_hz = 450.0;
    ms.samples = kN;
    ms.period = period;
    ms.inputs = 2;
    ms.seed = 21;
    const auto r = sysid::check_data(two_by_two(sysid::multisine(ms), 0.05, 22));
    ASSERT_EQ(r.feedback.size(), 4u);
    EXPECT_FALSE(any_finding(r, "closed-loop")) << "period " << period << "\n" << r.report();
  }
  // The stated level holds for the whole log, not per pair and lag: over 40 open-loop
  // logs (two white or low-pass inputs, four pairs, 25 lags each) at 1 %, expect 0.4
  // logs with a warning; 3 or more has probability 0.8 % (binomial, p = 0.01).
  int warned = 0;
  for (std::uint64_t k = 0; k < 40; ++k) {
    MatrixXd u(kN, 2);
    u.col(0) = white(kN, 100 + 3 * k);
    u.col(1) = sysid::filter_polynomial(VectorXd::Ones(1), (VectorXd(3) << 1.0, -1.6, 0.7).finished(), white(kN, 101 + 3 * k));
    warned += any_finding(sysid::check_data(two_by_two(u, 0.1, 102 + 3 * k)), "closed-loop") ? 1 : 0;
  }
  EXPECT_LE(warned, 2);
}

TEST(DataCheck, FeedbackIsFoundInAPositionLoopWithEncoderQuantisation) {
  // A PD position loop around the plant: the logged input is the controller's
  // output computed from the quantised measured position (steps of 1/200 of its
  // standard deviation) of the previous sample (a digital controller's
  // computation delay), plus a white reference; a force disturbance (30 % of the reference) acts on
  // the plant, so the loop carries noise back into the input, which is what
  // biases output-error and subspace methods (a loop without any noise would
  // not: nothing then correlates the input with the output's innovation). Two
  // inputs and outputs so the Bonferroni level covers several pairs.
  const sysid::StateSpace g = plant();
  const VectorXd ref1 = white(kN, 31), ref2 = white(kN, 32), force1 = 0.3 * white(kN, 33), force2 = 0.3 * white(kN, 34);
  MatrixXd u(kN, 2), y(kN, 2);
  Eigen::VectorXd x1 = Eigen::VectorXd::Zero(2), x2 = Eigen::VectorXd::Zero(2);
  double previous1 = 0.0, before1 = 0.0;
  constexpr double kQuantum = 0.005;
  for (Eigen::Index t = 0; t < kN; ++t) {
    const double measured1 = kQuantum * std::round((g.C * x1)(0) / kQuantum);
    u(t, 0) = ref1(t) - 0.1 * previous1 - 0.05 * (previous1 - before1);
    u(t, 1) = ref2(t);  // the second axis runs open loop
    before1 = previous1;
    previous1 = measured1;
    y(t, 0) = measured1;
    y(t, 1) = (g.C * x2)(0);
    x1 = g.A * x1 + g.B * (u(t, 0) + force1(t));
    x2 = g.A * x2 + g.B * (u(t, 1) + force2(t));
  }
  sysid::IoData d;
  d.Ts = kTs;
  d.input_names = {"u1", "u2"};
  d.output_names = {"y1", "y2"};
  d.experiments.push_back({u, y, "test"});
  const auto r = sysid::check_data(d);
  ASSERT_EQ(r.feedback.size(), 4u);
  EXPECT_TRUE(r.feedback[0].likely) << r.report();  // u1 <- y1
  EXPECT_FALSE(r.feedback[3].likely) << r.report();  // u2 <- y2: open loop
  EXPECT_TRUE(any_finding(r, "closed-loop")) << r.report();
}

TEST(DataCheck, TimeColumnGapsAndJitter) {
  const VectorXd u = white(kN, 13);
  VectorXd t = VectorXd::LinSpaced(kN, 0.0, static_cast<double>(kN - 1) * kTs);
  t.tail(100).array() += 5.0 * kTs;  // five samples lost before the last 100
  auto r = sysid::check_data(log_of(u, respond(u, 0.05, 14)), t);
  EXPECT_TRUE(r.sampling.checked);
  EXPECT_EQ(r.sampling.gaps, 1);
  EXPECT_TRUE(any_finding(r, "gap")) << r.report();
}

TEST(DataCheck, TooShortARecordIsRefused) {
  const VectorXd u = white(100, 15);
  EXPECT_THROW(sysid::check_data(log_of(u, u)), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_diagnose_data_check
