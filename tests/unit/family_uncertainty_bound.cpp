// Tests for include/sysid/family/uncertainty_bound.hpp: the deviation of a member
// from the nominal in the three forms, the bound over a family with and without
// the estimation allowance, the choice of the nominal, the frequency grid and the
// form's names.
#include <sysid/family/uncertainty_bound.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>
#include <vector>

namespace test_unit_family_uncertainty_bound {

namespace {

using cd = std::complex<double>;
using sysid::UncertaintyForm;
constexpr cd kJ(0.0, 1.0);

Eigen::MatrixXcd m22(cd a, cd b, cd c, cd d) {
  Eigen::MatrixXcd m(2, 2);
  m << a, b, c, d;
  return m;
}

Eigen::MatrixXcd scalar(cd x) { return Eigen::MatrixXcd::Constant(1, 1, x); }

/// First-order plant g / (1 + j f / fc) on a grid.
std::vector<Eigen::MatrixXcd> first_order(double gain, const Eigen::VectorXd& f, double fc = 10.0) {
  std::vector<Eigen::MatrixXcd> out;
  for (Eigen::Index k = 0; k < f.size(); ++k) out.push_back(scalar(gain / (1.0 + kJ * f(k) / fc)));
  return out;
}

Eigen::VectorXd grid5() {
  Eigen::VectorXd f(5);
  f << 0.1, 1.0, 10.0, 50.0, 200.0;
  return f;
}

sysid::ModeEstimate resonance(double f, double zeta) {
  sysid::ModeEstimate m;
  m.freq_hz = f;
  m.damping = zeta;
  return m;
}

}  // namespace

// ---- deviation_from_nominal ---------------------------------------------------

TEST(FamilyDeviationFromNominal, TheThreeFormsOnHandComputedMatrices) {
  // P0 = diag(4, 0.5 j), P - P0 = E = [0 2; 0 0]; P0^-1 = diag(0.25, -2 j):
  //   output E P0^-1 = [0 -4j; 0 0] -> 4; input P0^-1 E = [0 0.5; 0 0] -> 0.5;
  //   additive E -> 2.
  const Eigen::MatrixXcd P0 = m22(4.0, 0.0, 0.0, 0.5 * kJ);
  const Eigen::MatrixXcd P = P0 + m22(0.0, 2.0, 0.0, 0.0);
  EXPECT_NEAR(sysid::deviation_from_nominal(P, P0, UncertaintyForm::multiplicative_output), 4.0, 1e-12);
  EXPECT_NEAR(sysid::deviation_from_nominal(P, P0, UncertaintyForm::multiplicative_input), 0.5, 1e-12);
  EXPECT_NEAR(sysid::deviation_from_nominal(P, P0, UncertaintyForm::additive), 2.0, 1e-12);
  // A full-rank difference: E = diag(3, 4j) -> additive 4, both relative forms
  // max(3 / 4, 4 / 0.5) = 8.
  const Eigen::MatrixXcd Q = P0 + m22(3.0, 0.0, 0.0, 4.0 * kJ);
  EXPECT_NEAR(sysid::deviation_from_nominal(Q, P0, UncertaintyForm::additive), 4.0, 1e-12);
  EXPECT_NEAR(sysid::deviation_from_nominal(Q, P0, UncertaintyForm::multiplicative_output), 8.0, 1e-12);
  EXPECT_NEAR(sysid::deviation_from_nominal(Q, P0, UncertaintyForm::multiplicative_input), 8.0, 1e-12);
  // Rotating E by a unitary factor: sigma_max([1 1; -1 1] / sqrt 2 * 3) = 3.
  const Eigen::MatrixXcd R = P0 + m22(3.0, 3.0, -3.0, 3.0) / std::sqrt(2.0);
  EXPECT_NEAR(sysid::deviation_from_nominal(R, P0, UncertaintyForm::additive), 3.0, 1e-12);
  // The member itself: 0 in every form.
  for (UncertaintyForm form : {UncertaintyForm::multiplicative_output, UncertaintyForm::multiplicative_input,
                               UncertaintyForm::additive})
    EXPECT_EQ(sysid::deviation_from_nominal(P0, P0, form), 0.0);
}

TEST(FamilyDeviationFromNominal, ASingularNominalUsesThePseudoInverse) {
  // P0 = [1 1; 1 1] (rank 1, sigma 2), P = 1.5 P0: P0^+ = P0 / 4, so
  // (P - P0) P0^+ = 0.5 P0 P0 / 4 = P0 / 4 -> 0.5 (an inverse would be infinite).
  const Eigen::MatrixXcd P0 = m22(1.0, 1.0, 1.0, 1.0);
  const double out = sysid::deviation_from_nominal(1.5 * P0, P0, UncertaintyForm::multiplicative_output);
  EXPECT_NEAR(out, 0.5, 1e-12);
  EXPECT_NEAR(sysid::deviation_from_nominal(1.5 * P0, P0, UncertaintyForm::multiplicative_input), 0.5, 1e-12);
  // SISO: |(2 + j) - 2| / |2| = 0.5.
  EXPECT_NEAR(sysid::deviation_from_nominal(scalar(2.0 + kJ), scalar(2.0), UncertaintyForm::multiplicative_output), 0.5,
              1e-15);
  // Non-square (2 outputs, 1 input): P0 = [3; 4] (sigma 5), P = P0 + [0; 1]:
  // output (P - P0) P0^+ = [0; 1] [3 4] / 25 -> 5 / 25 = 0.2; input P0^+ (P - P0) = 4 / 25.
  Eigen::MatrixXcd col0(2, 1), col1(2, 1);
  col0 << 3.0, 4.0;
  col1 << 3.0, 5.0;
  EXPECT_NEAR(sysid::deviation_from_nominal(col1, col0, UncertaintyForm::multiplicative_output), 0.2, 1e-14);
  EXPECT_NEAR(sysid::deviation_from_nominal(col1, col0, UncertaintyForm::multiplicative_input), 0.16, 1e-14);
  EXPECT_THROW(sysid::deviation_from_nominal(col1, P0, UncertaintyForm::additive), std::invalid_argument);
}

// ---- uncertainty_bound ----------------------------------------------------------

TEST(FamilyUncertaintyBound, TheMemberWithTheSmallestPeakIsTheNominal) {
  // Gains 1.1, 0.8, 1.2, 1.0, 0.9 (shuffled): the relative deviation |g_i / g_0 - 1|
  // does not depend on frequency; its peak is smallest (0.2) for g_0 = 1.0, member 3.
  const Eigen::VectorXd f = grid5();
  const std::vector<double> gains = {1.1, 0.8, 1.2, 1.0, 0.9};
  std::vector<std::vector<Eigen::MatrixXcd>> frf;
  for (double g : gains) frf.push_back(first_order(g, f));
  const std::vector<Eigen::VectorXd> no_sd(gains.size());
  const sysid::UncertaintyBound b = sysid::uncertainty_bound(frf, no_sd);
  EXPECT_EQ(b.nominal_member, 3);
  EXPECT_FALSE(b.with_allowance);
  EXPECT_NE(b.criterion.find("smallest peak"), std::string::npos) << b.criterion;
  ASSERT_EQ(b.bound.size(), f.size());
  ASSERT_EQ(b.spread.size(), f.size());
  for (Eigen::Index k = 0; k < f.size(); ++k) {
    EXPECT_NEAR(b.bound(k), 0.2, 1e-12) << k;
    EXPECT_EQ(b.spread(k), b.bound(k)) << "no allowance: the bound is the spread";
  }
  // Each member's peak as the nominal: max_i |g_i / g_c - 1|.
  ASSERT_EQ(b.peak_by_nominal.size(), 5);
  for (std::size_t c = 0; c < gains.size(); ++c) {
    double peak = 0.0;
    for (double g : gains) peak = std::max(peak, std::abs(g / gains[c] - 1.0));
    EXPECT_NEAR(b.peak_by_nominal(static_cast<Eigen::Index>(c)), peak, 1e-12) << c;
  }
}

TEST(FamilyUncertaintyBound, AdditiveFormIsAbsoluteAndFollowsTheGain) {
  const Eigen::VectorXd f = grid5();
  std::vector<std::vector<Eigen::MatrixXcd>> frf;
  for (double g : {0.8, 1.0, 1.3}) frf.push_back(first_order(g, f));
  sysid::UncertaintyBoundOptions o;
  o.form = UncertaintyForm::additive;
  const sysid::UncertaintyBound b = sysid::uncertainty_bound(frf, std::vector<Eigen::VectorXd>(3), o);
  // Nominal 1.0 gives max |g - g0| = 0.3 (0.8: 0.5; 1.3: 0.5).
  EXPECT_EQ(b.nominal_member, 1);
  for (Eigen::Index k = 0; k < f.size(); ++k)
    EXPECT_NEAR(b.bound(k), 0.3 / std::abs(1.0 + kJ * f(k) / 10.0), 1e-12) << k;
  EXPECT_NE(b.criterion.find("additive"), std::string::npos) << b.criterion;
}

TEST(FamilyUncertaintyBound, TheAllowanceAddsCoverageTimesTheCombinedStandardDeviation) {
  // Fixed nominal (member 2, gain 1.0); standard deviations s_i varying over the
  // grid. Bound_k = max_i |g_i - 1| + coverage hypot(s_i(k), s_0(k)) / |P0(f_k)|.
  const Eigen::VectorXd f = grid5();
  const std::vector<double> gains = {0.9, 1.15, 1.0, 1.05};
  std::vector<std::vector<Eigen::MatrixXcd>> frf;
  std::vector<Eigen::VectorXd> sd;
  for (std::size_t i = 0; i < gains.size(); ++i) {
    frf.push_back(first_order(gains[i], f));
    Eigen::VectorXd s(f.size());
    for (Eigen::Index k = 0; k < f.size(); ++k) s(k) = 0.001 * static_cast<double>((i + 1) * (k + 1) % 7 + 1);
    sd.push_back(s);
  }
  sysid::UncertaintyBoundOptions o;
  o.nominal_member = 2;
  o.coverage = 3.0;
  const sysid::UncertaintyBound b = sysid::uncertainty_bound(frf, sd, o);
  EXPECT_TRUE(b.with_allowance);
  EXPECT_EQ(b.nominal_member, 2);
  EXPECT_NE(b.criterion.find("as asked"), std::string::npos) << b.criterion;
  for (Eigen::Index k = 0; k < f.size(); ++k) {
    const double inv_norm = std::abs(1.0 + kJ * f(k) / 10.0);  // sigma_max(P0^+) = 1 / |P0|
    double expected = 0.0, spread = 0.0;
    for (std::size_t i = 0; i < gains.size(); ++i) {
      if (i == 2) continue;
      const double d = std::abs(gains[i] - 1.0);
      spread = std::max(spread, d);
      expected = std::max(expected, d + 3.0 * std::hypot(sd[i](k), sd[2](k)) * inv_norm);
    }
    EXPECT_NEAR(b.bound(k), expected, 1e-12 * expected) << k;
    EXPECT_NEAR(b.spread(k), spread, 1e-12) << k;
    EXPECT_GT(b.bound(k), b.spread(k));
  }
  // Fixed nominal: only its own peak is known.
  EXPECT_DOUBLE_EQ(b.peak_by_nominal(2), b.bound.maxCoeff());
  EXPECT_TRUE(std::isnan(b.peak_by_nominal(0)));
  EXPECT_TRUE(std::isnan(b.peak_by_nominal(3)));

  // The nominal without a standard deviation: no allowance at all.
  std::vector<Eigen::VectorXd> partial = sd;
  partial[2].resize(0);
  const sysid::UncertaintyBound p = sysid::uncertainty_bound(frf, partial, o);
  EXPECT_FALSE(p.with_allowance);
  for (Eigen::Index k = 0; k < f.size(); ++k) EXPECT_NEAR(p.bound(k), 0.15, 1e-12);
}

TEST(FamilyUncertaintyBound, AFixedNominalIsHonouredEvenWhenItIsNotTheBest) {
  const Eigen::VectorXd f = grid5();
  std::vector<std::vector<Eigen::MatrixXcd>> frf;
  for (double g : {0.8, 0.9, 1.0, 1.1, 1.2}) frf.push_back(first_order(g, f));
  sysid::UncertaintyBoundOptions o;
  o.nominal_member = 0;
  const sysid::UncertaintyBound b = sysid::uncertainty_bound(frf, std::vector<Eigen::VectorXd>(5), o);
  EXPECT_EQ(b.nominal_member, 0);
  for (Eigen::Index k = 0; k < f.size(); ++k) EXPECT_NEAR(b.bound(k), 1.2 / 0.8 - 1.0, 1e-12);
  // The same family without a fixed nominal chooses the middle one.
  EXPECT_EQ(sysid::uncertainty_bound(frf, std::vector<Eigen::VectorXd>(5)).nominal_member, 2);
}

TEST(FamilyUncertaintyBound, OneMemberHasANullBound) {
  const Eigen::VectorXd f = grid5();
  const sysid::UncertaintyBound b = sysid::uncertainty_bound({first_order(1.0, f)}, {Eigen::VectorXd()});
  EXPECT_EQ(b.nominal_member, 0);
  EXPECT_EQ(b.bound.size(), f.size());
  EXPECT_EQ(b.bound.cwiseAbs().maxCoeff(), 0.0);
}

TEST(FamilyUncertaintyBound, BadSizesAreRefused) {
  const Eigen::VectorXd f = grid5();
  const std::vector<Eigen::MatrixXcd> a = first_order(1.0, f), b = first_order(1.1, f);
  const std::vector<Eigen::VectorXd> none2(2);
  EXPECT_THROW(sysid::uncertainty_bound({}, {}), std::invalid_argument);
  EXPECT_THROW(sysid::uncertainty_bound({a, b}, std::vector<Eigen::VectorXd>(1)), std::invalid_argument);
  // Grids of different sizes.
  std::vector<Eigen::MatrixXcd> shorter = b;
  shorter.pop_back();
  EXPECT_THROW(sysid::uncertainty_bound({a, shorter}, none2), std::invalid_argument);
  // Different channel counts.
  std::vector<Eigen::MatrixXcd> wide = b;
  for (Eigen::MatrixXcd& p : wide) p = Eigen::MatrixXcd::Ones(1, 2);
  EXPECT_THROW(sysid::uncertainty_bound({a, wide}, none2), std::invalid_argument);
  // A standard deviation off the grid.
  EXPECT_THROW(sysid::uncertainty_bound({a, b}, {Eigen::VectorXd::Ones(f.size()), Eigen::VectorXd::Ones(f.size() + 1)}),
               std::invalid_argument);
  // Nominal out of range.
  for (int bad : {-1, 2}) {
    sysid::UncertaintyBoundOptions o;
    o.nominal_member = bad;
    EXPECT_THROW(sysid::uncertainty_bound({a, b}, none2, o), std::invalid_argument) << bad;
  }
}

// ---- family_frequency_grid ----------------------------------------------------

TEST(FamilyFrequencyGrid, LogarithmicOverTheBandAndDenserAtResonances) {
  const Eigen::VectorXd plain = sysid::family_frequency_grid(1.0, 200.0, {}, 200);
  ASSERT_EQ(plain.size(), 200);
  EXPECT_DOUBLE_EQ(plain(0), 1.0);
  EXPECT_DOUBLE_EQ(plain(199), 200.0);
  const double step = std::pow(200.0, 1.0 / 199.0);  // 2.7 % per point
  for (Eigen::Index k = 1; k < plain.size(); ++k) {
    ASSERT_GT(plain(k), plain(k - 1)) << k;
    EXPECT_NEAR(plain(k) / plain(k - 1), step, 1e-9) << k;
  }
  // One resonance in the band (50 Hz, zeta 0.02), one above it (500 Hz).
  const std::vector<std::vector<sysid::ModeEstimate>> modes = {{resonance(50.0, 0.02), resonance(500.0, 0.02)}};
  const Eigen::VectorXd g = sysid::family_frequency_grid(1.0, 200.0, modes, 200);
  for (Eigen::Index k = 1; k < g.size(); ++k) ASSERT_GT(g(k), g(k - 1)) << k;
  EXPECT_DOUBLE_EQ(g(0), 1.0);
  EXPECT_DOUBLE_EQ(g(g.size() - 1), 200.0);
  // The base grid is all there; every added point is one of the 13 across the
  // in-band resonance, f (1 + k zeta / 2), k = -6..6 (47 .. 53 Hz).
  for (Eigen::Index k = 0; k < plain.size(); ++k)
    EXPECT_LT(((g.array() - plain(k)).abs()).minCoeff(), 1e-12 * plain(k)) << plain(k);
  Eigen::Index added = 0;
  for (Eigen::Index k = 0; k < g.size(); ++k) {
    if (((plain.array() - g(k)).abs()).minCoeff() <= 1e-12 * g(k)) continue;
    ++added;
    const double j = (g(k) / 50.0 - 1.0) / 0.01;
    EXPECT_NEAR(j, std::round(j), 1e-9) << g(k) << " Hz is no resonance point";
    EXPECT_LE(std::abs(j), 6.0 + 1e-9) << g(k);
  }
  EXPECT_GE(added, 8) << "at most one resonance point dropped per base point nearby (4 or 5 in 47..53 Hz)";
  EXPECT_LE(added, 13);
  EXPECT_EQ(g.size(), 200 + added);
  // Denser there: at most ~1.5 % between neighbours across 47..53 Hz, 2.7 % elsewhere.
  for (Eigen::Index k = 1; k < g.size(); ++k)
    if (g(k - 1) >= 47.0 && g(k) <= 53.0) EXPECT_LT(g(k) / g(k - 1), 1.016) << g(k - 1) << " .. " << g(k);
}

TEST(FamilyFrequencyGrid, MembersWithNearlyOneResonanceAddItOnce) {
  // 20 members with the mode within 0.4 % of 50 Hz: their resonance points fall
  // within zeta / 4 of each other, so together they add about what one adds.
  std::vector<std::vector<sysid::ModeEstimate>> one = {{resonance(50.0, 0.02)}}, many;
  for (int j = 0; j < 20; ++j) many.push_back({resonance(50.0 * (1.0 + 0.0002 * j), 0.02)});
  const Eigen::Index base = sysid::family_frequency_grid(1.0, 200.0, {}, 200).size();
  const Eigen::Index single = sysid::family_frequency_grid(1.0, 200.0, one, 200).size();
  const Eigen::Index crowd = sysid::family_frequency_grid(1.0, 200.0, many, 200).size();
  EXPECT_GT(single, base);
  EXPECT_LE(crowd, single + 13) << "20 members x 13 points would be " << base + 260;
  // Two resonances far apart each add their own points.
  const Eigen::Index two =
      sysid::family_frequency_grid(1.0, 200.0, {{resonance(50.0, 0.02)}, {resonance(120.0, 0.02)}}, 200).size();
  EXPECT_GE(two, single + 8);
}

TEST(FamilyFrequencyGrid, ABandFromZeroStartsAThousandthBelowItsTop) {
  const Eigen::VectorXd g = sysid::family_frequency_grid(0.0, 100.0, {}, 250);
  ASSERT_EQ(g.size(), 250);
  EXPECT_DOUBLE_EQ(g(0), 0.1);
  EXPECT_DOUBLE_EQ(g(249), 100.0);
  EXPECT_THROW(sysid::family_frequency_grid(10.0, 10.0, {}, 200), std::invalid_argument);
  EXPECT_THROW(sysid::family_frequency_grid(-1.0, 10.0, {}, 200), std::invalid_argument);
  EXPECT_THROW(sysid::family_frequency_grid(1.0, 10.0, {}, 1), std::invalid_argument);
}

// ---- names ----------------------------------------------------------------------

TEST(FamilyUncertaintyForm, NamesRoundTripAndOthersAreRefused) {
  for (UncertaintyForm f : {UncertaintyForm::multiplicative_output, UncertaintyForm::multiplicative_input,
                            UncertaintyForm::additive})
    EXPECT_EQ(sysid::uncertainty_form_from_name(sysid::to_string(f)), f);
  EXPECT_STREQ(sysid::to_string(UncertaintyForm::multiplicative_output), "multiplicative-output");
  EXPECT_STREQ(sysid::to_string(UncertaintyForm::multiplicative_input), "multiplicative-input");
  EXPECT_STREQ(sysid::to_string(UncertaintyForm::additive), "additive");
  for (const char* bad : {"multiplicative", "Additive", "", "multiplicative_output"}) {
    try {
      sysid::uncertainty_form_from_name(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("multiplicative-output"), std::string::npos) << what;
      EXPECT_NE(what.find("additive"), std::string::npos) << what;
    }
  }
}

}  // namespace test_unit_family_uncertainty_bound
