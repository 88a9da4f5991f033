// Tests for sysid::mode_spread and sysid::condition_text
// (include/sysid/family/mode_spread.hpp): a followed mode's range, its least-squares
// slope against each numeric condition and its mean per label, over the members
// that have it.
#include <sysid/family/mode_spread.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace test_unit_family_mode_spread {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

sysid::TrackedMode tracked(const std::vector<double>& f, const std::vector<double>& zeta) {
  sysid::TrackedMode t;
  t.freq_hz = Eigen::Map<const Eigen::VectorXd>(f.data(), static_cast<Eigen::Index>(f.size()));
  t.damping = Eigen::Map<const Eigen::VectorXd>(zeta.data(), static_cast<Eigen::Index>(zeta.size()));
  return t;
}

sysid::Condition numeric(const std::string& name, const std::vector<double>& values) {
  sysid::Condition c;
  c.name = name;
  for (double v : values) c.values.emplace_back(v);
  return c;
}

sysid::Condition labels(const std::string& name, const std::vector<std::string>& values) {
  sysid::Condition c;
  c.name = name;
  for (const std::string& v : values) c.values.emplace_back(v);
  return c;
}

}  // namespace

TEST(FamilyModeSpread, ExactLinearDataGiveTheSlopeWithZeroStandardError) {
  // f = 28.4 - 3.2 p and zeta = 0.02 + 0.004 p exactly, p in an unsorted order;
  // member 2 lacks the mode (its values must not count, whatever they are).
  const std::vector<double> p = {1.5, 0.0, 9.0, 2.5, 0.5, 2.0, 1.0};
  std::vector<double> f, z;
  for (double x : p) {
    f.push_back(28.4 - 3.2 * x);
    z.push_back(0.02 + 0.004 * x);
  }
  f[2] = kNaN;
  z[2] = kNaN;
  const sysid::ModeSpread s = sysid::mode_spread(tracked(f, z), {numeric("payload_kg", p)});
  EXPECT_EQ(s.present, 6);
  EXPECT_NEAR(s.freq_min, 28.4 - 3.2 * 2.5, 1e-12);
  EXPECT_NEAR(s.freq_max, 28.4, 1e-12);
  EXPECT_NEAR(s.freq_mean, 28.4 - 3.2 * 1.25, 1e-12);  // mean payload of the six: 7.5 / 6
  EXPECT_NEAR(s.damping_min, 0.02, 1e-15);
  EXPECT_NEAR(s.damping_max, 0.03, 1e-15);
  EXPECT_NEAR(s.damping_mean, 0.025, 1e-15);
  ASSERT_EQ(s.effects.size(), 1u);
  const sysid::ConditionEffect& e = s.effects[0];
  EXPECT_EQ(e.condition, "payload_kg");
  EXPECT_TRUE(e.numeric);
  EXPECT_NEAR(e.freq_slope, -3.2, 1e-12);
  EXPECT_NEAR(e.freq_slope_se, 0.0, 1e-12);
  EXPECT_NEAR(e.damping_slope, 0.004, 1e-15);
  EXPECT_NEAR(e.damping_slope_se, 0.0, 1e-15);
  EXPECT_TRUE(e.freq_by_label.empty());
}

TEST(FamilyModeSpread, TheStandardErrorIsTheTextbookOne) {
  // x = 0 1 2 3, f = 0 1 1 3: b = 4.5 / 5 = 0.9, residuals 0.1 0.2 -0.7 0.4,
  // s_b = sqrt(0.7 / 2 / 5) = sqrt(0.07).
  const sysid::ModeSpread s =
      sysid::mode_spread(tracked({10.0, 11.0, 11.0, 13.0}, {0.01, 0.01, 0.01, 0.01}), {numeric("x", {0, 1, 2, 3})});
  ASSERT_EQ(s.effects.size(), 1u);
  EXPECT_NEAR(s.effects[0].freq_slope, 0.9, 1e-13);
  EXPECT_NEAR(s.effects[0].freq_slope_se, std::sqrt(0.07), 1e-13);
  EXPECT_NEAR(s.effects[0].damping_slope, 0.0, 1e-15);
}

TEST(FamilyModeSpread, LabelsGiveTheMeanPerValueInManifestOrder) {
  // Labels first seen in the order right, left, center; "top" only where the mode
  // is absent -> NaN.
  const std::vector<std::string> side = {"right", "left", "right", "center", "left", "top", "left"};
  const sysid::TrackedMode t =
      tracked({30.0, 20.0, 32.0, 25.0, 22.0, kNaN, kNaN}, {0.01, 0.02, 0.03, 0.04, 0.06, kNaN, kNaN});
  const sysid::ModeSpread s = sysid::mode_spread(t, {labels("side", side), numeric("level", {1, 2, 3, 4, 5, 6, 7})});
  ASSERT_EQ(s.effects.size(), 2u);
  const sysid::ConditionEffect& e = s.effects[0];
  EXPECT_EQ(e.condition, "side");
  EXPECT_FALSE(e.numeric);
  ASSERT_EQ(e.freq_by_label.size(), 4u);
  ASSERT_EQ(e.damping_by_label.size(), 4u);
  EXPECT_EQ(e.freq_by_label[0].first, "right");
  EXPECT_EQ(e.freq_by_label[1].first, "left");
  EXPECT_EQ(e.freq_by_label[2].first, "center");
  EXPECT_EQ(e.freq_by_label[3].first, "top");
  EXPECT_DOUBLE_EQ(e.freq_by_label[0].second, 31.0);
  EXPECT_DOUBLE_EQ(e.freq_by_label[1].second, 21.0);  // member 6 (left) lacks the mode
  EXPECT_DOUBLE_EQ(e.freq_by_label[2].second, 25.0);
  EXPECT_TRUE(std::isnan(e.freq_by_label[3].second));
  EXPECT_DOUBLE_EQ(e.damping_by_label[0].second, 0.02);
  EXPECT_DOUBLE_EQ(e.damping_by_label[1].second, 0.04);
  EXPECT_EQ(e.damping_by_label[1].first, "left");
  // The second condition, in the given order, is numeric.
  EXPECT_EQ(s.effects[1].condition, "level");
  EXPECT_TRUE(s.effects[1].numeric);
  EXPECT_TRUE(s.effects[1].freq_by_label.empty());
  EXPECT_EQ(s.present, 5);
}

TEST(FamilyModeSpread, SlopesNeedThreeMembersAndAVaryingCondition) {
  // Two members present: no slope (NaN), whatever the condition.
  const sysid::ModeSpread two =
      sysid::mode_spread(tracked({10.0, kNaN, 12.0, kNaN}, {0.01, kNaN, 0.02, kNaN}), {numeric("p", {0, 1, 2, 3})});
  EXPECT_EQ(two.present, 2);
  EXPECT_TRUE(std::isnan(two.effects[0].freq_slope));
  EXPECT_TRUE(std::isnan(two.effects[0].freq_slope_se));
  EXPECT_TRUE(std::isnan(two.effects[0].damping_slope));
  // Three members present: a slope.
  const sysid::ModeSpread three =
      sysid::mode_spread(tracked({10.0, 11.0, 12.0, kNaN}, {0.01, 0.01, 0.02, kNaN}), {numeric("p", {0, 1, 2, 3})});
  EXPECT_NEAR(three.effects[0].freq_slope, 1.0, 1e-13);
  // The condition constant among the members that have the mode: NaN.
  const sysid::ModeSpread flat =
      sysid::mode_spread(tracked({10.0, 11.0, 12.0, kNaN}, {0.01, 0.01, 0.02, kNaN}), {numeric("p", {2, 2, 2, 3})});
  EXPECT_TRUE(std::isnan(flat.effects[0].freq_slope));
  // No member has the mode: NaN statistics, present 0.
  const sysid::ModeSpread none = sysid::mode_spread(tracked({kNaN, kNaN}, {kNaN, kNaN}), {numeric("p", {0, 1})});
  EXPECT_EQ(none.present, 0);
  EXPECT_TRUE(std::isnan(none.freq_mean));
  EXPECT_TRUE(std::isnan(none.freq_min));
  EXPECT_TRUE(std::isnan(none.damping_max));
}

TEST(FamilyModeSpread, ConditionsNeedOneValuePerMember) {
  EXPECT_THROW(sysid::mode_spread(tracked({10.0, 11.0, 12.0}, {0.01, 0.01, 0.01}), {numeric("p", {0, 1})}),
               std::invalid_argument);
  EXPECT_NO_THROW(sysid::mode_spread(tracked({10.0, 11.0, 12.0}, {0.01, 0.01, 0.01}), {}));
}

TEST(FamilyModeSpread, ANumericConditionIsOneWithOnlyNumbers) {
  EXPECT_TRUE(numeric("p", {0.0, 1.5}).numeric());
  sysid::Condition mixed = numeric("p", {0.0, 1.5});
  mixed.values.emplace_back(std::string("high"));
  EXPECT_FALSE(mixed.numeric());
  EXPECT_FALSE(labels("side", {"1", "2"}).numeric()) << "text that looks like a number is still a label";
}

TEST(FamilyModeSpread, ConditionTextIsShortAndReadsBack) {
  EXPECT_EQ(sysid::condition_text(0.5), "0.5");
  EXPECT_EQ(sysid::condition_text(2.0), "2");
  EXPECT_EQ(sysid::condition_text(-0.0), "0");
  EXPECT_EQ(sysid::condition_text(1e-7), "1e-07");
  EXPECT_EQ(sysid::condition_text(std::string("Pos 2, left")), "Pos 2, left");
  EXPECT_EQ(sysid::condition_text(std::string("")), "");
  // Numbers that need 16 or 17 digits still read back to the same double.
  for (double x : {0.1 + 0.2, 1.0 / 3.0, 2.0 / 3.0 * 1e10, 5e-324, 1.7976931348623157e308}) {
    const std::string text = sysid::condition_text(x);
    EXPECT_EQ(std::strtod(text.c_str(), nullptr), x) << text;
  }
  EXPECT_EQ(sysid::condition_text(0.1 + 0.2), "0.30000000000000004");
}

}  // namespace test_unit_family_mode_spread
