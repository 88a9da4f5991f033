// Implementation of family/mode_spread.hpp (method in the header).
#include <sysid/family/mode_spread.hpp>
#include <sysid/core/format_number.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <stdexcept>
#include <tuple>

namespace sysid {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Slope of the least-squares line y = a + b x and its standard error.
std::pair<double, double> line_slope(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = x.size();
  if (n < 3) return {kNaN, kNaN};
  double mx = 0.0, my = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    mx += x[k];
    my += y[k];
  }
  mx /= static_cast<double>(n);
  my /= static_cast<double>(n);
  double sxx = 0.0, sxy = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    sxx += (x[k] - mx) * (x[k] - mx);
    sxy += (x[k] - mx) * (y[k] - my);
  }
  if (!(sxx > 0.0)) return {kNaN, kNaN};
  const double b = sxy / sxx;
  double rss = 0.0;
  for (std::size_t k = 0; k < n; ++k) rss += std::pow(y[k] - my - b * (x[k] - mx), 2);
  return {b, std::sqrt(rss / static_cast<double>(n - 2) / sxx)};
}

}  // namespace

bool Condition::numeric() const {
  return std::all_of(values.begin(), values.end(), [](const ConditionValue& v) { return std::holds_alternative<double>(v); });
}

std::string condition_text(const ConditionValue& value) {
  if (const double* d = std::get_if<double>(&value)) {
    // The fewest of 15..17 significant digits that read back to the same double
    // (15 digits alone print 0.1 + 0.2 as "0.3" and DBL_MAX as a number that
    // reads back as inf).
    for (int digits = 15; digits < 17; ++digits) {
      const std::string text = format_number(*d, digits);
      if (std::strtod(text.c_str(), nullptr) == *d) return text;
    }
    return format_number(*d, 17);
  }
  return std::get<std::string>(value);
}

ModeSpread mode_spread(const TrackedMode& mode, const std::vector<Condition>& conditions) {
  const Eigen::Index members = mode.freq_hz.size();
  for (const Condition& c : conditions)
    if (static_cast<Eigen::Index>(c.values.size()) != members)
      throw std::invalid_argument("mode_spread: condition '" + c.name + "' needs one value per member");
  ModeSpread s;
  s.freq_min = s.damping_min = std::numeric_limits<double>::infinity();
  s.freq_max = s.damping_max = -std::numeric_limits<double>::infinity();
  for (Eigen::Index k = 0; k < members; ++k) {
    if (std::isnan(mode.freq_hz(k))) continue;
    ++s.present;
    s.freq_mean += mode.freq_hz(k);
    s.damping_mean += mode.damping(k);
    s.freq_min = std::min(s.freq_min, mode.freq_hz(k));
    s.freq_max = std::max(s.freq_max, mode.freq_hz(k));
    s.damping_min = std::min(s.damping_min, mode.damping(k));
    s.damping_max = std::max(s.damping_max, mode.damping(k));
  }
  if (s.present == 0) {
    s.freq_mean = s.freq_min = s.freq_max = s.damping_mean = s.damping_min = s.damping_max = kNaN;
  } else {
    s.freq_mean /= s.present;
    s.damping_mean /= s.present;
  }
  for (const Condition& c : conditions) {
    ConditionEffect e;
    e.condition = c.name;
    e.numeric = c.numeric();
    if (e.numeric) {
      std::vector<double> x, f, z;
      for (Eigen::Index k = 0; k < members; ++k)
        if (!std::isnan(mode.freq_hz(k))) {
          x.push_back(std::get<double>(c.values[static_cast<std::size_t>(k)]));
          f.push_back(mode.freq_hz(k));
          z.push_back(mode.damping(k));
        }
      std::tie(e.freq_slope, e.freq_slope_se) = line_slope(x, f);
      std::tie(e.damping_slope, e.damping_slope_se) = line_slope(x, z);
    } else {
      // Labels in the order they first appear in the manifest.
      std::vector<std::string> labels;
      std::map<std::string, std::pair<double, double>> sum;
      std::map<std::string, int> count;
      for (Eigen::Index k = 0; k < members; ++k) {
        const std::string label = condition_text(c.values[static_cast<std::size_t>(k)]);
        if (std::find(labels.begin(), labels.end(), label) == labels.end()) labels.push_back(label);
        if (std::isnan(mode.freq_hz(k))) continue;
        sum[label].first += mode.freq_hz(k);
        sum[label].second += mode.damping(k);
        ++count[label];
      }
      for (const std::string& label : labels) {
        const int n = count[label];
        e.freq_by_label.emplace_back(label, n > 0 ? sum[label].first / n : kNaN);
        e.damping_by_label.emplace_back(label, n > 0 ? sum[label].second / n : kNaN);
      }
    }
    s.effects.push_back(std::move(e));
  }
  return s;
}

}  // namespace sysid
