#pragma once
/// @file
/// Purpose: OKID, observer/Kalman filter identification: the Markov parameters
/// of a (lightly damped) system from arbitrary input/output records, for ERA
/// (realization/era.hpp). Robust where a direct FIR fit fails: a lightly
/// damped system's impulse response is far longer than any affordable FIR, but
/// that of an observer with poles placed inside the unit circle is short.
///
/// Method (Juang, Phan, Horta & Longman 1993): with an observer gain G the
/// system x(k+1) = A x + B u, y = C x + D u is rewritten as
///   x(k+1) = Abar x(k) + Bbar v(k),  Abar = A + G C,  Bbar = [B + G D, -G],
///   v(k) = [u(k); y(k)],
/// so that, if Abar^p ~ 0 (deadbeat or Kalman observer, eq. 10-14),
///   y(k) = D u(k) + sum_{i=1}^{p} Ybar_i v(k - i) + eps(k),
///   Ybar_i = C Abar^(i-1) Bbar = [Ybar_i^(1), -Ybar_i^(2)]      (observer Markov parameters).
/// 1. Least squares for [D, Ybar_1, ..., Ybar_p] over the samples k >= p of
///    every record (each record its own start, so no initial condition is
///    assumed and records never see each other's samples); rows streamed through
///    a Householder QR (core/streaming_qr.hpp), never normal equations; a
///    rank-deficient R is solved by complete orthogonal decomposition.
/// 2. System Markov parameters (eq. 23-24 of the paper, written with M2_i =
///    -Ybar_i^(2), the fitted coefficient of y(k - i)):
///      Y_0 = D,  Y_k = Ybar_k^(1) + sum_{i=1}^{min(k,p)} M2_i Y_(k-i)   (Ybar_k^(1) = 0 for k > p).
/// 3. Observer-gain Markov parameters C A^(k-1) G (eq. 28):
///      Y^o_1 = -M2_1,  Y^o_k = -M2_k + sum_{i=1}^{k-1} M2_i Y^o_(k-i)   (M2_k = 0 for k > p).
///    Returned with the Kalman-predictor sign, C A^(k-1) K with K = -G
///    (x^(k+1) = A x^ + B u + K (y - C x^ - D u)).
/// With noisy data the least-squares observer is an estimate of the steady-state
/// Kalman filter (paper, sec. 4): p must be large enough that the Kalman
/// filter's impulse response has decayed within p samples.
/// For ERA on the result: beyond h[p] the Markov parameters follow the order-p l
/// recursion of step 2, so their Hankel matrix has a genuine rank gap at p l as
/// well; give ERA's automatic order rule a max_order below p l.
///
/// Preconditions (std::invalid_argument): p = observer_order >= 1;
/// markov_count >= 0; data with m >= 1 inputs; more equations than unknowns
/// (sum over records of N_e - p > m + p (m + l)). The data are deviations from an
/// operating point (remove means beforehand, e.g. remove_means() in io_data.hpp).
/// Numerical aspects: O(N q^2) flops with q = m + p (m + l) unknowns per output,
/// memory O(q^2) whatever N; the recovery is O(count p l^2 m).
///
/// References: J.-N. Juang, M. Phan, L. G. Horta, R. W. Longman, "Identification
/// of observer/Kalman filter Markov parameters: theory and experiments", Journal
/// of Guidance, Control, and Dynamics 16(2):320-329, 1993.
#include <sysid/core/io_data.hpp>
#include <sysid/realization/markov_parameters.hpp>

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace sysid {

struct OkidOptions {
  /// p: number of observer Markov parameters. Needs p l >= n for a deadbeat
  /// observer to exist; with noise, larger (the Kalman filter's decay time in samples).
  int observer_order = 20;
  /// Number of system Markov parameters h[1..count] returned (plus h[0] = D);
  /// 0 = 4 p. Beyond p they follow from the identified observer (step 2).
  int markov_count = 0;
  bool estimate_feedthrough = true;  ///< false: D = 0 and u(k) is left out of the regression
};

struct OkidResult {
  MarkovParameters markov;                   ///< h[0] = D, h[k] = C A^(k-1) B, k = 1..markov_count
  std::vector<Eigen::MatrixXd> gain_markov;  ///< C A^(k-1) K, k = 1..markov_count (l x l), K = Kalman predictor gain
  std::vector<Eigen::MatrixXd> observer_markov;  ///< Ybar_i = [C Abar^(i-1) Bbar], i = 1..p (l x (m + l))
  double condition = 0.0;     ///< of the column-scaled regressor (from R)
  double residual_rms = 0.0;  ///< RMS one-step prediction error of the observer model
  Eigen::Index equations = 0;
  bool rank_deficient = false;
  std::vector<std::string> warnings;
};

/// Purpose: OKID on one or several records (file comment).
/// Warnings: rank-deficient or ill-conditioned regression (cond > 1e10: input
/// not persistently exciting); observer Markov parameters not decayed
/// (||Ybar_p|| > 10 % of max ||Ybar_i||: increase p); fewer than 5 equations per
/// unknown.
OkidResult okid(const IoData& data, const OkidOptions& options = {});

}  // namespace sysid
