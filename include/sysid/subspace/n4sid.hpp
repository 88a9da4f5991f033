#pragma once
/// @file
/// Purpose: combined deterministic-stochastic subspace identification of a
/// discrete-time innovation-form state-space model
///
///   x[k+1] = A x[k] + B u[k] + K e[k],   y[k] = C x[k] + D u[k] + e[k],
///
/// from input/output data, MIMO, one or several experiments, with the N4SID,
/// MOESP or CVA weighting behind one option.
///
/// Method (P. Van Overschee & B. De Moor, "Subspace Identification for Linear
/// Systems", Kluwer 1996, referred to as VODM):
///  1. The block-Hankel matrix [U_{0|2i-1}; Y_{0|2i-1}] is compressed to its
///     R factor (hankel/block_hankel.hpp); every projection below is computed on
///     coefficient rows of L = R^T, never on the data.
///  2. Oblique projection O_i = Y_f /_{U_f} W_p (VODM eq. 1.7/Theorem 12):
///     with M = W_p Pi_{U_f}^perp, O_i = Y_f M^+ W_p.
///  3. Weighted SVD W1 O_i W2 = U S V^T (VODM Theorem 13 and table 4.1):
///     N4SID W1 = I, W2 = I; MOESP W1 = I, W2 = Pi_{U_f}^perp;
///     CVA W1 = (Y_f Pi_{U_f}^perp Y_f^T)^{-1/2}, W2 = Pi_{U_f}^perp.
///     The singular values choose the order (subspace/order_selection.hpp).
///  4. Extended observability Gamma_i = W1^{-1} U_1 S_1^{1/2}; C is its first
///     block row, A solves the shift equation Gamma_i(0:i-2) A = Gamma_i(1:i-1)
///     in least squares (VODM sec. 4.3.1), or, with enforce_stability, the
///     zero-padded shift of Chui & Maciejowski ("Realization of stable models
///     with subspace methods", Automatica 32 (1996) 1587-1595), which yields a
///     stable A.
///  5. State sequences X_i = Gamma_i^+ O_i and X_{i+1} = Gamma_{i-1}^+ O_{i-1};
///     B, D by least squares in [X_{i+1} - A X_i; Y_{i|i} - C X_i] = [B; D] U_{i|i} + rho;
///     the residual covariance rho rho^T / j gives Q, S, R, and the steady-state
///     Kalman filter gives K and the innovation covariance (VODM sec. 4.3.3).
///  6. B, D and x0 are re-estimated by linear least squares on the simulation
///     error over the data (A and C fixed), which is what the simulation fit
///     measures (the approach of SLICOT IB01CD / MATLAB's n4sid 'Focus simulation';
///     subspace/bdx_least_squares.hpp).
///
/// Data are mean-removed (offsets returned) and every channel is scaled to unit
/// RMS before identification; the model is returned in the original units.
///
/// Preconditions: horizon * outputs > order; order >= 1; every input excited
/// (non-constant); enough samples for the horizon (see block_hankel.hpp).
/// Violations throw std::invalid_argument naming the inequality.
///
/// Numerical aspects: cost O(N i (m+l)^2) on the cholesky route (O(N k^2) on
/// the qr route) plus O(k^3) for the projections, k = 2 i (m+l); memory O(k^2)
/// besides the data. The B/D/x0 regression costs O(N l p^2) with
/// p = n m + l m + n; it uses at most `bdx_max_samples` samples per experiment.
///
/// Cores (core/parallel_for.hpp): the excited-band estimate and decimation run
/// beside the model-free data checks, the three lagged-sum products of the
/// Gram matrix beside each other, O_i beside O_{i-1}, and the B/D/x0 regression
/// in two pieces. Each piece's arithmetic is fixed, so the model is the same
/// on any number of cores.
#include <sysid/core/io_data.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/hankel/block_hankel.hpp>
#include <sysid/subspace/order_selection.hpp>
#include <sysid/subspace/stabilization_diagram.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace sysid {

enum class SubspaceWeighting { n4sid, moesp, cva };

inline const char* to_string(SubspaceWeighting w) {
  switch (w) {
    case SubspaceWeighting::n4sid: return "n4sid";
    case SubspaceWeighting::moesp: return "moesp";
    case SubspaceWeighting::cva: return "cva";
  }
  return "?";
}

/// The weighting named `name` (to_string's names: the command line's --method and
/// Python's method=); std::invalid_argument otherwise.
inline SubspaceWeighting subspace_weighting_from_name(const std::string& name) {
  for (const SubspaceWeighting w : {SubspaceWeighting::n4sid, SubspaceWeighting::moesp, SubspaceWeighting::cva})
    if (name == to_string(w)) return w;
  throw std::invalid_argument("method: expected 'n4sid', 'moesp' or 'cva', found '" + name + "'");
}

/// When n4sid re-estimates the poles on the simulation error (N4sidOptions::refine_poles).
enum class PoleRefinementMode { automatic, always, never };

/// "auto", "always", "never" (the command line's --refine, Python's refine=); std::invalid_argument otherwise.
inline PoleRefinementMode pole_refinement_mode_from_name(const std::string& name) {
  if (name == "auto") return PoleRefinementMode::automatic;
  if (name == "always") return PoleRefinementMode::always;
  if (name == "never") return PoleRefinementMode::never;
  throw std::invalid_argument("refine: expected 'auto', 'always' or 'never', found '" + name + "'");
}

/// One Jacobian of the automatic pole refinement at most (refinement_cost): 5e8
/// floating-point operations by that count. The Par2 log at order 10 (1.8e8)
/// takes 0.12 s a Jacobian and 1.9 s in all from horizon 60 (two raced starts,
/// clang -O2, one 2-core VM); an F-16 family member (3 outputs, order 30, 50 000 samples: 1.8e10)
/// ran for minutes, and 28 outputs at order 30 on 8 500 samples (1.5e11) would
/// take longer: those are left to refine_poles = always.
inline constexpr double kPoleRefinementBudget = 5e8;

struct N4sidOptions {
  SubspaceWeighting weighting = SubspaceWeighting::n4sid;
  /// Model order; 0 = choose automatically from the singular values (see order_rule).
  int order = 0;
  /// Largest order considered by the automatic choice; 0 = no cap: every order
  /// the horizon allows (horizon x outputs - 1; the gap rule stops where the
  /// singular values reach rank_tolerance).
  int max_order = 0;
  OrderRule order_rule = OrderRule::automatic;  ///< see subspace/order_selection.hpp
  /// Block rows i of the past (and of the future); 0 = automatic: for a given
  /// order n, i = max(10, 2 ceil(n / l)); for the automatic order choice
  /// i = max(10, ceil(1.5 M / l)) with M = max_order, or 20 when max_order is 0,
  /// to choose the order, then the model of the chosen order is identified again
  /// with the horizon for that order. Then the slowest-mode rule: the past and
  /// future windows (2 i samples of the grid identified on) must span one period
  /// of the slowest oscillatory mode of that model (damping <= 0.3); when they do
  /// not, the model is identified once more at i = ceil(period / 2), up to
  /// kSlowestModeMaxHankelRows Hankel rows (a 23 Hz mode at 2 kHz: i = 44, where
  /// 2 ceil(8 / 1) = 16 missed it). Reduced if the data are short. The result's
  /// horizon_rule says which rule set it.
  int horizon = 0;
  HankelRoute route = HankelRoute::automatic;
  bool remove_means = true;        ///< subtract channel means first (offsets returned in the result)
  bool enforce_stability = false;  ///< A from the zero-padded shift (Chui & Maciejowski 1996): always stable
  /// Keep an unstable least-squares A. By default (false) an A with a pole on or
  /// outside the unit circle has those poles reflected to 1/conj(z) (the same
  /// frequency, the mirrored damping; B, D, x0 then fitted to it) and a warning
  /// says so: from a stable plant's data an unstable estimate is an artefact of the
  /// horizon or the order, and its simulation diverges. The unstable estimate is
  /// kept, with a warning, when it fits the estimation data by more than 5 points
  /// better than the reflected one (a growing record: a plant that is itself
  /// unstable). Set it to keep the unstable estimate in any case.
  bool allow_unstable = false;
  /// Poles re-estimated on the simulation error after the subspace step
  /// (subspace/pole_refinement.hpp: A's eigenvalues by Levenberg-Marquardt, B, D,
  /// x0 by least squares, C held). automatic: when the horizon was given (a
  /// user's guess: the subspace poles of the directions the projection leaves
  /// near its noise floor move with it, the refined ones do not; the automatic
  /// horizon is sized to the order and the slowest mode) and one Jacobian costs
  /// at most kPoleRefinementBudget floating-point operations; always; never.
  PoleRefinementMode refine_poles = PoleRefinementMode::automatic;
  bool estimate_kalman_gain = true;
  bool refine_bdx = true;               ///< B, D, x0 by least squares on the simulation error (step 6)
  /// Per experiment, bounds the cost of step 6 (O(N l p^2)); 50 000 samples
  /// determine B, D and x0 far beyond the noise level for the orders used here.
  Eigen::Index bdx_max_samples = 50000;
  /// Identification on a decimated grid for oversampled data: 0 = automatic (when
  /// the inputs excite only the lowest quarter of the Nyquist band, the data are
  /// low-pass filtered and decimated by the largest odd factor r <= fs / (4 f_high),
  /// the subspace step runs there, A is mapped back by its principal r-th root
  /// and B, D, x0 are fitted at the original rate); 1 = never; an odd r > 1 = force r.
  int decimation = 0;
  /// The Par2 paper's remedy for a band-limited excitation: when > 0, inputs
  /// and outputs are pre-filtered by the same causal Butterworth low-pass at
  /// this frequency (which leaves their relation unchanged but takes the
  /// undetermined band out of the fit), and the returned model is the
  /// identified one in series with that filter at its inputs, so its gain above
  /// the band follows the filter instead of being arbitrary.
  double band_limit_hz = 0.0;
  int band_limit_order = 5;  ///< order of that Butterworth filter (the Par2 paper: 5th order at 100 Hz, fs = 2 kHz)
  /// Relative threshold (to the largest singular value) below which directions
  /// are treated as null in the pseudo-inverses of the projections.
  double rank_tolerance = 1e-10;
  /// Past directions whose principal angle to the future inputs has a sine at or
  /// below this are left out of the oblique projection O_i (see
  /// detail::oblique_projection): it bounds the noise amplification in O_i by
  /// 1 / oblique_min_sine. Matters for band-limited inputs and the N4SID
  /// weighting (which uses O_i itself); 0 = keep every direction.
  double oblique_min_sine = 0.1;
  /// Stabilisation diagram (subspace/stabilization_diagram.hpp): the poles of every
  /// order stabilization_order_lo..stabilization_order_hi, from this run's SVD (no
  /// further compression), in N4sidResult::stabilization; hi = 0: none, unless
  /// order_rule is stabilization, which uses orders max(lo, 1)..the largest
  /// searched. hi must fit under the horizon (horizon x outputs > hi): with
  /// horizon 0 the automatic horizon is sized for max(max_order, hi) and is at
  /// least detail::kStabilizationMinHorizon.
  int stabilization_order_lo = 0, stabilization_order_hi = 0;
  StabilizationOptions stabilization;
  /// An input is "not excited" when its standard deviation is below this
  /// fraction of its mean magnitude (or exactly zero).
  double constant_input_tolerance = 1e-12;
};

struct N4sidResult {
  StateSpace model;                 ///< A, B, C, D in original units (deviations from the offsets)
  Eigen::MatrixXd K;                ///< Kalman gain (n x l); empty if not estimated
  Eigen::MatrixXd noise_covariance;  ///< innovation covariance (l x l)
  Eigen::VectorXd x0;               ///< initial state of the first experiment
  Eigen::VectorXd input_offset, output_offset;
  Eigen::VectorXd singular_values;  ///< of the weighted projection, descending
  /// Canonical correlations between future outputs (future inputs projected
  /// out) and past data (the CVA singular values), used by the SVC order rule.
  Eigen::VectorXd canonical_correlations;
  int order = 0;
  int horizon = 0;
  std::string horizon_rule;  ///< which rule set the horizon (or "given by the user")
  std::string order_rule;  ///< which rule chose the order (or "given by the user")
  SubspaceWeighting weighting = SubspaceWeighting::n4sid;
  HankelRoute route_used = HankelRoute::qr;
  double gram_condition_estimate = 0;
  double observability_condition = 0;  ///< cond(Gamma_i), large means a poorly determined A
  /// Smallest sine of the principal angles between past data and future inputs
  /// (near 0: the input is band-limited or too smooth to separate them).
  double past_future_min_sine = 1;
  int oblique_dropped_directions = 0;  ///< past directions left out of O_i (N4sidOptions::oblique_min_sine)
  /// Spectral radius of the least-squares A when it was unstable and its poles
  /// were reflected (N4sidOptions::allow_unstable); 0 when not needed.
  double reflected_spectral_radius = 0;
  Eigen::VectorXd fit_percent;         ///< simulation fit on the estimation data, per output
  double excited_band_low_hz = 0, excited_band_high_hz = 0;  ///< where the inputs carry power
  double out_of_band_gain_ratio = 0;  ///< max gain above the excited band / max gain inside it
  Eigen::Index bdx_samples_used = 0;
  /// Of those, the samples where C A^t had decayed below 1e-17 of its peak: their
  /// x0 regressors were taken as zero and a narrower QR took them (cheaper; same R).
  Eigen::Index bdx_samples_without_initial_response = 0;
  int decimation = 1;  ///< factor of the grid the subspace step ran on (1 = original rate)
  bool band_limited = false;  ///< model includes the band-limiting Butterworth filter at its inputs (order + m * filter order)
  std::vector<std::string> warnings;
  /// The pole refinement (N4sidOptions::refine_poles): whether it ran and changed
  /// A, the estimation fits before and after, and in words what happened
  /// ("" when it did not run).
  bool poles_refined = false;
  double refinement_fit_before = 0, refinement_fit_after = 0;
  std::string refinement;
  int kalman_iterations = 0;
  /// The stabilisation diagram when asked for (N4sidOptions::stabilization_order_hi
  /// or the stabilization order rule); order_hi = 0 otherwise.
  StabilizationDiagram stabilization;

  std::string brief_report() const {
    std::ostringstream s;
    s << to_string(weighting) << ": order " << order << " (" << order_rule << "), horizon " << horizon
      << (horizon_rule.empty() ? std::string() : " (" + horizon_rule + ")") << ", "
      << model.inputs() << " input(s), " << model.outputs() << " output(s), Hankel route " << to_string(route_used);
    return s.str();
  }
};

namespace detail {

/// The order the automatic horizon is sized for when max_order is 0 (no cap).
inline constexpr int kHorizonNominalMaxOrder = 20;

/// The automatic horizon of N4sidOptions::horizon (before the slowest-mode rule).
inline int automatic_horizon(int order, int max_order, Eigen::Index outputs) {
  const auto l = static_cast<double>(outputs);
  if (order > 0) return std::max(10, 2 * static_cast<int>(std::ceil(order / l)));
  const int sized_for = max_order > 0 ? max_order : kHorizonNominalMaxOrder;
  return std::max(10, static_cast<int>(std::ceil(1.5 * sized_for / l)));
}

/// `horizon` shortened until the data hold it: 2 i samples in the shortest
/// experiment and at least ~4 Hankel columns per row (8 i (m + l) <= samples).
inline int record_limited_horizon(int horizon, const IoData& data) {
  const Eigen::Index m = data.inputs(), l = data.outputs();
  Eigen::Index shortest = data.experiments.front().samples();
  for (const auto& e : data.experiments) shortest = std::min(shortest, e.samples());
  while (horizon > 2 && (2 * horizon > shortest || 4 * 2 * horizon * (m + l) > data.total_samples())) --horizon;
  return horizon;
}

/// The smallest automatic horizon of a stabilisation diagram: twice the
/// identification default, because a diagram needs the low modes' damping to
/// settle from order to order (the 28-sensor beam of the acceptance tests: at
/// horizon 10 the 14.6 and 38.8 Hz modes never stabilise within 5 % in damping
/// over orders 2..60, at 20 all twelve modes do).
inline constexpr int kStabilizationMinHorizon = 20;

/// Hankel rows 2 i (m + l) up to which the slowest-mode rule may lengthen the
/// automatic horizon (the compression costs O(N rows^2)): 400, i = 100 for one
/// input and one output; with many channels the rule does not lengthen past the
/// automatic horizon.
inline constexpr int kSlowestModeMaxHankelRows = 400;

}  // namespace detail

/// Identifies an innovation-form model from `data` (taken by value: it is
/// mean-removed and scaled in place; pass std::move(data) to avoid a copy).
N4sidResult n4sid(IoData data, const N4sidOptions& options = {});

}  // namespace sysid
