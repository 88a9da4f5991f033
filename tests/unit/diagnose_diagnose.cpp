// Tests for the diagnose loop (include/sysid/diagnose/diagnose.hpp) and the
// candidate fit (candidate_fit.hpp) on data made by the augmented simulator
// itself: the loop must find the block that made the data, recover its
// parameters, and find nothing when the nominal is right. The independent
// check against continuous-time plants is tests/acceptance/diagnose_concealed.cpp.
#include <sysid/core/discretize.hpp>
#include <sysid/core/math_constants.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/diagnose/diagnose.hpp>
#include <sysid/validate/fit.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <numbers>

#include "../support/diagnose_cases.hpp"
#include "../support/sanitizers.hpp"

namespace test_unit_diagnose_diagnose {

namespace {

using Eigen::MatrixXd;
using sysid::PhysicsBlock;
using sysid::StateSpace;

constexpr double kTs = 0.5e-3;
using sysid::kTwoPi;
// A record of 10 s; under the sanitizers (tests/support/sanitizers.hpp) the
// searches for a cubic spring and the MIMO cases see 5 s of it, where each diagnose
// costs half a minute at full length (checked to hold in the optimised build).
constexpr Eigen::Index kSamples = 20000;
constexpr Eigen::Index kSearchSamples = sysid::test::kSanitized ? 10000 : kSamples;
// Confirmation mode cuts a record as a machine's two runs would be: 70 % to
// diagnose, the 30 % after them (starting wherever the structure was) to confirm.
constexpr Eigen::Index kConfirmSamples = 3 * kSearchSamples / 10;
constexpr Eigen::Index kDiagnoseSamples = kSearchSamples - kConfirmSamples;

StateSpace structure() { return sysid::test::two_mode_structure(kTs); }
MatrixXd excitation(Eigen::Index n, std::uint64_t seed) { return sysid::test::reversing_excitation(n, kTs, seed); }
using sysid::test::physics_block;

struct Case {
  sysid::AugmentedModel nominal;
  MatrixXd u, y;
};

Case make_case(const std::vector<PhysicsBlock>& truth, double noise_fraction, std::uint64_t seed,
               Eigen::Index samples = kSamples) {
  Case c;
  c.nominal.nominal = structure();
  c.u = excitation(samples, seed);
  const sysid::AugmentedSimulator sim(c.nominal.nominal, 4);
  const MatrixXd clean = sim.simulate(truth, c.u);
  const double rms = std::sqrt(clean.squaredNorm() / clean.size());
  c.y = clean + noise_fraction * rms * sysid::test::white_noise(clean.rows(), 1, seed + 100);
  return c;
}

TEST(Diagnose, CorrectNominalGivesNoFinding) {
  for (std::uint64_t seed : {1u, 2u}) {
    const Case c = make_case({}, 0.05, seed);
    const sysid::DiagnoseReport r = sysid::diagnose(c.nominal, c.u, c.y);
    EXPECT_TRUE(r.findings.empty()) << "seed " << seed << ": " << (r.findings.empty() ? "" : r.findings[0].summary);
    EXPECT_NEAR(r.fit_after, r.fit_before, 1e-12);
    EXPECT_FALSE(r.considered.empty());  // candidates were tried and rejected
  }
}

TEST(Diagnose, FindsCubicStiffnessAndItsCoefficient) {
  const StateSpace s = structure();
  const MatrixXd u = excitation(kSearchSamples, 3);
  const double ymax = sysid::simulate(s, u).cwiseAbs().maxCoeff();
  const double k3 = 0.5 * 1e4 / (ymax * ymax * ymax);  // half the typical force at the peak
  const Case c =
      make_case({physics_block("cubic_stiffness", {{"coefficient", k3}, {"linear_coefficient", 0.0}})}, 0.03, 3, kSearchSamples);
  const sysid::DiagnoseReport r = sysid::diagnose(c.nominal, c.u, c.y);
  ASSERT_FALSE(r.findings.empty());
  EXPECT_EQ(r.findings[0].candidate.block.kind, "cubic_stiffness") << r.findings[0].summary;
  EXPECT_NEAR(r.findings[0].candidate.block.param("coefficient") / k3, 1.0, 0.05);
  EXPECT_GE(r.fit_after - r.fit_before, 1.0);
}

TEST(Diagnose, FindsAHumBelowTheNoise) {
  const Case clean = make_case({}, 0.0, 4);
  const double rms = std::sqrt(clean.y.squaredNorm() / clean.y.size());
  const double noise = 0.08, amplitude = 0.8 * noise * rms * std::sqrt(2.0);  // hum RMS = 0.8 noise RMS
  const Case c = make_case({physics_block("periodic_disturbance", {{"freq_hz", 50.0}, {"amplitude", amplitude}, {"phase_rad", 1.0}})},
                           noise, 4);
  const sysid::DiagnoseReport r = sysid::diagnose(c.nominal, c.u, c.y);
  ASSERT_FALSE(r.findings.empty());
  const auto& b = r.findings[0].candidate.block;
  EXPECT_EQ(b.kind, "periodic_disturbance");
  EXPECT_NEAR(b.param("freq_hz"), 50.0, 0.005);
  EXPECT_NEAR(b.param("amplitude") / amplitude, 1.0, 0.05);
  EXPECT_GE(r.fit_after - r.fit_before, 1.0);
}

TEST(CandidateFit, RecoversADeadZoneFromAPoorStart) {
  const StateSpace s = structure();
  const MatrixXd u = excitation(6000, 5);
  const double width = 0.3 * std::sqrt(u.squaredNorm() / u.size());
  const sysid::AugmentedSimulator sim(s);
  const MatrixXd y = sim.simulate({physics_block("deadzone", {{"width", width}})}, u);
  sysid::Candidate c;
  c.block = physics_block("deadzone", {{"width", 0.5 * width}});
  c.free = {{"width", 0.0, 4 * width}};
  const auto r = sysid::fit_candidates(sim, {}, {c}, u, y, 6000);
  EXPECT_NEAR(r.fitted[0].block.param("width") / width, 1.0, 1e-3);
  EXPECT_LT(r.cost, 1e-6 * r.start_cost);
}

/// Two uncoupled two-mode structures side by side (u1 -> y1, u2 -> y2; the second
/// one's modes moved to 18 and 47 Hz), the kind of 2x2 nominal a MIMO machine's
/// simulation gives when it ignores the coupling between its axes.
Case make_mimo_case(const std::vector<PhysicsBlock>& truth, double noise_fraction, std::uint64_t seed) {
  const StateSpace a = structure();
  const StateSpace b = sysid::test::two_mode_structure(kTs, 18.0, 47.0, 1.5);
  MatrixXd A = MatrixXd::Zero(8, 8), B = MatrixXd::Zero(8, 2), C = MatrixXd::Zero(2, 8);
  A.topLeftCorner(4, 4) = a.A;
  A.bottomRightCorner(4, 4) = b.A;
  B.block(0, 0, 4, 1) = a.B;
  B.block(4, 1, 4, 1) = b.B;
  C.block(0, 0, 1, 4) = a.C;
  C.block(1, 4, 1, 4) = b.C;
  Case c;
  c.nominal.nominal = StateSpace(A, B, C, MatrixXd::Zero(2, 2), kTs);
  c.nominal.nominal.input_names = {"u1", "u2"};
  c.nominal.nominal.output_names = {"y1", "y2"};
  c.nominal.substeps = 4;
  c.u.resize(kSearchSamples, 2);
  c.u << excitation(kSearchSamples, seed), excitation(kSearchSamples, seed + 50);
  const sysid::AugmentedSimulator sim(c.nominal.nominal, 4);
  const MatrixXd clean = sim.simulate(truth, c.u);
  c.y = clean;
  for (Eigen::Index i = 0; i < 2; ++i) {
    const double rms = std::sqrt(clean.col(i).squaredNorm() / static_cast<double>(clean.rows()));
    c.y.col(i) += noise_fraction * rms * sysid::test::white_noise(clean.rows(), 1, seed + 100 + static_cast<std::uint64_t>(i));
  }
  return c;
}

TEST(Diagnose, FindsCrossCouplingBetweenTheAxesOfAMimoMachine) {
  // Axis 1's motion leaks into sensor 2 at 30 % of axis 1's own response.
  const Case c = make_mimo_case({physics_block("cross_coupling", {{"gain", 0.3}}, 0, 1)}, 0.03, 7);
  const sysid::DiagnoseReport r = sysid::diagnose(c.nominal, c.u, c.y);
  ASSERT_FALSE(r.findings.empty());
  const PhysicsBlock& b = r.findings[0].candidate.block;
  EXPECT_EQ(b.kind, "cross_coupling") << r.findings[0].summary;
  EXPECT_EQ(b.input, 0);
  EXPECT_EQ(b.output, 1);
  EXPECT_NEAR(b.param("gain"), 0.3, 0.03);
  EXPECT_EQ(r.findings.size(), 1u) << r.findings.back().summary;
  // Per channel: sensor 2 improves, sensor 1 (right all along) does not move.
  ASSERT_EQ(r.fit_after_per_output.size(), 2);
  EXPECT_GE(r.fit_after_per_output(1) - r.fit_before_per_output(1), 5.0);
  EXPECT_NEAR(r.fit_after_per_output(0), r.fit_before_per_output(0), 0.05);
  EXPECT_NE(r.findings[0].summary.find("u1"), std::string::npos) << r.findings[0].summary;
  EXPECT_NE(r.findings[0].summary.find("y2"), std::string::npos) << r.findings[0].summary;
}

TEST(Diagnose, NamesTheChannelOfAMimoSensorEffect) {
  // Sensor 2 reads 12 % high; sensor 1 and both actuators are right.
  const Case c = make_mimo_case({physics_block("gain_error", {{"ratio", 1.12}}, 0, 1)}, 0.03, 8);
  const sysid::DiagnoseReport r = sysid::diagnose(c.nominal, c.u, c.y);
  ASSERT_FALSE(r.findings.empty());
  const PhysicsBlock& b = r.findings[0].candidate.block;
  EXPECT_EQ(b.kind, "gain_error") << r.findings[0].summary;
  EXPECT_EQ(b.output, 1);
  EXPECT_NEAR(b.param("ratio"), 1.12, 0.01);
  EXPECT_NEAR(r.fit_after_per_output(0), r.fit_before_per_output(0), 0.05);
  // And a right 2x2 nominal gives nothing.
  const Case null_case = make_mimo_case({}, 0.03, 9);
  const sysid::DiagnoseReport none = sysid::diagnose(null_case.nominal, null_case.u, null_case.y);
  EXPECT_TRUE(none.findings.empty()) << none.findings[0].summary;
}

TEST(Diagnose, EachFindingListsTheWindowsItExplains) {
  // Two effects at different times: the actuator saturates only during two loud
  // stretches (2.0-3.5 s in the fitting part, 5.2-5.9 s in the selection part: an
  // effect absent from the selection part cannot be accepted), and the sensor
  // drifts (felt most at the ends of the 7 s estimation part, where the centred
  // drift is largest).
  Case c = make_case({}, 0.0, 11);
  const double quiet_peak = c.u.cwiseAbs().maxCoeff();
  const auto loud = [](double t0, double t1) { return (t0 >= 2.0 - 0.36 && t1 <= 3.5 + 0.36) || (t0 >= 5.2 - 0.36 && t1 <= 5.9 + 0.36); };
  for (Eigen::Index k = 0; k < c.u.rows(); ++k)
    if ((k >= 4000 && k < 7000) || (k >= 10400 && k < 11800)) c.u(k, 0) *= 3.0;
  const sysid::AugmentedSimulator sim(c.nominal.nominal, 4);
  const MatrixXd clean = sim.simulate({physics_block("saturation", {{"limit", 1.2 * quiet_peak}})}, c.u);
  const double rms = std::sqrt(clean.squaredNorm() / static_cast<double>(clean.size()));
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(clean.rows(), 0.0, static_cast<double>(clean.rows() - 1) * kTs);
  c.y = clean + 0.03 * rms * sysid::test::white_noise(clean.rows(), 1, 111);
  c.y.col(0) += 0.02 * rms * t;  // 0.2 rms over the 10 s
  const sysid::DiagnoseReport r = sysid::diagnose(c.nominal, c.u, c.y);
  const sysid::Finding* saturation = nullptr;
  const sysid::Finding* drift = nullptr;
  for (const auto& f : r.findings) {
    if (f.candidate.block.kind == "saturation") saturation = &f;
    if (f.candidate.block.kind == "offset_drift") drift = &f;
  }
  std::string all;
  for (const auto& f : r.findings) all += f.summary + " | ";
  ASSERT_NE(saturation, nullptr) << all;
  ASSERT_FALSE(saturation->time_windows_s.empty());
  // Windows are 0.35 s long: the loud stretches' windows only.
  for (const auto& [t0, t1] : saturation->time_windows_s) EXPECT_TRUE(loud(t0, t1)) << t0 << " " << t1;
  ASSERT_NE(drift, nullptr) << all;
  // The drift does not claim the saturation's windows, though they are flagged
  // windows of the same output (which every finding of that output used to list).
  for (const auto& [t0, t1] : drift->time_windows_s) EXPECT_FALSE(loud(t0, t1)) << t0 << " " << t1;
}

TEST(ValidateOnRecording, EstimatesTheStateTheRecordingStartsIn) {
  // A recording cut from the middle of a run: the structure is moving at its start.
  const Case c = make_case({}, 0.0, 10);
  const MatrixXd u = c.u.bottomRows(6000), y = c.y.bottomRows(6000);
  const sysid::RecordingValidation v = sysid::validate_on_recording(c.nominal, c.nominal, u, y);
  EXPECT_GT(v.fit_before(0), 99.99);
  EXPECT_EQ(v.fit_after(0), v.fit_before(0));
  // From a zero state the same right model loses points to the start-up transient.
  const double zero_state = sysid::fit_percent(y, sysid::simulate_augmented(c.nominal, u))(0);
  EXPECT_LT(zero_state, 99.0);
  EXPECT_THROW(sysid::validate_on_recording(c.nominal, c.nominal, u, y.topRows(10)), std::invalid_argument);
  // The augmented model may carry a refitted core (refit_nominal), each model
  // from its own initial state; it must have the nominal's channels.
  sysid::AugmentedModel other = c.nominal;
  other.nominal = sysid::test::two_mode_structure(kTs, 18.0, 47.0);
  const sysid::RecordingValidation moved = sysid::validate_on_recording(c.nominal, other, u, y);
  EXPECT_EQ(moved.fit_before(0), v.fit_before(0));
  EXPECT_LT(moved.fit_after(0), 90.0);  // the wrong modes fit worse
  other.nominal = make_mimo_case({}, 0.0, 1).nominal.nominal;  // other channels
  EXPECT_THROW(sysid::validate_on_recording(c.nominal, other, u, y), std::invalid_argument);
}

// Confirmation mode: the log fits and ranks, an independent recording confirms.

sysid::DiagnoseReport diagnose_confirmed(const Case& c) {
  return sysid::diagnose_confirmed(c.nominal, c.u.topRows(kDiagnoseSamples), c.y.topRows(kDiagnoseSamples),
                                   c.u.bottomRows(kConfirmSamples), c.y.bottomRows(kConfirmSamples));
}

TEST(DiagnoseConfirmed, CorrectNominalGivesNoFinding) {
  for (std::uint64_t seed : {1u, 2u}) {
    if (sysid::test::kSanitized && seed > 1) break;  // one seed under the sanitizers
    const Case c = make_case({}, 0.05, seed, kSearchSamples);
    const sysid::DiagnoseReport r = diagnose_confirmed(c);
    EXPECT_TRUE(r.findings.empty()) << "seed " << seed << ": " << (r.findings.empty() ? "" : r.findings[0].summary);
    EXPECT_NEAR(r.fit_after, r.fit_before, 1e-12);
    // The right model from the state the recording starts in: only the noise
    // (5 % of the output RMS) is left, a fit of about 95 %.
    EXPECT_GT(r.fit_before, 94.0);
    ASSERT_FALSE(r.considered.empty());
    // One test per round, at the full level: the threshold is the 1 % normal quantile.
    EXPECT_NEAR(r.considered.front().t_threshold, 2.3263, 1e-3);
  }
}

TEST(DiagnoseConfirmed, FindsCubicStiffnessAndTheRecordingConfirmsIt) {
  const StateSpace s = structure();
  const MatrixXd u = excitation(kSearchSamples, 3);
  const double ymax = sysid::simulate(s, u).cwiseAbs().maxCoeff();
  const double k3 = 0.5 * 1e4 / (ymax * ymax * ymax);
  const Case c =
      make_case({physics_block("cubic_stiffness", {{"coefficient", k3}, {"linear_coefficient", 0.0}})}, 0.03, 3, kSearchSamples);
  const sysid::DiagnoseReport r = diagnose_confirmed(c);
  ASSERT_FALSE(r.findings.empty());
  EXPECT_EQ(r.findings[0].candidate.block.kind, "cubic_stiffness") << r.findings[0].summary;
  EXPECT_NEAR(r.findings[0].candidate.block.param("coefficient") / k3, 1.0, 0.05);
  EXPECT_GE(r.fit_after - r.fit_before, 1.0);
  EXPECT_NE(r.validation.find("independent recording (" + std::to_string(kConfirmSamples) + " samples"), std::string::npos)
      << r.validation;
  // Each round tests only its best-ranked candidate: at most one is significant
  // per round, and it is the one with the largest penalised in-sample gain.
  for (int round = 1; round <= 4; ++round) {
    int significant = 0;
    for (const auto& j : r.considered) significant += j.round == round && j.significant;
    EXPECT_LE(significant, 1) << "round " << round;
  }
  EXPECT_GT(r.findings[0].t_statistic, r.considered.front().t_threshold);
  // The fits reported are those of the recording: the same as validate_on_recording's.
  const sysid::RecordingValidation v =
      sysid::validate_on_recording(c.nominal, r.augmented, c.u.bottomRows(kConfirmSamples), c.y.bottomRows(kConfirmSamples));
  EXPECT_NEAR(v.fit_before(0), r.fit_before, 1e-9);
  EXPECT_NEAR(v.fit_after(0), r.fit_after, 1e-9);
}

TEST(DiagnoseConfirmed, RejectsRecordingsThatCannotConfirm) {
  const Case c = make_case({}, 0.05, 6);
  const MatrixXd u = c.u.topRows(14000), y = c.y.topRows(14000);
  EXPECT_THROW(sysid::diagnose_confirmed(c.nominal, u, y, c.u.bottomRows(100), c.y.bottomRows(100)), std::invalid_argument);
  EXPECT_THROW(sysid::diagnose_confirmed(c.nominal, u, y, c.u.bottomRows(6000), c.y.bottomRows(5000)), std::invalid_argument);
  EXPECT_THROW(sysid::diagnose_confirmed(c.nominal, u, y, c.u.bottomRows(6000), MatrixXd::Zero(6000, 2)), std::invalid_argument);
  MatrixXd broken = c.y.bottomRows(6000);
  broken(10, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(sysid::diagnose_confirmed(c.nominal, u, y, c.u.bottomRows(6000), broken), std::invalid_argument);
  EXPECT_THROW(sysid::diagnose_confirmed(c.nominal, u.topRows(100), y.topRows(100), c.u.bottomRows(6000), c.y.bottomRows(6000)),
               std::invalid_argument);
}

TEST(Diagnose, RejectsTooShortRecords) {
  const Case c = make_case({}, 0.05, 6);
  EXPECT_THROW(sysid::diagnose(c.nominal, c.u.topRows(500), c.y.topRows(500)), std::invalid_argument);
  EXPECT_THROW(sysid::diagnose(c.nominal, c.u, c.y.topRows(100)), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_diagnose_diagnose
