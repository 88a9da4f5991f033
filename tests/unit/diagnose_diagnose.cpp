// Tests for the diagnose loop (include/sysid/diagnose/diagnose.hpp) and the
// candidate fit (candidate_fit.hpp) on data made by the augmented simulator
// itself: the loop must find the block that made the data, recover its
// parameters, and find nothing when the nominal is right. The independent
// check against continuous-time plants is tests/acceptance/diagnose_concealed.cpp.
#include <sysid/core/discretize.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/diagnose/diagnose.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>

#include "../support/diagnose_cases.hpp"

namespace {

using Eigen::MatrixXd;
using sysid::PhysicsBlock;
using sysid::StateSpace;

constexpr double kTs = 0.5e-3;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

StateSpace structure() { return sysid::test::two_mode_structure(kTs); }
MatrixXd excitation(Eigen::Index n, std::uint64_t seed) { return sysid::test::reversing_excitation(n, kTs, seed); }
using sysid::test::physics_block;

struct Case {
  sysid::AugmentedModel nominal;
  MatrixXd u, y;
};

Case make_case(const std::vector<PhysicsBlock>& truth, double noise_fraction, std::uint64_t seed) {
  Case c;
  c.nominal.nominal = structure();
  c.u = excitation(20000, seed);
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
  const MatrixXd u = excitation(20000, 3);
  const double ymax = sysid::simulate(s, u).cwiseAbs().maxCoeff();
  const double k3 = 0.5 * 1e4 / (ymax * ymax * ymax);  // half the typical force at the peak
  const Case c = make_case({physics_block("cubic_stiffness", {{"coefficient", k3}, {"linear_coefficient", 0.0}})}, 0.03, 3);
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

TEST(Diagnose, RejectsTooShortRecords) {
  const Case c = make_case({}, 0.05, 6);
  EXPECT_THROW(sysid::diagnose(c.nominal, c.u.topRows(500), c.y.topRows(500)), std::invalid_argument);
  EXPECT_THROW(sysid::diagnose(c.nominal, c.u, c.y.topRows(100)), std::invalid_argument);
}

}  // namespace
