// Implementation of family/mode_tracking.hpp (method in the header).
#include <sysid/family/mode_tracking.hpp>
#include <sysid/core/modal_assurance_criterion.hpp>
#include <sysid/core/modal_table.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <stdexcept>
#include <utility>

namespace sysid {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// MAC, or 1 (no evidence against the pairing) when a shape is missing.
double mac(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  if (a.size() == 0 || b.size() == 0 || a.size() != b.size()) return 1.0;
  return modal_assurance_criterion(a, b);
}

/// Cost of pairing two modes, or +inf when the pair fails the gate.
double pair_cost(const ModeEstimate& a, const ModeEstimate& b, const ModeTrackingOptions& o) {
  const double df = std::abs(std::log(a.freq_hz / b.freq_hz));
  const double m = mac(a.shape, b.shape);
  if (!(df <= o.frequency_gate) || m < o.mac_gate) return std::numeric_limits<double>::infinity();
  const double dz = (a.damping - b.damping) / (o.damping_scale * 0.5 * (a.damping + b.damping) + 0.005);
  const double dm = (1.0 - m) / o.mac_scale;
  return std::pow(df / o.frequency_scale, 2) + dz * dz + dm * dm;
}

/// Greedy matching by increasing cost: pairs (index in a, index in b), each used once.
std::vector<std::pair<int, int>> match(const std::vector<ModeEstimate>& a, const std::vector<ModeEstimate>& b,
                                       const ModeTrackingOptions& o, double* total_cost = nullptr) {
  struct Candidate {
    double cost;
    int i, j;
  };
  std::vector<Candidate> candidates;
  for (int i = 0; i < static_cast<int>(a.size()); ++i)
    for (int j = 0; j < static_cast<int>(b.size()); ++j) {
      const double c = pair_cost(a[static_cast<std::size_t>(i)], b[static_cast<std::size_t>(j)], o);
      if (std::isfinite(c)) candidates.push_back({c, i, j});
    }
  std::stable_sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) { return x.cost < y.cost; });
  std::vector<bool> used_a(a.size(), false), used_b(b.size(), false);
  std::vector<std::pair<int, int>> pairs;
  double cost = 0.0;
  for (const Candidate& c : candidates) {
    if (used_a[static_cast<std::size_t>(c.i)] || used_b[static_cast<std::size_t>(c.j)]) continue;
    used_a[static_cast<std::size_t>(c.i)] = used_b[static_cast<std::size_t>(c.j)] = true;
    pairs.emplace_back(c.i, c.j);
    cost += c.cost;
  }
  if (total_cost != nullptr) {
    const double unmatched = std::pow(o.frequency_gate / o.frequency_scale, 2);
    *total_cost = cost + unmatched * static_cast<double>(a.size() + b.size() - 2 * pairs.size());
  }
  return pairs;
}

/// Prim's minimum spanning tree over the members; parent[root] = -1.
std::vector<int> spanning_tree(const Eigen::MatrixXd& distance, int root) {
  const int n = static_cast<int>(distance.rows());
  std::vector<int> parent(static_cast<std::size_t>(n), -1);
  std::vector<double> best(static_cast<std::size_t>(n), std::numeric_limits<double>::infinity());
  std::vector<bool> in_tree(static_cast<std::size_t>(n), false);
  best[static_cast<std::size_t>(root)] = 0.0;
  for (int step = 0; step < n; ++step) {
    int next = -1;
    for (int k = 0; k < n; ++k)
      if (!in_tree[static_cast<std::size_t>(k)] && (next < 0 || best[static_cast<std::size_t>(k)] < best[static_cast<std::size_t>(next)]))
        next = k;
    in_tree[static_cast<std::size_t>(next)] = true;
    for (int k = 0; k < n; ++k)
      if (!in_tree[static_cast<std::size_t>(k)] && distance(next, k) < best[static_cast<std::size_t>(k)]) {
        best[static_cast<std::size_t>(k)] = distance(next, k);
        parent[static_cast<std::size_t>(k)] = next;
      }
  }
  return parent;
}

/// One member's mode in a track: the member, the mode's index among the member's
/// trackable modes, and the mode.
struct Entry {
  int member = 0;
  int index = 0;
  ModeEstimate mode;
};

/// The mean of a track's modes (frequency geometric, damping arithmetic, shape of
/// the member nearest to the mean frequency), as a ModeEstimate for the merge pass.
ModeEstimate track_summary(const std::vector<Entry>& entries) {
  ModeEstimate s;
  double log_f = 0.0, zeta = 0.0;
  for (const Entry& e : entries) {
    log_f += std::log(e.mode.freq_hz);
    zeta += e.mode.damping;
  }
  s.freq_hz = std::exp(log_f / static_cast<double>(entries.size()));
  s.damping = zeta / static_cast<double>(entries.size());
  double nearest = std::numeric_limits<double>::infinity();
  for (const Entry& e : entries)
    if (std::abs(std::log(e.mode.freq_hz / s.freq_hz)) < nearest) {
      nearest = std::abs(std::log(e.mode.freq_hz / s.freq_hz));
      s.shape = e.mode.shape;
    }
  return s;
}

}  // namespace

std::vector<ModeEstimate> trackable_modes(const StateSpace& model, double band_lo_hz, double band_hi_hz, double max_damping) {
  std::vector<ModeEstimate> out;
  const bool shapes = model.outputs() > 1 && model.order() > 0;
  Eigen::EigenSolver<Eigen::MatrixXd> eig;
  if (shapes) eig.compute(model.A, true);
  for (const Mode& md : modal_table(model)) {
    if (!md.complex_pair || !md.stable || md.damping > max_damping || md.freq_hz < band_lo_hz || md.freq_hz > band_hi_hz)
      continue;
    ModeEstimate e;
    e.freq_hz = md.freq_hz;
    e.damping = md.damping;
    if (shapes && eig.info() == Eigen::Success) {
      Eigen::Index nearest = 0;
      (eig.eigenvalues().array() - md.pole).abs().minCoeff(&nearest);
      e.shape = model.C.cast<std::complex<double>>() * eig.eigenvectors().col(nearest);
      const double norm = e.shape.norm();
      if (norm > 0.0) e.shape /= norm;
    }
    out.push_back(std::move(e));
  }
  return out;
}

double TrackedMode::mean_freq_hz() const {
  double sum = 0.0;
  Eigen::Index count = 0;
  for (Eigen::Index k = 0; k < freq_hz.size(); ++k)
    if (!std::isnan(freq_hz(k))) {
      sum += freq_hz(k);
      ++count;
    }
  return count > 0 ? sum / static_cast<double>(count) : kNaN;
}

ModeTrackingResult track_modes(const std::vector<std::vector<ModeEstimate>>& member_modes, const ModeTrackingOptions& options) {
  const int members = static_cast<int>(member_modes.size());
  if (members < 1) throw std::invalid_argument("track_modes: need at least one member");
  // Step 3: the tree over the members, rooted at the member with the most modes.
  Eigen::MatrixXd distance = Eigen::MatrixXd::Zero(members, members);
  for (int i = 0; i < members; ++i)
    for (int j = i + 1; j < members; ++j) {
      double cost = 0.0;
      match(member_modes[static_cast<std::size_t>(i)], member_modes[static_cast<std::size_t>(j)], options, &cost);
      distance(i, j) = distance(j, i) = cost;
    }
  int root = 0;
  for (int i = 1; i < members; ++i)
    if (member_modes[static_cast<std::size_t>(i)].size() > member_modes[static_cast<std::size_t>(root)].size()) root = i;
  ModeTrackingResult result;
  result.tree_parent = spanning_tree(distance, root);

  // Breadth-first walk: each member inherits the tracks its parent knows.
  std::vector<std::vector<Entry>> tracks;
  std::vector<std::vector<std::pair<int, ModeEstimate>>> known(static_cast<std::size_t>(members));  // (track, latest mode)
  std::vector<std::vector<int>> children(static_cast<std::size_t>(members));
  for (int k = 0; k < members; ++k)
    if (result.tree_parent[static_cast<std::size_t>(k)] >= 0)
      children[static_cast<std::size_t>(result.tree_parent[static_cast<std::size_t>(k)])].push_back(k);
  std::queue<int> order;
  order.push(root);
  while (!order.empty()) {
    const int member = order.front();
    order.pop();
    const int parent = result.tree_parent[static_cast<std::size_t>(member)];
    const std::vector<ModeEstimate>& own = member_modes[static_cast<std::size_t>(member)];
    std::vector<std::pair<int, ModeEstimate>> inherited = parent >= 0 ? known[static_cast<std::size_t>(parent)]
                                                                       : std::vector<std::pair<int, ModeEstimate>>{};
    std::vector<ModeEstimate> candidates;
    for (const auto& [track, m] : inherited) candidates.push_back(m);
    std::vector<int> assigned(own.size(), -1);
    for (const auto& [i, j] : match(candidates, own, options))
      assigned[static_cast<std::size_t>(j)] = inherited[static_cast<std::size_t>(i)].first;
    for (std::size_t j = 0; j < own.size(); ++j) {
      if (assigned[j] < 0) {
        assigned[j] = static_cast<int>(tracks.size());
        tracks.emplace_back();
      }
      tracks[static_cast<std::size_t>(assigned[j])].push_back({member, static_cast<int>(j), own[j]});
      bool replaced = false;
      for (auto& [track, m] : inherited)
        if (track == assigned[j]) {
          m = own[j];
          replaced = true;
        }
      if (!replaced) inherited.emplace_back(assigned[j], own[j]);
    }
    known[static_cast<std::size_t>(member)] = std::move(inherited);
    for (int child : children[static_cast<std::size_t>(member)]) order.push(child);
  }

  // Step 4: merge tracks that are one mode seen in different branches of the
  // tree. Tracks that share no member merge when their summaries pass the gate.
  // A spurious mode next to a physical one (a noise mode of a member identified at
  // a higher order) can pull that member's neighbours into a second track that
  // shares the one member with the first: tracks sharing a few members (the
  // smaller at least 2 x shared + 1 entries) merge too, each shared member keeping
  // the mode nearer to its tree neighbours' in the merged track, the other mode
  // going to a track of its own.
  const double unmatched_cost = std::pow(options.frequency_gate / options.frequency_scale, 2);
  for (;;) {
    double best_cost = std::numeric_limits<double>::infinity();
    std::size_t best_a = 0, best_b = 0;
    for (std::size_t a = 0; a < tracks.size(); ++a)
      for (std::size_t b = a + 1; b < tracks.size(); ++b) {
        if (tracks[a].empty() || tracks[b].empty()) continue;
        std::size_t shared = 0;
        for (const Entry& ea : tracks[a])
          for (const Entry& eb : tracks[b]) shared += ea.member == eb.member ? 1 : 0;
        if (shared > 0 && std::min(tracks[a].size(), tracks[b].size()) < 2 * shared + 1) continue;
        const double c = pair_cost(track_summary(tracks[a]), track_summary(tracks[b]), options) +
                         unmatched_cost * static_cast<double>(shared);
        if (c < best_cost) {
          best_cost = c;
          best_a = a;
          best_b = b;
        }
      }
    if (!std::isfinite(best_cost)) break;
    std::vector<Entry> merged = tracks[best_a], displaced;
    for (const Entry& eb : tracks[best_b]) {
      auto clash = std::find_if(merged.begin(), merged.end(), [&](const Entry& e) { return e.member == eb.member; });
      if (clash == merged.end()) {
        merged.push_back(eb);
        continue;
      }
      // The reference: the merged track's modes of the member's tree neighbours.
      double log_sum = 0.0;
      int count = 0;
      for (const Entry& e : merged) {
        if (e.member == eb.member) continue;
        const bool neighbour = result.tree_parent[static_cast<std::size_t>(e.member)] == eb.member ||
                               result.tree_parent[static_cast<std::size_t>(eb.member)] == e.member;
        if (neighbour) {
          log_sum += std::log(e.mode.freq_hz);
          ++count;
        }
      }
      if (count == 0)
        for (const Entry& e : merged)
          if (e.member != eb.member) {
            log_sum += std::log(e.mode.freq_hz);
            ++count;
          }
      const double reference = count > 0 ? log_sum / count : std::log(clash->mode.freq_hz);
      if (std::abs(std::log(eb.mode.freq_hz) - reference) < std::abs(std::log(clash->mode.freq_hz) - reference)) {
        displaced.push_back(*clash);
        *clash = eb;
      } else {
        displaced.push_back(eb);
      }
    }
    tracks[best_a] = std::move(merged);
    tracks[best_b].clear();
    for (const Entry& e : displaced) tracks.push_back({e});
  }

  // Output sorted by mean frequency.
  std::vector<std::size_t> live;
  for (std::size_t t = 0; t < tracks.size(); ++t)
    if (!tracks[t].empty()) live.push_back(t);
  std::vector<TrackedMode> modes;
  for (std::size_t t : live) {
    TrackedMode tm;
    tm.freq_hz = Eigen::VectorXd::Constant(members, kNaN);
    tm.damping = Eigen::VectorXd::Constant(members, kNaN);
    for (const Entry& e : tracks[t]) {
      tm.freq_hz(e.member) = e.mode.freq_hz;
      tm.damping(e.member) = e.mode.damping;
    }
    modes.push_back(std::move(tm));
  }
  std::vector<std::size_t> rank(modes.size());
  std::iota(rank.begin(), rank.end(), 0);
  std::stable_sort(rank.begin(), rank.end(),
                   [&](std::size_t a, std::size_t b) { return modes[a].mean_freq_hz() < modes[b].mean_freq_hz(); });
  std::vector<int> position(tracks.size(), -1);
  for (std::size_t r = 0; r < rank.size(); ++r) {
    result.modes.push_back(modes[rank[r]]);
    position[live[rank[r]]] = static_cast<int>(r);
  }
  result.mode_track.resize(static_cast<std::size_t>(members));
  for (int k = 0; k < members; ++k)
    result.mode_track[static_cast<std::size_t>(k)].assign(member_modes[static_cast<std::size_t>(k)].size(), -1);
  for (std::size_t t : live)
    for (const Entry& e : tracks[t])
      result.mode_track[static_cast<std::size_t>(e.member)][static_cast<std::size_t>(e.index)] = position[t];
  return result;
}

}  // namespace sysid
