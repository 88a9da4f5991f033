#pragma once
/// @file
/// Purpose: tell `sysid diagnose` when a record looks closed-loop (issue 33, item
/// 5). On a drive under position control the logged input u is the controller's
/// output, computed from the measured output y: the open-loop simulation of the
/// nominal from the logged u stays valid, but the report must say so, because the
/// residual's noise then feeds back into the input (and a refit of the nominal's
/// linear dynamics from such data is biased).
///
/// Method: a Sims test on the simulation residual v = y - y_simulated (C. A. Sims,
/// "Money, income, and causality", Amer. Econ. Rev. 62 (1972) 540-552, theorem 2:
/// u is exogenous to v — no feedback from v into u — iff, in the regression of v on
/// u, the coefficients of future u are zero), made a chi-square test of
/// residual-input independence at negative lags as in Ljung, "System
/// Identification", 2nd ed. (1999), sec. 16.6 (the x^2 test (16.62) with the input's
/// covariance matrix) and Söderström & Stoica (1989) sec. 12.5. Per output i, the
/// least-squares (column-pivoting QR) regression
///   v_i(t) = c + sum_{k=1..output_lags} a_k' v(t - k)                  (all outputs)
///              + sum_{k=0..output_lags} s_k' y_simulated(t - k)           (all outputs)
///              + sum_{k=input_delay..input_lags} b_k' u(t - k)           (all inputs)
///              + sum_{k=1..lags} f_k u_j(t + k)  + eps(t)                (input j's future)
/// and the test of f = 0 (the future block, after the past block is projected out),
/// statistic chi2 = (n - p) (SSR_without - SSR_with) / SSR_with with `dof` = rank of
/// the future block, against chi2_{1 - significance / pairs}(dof), Bonferroni over
/// the tested input-output pairs. Why this form, against the pitfalls:
/// - Open loop, u is independent of the noise: conditioned on the whole input
///   sequence, eps is the noise's innovation and the future inputs are fixed
///   regressors, so the test holds its level for any input — white, coloured,
///   band-limited or a multisine — with no prewhitening filter of u (which cannot
///   whiten a multisine: data_check.hpp). Its innovations are never formed.
/// - A periodic input whose future is a linear function of its own past (period
///   shorter than input_lags + lags) leaves nothing of the future block once the
///   past is projected out: columns below `predictable_tolerance` of their RMS do
///   not count, and with none left the pair is not tested (feedback from the noise
///   would have made the input unpredictable). A band-limited input is nearly so:
///   a multisine up to 2/5 of Nyquist keeps 4 of 10 future columns (dof = 4).
/// - Model mismatch (a missing mode, a wrong gain, friction) makes v depend on past
///   u. The input lags absorb it as a response of input_lags samples; the
///   simulation's lags absorb the part with the nominal's poles (a wrong gain or
///   frequency), the residual's lags the part with the missing poles (an ARX form),
///   and they whiten coloured noise. What none absorbs is a function of u's far
///   past, which correlates with u's future only through what u's near past does
///   not already explain: nothing for white or autoregressive inputs; for a
///   multisine (deterministic) a leak in proportion to (its variance / the
///   noise's) x N / (excited lines). Measured with the defaults on a 20 Hz drive
///   plus a 120 Hz mode, nominal missing the mode with its own mode 10 % low and
///   gain 20 % low (mismatch twice the noise's RMS), N = 4000, 100 records each:
///   1 alarm at 1 % with a multisine over the record, 0 with 8 periods, 0 with
///   low-pass or white noise inputs. The past block is never rank-truncated: a
///   column-pivoting QR that dropped columns below 1e-10 of the largest pivot
///   (nearly collinear lags of a smooth residual) left part of the mismatch in
///   place: in a draft without the simulation's lags, 13 and 16 of those 100
///   multisine records raised an alarm (1 and 0 with the plain QR).
/// - Under feedback, u(t + k) depends on the noise at t (through the controller, the
///   encoder's quantisation included), which no past regressor holds: f != 0.
/// Not detected: a controller acting within the sample (u(t) from y(t)) whose later
/// samples do not react to y(t); nor a loop without noise (nothing in y then differs
/// from its simulation: such a loop does not bias the open-loop simulation either).
/// The strongest lag is the k whose column, alone, explains most of eps.
///
/// Preconditions (std::invalid_argument): u N x m, y and y_simulated N x l, m, l >= 1,
/// finite values; 0 < Ts < inf; lags >= 1, output_lags >= 0,
/// 0 <= input_delay <= input_lags, 0 < significance < 1, predictable_tolerance in
/// (0, 1); N >= max(output_lags, input_lags) + lags + 4 p, p = 1 + l (2 output_lags
/// + 1) + m (input_lags - input_delay + 1) + lags (four samples per parameter).
/// Numerical aspects: one Householder QR of the N x p past block (backward stable
/// also when it is rank-deficient, as for a periodic input: the projection then
/// removes a few more directions, all functions of the inputs), one
/// column-pivoting QR of each input's N x lags future block; O(N p^2), p = 72 for
/// one input and one output with the defaults. Columns are scaled to unit RMS about
/// their mean; constant channels are left out.
#include <Eigen/Dense>
#include <string>
#include <vector>

namespace sysid {

struct OutputFeedbackOptions {
  int lags = 10;               ///< future input samples tested, u(t + 1) .. u(t + lags)
  /// Past residual samples v(t - 1) .. v(t - output_lags), and simulated samples
  /// y_simulated(t) .. y_simulated(t - output_lags), of every output.
  int output_lags = 10;
  /// Past input samples u(t - input_delay) .. u(t - input_lags) of every input; a
  /// mismatch that the simulation's and the residual's lags cannot absorb (not
  /// rational of order <= output_lags) needs about its settling time in samples.
  int input_lags = 40;
  /// First past input lag: 1 for a strictly proper plant (a sampled mechanical drive);
  /// 0 when the mismatch may have a direct feedthrough (u(t) then joins the past
  /// block, and a controller acting within the sample is harder to see).
  int input_delay = 1;
  double significance = 0.01;  ///< family-wise false-alarm probability (Bonferroni over the tested pairs)
  /// A future input column whose part unexplained by the past block is below this
  /// fraction of its RMS is predictable (a periodic input) and is not tested.
  double predictable_tolerance = 1e-6;
};

/// One input-output pair: does input j react to output i's residual?
struct OutputFeedbackPair {
  Eigen::Index input = 0, output = 0;
  bool tested = false;         ///< false: the input is constant or predictable, or the residual is zero
  bool detected = false;
  double statistic = 0.0;      ///< chi-square statistic of the future block (file comment)
  double threshold = 0.0;      ///< chi2_{1 - significance / pairs}(dof)
  double p_value = 1.0;        ///< chi-square tail probability of the statistic (not Bonferroni-corrected)
  int dof = 0;                 ///< rank of the future block after the past is projected out
  int strongest_lag = 0;       ///< k in 1..lags whose u_j(t + k) alone explains most of the residual's innovation
  double explained_share = 0.0;  ///< share of the innovation's variance explained by the future block
};

struct OutputFeedbackCheck {
  bool feedback_detected = false;
  bool tested = false;         ///< at least one pair was tested
  double statistic = 0.0, threshold = 0.0;  ///< of the most significant pair (largest statistic / threshold)
  int lags = 0;                ///< future lags tested
  int pairs_tested = 0;        ///< Bonferroni divisor
  Eigen::Index samples = 0;    ///< rows of the regression
  Eigen::Index input = 0, output = 0;  ///< the most significant pair
  double strongest_lag_s = 0.0;  ///< strongest lag of that pair, seconds
  std::vector<OutputFeedbackPair> pairs;  ///< every input-output pair, output-major
  std::string evidence;        ///< one sentence in plain words, with the numbers
};

/// Purpose: whether the inputs u (N x m) react to the noise of the outputs y
/// (N x l), given the nominal's open-loop simulation y_simulated (N x l) from u
/// (file comment). Ts only converts the strongest lag to seconds.
OutputFeedbackCheck check_output_feedback(const Eigen::Ref<const Eigen::MatrixXd>& u,
                                          const Eigen::Ref<const Eigen::MatrixXd>& y,
                                          const Eigen::Ref<const Eigen::MatrixXd>& y_simulated, double Ts,
                                          const OutputFeedbackOptions& options = {});

}  // namespace sysid
