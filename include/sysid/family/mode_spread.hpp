#pragma once
/// @file
/// Purpose: how each followed mode moves with the operating conditions: its
/// frequency and damping over the members (mean, min, max), a least-squares line
/// against each numeric condition (payload, level ...) and the mean per value of
/// each label condition (stop position ...).
///
/// Method: only the members that have the mode take part. The slope against a
/// numeric condition c is the least-squares line f = a + b c over those members
/// (b = cov(c, f) / var(c)), with its standard error from the residuals
/// (s_b = sqrt(sum r^2 / (n - 2) / sum (c - mean c)^2)); it is left out (NaN) when
/// fewer than three members have the mode or the condition does not vary among
/// them. In a full factorial design this is the condition's main effect.
#include <sysid/family/mode_tracking.hpp>

#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace sysid {

/// One condition value of one experiment: a number (payload 0.5) or a label (Pos2).
using ConditionValue = std::variant<double, std::string>;

/// One condition column of a family's manifest.
struct Condition {
  std::string name;
  std::vector<ConditionValue> values;  ///< per member
  bool numeric() const;                ///< every value a number
};

/// A mode's dependence on one condition.
struct ConditionEffect {
  std::string condition;
  bool numeric = false;
  double freq_slope = 0.0, freq_slope_se = 0.0;        ///< Hz per unit of the condition (numeric only; NaN: not estimable)
  double damping_slope = 0.0, damping_slope_se = 0.0;  ///< damping ratio per unit (numeric only)
  std::vector<std::pair<std::string, double>> freq_by_label, damping_by_label;  ///< mean per label (label conditions only)
};

struct ModeSpread {
  int present = 0;  ///< members that have the mode
  double freq_mean = 0.0, freq_min = 0.0, freq_max = 0.0;
  double damping_mean = 0.0, damping_min = 0.0, damping_max = 0.0;
  std::vector<ConditionEffect> effects;  ///< one per condition, in the given order
};

/// Purpose: the spread of one followed mode (file comment).
/// Preconditions (std::invalid_argument): every condition has one value per member.
ModeSpread mode_spread(const TrackedMode& mode, const std::vector<Condition>& conditions);

/// The condition value as text (a number in the shortest form that reads back).
std::string condition_text(const ConditionValue& value);

}  // namespace sysid
