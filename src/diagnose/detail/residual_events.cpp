// Where a residual lives in time; see residual_events.hpp.
#include "diagnose/detail/residual_events.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"

namespace sysid {

namespace {

/// Indices where x changes sign, ignoring excursions inside +-band (hysteresis:
/// a sign is kept until x leaves the band on the other side).
std::vector<Eigen::Index> sign_changes(const Eigen::VectorXd& x, double band) {
  std::vector<Eigen::Index> out;
  int sign = 0;
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    const int s = x[k] > band ? 1 : (x[k] < -band ? -1 : 0);
    if (s == 0) continue;
    if (sign != 0 && s != sign) out.push_back(k);
    sign = s;
  }
  return out;
}

/// Mean square of r within +-k of the events, over its overall mean square; the
/// number of samples near them goes to `near`.
double near_ratio(const Eigen::VectorXd& r, const std::vector<Eigen::Index>& events, Eigen::Index k, Eigen::Index& near) {
  std::vector<char> mark(static_cast<std::size_t>(r.size()), 0);
  for (Eigen::Index e : events)
    for (Eigen::Index t = std::max<Eigen::Index>(0, e - k); t <= std::min<Eigen::Index>(r.size() - 1, e + k); ++t)
      mark[static_cast<std::size_t>(t)] = 1;
  double sum = 0.0;
  near = 0;
  for (Eigen::Index t = 0; t < r.size(); ++t)
    if (mark[static_cast<std::size_t>(t)]) sum += r[t] * r[t], ++near;
  const double overall = r.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, r.size()));
  return near > 0 && overall > 0.0 ? sum / static_cast<double>(near) / overall : 0.0;
}

}  // namespace

ResidualEvents residual_events(const Eigen::VectorXd& residual, const Eigen::VectorXd& velocity, const Eigen::VectorXd& command,
                               Eigen::Index halfwidth) {
  ResidualEvents e;
  const Eigen::Index n = std::min({residual.size(), velocity.size(), command.size()});
  if (n < 4) return e;
  const Eigen::VectorXd r = residual.head(n).array() - residual.head(n).mean();
  const auto reversals = sign_changes(velocity.head(n), 0.01 * rms(velocity.head(n)));
  const auto crossings = sign_changes(command.head(n), 0.01 * rms(command.head(n)));
  e.reversals = static_cast<Eigen::Index>(reversals.size());
  e.crossings = static_cast<Eigen::Index>(crossings.size());
  if (reversals.size() < 2 || crossings.empty()) return e;
  if (halfwidth <= 0) {
    std::vector<Eigen::Index> gaps;
    for (std::size_t k = 1; k < reversals.size(); ++k) gaps.push_back(reversals[k] - reversals[k - 1]);
    std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2), gaps.end());
    halfwidth = std::max<Eigen::Index>(1, gaps[gaps.size() / 2] / 10);
  }
  e.halfwidth = halfwidth;
  Eigen::Index near_r = 0, near_c = 0;
  e.near_reversals = near_ratio(r, reversals, halfwidth, near_r);
  e.near_crossings = near_ratio(r, crossings, halfwidth, near_c);
  e.tested = near_r > 0 && near_c > 0 && near_r < n && near_c < n;
  return e;
}

std::string describe(const ResidualEvents& e, double Ts) {
  if (!e.tested)
    return "where the residual lives was not measured (" + std::to_string(e.reversals) + " velocity reversals, " +
           std::to_string(e.crossings) + " zero crossings of the command)";
  return "the residual before it is " + format_number(e.near_reversals, 3) + " times its mean square within " +
         format_number(1e3 * static_cast<double>(e.halfwidth) * Ts, 3) + " ms of the " + std::to_string(e.reversals) +
         " velocity reversals and " + format_number(e.near_crossings, 3) + " times near the " + std::to_string(e.crossings) +
         " zero crossings of the command";
}

std::string where_it_lives(const Eigen::VectorXd& residual, const Eigen::VectorXd& velocity, const Eigen::VectorXd& command,
                           double Ts, bool at_reversals) {
  const ResidualEvents e = residual_events(residual, velocity, command);
  if (!e.tested) return describe(e, Ts);
  const char* reversals = "the velocity reversals, where friction";
  const char* crossings = "the zero crossings of the command, where a dead zone";
  const bool own = at_reversals ? e.near_reversals >= e.near_crossings : e.near_crossings >= e.near_reversals;
  return describe(e, Ts) + (own ? ": it lives at " + std::string(at_reversals ? reversals : crossings) + " acts"
                                : ": it lives nearer " + std::string(at_reversals ? crossings : reversals) +
                                      " would act, yet this kind fitted better");
}

}  // namespace sysid
