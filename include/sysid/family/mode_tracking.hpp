#pragma once
/// @file
/// Purpose: follow each physical mode across the members of a model family (one
/// model per operating condition: payload, stop position, excitation level ...),
/// so that "the 28 Hz mode" is one entry whose frequency and damping are known per
/// member, and a mode that a member does not show is marked absent in that member
/// instead of being paired with a neighbouring mode.
///
/// Method:
///  1. Each member's trackable modes (trackable_modes): its complex pole pairs that
///     are stable, lightly damped (damping <= max_damping) and inside the band, with
///     the mode shape C v of the eigenvector v when the model has several outputs.
///  2. Two modes may pair when their frequencies differ by at most frequency_gate
///     (relative, |ln(f_a / f_b)|) and, with shapes, their modal assurance criterion
///     MAC = |phi_a^H phi_b|^2 / (|phi_a|^2 |phi_b|^2) is at least mac_gate
///     (Allemang 2003, "The modal assurance criterion - twenty years of use and
///     abuse"). The cost of a pair is (ln(f_a/f_b)/frequency_scale)^2 +
///     ((zeta_a - zeta_b)/(damping_scale (zeta_a + zeta_b)/2 + 0.005))^2 +
///     ((1 - MAC)/mac_scale)^2. Sets of modes are matched greedily by increasing
///     cost, each mode used once (modes of one member are far apart compared with
///     the gate, where greedy and optimal assignment agree).
///  3. Members are linked by a minimum spanning tree (Prim) over the cost of
///     matching their whole mode sets (each unmatched mode costs the gate): modes
///     move little between neighbouring conditions, so pairing along the tree's
///     edges never needs a large jump even when the family's extremes differ a lot.
///     Walking the tree from the member with the most modes, each member's modes are
///     paired with the modes its parent knows — the parent's own, or, for a mode the
///     parent lacks, the latest ancestor's — and an unpaired mode starts a new track.
///  4. Tracks whose mean frequencies, dampings and shapes pass the gate are one
///     mode seen in different branches of the tree: they are merged, closest pair
///     first. Tracks that share a few members merge too (the smaller track at
///     least 2 x shared + 1 entries, a gate-sized cost per shared member): a
///     member identified at a higher order can carry a noise mode beside a
///     physical one and pull its neighbours into a second track; each shared
///     member keeps the mode nearer to its tree neighbours' and the other becomes
///     a track of its own (a mode "in 1 of N members").
///
/// Output: tracks sorted by mean frequency; NaN where a member does not have the mode.
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <vector>

namespace sysid {

/// One mode of one member.
struct ModeEstimate {
  double freq_hz = 0.0;
  double damping = 0.0;
  Eigen::VectorXcd shape;  ///< C v, unit norm; empty for a single-output model
};

/// Purpose: the modes of `model` a family follows: stable complex pairs with
/// damping <= max_damping and band_lo_hz <= f <= band_hi_hz, sorted by frequency.
/// Preconditions: a valid discrete or continuous StateSpace.
std::vector<ModeEstimate> trackable_modes(const StateSpace& model, double band_lo_hz, double band_hi_hz,
                                          double max_damping = 0.3);

struct ModeTrackingOptions {
  double frequency_gate = 0.12;   ///< largest |ln(f_a / f_b)| of a pair (12 %)
  double mac_gate = 0.6;          ///< smallest MAC of a pair (several outputs only)
  double frequency_scale = 0.02;  ///< cost unit of |ln(f_a / f_b)|
  double damping_scale = 0.5;     ///< cost unit of |zeta_a - zeta_b|, relative to their mean
  double mac_scale = 0.1;         ///< cost unit of 1 - MAC
};

/// One physical mode across the members.
struct TrackedMode {
  Eigen::VectorXd freq_hz;  ///< per member; NaN where absent
  Eigen::VectorXd damping;  ///< per member; NaN where absent
  Eigen::Index members_present() const { return (freq_hz.array() == freq_hz.array()).count(); }
  double mean_freq_hz() const;
};

struct ModeTrackingResult {
  std::vector<TrackedMode> modes;           ///< sorted by mean frequency
  std::vector<int> tree_parent;             ///< per member: the member it was paired with (-1: the root)
  std::vector<std::vector<int>> mode_track;  ///< per member, per trackable mode: its index in `modes`
};

/// Purpose: follow the modes of every member across the family (file comment).
/// Preconditions: at least one member.
ModeTrackingResult track_modes(const std::vector<std::vector<ModeEstimate>>& member_modes,
                               const ModeTrackingOptions& options = {});

}  // namespace sysid
