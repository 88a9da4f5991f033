// Isolated output spikes (see include/sysid/core/isolated_spikes.hpp).
#include "sysid/core/isolated_spikes.hpp"

#include <algorithm>
#include <cmath>

#include "sysid/core/median.hpp"

namespace sysid {

namespace {

/// 1.4826 MAD of the first difference, or its RMS when the MAD is zero.
double robust_difference_scale(const Eigen::VectorXd& x) {
  const Eigen::Index n = x.size() - 1;
  std::vector<double> d(static_cast<std::size_t>(n));
  for (Eigen::Index t = 0; t < n; ++t) d[static_cast<std::size_t>(t)] = x(t + 1) - x(t);
  const double centre = median(d);
  std::vector<double> deviation(d.size());
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    deviation[i] = std::abs(d[i] - centre);
    sum_sq += d[i] * d[i];
  }
  const double mad = 1.4826 * median(std::move(deviation));
  return mad > 0.0 ? mad : std::sqrt(sum_sq / static_cast<double>(d.size()));
}

}  // namespace

std::vector<Eigen::Index> isolated_spikes(const Eigen::VectorXd& x, double threshold) {
  std::vector<Eigen::Index> spikes;
  if (x.size() < 3 || !x.allFinite()) return spikes;
  const double limit = threshold * robust_difference_scale(x);
  if (!(limit > 0.0)) return spikes;
  // Isolated also means large against the local activity: the RMS of the other
  // first differences within kLocalHalfWidth samples. A burst of ringing near the
  // Nyquist rate (a hammer tap exciting a high mode) has peaks that depart from
  // both neighbours by many global sigmas, but its neighbourhood moves as much; a
  // glitch stands out of its neighbourhood. Prefix sums make it O(N).
  constexpr Eigen::Index kLocalHalfWidth = 8;
  const Eigen::Index N = x.size();
  Eigen::VectorXd energy = Eigen::VectorXd::Zero(N);  // energy(k) = sum of d_j^2, j < k
  for (Eigen::Index k = 0; k + 1 < N; ++k) energy(k + 1) = energy(k) + (x(k + 1) - x(k)) * (x(k + 1) - x(k));
  for (Eigen::Index t = 1; t + 1 < N; ++t) {
    const double a = x(t) - x(t - 1), b = x(t) - x(t + 1);
    const double step = std::min(std::abs(a), std::abs(b));
    if (!(a * b > 0.0 && step > limit)) continue;
    const Eigen::Index lo = std::max<Eigen::Index>(0, t - 1 - kLocalHalfWidth), hi = std::min(N - 1, t + 1 + kLocalHalfWidth);
    const double others = energy(hi) - energy(lo) - a * a - b * b;  // differences lo..hi-1 but d_{t-1}, d_t
    const double count = static_cast<double>(hi - lo - 2);
    const double local = count > 0 ? std::sqrt(std::max(others, 0.0) / count) : 0.0;
    if (step > threshold * local) spikes.push_back(t);
  }
  return spikes;
}

namespace {

/// Samples near a sudden input change (a step or an impulse, by the spike
/// criterion on the input's differences, either neighbour or both), over the
/// concatenated experiments: a spike there may be the plant's answer.
std::vector<bool> input_guard(const IoData& data, const IsolatedSpikeOptions& o) {
  std::vector<bool> guarded(static_cast<std::size_t>(data.total_samples()), false);
  Eigen::Index offset = 0;
  for (const auto& e : data.experiments) {
    const Eigen::Index N = e.samples();
    for (Eigen::Index j = 0; j < e.u.cols() && N >= 3; ++j) {
      const double limit = o.threshold * robust_difference_scale(e.u.col(j));
      for (Eigen::Index t = 1; t < N; ++t)
        if (std::abs(e.u(t, j) - e.u(t - 1, j)) > limit)
          for (Eigen::Index k = std::max<Eigen::Index>(0, t - 1 - o.input_guard);
               k <= std::min<Eigen::Index>(N - 1, t + o.input_guard); ++k)
            guarded[static_cast<std::size_t>(offset + k)] = true;
    }
    offset += N;
  }
  return guarded;
}

}  // namespace

std::vector<std::string> isolated_spike_warnings(const IoData& data, const std::string& who,
                                                 const IsolatedSpikeOptions& o) {
  std::vector<std::string> out;
  // The guard depends on the inputs only: computed once for every output (its
  // robust scales are medians over the whole record).
  const std::vector<bool> guarded = input_guard(data, o);
  for (Eigen::Index i = 0; i < data.outputs(); ++i) {
    std::vector<std::string> where;
    Eigen::Index count = 0;
    Eigen::Index offset = 0;  // sample index over the concatenated experiments
    for (const auto& e : data.experiments) {
      for (Eigen::Index t : isolated_spikes(e.y.col(i), o.threshold)) {
        if (guarded[static_cast<std::size_t>(offset + t)]) continue;
        if (++count <= 5) where.push_back(std::to_string(offset + t));
      }
      offset += e.samples();
    }
    if (count == 0) continue;
    std::string list;
    for (const auto& w : where) list += (list.empty() ? "" : ", ") + w;
    out.push_back((who.empty() ? std::string() : who + ": ") + "output " + data.output_name(i) + " has " +
                  std::to_string(count) + " isolated spike" + (count > 1 ? "s" : "") + " (sample" +
                  (count > 1 ? "s " : " ") + list + (count > 5 ? ", ..." : "") + ", counted from 0) more than " +
                  std::to_string(static_cast<int>(o.threshold)) +
                  " robust standard deviations from both neighbours: sensor glitches that a least-squares fit weighs "
                  "like any other sample; remove or interpolate them before identifying");
  }
  return out;
}

}  // namespace sysid
