#pragma once
/// @file
/// Purpose: residual analysis of an identified model (the validation step of
/// Ljung, System Identification: Theory for the User, 2nd ed., 1999, sec. 16.6
/// "Residual analysis"): are the one-step prediction errors white, and are they
/// independent of the past inputs (and, at negative lags, are the inputs
/// independent of the past residuals, i.e. no feedback)?
///
/// Contents:
/// - sample_correlation: normalised sample cross-correlation at a range of lags;
/// - model_residuals: e(t) = y(t) - y^(t|t-1) of a model on a record (the
///   innovation-form one-step predictor of compare.hpp; with no K, the simulation
///   error);
/// - analyze_residuals: autocorrelations, residual-input cross-correlations with
///   confidence bounds valid for coloured signals, Ljung-Box, verdicts in words.
///
/// The chi-square distribution behind the Ljung-Box p-value is in
/// core/distributions.hpp, the lag lists of the verdicts in core/format_lags.hpp;
/// model_residuals and analyze_residuals are compiled in
/// src/validate/residual_analysis.cpp.
///
/// Lag convention (Ljung eq. 16.61-16.62 form): r_eu(tau) correlates e(t + tau)
/// with u(t). tau > 0: the input leads the residual (dynamics from u the model
/// missed); tau < 0: the residual leads the input (output feedback into u).
#include <sysid/core/io_data.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/validate/compare.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

// ---------------------------------------------------------------------------
// Sample correlations
// ---------------------------------------------------------------------------

namespace detail {

/// (1/N) sum_t x(t + lag) y(t) over the overlapping samples (x, y of equal length N).
inline double lagged_product(const Eigen::VectorXd& x, const Eigen::VectorXd& y, Eigen::Index lag) {
  const Eigen::Index N = x.size(), overlap = N - (lag < 0 ? -lag : lag);
  if (overlap <= 0) return 0.0;
  const double s = lag >= 0 ? x.tail(overlap).dot(y.head(overlap)) : x.head(overlap).dot(y.tail(overlap));
  return s / static_cast<double>(N);
}

}  // namespace detail

/// Purpose: normalised sample cross-correlation of two signals at the lags
/// lag_from..lag_to (element k is lag lag_from + k):
///   r_xy(tau) = R_xy(tau) / sqrt(R_xx(0) R_yy(0)),
///   R_xy(tau) = (1/N) sum_t (x(t + tau) - xbar) (y(t) - ybar)
/// (Ljung 1999, eq. 16.61-16.62 with the sample means removed). x = y gives the
/// autocorrelation, r(0) = 1.
/// Method: the biased 1/N estimator (not 1/(N - |tau|)): its sequence is positive
/// semidefinite and has the smaller mean-square error (Box, Jenkins & Reinsel,
/// Time Series Analysis, sec. 2.1.6).
/// Preconditions: x, y vectors of equal length N >= 1, finite; lag_from <= lag_to;
/// |lag| < N (std::invalid_argument). A constant signal (zero variance) gives
/// all zeros: the correlation is undefined and "no evidence of correlation".
/// Numerical aspects: O(N (lag_to - lag_from + 1)) by vectorised dot products.
template <class DX, class DY>
Eigen::VectorXd sample_correlation(const Eigen::MatrixBase<DX>& x, const Eigen::MatrixBase<DY>& y, Eigen::Index lag_from,
                                   Eigen::Index lag_to) {
  if (x.cols() != 1 && x.rows() != 1) throw std::invalid_argument("sample_correlation: need x to be a vector");
  if (y.cols() != 1 && y.rows() != 1) throw std::invalid_argument("sample_correlation: need y to be a vector");
  if (x.size() != y.size())
    throw std::invalid_argument("sample_correlation: need x.size() == y.size() (" + std::to_string(x.size()) +
                                " != " + std::to_string(y.size()) + ")");
  const Eigen::Index N = x.size();
  if (N < 1) throw std::invalid_argument("sample_correlation: need at least 1 sample");
  if (lag_from > lag_to) throw std::invalid_argument("sample_correlation: need lag_from <= lag_to");
  if (std::max(std::abs(lag_from), std::abs(lag_to)) >= N)
    throw std::invalid_argument("sample_correlation: need |lag| < N = " + std::to_string(N));
  Eigen::VectorXd xc(N), yc(N);
  for (Eigen::Index t = 0; t < N; ++t) {
    xc(t) = x(t);
    yc(t) = y(t);
  }
  if (!xc.allFinite() || !yc.allFinite()) throw std::invalid_argument("sample_correlation: need finite samples");
  xc.array() -= xc.mean();
  yc.array() -= yc.mean();
  Eigen::VectorXd r = Eigen::VectorXd::Zero(lag_to - lag_from + 1);
  const double scale = std::sqrt(detail::lagged_product(xc, xc, 0) * detail::lagged_product(yc, yc, 0));
  if (!(scale > 0.0)) return r;
  for (Eigen::Index k = 0; k < r.size(); ++k) r(k) = detail::lagged_product(xc, yc, lag_from + k) / scale;
  return r;
}

// ---------------------------------------------------------------------------
// The residuals of a model
// ---------------------------------------------------------------------------

/// Purpose: the residuals of a model on one record: with the Kalman gain K (n x l),
/// the one-step-ahead prediction errors e(t) = y(t) - y^(t|t-1) of the innovation
/// predictor x(t+1) = A x + B u + K (y - C x - D u) (the innovations, white for
/// the true model); with K empty, the simulation errors y - G u, which are white
/// only when the disturbance itself is white (output-error models).
/// Method: compare() with predict_steps = 1 (K given) or 0 (K empty); `options`
/// supplies the offsets and the initial state (by default x0 is estimated by least
/// squares on the record, so the start-up transient does not pollute the
/// correlations; with K the predictor forgets x0 at the rate of A - K C anyway).
/// Preconditions: as compare(); options.predict_steps is overridden.
/// Returns N x l, in the units of the log's outputs.
Eigen::MatrixXd model_residuals(const StateSpace& sys, const Eigen::MatrixXd& K, const Experiment& data,
                                CompareOptions options = {});

// ---------------------------------------------------------------------------
// Residual analysis
// ---------------------------------------------------------------------------

struct ResidualAnalysisOptions {
  /// Largest lag M: autocorrelations at 0..M, residual-input cross-correlations
  /// at -M..M. Need 1 <= M < N.
  Eigen::Index max_lag = 25;
  /// Confidence level of the bounds and of the verdicts' tests (0.99: 99 %,
  /// i.e. test level alpha = 1 - confidence = 1 %). Need 0 < confidence < 1.
  double confidence = 0.99;
  /// Lags h of the Ljung-Box statistic; 0 = max_lag. Need 1 <= h < N.
  Eigen::Index ljung_box_lags = 0;
  /// Number of estimated noise-model parameters (e.g. na + nc of an ARMA model),
  /// subtracted from h for the chi-square degrees of freedom (Ljung & Box 1978).
  /// Need 0 <= noise_parameters < h.
  Eigen::Index noise_parameters = 0;
  /// Lags K of the sums sum_{|k|<=K} r_ee(k) r_uu(k) in the variance of the
  /// residual-input cross-correlation; 0 = max(max_lag, 25), capped at N - 1.
  /// It must cover the correlation time of the slower of e and u (a pole at
  /// 0.9 needs ~25 lags); a much larger K only adds estimation noise.
  Eigen::Index variance_lags = 0;
  /// Channel names for the verdicts; empty = y1, y2, ... and u1, u2, ...
  std::vector<std::string> output_names, input_names;
};

/// Verdicts for one output's residual.
struct ResidualVerdict {
  bool white = true;                        ///< whiteness not rejected at level 1 - confidence
  std::vector<Eigen::Index> lags_outside;   ///< lags 1..M where |r_ee| exceeds the pointwise bound
  /// Per other output j (index j; empty for j = this output): lags 1..M where the
  /// correlation of this residual with the earlier residual of output j exceeds the bound.
  std::vector<std::vector<Eigen::Index>> output_lags_outside;
  std::vector<bool> independent;                         ///< per input: independence not rejected
  std::vector<std::vector<Eigen::Index>> input_lags_outside;  ///< per input: lags -M..M outside the bound
  std::string whiteness;                    ///< "white" / "not white: autocorrelation outside ... at lags 3, 7"
  std::vector<std::string> independence;    ///< per input: "independent of input u" / "correlated with input u at lags -2..4 ..."
};

struct ResidualAnalysisResult {
  Eigen::Index samples = 0;       ///< N
  Eigen::Index max_lag = 0;       ///< M
  double confidence = 0.99;
  double z = 0.0;                 ///< pointwise normal quantile z_{1 - alpha/2} (2.576 at 99 %)
  /// (M+1) x l: column i is the autocorrelation of residual i at lags 0..M (r(0) = 1).
  Eigen::MatrixXd autocorrelation;
  /// Pointwise bound on the autocorrelation at lags >= 1 (and on the residual
  /// cross-correlations between outputs): z / sqrt(N).
  double autocorrelation_bound = 0.0;
  /// M+1 matrices l x l (index = lag tau = 0..M): entry (i, j) correlates
  /// e_i(t + tau) with e_j(t); the diagonal repeats `autocorrelation`. Lag 0
  /// off-diagonal entries are the innovation correlations (not tested).
  std::vector<Eigen::MatrixXd> output_correlation;
  /// (2M+1) x (l m): column i m + j is r_{e_i u_j}(tau), row tau + M for tau = -M..M.
  Eigen::MatrixXd input_correlation;
  /// l m: pointwise bound on column i m + j, z sqrt(P_ij / N) with
  /// P_ij = sum_{|k|<=K} r_{e_i}(k) r_{u_j}(k) (Bartlett's formula).
  Eigen::VectorXd input_correlation_bound;
  /// The factor P_ij above (1 for white e or white u): how much wider than
  /// z / sqrt(N) the coloured-signal bound is, squared.
  Eigen::VectorXd input_variance_factor;
  Eigen::Index ljung_box_lags = 0;     ///< h
  double ljung_box_dof = 0;            ///< h - noise_parameters
  Eigen::VectorXd ljung_box_q;         ///< per output: N (N+2) sum_{k=1}^h r(k)^2 / (N - k)
  Eigen::VectorXd ljung_box_p;         ///< per output: P(chi2(dof) > Q)
  Eigen::VectorXd mean;                ///< per output: residual mean (removed before correlating)
  Eigen::VectorXd rms;                 ///< per output: residual RMS about the mean
  std::vector<ResidualVerdict> verdicts;  ///< per output
  std::vector<std::string> warnings;
};

/// Purpose: residual analysis of a model: whiteness of each output's residual and
/// its independence of each input, with bounds, the Ljung-Box test and verdicts.
///
/// Method (Ljung 1999, sec. 16.6):
/// - autocorrelation r_e(tau), tau = 0..M, and the residual cross-correlations
///   between outputs; under whiteness sqrt(N) r_e(tau) ~ N(0, 1) for tau != 0,
///   hence the pointwise bound +-z_{1-alpha/2} / sqrt(N);
/// - residual-input cross-correlation r_eu(tau), tau = -M..M. If e and u are
///   independent stationary signals (each possibly coloured), sqrt(N) R_eu(tau)
///   is asymptotically normal with variance P = sum_k R_e(k) R_u(k) (Ljung 1999,
///   sec. 16.6, the variance of the cross-correlation test statistic — eq.
///   16.66-16.67 region in the 2nd ed.; the equation numbers were not verified
///   against the book; the result is Bartlett's formula, M. S. Bartlett, "Some
///   aspects of the time-correlation problem in regard to tests of significance",
///   J. R. Stat. Soc. 98 (1935) 536-543). Normalised: Var r_eu(tau) ~ (1/N)
///   sum_k r_e(k) r_u(k), summed here over |k| <= K with the sample
///   autocorrelations. The naive +-z/sqrt(N) assumes P = 1, valid only when e or
///   u is white; two independent AR(1) signals with pole 0.9 have P = 1.81/0.19
///   = 9.5, so the naive bound is 3.1 times too narrow and flags ~40 % of lags;
/// - Ljung-Box: Q = N (N + 2) sum_{k=1}^{h} r_e(k)^2 / (N - k) ~ chi2(h - p)
///   under whiteness (G. M. Ljung & G. E. P. Box, "On a measure of lack of fit
///   in time series models", Biometrika 65 (1978) 297-303), p = noise_parameters.
///
/// Verdicts (level alpha = 1 - confidence per test). Pointwise bounds are
/// exceeded by chance at alpha of the lags, so "some lag outside the bound" would
/// reject white noise at 1 - (1 - alpha)^M (22 % for M = 25 at 99 %). Hence:
/// - not white if Ljung-Box p < alpha, or some |r_e(tau)| (tau = 1..M) or some
///   residual correlation with another output exceeds the simultaneous
///   (Bonferroni) bound z_{1 - alpha/(2M)} / sqrt(N);
/// - correlated with input u if some |r_eu(tau)| exceeds the simultaneous bound
///   z_{1 - alpha/(2(2M+1))} sqrt(P/N). Bonferroni stays valid when the estimates
///   at neighbouring lags are correlated (coloured signals), where counting the
///   pointwise exceedances would not;
/// - the words list the lags outside the pointwise bounds (what a plot shows) and
///   the peak lag. The cross-correlation is not prewhitened: with a coloured
///   input, r_eu is the true impulse response smeared by r_uu, so lags of both
///   signs are attributed to the side of the peak and the other side is called
///   ambiguous (prewhitening, Box, Jenkins & Reinsel sec. 12.2, would separate
///   them; not done here).
///
/// Preconditions (std::invalid_argument): e is N x l (l >= 1), u is N x m (m may be
/// 0: a time series), both finite; N > max_lag >= 1; 0 < confidence < 1;
/// 0 <= noise_parameters < h < N; 0 <= variance_lags < N; names empty or of size
/// l (m).
/// Numerical aspects: O(N (M l^2 + (2M + 1) l m + K (l + m))) by dot products.
/// Warnings: fewer than 10 M samples (bounds rough); a constant residual or input
/// (correlation undefined, reported as 0); a residual mean larger than its
/// bound z rms / sqrt(N) (an offset the model does not explain; meaningful when
/// the residual is white); a non-positive estimated variance factor.
/// Example: `ResidualAnalysisResult r = analyze_residuals(model_residuals(sys, K, exp), exp.u);`
/// (Any Eigen expression converts to the MatrixXd arguments; the analysis works on
/// copies of e and u anyway.)
ResidualAnalysisResult analyze_residuals(const Eigen::MatrixXd& e, const Eigen::MatrixXd& u,
                                         const ResidualAnalysisOptions& options = {});

}  // namespace sysid
