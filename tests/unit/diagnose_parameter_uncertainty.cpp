// Tests for include/sysid/diagnose/parameter_uncertainty.hpp: on a model linear in
// its parameters the standard errors are those of least squares; on a nonlinear
// block fitted by fit_candidates over many noise seeds they match the spread of
// the estimates, white or coloured noise; a parameter the data cannot determine
// gets +inf and a warning.
#include <sysid/diagnose/candidate_fit.hpp>
#include <sysid/diagnose/parameter_uncertainty.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <vector>

#include "../support/checks.hpp"
#include "../support/diagnose_cases.hpp"
#include "../support/random_matrices.hpp"
#include "../support/sanitizers.hpp"

namespace test_unit_diagnose_parameter_uncertainty {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using sysid::test::physics_block;

constexpr double kTs = 0.5e-3;

/// First-order discrete plant, pole 0.95, one input, `outputs` outputs (gains 1, 0.5, ...).
sysid::StateSpace small_plant(Eigen::Index outputs) {
  MatrixXd C(outputs, 1);
  for (Eigen::Index i = 0; i < outputs; ++i) C(i, 0) = 1.0 / static_cast<double>(i + 1);
  return sysid::StateSpace(MatrixXd{{0.95}}, MatrixXd{{0.05}}, C, MatrixXd::Zero(outputs, 1), kTs);
}

sysid::Candidate candidate(const sysid::PhysicsBlock& block, std::vector<sysid::FreeParameter> free) {
  sysid::Candidate c;
  c.block = block;
  c.free = std::move(free);
  return c;
}

/// Newey-West covariance of ordinary least squares y = X b + e, coded
/// independently (normal equations) of the library: (X'X)^-1 S (X'X)^-1, S with
/// the header's fixed-b correction.
MatrixXd newey_west_ols(const MatrixXd& X, const VectorXd& e, Eigen::Index L) {
  const MatrixXd G = X.array().colwise() * e.array();
  MatrixXd S = G.transpose() * G;
  for (Eigen::Index k = 1; k <= L; ++k) {
    const MatrixXd gamma = G.topRows(X.rows() - k).transpose() * G.bottomRows(X.rows() - k);
    S += (1.0 - static_cast<double>(k) / static_cast<double>(L + 1)) * (gamma + gamma.transpose());
  }
  const double b = static_cast<double>(L) / static_cast<double>(X.rows());  // fixed-b bias correction
  const MatrixXd A_inv = (X.transpose() * X).inverse();
  return A_inv * (S / (1.0 - b + b * b / 3.0)) * A_inv;
}

// y = ratio * y_lin + offset + slope * t + white noise: linear in (ratio, offset,
// slope), so the Gauss-Newton covariance is exact and the finite differences are
// too. At the least-squares estimate, the white-noise sandwich (lag 0) is the
// classical sigma^2 (X'X)^-1 up to its sampling error, whose relative size for
// these regressors is about sqrt(2 kurtosis(x) / N) <= 1.7 % at N = 20000 (5 %
// is three of those); with the default window it equals the Newey-West formula
// coded here by normal equations to round-off.
TEST(ParameterUncertainty, LinearInParametersGivesTheLeastSquaresStandardErrors) {
  constexpr Eigen::Index N = 20000;
  const sysid::AugmentedSimulator sim(small_plant(1));
  const MatrixXd u = sysid::test::white_noise(N, 1, 11);
  const VectorXd y_lin = sim.simulate({}, u).col(0);
  MatrixXd X(N, 3);
  for (Eigen::Index t = 0; t < N; ++t) X.row(t) << y_lin(t), 1.0, static_cast<double>(t) * kTs;
  const double sigma = 0.3 * std::sqrt(y_lin.squaredNorm() / N);
  const MatrixXd y = X * Eigen::Vector3d(1.1, 0.3, 0.5) + sysid::test::white_noise(N, 1, 12, sigma);
  const VectorXd b = X.colPivHouseholderQr().solve(y.col(0));
  const VectorXd e = y.col(0) - X * b;
  const std::vector<sysid::Candidate> fitted = {
      candidate(physics_block("gain_error", {{"ratio", b(0)}}), {{"ratio", 0.5, 2.0}}),
      candidate(physics_block("offset_drift", {{"offset", b(1)}, {"slope", b(2)}}), {{"offset", -10.0, 10.0}, {"slope", -10.0, 10.0}})};

  sysid::ParameterUncertaintyOptions white;
  white.max_correlation_lag = 0;
  const sysid::ParameterUncertainty r0 = sysid::parameter_uncertainty(sim, {}, fitted, u, y, N, white);
  const VectorXd classical = ((e.squaredNorm() / (N - 3)) * (X.transpose() * X).inverse()).diagonal().cwiseSqrt();
  ASSERT_EQ(r0.names, (std::vector<std::string>{"gain_error.ratio", "offset_drift.offset", "offset_drift.slope"}));
  EXPECT_NEAR(r0.standard_errors[0].at("ratio") / classical(0), 1.0, 0.05);
  EXPECT_NEAR(r0.standard_errors[1].at("offset") / classical(1), 1.0, 0.05);
  EXPECT_NEAR(r0.standard_errors[1].at("slope") / classical(2), 1.0, 0.05);
  EXPECT_EQ(r0.rank, 3);
  EXPECT_TRUE(std::isfinite(r0.condition_number));
  EXPECT_TRUE(r0.warnings.empty());

  const sysid::ParameterUncertainty r = sysid::parameter_uncertainty(sim, {}, fitted, u, y, N);
  EXPECT_EQ(r.correlation_lag, 500);
  const MatrixXd reference = newey_west_ols(X, e, 500);
  EXPECT_LT((r.covariance - reference).norm(), 1e-6 * reference.norm());
  EXPECT_NEAR(r.standard_errors[1].at("slope"), std::sqrt(reference(2, 2)), 1e-6 * std::sqrt(reference(2, 2)));
}

// Two outputs with their own parameters and very different scales: each output's
// scores are summed on their own and the weights 1 / std(y_i) cancel.
TEST(ParameterUncertainty, EachOutputIsSummedOnItsOwn) {
  constexpr Eigen::Index N = 3000;
  const sysid::AugmentedSimulator sim(small_plant(2));
  const MatrixXd u = sysid::test::white_noise(N, 1, 21);
  const MatrixXd y_lin = sim.simulate({}, u);
  MatrixXd y = y_lin;
  y.col(0) = 0.9 * y_lin.col(0) + sysid::test::white_noise(N, 1, 22, 0.05);
  y.col(1) = 1e3 * (y_lin.col(1).array() + 0.2 + sysid::test::white_noise(N, 1, 23, 0.05).col(0).array()).matrix();
  const VectorXd x0 = y_lin.col(0), ones = VectorXd::Ones(N);
  const double ratio = x0.dot(y.col(0)) / x0.squaredNorm();
  // Output 1 carries a gain of 1e3 the nominal lacks: fit gain and offset there
  // jointly (linear in both) and the ratio on output 0.
  MatrixXd X1(N, 2);
  X1 << y_lin.col(1), ones;
  const VectorXd b1 = X1.colPivHouseholderQr().solve(y.col(1));
  const std::vector<sysid::Candidate> fitted = {
      candidate(physics_block("gain_error", {{"ratio", ratio}}, 0, 0), {{"ratio", 0.5, 2.0}}),
      candidate(physics_block("gain_error", {{"ratio", b1(0)}}, 0, 1), {{"ratio", 500.0, 2000.0}}),
      candidate(physics_block("offset_drift", {{"offset", b1(1)}, {"slope", 0.0}}, 0, 1), {{"offset", -1e3, 1e3}})};
  const sysid::ParameterUncertainty r = sysid::parameter_uncertainty(sim, {}, fitted, u, y, N);
  const MatrixXd c0 = newey_west_ols(x0, y.col(0) - ratio * x0, 500);
  const MatrixXd c1 = newey_west_ols(X1, y.col(1) - X1 * b1, 500);
  EXPECT_NEAR(r.standard_errors[0].at("ratio") / std::sqrt(c0(0, 0)), 1.0, 1e-6);
  EXPECT_NEAR(r.standard_errors[1].at("ratio") / std::sqrt(c1(0, 0)), 1.0, 1e-6);
  EXPECT_NEAR(r.standard_errors[2].at("offset") / std::sqrt(c1(1, 1)), 1.0, 1e-6);
  EXPECT_NEAR(r.covariance(1, 2) / c1(0, 1), 1.0, 1e-6);
  EXPECT_NEAR(r.covariance(0, 1), 0.0, 1e-9 * std::sqrt(c0(0, 0) * c1(0, 0)));  // outputs not crossed
}

/// A dead zone on the two-mode structure, refitted by fit_candidates on `seeds`
/// noise records (the same input: the standard error is conditional on it).
struct MonteCarlo {
  double spread = 0.0;          ///< sample standard deviation of the estimates
  double mean_se = 0.0;         ///< mean reported standard error (default window)
  double mean_white_se = 0.0;   ///< the same with max_correlation_lag = 0 (white noise)
  double mean_bias = 0.0;       ///< mean estimate - truth
};

MonteCarlo dead_zone_monte_carlo(double pole, int seeds, Eigen::Index samples) {
  const sysid::StateSpace s = sysid::test::two_mode_structure(kTs);
  const MatrixXd u = sysid::test::reversing_excitation(samples, kTs, 31);
  const double width = 0.3 * std::sqrt(u.squaredNorm() / static_cast<double>(u.size()));
  const sysid::AugmentedSimulator sim(s);
  const MatrixXd clean = sim.simulate({physics_block("deadzone", {{"width", width}})}, u);
  const double rms = std::sqrt(clean.squaredNorm() / static_cast<double>(clean.size()));
  sysid::CandidateFitOptions fit;
  fit.global_evaluations_per_parameter = 0;  // the estimator is the optimum near the truth
  fit.local_evaluations = 200;
  fit.relative_tolerance = 1e-13;  // the cost's relative rise at one standard error is ~1 / samples
  sysid::ParameterUncertaintyOptions white;
  white.max_correlation_lag = 0;
  std::vector<double> estimates;
  MonteCarlo mc;
  for (int k = 0; k < seeds; ++k) {
    // AR(1) noise of pole `pole` (0: white) and variance (0.05 rms)^2.
    const MatrixXd w = sysid::test::white_noise(samples, 1, 1000 + static_cast<std::uint64_t>(k));
    MatrixXd noise(samples, 1);
    double state = w(0, 0) / std::sqrt(1.0 - pole * pole);
    for (Eigen::Index t = 0; t < samples; ++t) {
      if (t > 0) state = pole * state + w(t, 0);
      noise(t, 0) = state * std::sqrt(1.0 - pole * pole);
    }
    const MatrixXd y = clean + 0.05 * rms * noise;
    sysid::Candidate c = candidate(physics_block("deadzone", {{"width", width}}), {{"width", 0.0, 4.0 * width}});
    const sysid::CandidateFitResult fitted = sysid::fit_candidates(sim, {}, {c}, u, y, samples, fit);
    estimates.push_back(fitted.fitted[0].block.param("width"));
    mc.mean_se += sysid::parameter_uncertainty(sim, {}, fitted.fitted, u, y, samples).standard_errors[0].at("width");
    mc.mean_white_se += sysid::parameter_uncertainty(sim, {}, fitted.fitted, u, y, samples, white).standard_errors[0].at("width");
  }
  double mean = 0.0;
  for (double e : estimates) mean += e / seeds;
  for (double e : estimates) mc.spread += (e - mean) * (e - mean) / (seeds - 1);
  mc.spread = std::sqrt(mc.spread);
  mc.mean_se /= seeds;
  mc.mean_white_se /= seeds;
  mc.mean_bias = mean - width;
  return mc;
}

// The sample standard deviation of M estimates has a relative sampling error of
// about 1 / sqrt(2 (M - 1)) (7 % at M = 100; 10 % at the sanitizers' 50):
// [0.7, 1.4] is more than three of those either side, leaving room for the
// linearisation and the lag window's bias.
constexpr int kSeeds = sysid::test::kSanitized ? 50 : 100;

TEST(ParameterUncertaintyMonteCarlo, DeadZoneWidthWhiteNoise) {
  const MonteCarlo mc = dead_zone_monte_carlo(0.0, kSeeds, 3000);
  std::cout << "white noise: spread " << mc.spread << ", mean SE " << mc.mean_se << " (ratio " << mc.mean_se / mc.spread
            << "), white-noise SE " << mc.mean_white_se << " (ratio " << mc.mean_white_se / mc.spread << "), bias "
            << mc.mean_bias << "\n";
  EXPECT_GE(mc.mean_se / mc.spread, 0.7);
  EXPECT_LE(mc.mean_se / mc.spread, 1.4);
  EXPECT_GE(mc.mean_white_se / mc.spread, 0.7);
  EXPECT_LE(mc.mean_white_se / mc.spread, 1.4);
}

// AR(1) noise of pole 0.9: the white-noise formula understates the spread, the
// Newey-West one does not.
TEST(ParameterUncertaintyMonteCarlo, DeadZoneWidthColouredNoise) {
  const MonteCarlo mc = dead_zone_monte_carlo(0.9, kSeeds, 3000);
  std::cout << "AR(1) 0.9: spread " << mc.spread << ", mean SE " << mc.mean_se << " (ratio " << mc.mean_se / mc.spread
            << "), white-noise SE " << mc.mean_white_se << " (ratio " << mc.mean_white_se / mc.spread << "), bias "
            << mc.mean_bias << "\n";
  EXPECT_GE(mc.mean_se / mc.spread, 0.7);
  EXPECT_LE(mc.mean_se / mc.spread, 1.4);
  EXPECT_LT(mc.mean_white_se / mc.spread, 0.6);
}

// Coulomb friction with a velocity scale far below every velocity on the record:
// tanh(v / velocity_scale) is +-1 at every sample whatever the scale, so the
// scale has no effect. Two offsets on one output act alike: neither is
// identifiable, their sum is. The level and the gain stay finite.
TEST(ParameterUncertainty, NonIdentifiableParametersGetInfinityAndAWarning) {
  constexpr Eigen::Index N = 3000;
  const sysid::StateSpace s = sysid::test::two_mode_structure(kTs);
  const sysid::AugmentedSimulator sim(s);
  const MatrixXd u = sysid::test::reversing_excitation(N, kTs, 41);
  const MatrixXd y_lin = sim.simulate({}, u);
  const double vrms = std::sqrt(((y_lin.col(0).tail(N - 1) - y_lin.col(0).head(N - 1)) / kTs).squaredNorm() / (N - 1));
  const double vs = 1e-12 * vrms, level = 0.1 * std::sqrt(u.squaredNorm() / N);
  const sysid::PhysicsBlock friction = physics_block("coulomb_friction", {{"level", level}, {"velocity_scale", vs}});
  const MatrixXd clean = sim.simulate({friction}, u);
  const MatrixXd y = clean + sysid::test::white_noise(N, 1, 42, 0.02 * std::sqrt(clean.squaredNorm() / N));
  const std::vector<sysid::Candidate> fitted = {
      candidate(friction, {{"level", 0.0, 4.0 * level}, {"velocity_scale", 1e-13 * vrms, 1e-11 * vrms, true}}),
      candidate(physics_block("offset_drift", {{"offset", 0.0}, {"slope", 0.0}}), {{"offset", -1.0, 1.0}}),
      candidate(physics_block("offset_drift", {{"offset", 0.0}, {"slope", 0.0}}), {{"offset", -1.0, 1.0}}),
      candidate(physics_block("gain_error", {{"ratio", 1.0}}), {{"ratio", 0.5, 2.0}}),
      candidate(physics_block("backlash", {{"width", 0.0}}), {{"width", 0.0, 0.0}})};  // empty box: held
  const sysid::ParameterUncertainty r = sysid::parameter_uncertainty(sim, {}, fitted, u, y, N);
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(r.standard_errors[0].at("velocity_scale"), inf);
  EXPECT_EQ(r.standard_errors[1].at("offset"), inf);
  EXPECT_EQ(r.standard_errors[2].at("offset"), inf);
  EXPECT_TRUE(std::isfinite(r.standard_errors[0].at("level")));
  EXPECT_GT(r.standard_errors[0].at("level"), 0.0);
  EXPECT_LT(r.standard_errors[0].at("level"), 0.1 * level);
  EXPECT_TRUE(std::isfinite(r.standard_errors[3].at("ratio")));
  EXPECT_EQ(r.standard_errors[4].at("width"), 0.0);
  EXPECT_EQ(r.identifiable, (std::vector<bool>{true, false, false, false, true, true}));
  EXPECT_EQ(r.condition_number, inf);
  EXPECT_EQ(r.rank, 3);  // level, ratio and the sum of the offsets (the held width is not counted)
  EXPECT_TRUE(std::isnan(r.covariance(0, 1)));
  EXPECT_TRUE(sysid::test::has_warning(r.warnings, "coulomb_friction.velocity_scale is not identifiable"));
  EXPECT_TRUE(sysid::test::has_warning(r.warnings, "offset_drift.offset is not identifiable"));
  EXPECT_TRUE(sysid::test::has_warning(r.warnings, "backlash.width: empty box"));
}

TEST(ParameterUncertainty, RejectsBadArguments) {
  constexpr Eigen::Index N = 200;
  const sysid::AugmentedSimulator sim(small_plant(1));
  const MatrixXd u = sysid::test::white_noise(N, 1, 51), y = sim.simulate({}, u);
  const std::vector<sysid::Candidate> ok = {candidate(physics_block("gain_error", {{"ratio", 1.0}}), {{"ratio", 0.5, 2.0}})};
  EXPECT_NO_THROW(sysid::parameter_uncertainty(sim, {}, ok, u, y, N));
  EXPECT_THROW(sysid::parameter_uncertainty(sim, {}, ok, u, y, N + 1), std::invalid_argument);
  EXPECT_THROW(sysid::parameter_uncertainty(sim, {}, ok, u, y, 1), std::invalid_argument);  // rows <= free parameters
  EXPECT_THROW(sysid::parameter_uncertainty(sim, {}, ok, u, y.topRows(N - 1), N - 1), std::invalid_argument);
  EXPECT_THROW(sysid::parameter_uncertainty(sim, {}, ok, MatrixXd::Zero(N, 2), y, N), std::invalid_argument);
  MatrixXd y_nan = y;
  y_nan(3, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(sysid::parameter_uncertainty(sim, {}, ok, u, y_nan, N), std::invalid_argument);
  sysid::ParameterUncertaintyOptions o;
  o.max_correlation_lag = -1;
  EXPECT_THROW(sysid::parameter_uncertainty(sim, {}, ok, u, y, N, o), std::invalid_argument);
  o = {};
  o.relative_step = 0.0;
  EXPECT_THROW(sysid::parameter_uncertainty(sim, {}, ok, u, y, N, o), std::invalid_argument);
  o = {};
  o.rank_tolerance = 1.0;
  EXPECT_THROW(sysid::parameter_uncertainty(sim, {}, ok, u, y, N, o), std::invalid_argument);
  auto bad = ok;
  bad[0].free[0].name = "gain";
  EXPECT_THROW(sysid::parameter_uncertainty(sim, {}, bad, u, y, N), std::invalid_argument);
  bad = ok;
  bad[0].free[0] = {"ratio", 2.0, 0.5};
  EXPECT_THROW(sysid::parameter_uncertainty(sim, {}, bad, u, y, N), std::invalid_argument);
  bad = ok;
  bad[0].free[0] = {"ratio", 1.5, 2.0};  // the value 1.0 outside its box
  EXPECT_THROW(sysid::parameter_uncertainty(sim, {}, bad, u, y, N), std::invalid_argument);
  bad = ok;
  bad[0].free[0] = {"ratio", 0.0, 2.0, true};
  EXPECT_THROW(sysid::parameter_uncertainty(sim, {}, bad, u, y, N), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_diagnose_parameter_uncertainty
