// Tests for sysid::analyse_model_family (include/sysid/family/model_family.hpp) on
// small synthetic families of exact models: two-mode plants whose modes move with
// a payload. The modes are followed, a middle member is the nominal, the bound
// covers the spread and the weight covers the bound; one member gives no bound;
// members that do not fit together are refused.
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/family/model_family.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "checks.hpp"
#include "random_matrices.hpp"

namespace test_unit_family_model_family {

namespace {

using Eigen::MatrixXd;
using sysid::test::kPi;

constexpr double kTs = 1e-3;

/// The modes of the member with payload p: 30 / sqrt(1 + 0.25 p) Hz (zeta 0.02)
/// and 90 / sqrt(1 + 0.08 p) Hz (zeta 0.03).
double f1(double p) { return 30.0 / std::sqrt(1.0 + 0.25 * p); }
double f2(double p) { return 90.0 / std::sqrt(1.0 + 0.08 * p); }

/// SISO (or `outputs` outputs) real modal form with the two modes.
sysid::StateSpace plant(double p, double Ts = kTs, Eigen::Index outputs = 1) {
  const double f[2] = {f1(p), f2(p)}, zeta[2] = {0.02, 0.03}, gain[2] = {1.0, 2.0};
  MatrixXd A = MatrixXd::Zero(4, 4), B = MatrixXd::Zero(4, 1), C = MatrixXd::Zero(outputs, 4);
  for (int k = 0; k < 2; ++k) {
    const double w = 2.0 * kPi * f[k], r = std::exp(-zeta[k] * w * Ts), th = w * std::sqrt(1.0 - zeta[k] * zeta[k]) * Ts;
    A.block(2 * k, 2 * k, 2, 2) << r * std::cos(th), r * std::sin(th), -r * std::sin(th), r * std::cos(th);
    B(2 * k + 1, 0) = gain[k];
    C.row(0)(2 * k) = 1.0;
    for (Eigen::Index i = 1; i < outputs; ++i) C(i, 2 * k) = 0.5 * static_cast<double>(i + k);
  }
  return sysid::StateSpace(A, B, C, MatrixXd::Zero(outputs, 1), Ts);
}

const std::vector<double> kPayloads = {0.0, 0.5, 1.0, 1.5, 2.0, 2.5};

std::vector<sysid::FamilyMemberModel> family(const std::vector<double>& payloads = kPayloads) {
  std::vector<sysid::FamilyMemberModel> m;
  for (double p : payloads) m.push_back({plant(p), {}});
  return m;
}

sysid::ModelFamilyOptions band_5_200() {
  sysid::ModelFamilyOptions o;
  o.band_hz = std::make_pair(5.0, 200.0);
  return o;
}

/// A flat standard deviation `sd` over 0..Nyquist with the band [lo, hi].
sysid::FrequencyResponseError flat_error(double sd, double lo, double hi) {
  sysid::FrequencyResponseError e;
  e.freq_hz = Eigen::VectorXd::LinSpaced(257, 0.0, 0.5 / kTs);
  e.standard_deviation = Eigen::VectorXd::Constant(257, sd);
  e.band_lo_hz = lo;
  e.band_hi_hz = hi;
  return e;
}

}  // namespace

TEST(FamilyModelFamily, SixExactMembersGiveTwoModesAMiddleNominalAndACoveringWeight) {
  const std::vector<sysid::FamilyMemberModel> members = family();
  const sysid::ModelFamilyResult r = sysid::analyse_model_family(members, band_5_200());
  EXPECT_EQ(r.band_lo_hz, 5.0);
  EXPECT_EQ(r.band_hi_hz, 200.0);
  EXPECT_EQ(r.band_source, "as given");

  // Both modes followed through every member, at their true frequencies.
  ASSERT_EQ(r.modes.modes.size(), 2u);
  for (std::size_t k = 0; k < kPayloads.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    EXPECT_NEAR(r.modes.modes[0].freq_hz(i), f1(kPayloads[k]), 1e-8 * f1(kPayloads[k])) << k;
    EXPECT_NEAR(r.modes.modes[1].freq_hz(i), f2(kPayloads[k]), 1e-8 * f2(kPayloads[k])) << k;
    EXPECT_NEAR(r.modes.modes[0].damping(i), 0.02, 1e-8) << k;
    EXPECT_NEAR(r.modes.modes[1].damping(i), 0.03, 1e-8) << k;
  }

  // The grid: at least 200 points over the band, increasing.
  ASSERT_GE(r.frequency_hz.size(), 200);
  EXPECT_GE(r.frequency_hz.minCoeff(), 5.0);
  EXPECT_LE(r.frequency_hz.maxCoeff(), 200.0);
  for (Eigen::Index k = 1; k < r.frequency_hz.size(); ++k) ASSERT_GT(r.frequency_hz(k), r.frequency_hz(k - 1));

  // The nominal: the member with the smallest peak, not one of the extremes.
  ASSERT_TRUE(r.bound.has_value());
  const sysid::UncertaintyBound& b = *r.bound;
  Eigen::Index best = 0;
  b.peak_by_nominal.minCoeff(&best);
  EXPECT_EQ(b.nominal_member, best);
  EXPECT_GT(b.nominal_member, 0);
  EXPECT_LT(b.nominal_member, 5);
  EXPECT_FALSE(b.with_allowance);
  EXPECT_TRUE(sysid::test::has_warning(r.warnings, "without their logs")) << "no errors given: no allowance, and said so";

  // Bound over the grid, >= the spread (equal without allowance), and it is the
  // largest deviation from the nominal, recomputed here.
  ASSERT_EQ(b.bound.size(), r.frequency_hz.size());
  const std::vector<Eigen::MatrixXcd> p0 =
      sysid::frequency_response(members[static_cast<std::size_t>(b.nominal_member)].model, r.frequency_hz);
  for (Eigen::Index k = 0; k < r.frequency_hz.size(); ++k) {
    EXPECT_GE(b.bound(k), b.spread(k)) << k;
    double deviation = 0.0;
    for (const sysid::FamilyMemberModel& m : members) {
      const Eigen::MatrixXcd p = sysid::frequency_response_at(
          m.model, std::exp(std::complex<double>(0.0, 2.0 * kPi * r.frequency_hz(k) * kTs)));
      deviation = std::max(deviation, std::abs(p(0, 0) / p0[static_cast<std::size_t>(k)](0, 0) - 1.0));
    }
    EXPECT_NEAR(b.bound(k), deviation, 1e-9 * (1.0 + deviation)) << "at " << r.frequency_hz(k) << " Hz";
  }

  // The weight: SISO at Ts, stable, minimum-phase, |W| >= bound at every grid point.
  ASSERT_TRUE(r.weight.has_value());
  const sysid::StateSpace& W = r.weight->weight;
  EXPECT_EQ(W.inputs(), 1);
  EXPECT_EQ(W.outputs(), 1);
  EXPECT_EQ(W.Ts, kTs);
  EXPECT_EQ(W.order(), 4) << "the default weight order";
  EXPECT_LT(sysid::poles(W).cwiseAbs().maxCoeff(), 1.0);
  EXPECT_LT(sysid::transmission_zeros(W).cwiseAbs().maxCoeff(), 1.0);
  const std::vector<Eigen::MatrixXcd> w = sysid::frequency_response(W, r.frequency_hz);
  for (Eigen::Index k = 0; k < r.frequency_hz.size(); ++k)
    EXPECT_GE(std::abs(w[static_cast<std::size_t>(k)](0, 0)), b.bound(k) * (1.0 - 1e-9)) << "at " << r.frequency_hz(k) << " Hz";
}

TEST(FamilyModelFamily, TheWeightOrderAndTheFormAreTheOptions) {
  sysid::ModelFamilyOptions o = band_5_200();
  o.weight_order = 2;
  o.bound.form = sysid::UncertaintyForm::additive;
  o.bound.nominal_member = 0;
  const sysid::ModelFamilyResult r = sysid::analyse_model_family(family(), o);
  ASSERT_TRUE(r.weight.has_value());
  EXPECT_EQ(r.weight->weight.order(), 2);
  ASSERT_TRUE(r.bound.has_value());
  EXPECT_EQ(r.bound->nominal_member, 0);
  // Additive: max_i |P_i - P_0| (member 0 the nominal), here at the lowest grid frequency.
  const std::vector<sysid::FamilyMemberModel> m = family();
  double deviation = 0.0;
  for (const sysid::FamilyMemberModel& member : m) {
    const Eigen::VectorXd f0 = r.frequency_hz.head(1);
    deviation = std::max(deviation, std::abs(sysid::frequency_response(member.model, f0)[0](0, 0) -
                                             sysid::frequency_response(m[0].model, f0)[0](0, 0)));
  }
  EXPECT_NEAR(r.bound->bound(0), deviation, 1e-9 * deviation);
}

TEST(FamilyModelFamily, LogsErrorsGiveTheCommonBandAndAnAllowance) {
  std::vector<sysid::FamilyMemberModel> members = family();
  const double bands[6][2] = {{2, 300}, {5, 250}, {3, 260}, {1, 240}, {4, 400}, {2, 280}};
  for (std::size_t k = 0; k < members.size(); ++k) members[k].error = flat_error(1e-3, bands[k][0], bands[k][1]);
  const sysid::ModelFamilyResult r = sysid::analyse_model_family(members);
  EXPECT_EQ(r.band_lo_hz, 5.0);
  EXPECT_EQ(r.band_hi_hz, 240.0);
  EXPECT_NE(r.band_source, "as given");
  ASSERT_TRUE(r.bound.has_value());
  EXPECT_TRUE(r.bound->with_allowance);
  EXPECT_FALSE(sysid::test::has_warning(r.warnings, "without their logs"));
  for (Eigen::Index k = 0; k < r.frequency_hz.size(); ++k) EXPECT_GT(r.bound->bound(k), r.bound->spread(k)) << k;
  ASSERT_TRUE(r.weight.has_value());
  EXPECT_GE(r.weight->min_ratio, 1.0);
}

TEST(FamilyModelFamily, OneMemberGivesModesButNoBoundAndAWarning) {
  const sysid::ModelFamilyResult r = sysid::analyse_model_family(family({1.0}), band_5_200());
  EXPECT_FALSE(r.bound.has_value());
  EXPECT_FALSE(r.weight.has_value());
  EXPECT_TRUE(sysid::test::has_warning(r.warnings, "one member")) << testing::PrintToString(r.warnings);
  ASSERT_EQ(r.modes.modes.size(), 2u);
  EXPECT_EQ(r.modes.modes[0].freq_hz.size(), 1);
  EXPECT_NEAR(r.modes.modes[0].freq_hz(0), f1(1.0), 1e-8);
  EXPECT_GE(r.frequency_hz.size(), 200);
}

TEST(FamilyModelFamily, IdenticalMembersHaveAZeroBoundAndNoWeight) {
  const sysid::ModelFamilyResult r = sysid::analyse_model_family(family({1.0, 1.0, 1.0}), band_5_200());
  ASSERT_TRUE(r.bound.has_value());
  EXPECT_EQ(r.bound->bound.maxCoeff(), 0.0);
  EXPECT_FALSE(r.weight.has_value());
  EXPECT_TRUE(sysid::test::has_warning(r.warnings, "do not differ")) << testing::PrintToString(r.warnings);
  ASSERT_EQ(r.modes.modes.size(), 2u);
  EXPECT_EQ(r.modes.modes[1].members_present(), 3);
}

TEST(FamilyModelFamily, MembersThatDoNotFitTogetherAreRefused) {
  const sysid::ModelFamilyOptions o = band_5_200();
  EXPECT_THROW(sysid::analyse_model_family({}, o), std::invalid_argument);
  // Another sample time.
  std::vector<sysid::FamilyMemberModel> m = family({0.0, 1.0});
  m.push_back({plant(2.0, 2e-3), {}});
  EXPECT_THROW(sysid::analyse_model_family(m, o), std::invalid_argument);
  // Another number of outputs.
  m = family({0.0, 1.0});
  m.push_back({plant(2.0, kTs, 2), {}});
  try {
    sysid::analyse_model_family(m, o);
    ADD_FAILURE() << "accepted members with 1 and 2 outputs";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("member 2"), std::string::npos) << e.what();
  }
  // A continuous member.
  m = family({0.0, 1.0});
  sysid::StateSpace continuous = m[1].model;
  continuous.Ts = 0.0;
  m[1].model = continuous;
  EXPECT_THROW(sysid::analyse_model_family(m, o), std::invalid_argument);
  // A band beyond Nyquist (500 Hz) or upside down.
  sysid::ModelFamilyOptions wide;
  wide.band_hz = std::make_pair(5.0, 800.0);
  EXPECT_THROW(sysid::analyse_model_family(family({0.0, 1.0}), wide), std::invalid_argument);
  sysid::ModelFamilyOptions upside_down;
  upside_down.band_hz = std::make_pair(100.0, 50.0);
  EXPECT_THROW(sysid::analyse_model_family(family({0.0, 1.0}), upside_down), std::invalid_argument);
}

}  // namespace test_unit_family_model_family
