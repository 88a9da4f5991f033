// Tests of sysid::check_output_feedback (include/sysid/diagnose/feedback_check.hpp).
//
// Set-up: Ts = 1 ms, N = 4000. The plant is a mass-spring-damper position drive
// (20 Hz, zeta 0.1, unit static gain from force to position), in the "true"
// machine with a 120 Hz structural mode added (gain 0.3, zeta 0.03). Output noise
// is coloured (white through 1 / (1 - 0.9 q^-1)) at 10 % of the output's RMS.
//
// False-alarm counts: at significance 0.01 a record raises a false alarm with
// probability <= 0.01, so over 20 independent records P(3 or more) <= C(20,3) 1e-6
// = 0.1 %; each open-loop sweep allows 2 of 20, and the 80 records of the first
// test 4 (P(5 or more) = 0.2 %). Detection: 19 of 20 in the closed
// loops (the statistic is far above its threshold there, so one miss in 20 is slack).
#include <sysid/core/discretize.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/diagnose/feedback_check.hpp>
#include <sysid/signal/excitation.hpp>
#include <sysid/signal/polynomial_filter.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <numbers>
#include <random>
#include <stdexcept>

namespace test_unit_diagnose_feedback_check {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
constexpr double kTs = 1e-3;
constexpr Eigen::Index kN = 4000;
constexpr int kSeeds = 20;

VectorXd white(Eigen::Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  VectorXd x(n);
  for (auto& v : x) v = g(rng);
  return x;
}

double rms(const VectorXd& x) { return std::sqrt((x.array() - x.mean()).square().mean()); }

/// Continuous resonator gain w^2 / (s^2 + 2 zeta w s + w^2), states (position, velocity).
sysid::StateSpace resonator(double f_hz, double zeta, double gain) {
  const double w = 2.0 * std::numbers::pi * f_hz;
  return sysid::StateSpace(MatrixXd{{0.0, 1.0}, {-w * w, -2.0 * zeta * w}}, MatrixXd{{0.0}, {gain * w * w}},
                           MatrixXd{{1.0, 0.0}}, MatrixXd::Zero(1, 1), 0.0);
}

/// Sum of two SISO continuous models (parallel connection), sampled with ZOH.
sysid::StateSpace parallel_zoh(const sysid::StateSpace& a, const sysid::StateSpace& b) {
  const Eigen::Index na = a.order(), nb = b.order();
  MatrixXd A = MatrixXd::Zero(na + nb, na + nb), B(na + nb, 1), C(1, na + nb);
  A.topLeftCorner(na, na) = a.A;
  A.bottomRightCorner(nb, nb) = b.A;
  B << a.B, b.B;
  C << a.C, b.C;
  return sysid::c2d_zoh(sysid::StateSpace(A, B, C, MatrixXd::Zero(1, 1), 0.0), kTs);
}

/// The machine: the drive's 20 Hz suspension mode and a 120 Hz structural mode.
sysid::StateSpace machine() { return parallel_zoh(resonator(20.0, 0.1, 1.0), resonator(120.0, 0.03, 0.3)); }
/// A correct nominal, and a wrong one: the structural mode missing, the drive's
/// mode 10 % low and its gain 20 % low (the residual then holds a response to u
/// twice the noise's size).
sysid::StateSpace correct_nominal() { return machine(); }
sysid::StateSpace wrong_nominal() { return sysid::c2d_zoh(resonator(18.0, 0.1, 0.8), kTs); }

VectorXd coloured_noise(Eigen::Index n, std::uint64_t seed) {
  return sysid::filter_polynomial(VectorXd::Ones(1), (VectorXd(2) << 1.0, -0.9).finished(), white(n, seed)).col(0);
}

VectorXd multisine_input(Eigen::Index period, std::uint64_t seed) {
  sysid::MultisineOptions ms;
  ms.fs_hz = 1.0 / kTs;
  ms.f_min_hz = 1.0;
  ms.f_max_hz = 200.0;
  ms.samples = kN;
  ms.period = period;
  ms.seed = seed;
  return sysid::multisine(ms).col(0);
}

/// The machine's response to u with Coulomb friction `coulomb` (in units of u)
/// opposing the drive's velocity (state 2 of the 20 Hz mode, ZOH keeps the basis).
VectorXd friction_response(const VectorXd& u, double coulomb) {
  const sysid::StateSpace g1 = sysid::c2d_zoh(resonator(20.0, 0.1, 1.0), kTs), g2 = sysid::c2d_zoh(resonator(120.0, 0.03, 0.3), kTs);
  VectorXd x1 = VectorXd::Zero(2), x2 = VectorXd::Zero(2), y(u.size());
  for (Eigen::Index t = 0; t < u.size(); ++t) {
    y(t) = x1(0) + (g2.C * x2)(0);
    const double friction = x1(1) > 0.0 ? coulomb : (x1(1) < 0.0 ? -coulomb : 0.0);
    x1 = g1.A * x1 + g1.B * (u(t) - friction);
    x2 = g2.A * x2 + g2.B * u(t);
  }
  return y;
}

sysid::OutputFeedbackCheck open_loop(const VectorXd& u, const sysid::StateSpace& nominal, std::uint64_t seed,
                                     double coulomb = 0.0) {
  const VectorXd clean = coulomb > 0.0 ? friction_response(u, coulomb) : VectorXd(sysid::simulate(machine(), MatrixXd(u)).col(0));
  VectorXd noise = coloured_noise(u.size(), seed);
  const VectorXd y = clean + 0.1 * rms(clean) / rms(noise) * noise;
  return sysid::check_output_feedback(u, y, sysid::simulate(nominal, MatrixXd(u)), kTs);
}

struct Loop {
  double kp = 2.0, kd = 0.005;  ///< u = kp (r - y_q) - kd (y_q[t] - y_q[t-1]) / Ts
  double quantum = 1e-3;        ///< encoder count
  double noise_std = 1e-3;      ///< white measurement noise before quantisation
};

/// A discrete PD position loop around the machine: the logged input is the
/// controller's output from the quantised measurement, the logged output that
/// measurement. Returns (u, y).
std::pair<VectorXd, VectorXd> closed_loop(const VectorXd& reference, const Loop& c, std::uint64_t seed) {
  const sysid::StateSpace g = machine();
  const VectorXd noise = c.noise_std * white(reference.size(), seed);
  VectorXd u(reference.size()), y(reference.size());
  VectorXd x = VectorXd::Zero(g.order());
  double previous = 0.0;
  for (Eigen::Index t = 0; t < reference.size(); ++t) {
    const double measured = c.quantum * std::round(((g.C * x)(0) + noise(t)) / c.quantum);
    u(t) = c.kp * (reference(t) - measured) - c.kd * (measured - previous) / kTs;
    y(t) = measured;
    previous = measured;
    x = g.A * x + g.B * u(t);
  }
  return {u, y};
}

/// A smooth reference: three slow sines with random phases, amplitude about 1.
VectorXd smooth_reference(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  VectorXd r(kN);
  const double p1 = phase(rng), p2 = phase(rng), p3 = phase(rng);
  for (Eigen::Index t = 0; t < kN; ++t) {
    const double s = static_cast<double>(t) * kTs;
    r(t) = 0.6 * std::sin(2.0 * std::numbers::pi * 0.5 * s + p1) + 0.3 * std::sin(2.0 * std::numbers::pi * 1.3 * s + p2) +
           0.2 * std::sin(2.0 * std::numbers::pi * 3.1 * s + p3);
  }
  return r;
}

TEST(OutputFeedbackCheck, OpenLoopRecordsRaiseAtMostTheExpectedFalseAlarms) {
  // Four open-loop sweeps of 20 records (see the file comment for the bound): a
  // multisine input with a correct and with a wrong nominal, a low-pass noise input
  // on a machine with Coulomb friction (5 % of the input's RMS) that the wrong
  // nominal also lacks, and a white input with the wrong nominal.
  int multisine_correct = 0, multisine_wrong = 0, filtered_wrong = 0, white_wrong = 0;
  const VectorXd lowpass = (VectorXd(3) << 1.0, -1.6, 0.7).finished();
  for (int s = 0; s < kSeeds; ++s) {
    const auto seed = static_cast<std::uint64_t>(100 + 10 * s);
    const VectorXd ms = multisine_input(0, seed);
    const auto a = open_loop(ms, correct_nominal(), seed + 1);
    const auto b = open_loop(ms, wrong_nominal(), seed + 2);
    const VectorXd filtered = sysid::filter_polynomial(VectorXd::Ones(1), lowpass, white(kN, seed + 3)).col(0);
    const auto c = open_loop(filtered / rms(filtered), wrong_nominal(), seed + 4, 0.05);  // and Coulomb friction
    const auto d = open_loop(white(kN, seed + 5), wrong_nominal(), seed + 6);
    for (const auto* r : {&a, &b, &c, &d}) EXPECT_TRUE(r->tested) << r->evidence;
    multisine_correct += a.feedback_detected;
    multisine_wrong += b.feedback_detected;
    filtered_wrong += c.feedback_detected;
    white_wrong += d.feedback_detected;
    if (s == 0) EXPECT_NE(b.evidence.find("no sign of feedback"), std::string::npos) << b.evidence;
  }
  std::printf("false alarms of %d: multisine/correct %d, multisine/wrong %d, filtered/wrong+friction %d, white/wrong %d\n", kSeeds,
              multisine_correct, multisine_wrong, filtered_wrong, white_wrong);
  EXPECT_LE(multisine_correct, 2);
  EXPECT_LE(multisine_wrong, 2);
  EXPECT_LE(filtered_wrong, 2);
  EXPECT_LE(white_wrong, 2);
  // All 80 at once: 5 or more alarms has probability 0.2 % (binomial, p = 0.01).
  EXPECT_LE(multisine_correct + multisine_wrong + filtered_wrong + white_wrong, 4);
}

TEST(OutputFeedbackCheck, APeriodicInputIsNotTestedAndRaisesNoAlarm) {
  // Period 25 samples < input_lags + lags: the input's future is a linear function
  // of its past, nothing is left to test. Period N / 8: tested, and quiet.
  const auto short_period = open_loop(multisine_input(25, 7), wrong_nominal(), 8);
  EXPECT_FALSE(short_period.tested) << short_period.evidence;
  EXPECT_FALSE(short_period.feedback_detected);
  EXPECT_EQ(short_period.pairs[0].dof, 0);
  int alarms = 0;
  for (int s = 0; s < kSeeds; ++s) {
    const auto r = open_loop(multisine_input(kN / 8, 200 + static_cast<std::uint64_t>(s)), wrong_nominal(), 300 + static_cast<std::uint64_t>(s));
    EXPECT_TRUE(r.tested);
    alarms += r.feedback_detected;
  }
  std::printf("false alarms of %d: multisine of 8 periods/wrong %d\n", kSeeds, alarms);
  EXPECT_LE(alarms, 2);
}

TEST(OutputFeedbackCheck, APdPositionLoopWithEncoderQuantisationIsDetected) {
  int smooth = 0, small_noise = 0;
  double lag_s = 0.0, weakest_smooth = 1e300, weakest_small = 1e300;
  for (int s = 0; s < kSeeds; ++s) {
    const auto seed = static_cast<std::uint64_t>(500 + 10 * s);
    // A smooth reference, encoder count 1e-3, noise 1e-3; the wrong nominal.
    const auto [u1, y1] = closed_loop(smooth_reference(seed), Loop{}, seed + 1);
    const auto a = sysid::check_output_feedback(u1, y1, sysid::simulate(wrong_nominal(), MatrixXd(u1)), kTs);
    smooth += a.feedback_detected;
    weakest_smooth = std::min(weakest_smooth, a.statistic / a.threshold);
    if (s == 0) {
      EXPECT_NE(a.evidence.find("closed-loop"), std::string::npos) << a.evidence;
      lag_s = a.strongest_lag_s;
    }
    // Tracking a broadband multisine reference, noise and count 1e-5 of its RMS:
    // what feeds back is the quantisation and the little noise.
    Loop quiet;
    quiet.quantum = 1e-5;
    quiet.noise_std = 1e-5;
    const auto [u2, y2] = closed_loop(multisine_input(0, seed + 2), quiet, seed + 3);
    const auto b = sysid::check_output_feedback(u2, y2, sysid::simulate(correct_nominal(), MatrixXd(u2)), kTs);
    small_noise += b.feedback_detected;
    weakest_small = std::min(weakest_small, b.statistic / b.threshold);
  }
  std::printf("detected of %d: smooth reference %d (smallest statistic / threshold %.3g), multisine reference with small "
              "noise %d (%.3g)\n",
              kSeeds, smooth, weakest_smooth, small_noise, weakest_small);
  EXPECT_GE(smooth, kSeeds - 1);
  EXPECT_GE(small_noise, kSeeds - 1);
  // The derivative term reacts to y(t) at t + 1.
  EXPECT_NEAR(lag_s, kTs, 1e-12);
}

TEST(OutputFeedbackCheck, MimoWithOneLoopClosedNamesThatPair) {
  // Two drives with cross-coupling; axis 1 under PD position control, axis 2
  // driven open loop by a multisine. Bonferroni over the four pairs.
  const sysid::StateSpace g = machine();
  const VectorXd ref = smooth_reference(41), u2 = multisine_input(0, 42);
  const VectorXd n1 = 1e-3 * white(kN, 43), n2 = coloured_noise(kN, 44);
  MatrixXd u(kN, 2), y(kN, 2);
  VectorXd x1 = VectorXd::Zero(g.order()), x2 = VectorXd::Zero(g.order());
  double previous = 0.0;
  const Loop c;
  for (Eigen::Index t = 0; t < kN; ++t) {
    const double measured = c.quantum * std::round(((g.C * x1)(0) + n1(t)) / c.quantum);
    u(t, 0) = c.kp * (ref(t) - measured) - c.kd * (measured - previous) / kTs;
    u(t, 1) = u2(t);
    previous = measured;
    y(t, 0) = measured;
    y(t, 1) = (g.C * x2)(0) + 0.01 * n2(t);
    x1 = g.A * x1 + g.B * (u(t, 0) + 0.3 * u(t, 1));
    x2 = g.A * x2 + g.B * (u(t, 1) + 0.2 * u(t, 0));
  }
  // The nominal: each axis's own drive model, the coupling missing.
  const sysid::StateSpace nominal = wrong_nominal();
  MatrixXd y_sim(kN, 2);
  y_sim.col(0) = sysid::simulate(nominal, MatrixXd(u.col(0))).col(0);
  y_sim.col(1) = sysid::simulate(nominal, MatrixXd(u.col(1))).col(0);
  const auto r = sysid::check_output_feedback(u, y, y_sim, kTs);
  ASSERT_EQ(r.pairs.size(), 4u);
  EXPECT_EQ(r.pairs_tested, 4);
  EXPECT_TRUE(r.feedback_detected) << r.evidence;
  EXPECT_EQ(r.input, 0);
  EXPECT_EQ(r.output, 0);
  EXPECT_TRUE(r.pairs[0].detected);   // u1 <- y1
  EXPECT_FALSE(r.pairs[1].detected);  // u2 <- y1
  EXPECT_FALSE(r.pairs[3].detected);  // u2 <- y2
  // A constant input is skipped, not a crash; all constant: no test.
  MatrixXd with_constant = u;
  with_constant.col(1).setConstant(0.5);
  const auto k = sysid::check_output_feedback(with_constant, y, y_sim, kTs);
  EXPECT_EQ(k.pairs_tested, 2);
  EXPECT_FALSE(k.pairs[1].tested);
  EXPECT_TRUE(k.pairs[0].detected);
  const auto none = sysid::check_output_feedback(MatrixXd::Constant(kN, 2, 1.0), y, y_sim, kTs);
  EXPECT_FALSE(none.tested);
  EXPECT_FALSE(none.feedback_detected);
  EXPECT_NE(none.evidence.find("constant"), std::string::npos) << none.evidence;
  // An output equal to its simulation: no noise, no test.
  const auto exact = sysid::check_output_feedback(u, y_sim, y_sim, kTs);
  EXPECT_FALSE(exact.tested) << exact.evidence;
}

TEST(OutputFeedbackCheck, BadArgumentsThrow) {
  const MatrixXd u = white(kN, 1), y = white(kN, 2);
  using sysid::check_output_feedback;
  EXPECT_THROW(check_output_feedback(u, y, MatrixXd(y.topRows(kN - 1)), kTs), std::invalid_argument);
  EXPECT_THROW(check_output_feedback(u, y, MatrixXd::Zero(kN, 2), kTs), std::invalid_argument);
  EXPECT_THROW(check_output_feedback(MatrixXd(u.topRows(10)), y, y, kTs), std::invalid_argument);
  EXPECT_THROW(check_output_feedback(MatrixXd(kN, 0), y, y, kTs), std::invalid_argument);
  EXPECT_THROW(check_output_feedback(u, y, y, 0.0), std::invalid_argument);
  EXPECT_THROW(check_output_feedback(u, y, y, -kTs), std::invalid_argument);
  EXPECT_THROW(check_output_feedback(u, y, y, std::nan("")), std::invalid_argument);
  EXPECT_THROW(check_output_feedback(u.topRows(200), y.topRows(200), y.topRows(200), kTs), std::invalid_argument);
  sysid::OutputFeedbackOptions o;
  o.significance = 1.0;
  EXPECT_THROW(check_output_feedback(u, y, y, kTs, o), std::invalid_argument);
  o = {};
  o.input_delay = 2;
  o.input_lags = 1;
  EXPECT_THROW(check_output_feedback(u, y, y, kTs, o), std::invalid_argument);
  o = {};
  o.lags = 0;
  EXPECT_THROW(check_output_feedback(u, y, y, kTs, o), std::invalid_argument);
  MatrixXd bad = y;
  bad(5, 0) = std::nan("");
  EXPECT_THROW(check_output_feedback(u, bad, y, kTs), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_diagnose_feedback_check
