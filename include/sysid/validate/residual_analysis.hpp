#pragma once
/// @file
/// Purpose: residual analysis of an identified model (the validation step of
/// Ljung, System Identification: Theory for the User, 2nd ed., 1999, sec. 16.6
/// "Residual analysis"): are the one-step prediction errors white, and are they
/// independent of the past inputs (and, at negative lags, are the inputs
/// independent of the past residuals, i.e. no feedback)?
///
/// Contents:
/// - regularized_gamma_p/q, chi_square_cdf/sf: the chi-square distribution for the
///   p-value of the Ljung-Box statistic;
/// - sample_correlation: normalised sample cross-correlation at a range of lags;
/// - model_residuals: e(t) = y(t) - y^(t|t-1) of a model on a record (the
///   innovation-form one-step predictor of compare.hpp; with no K, the simulation
///   error);
/// - analyze_residuals: autocorrelations, residual-input cross-correlations with
///   confidence bounds valid for coloured signals, Ljung-Box, verdicts in words.
///
/// Lag convention (Ljung eq. 16.61-16.62 form): r_eu(tau) correlates e(t + tau)
/// with u(t). tau > 0: the input leads the residual (dynamics from u the model
/// missed); tau < 0: the residual leads the input (output feedback into u).
#include <sysid/core/errors.hpp>
#include <sysid/core/format_number.hpp>
#include <sysid/core/io_data.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/spectral/confidence.hpp>
#include <sysid/validate/compare.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

// ---------------------------------------------------------------------------
// The chi-square distribution
// ---------------------------------------------------------------------------

namespace detail {

/// exp(-x + a ln x - lnGamma(a)): the common prefactor of the series and the
/// continued fraction (computed in logs: x^a and Gamma(a) overflow separately
/// long before their ratio does).
inline double gamma_prefactor(double a, double x) { return std::exp(-x + a * std::log(x) - std::lgamma(a)); }

/// P(a, x) by its power series (Abramowitz & Stegun 6.5.29):
///   gamma(a, x) = e^{-x} x^a sum_{n>=0} x^n / (a (a+1) ... (a+n)).
/// Used for x < a + 1, where the term ratio x / (a + n) < 1 from n = 1 on, so the
/// sum converges geometrically and every term is positive (no cancellation).
inline double gamma_p_series(double a, double x) {
  double term = 1.0 / a, sum = term;
  for (int n = 1; n < 100000; ++n) {
    term *= x / (a + n);
    sum += term;
    if (term < sum * std::numeric_limits<double>::epsilon()) return sum * gamma_prefactor(a, x);
  }
  throw NumericalError("regularized_gamma_p: the series did not converge (a = " + std::to_string(a) +
                       ", x = " + std::to_string(x) + ")");
}

/// Q(a, x) by Legendre's continued fraction (A&S 6.5.31, in the even form
///   Gamma(a, x) = e^{-x} x^a (1/(x+1-a-) 1(1-a)/(x+3-a-) 2(2-a)/(x+5-a-) ...)),
/// evaluated forward by the modified Lentz method (Lentz, Appl. Opt. 15 (1976)
/// 668; Thompson & Barnett, J. Comput. Phys. 64 (1986) 490): every convergent is
/// available without back-substitution, and zero denominators are nudged to
/// `tiny`. Used for x >= a + 1, where it converges in O(sqrt(a)) steps.
inline double gamma_q_continued_fraction(double a, double x) {
  constexpr double tiny = 1e-300;
  const double eps = std::numeric_limits<double>::epsilon();
  double b = x + 1.0 - a;
  double c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < eps) return h * gamma_prefactor(a, x);
  }
  throw NumericalError("regularized_gamma_q: the continued fraction did not converge (a = " + std::to_string(a) +
                       ", x = " + std::to_string(x) + ")");
}

inline void check_gamma_args(double a, double x, const char* who) {
  if (!(a > 0.0) || !std::isfinite(a)) throw std::invalid_argument(std::string(who) + ": need 0 < a < infinity");
  if (!(x >= 0.0)) throw std::invalid_argument(std::string(who) + ": need x >= 0");
}

}  // namespace detail

/// Purpose: the regularized lower incomplete gamma function
///   P(a, x) = gamma(a, x) / Gamma(a) = (1/Gamma(a)) int_0^x t^{a-1} e^{-t} dt.
/// Method: power series for x < a + 1, 1 - continued fraction otherwise (see the
/// detail functions; the split is where both converge fast and the one computed
/// directly is the smaller of P and Q, so neither loses digits to 1 - (~1)).
/// Preconditions: 0 < a < inf, x >= 0 (x = +inf gives 1); std::invalid_argument.
/// Numerical aspects: relative accuracy ~1e-14 for a up to ~1e3 (the prefactor
/// exp(a ln x - x - lnGamma(a)) loses ~|a ln x| eps); O(sqrt(a) + 1) work.
inline double regularized_gamma_p(double a, double x) {
  detail::check_gamma_args(a, x, "regularized_gamma_p");
  if (x == 0.0) return 0.0;
  if (std::isinf(x)) return 1.0;
  return x < a + 1.0 ? detail::gamma_p_series(a, x) : 1.0 - detail::gamma_q_continued_fraction(a, x);
}

/// Purpose: the regularized upper incomplete gamma function Q(a, x) = 1 - P(a, x),
/// computed directly in its tail (x >= a + 1), so tiny upper tails (p-values such
/// as 1e-30) keep their relative accuracy. Preconditions as regularized_gamma_p.
inline double regularized_gamma_q(double a, double x) {
  detail::check_gamma_args(a, x, "regularized_gamma_q");
  if (x == 0.0) return 1.0;
  if (std::isinf(x)) return 0.0;
  return x < a + 1.0 ? 1.0 - detail::gamma_p_series(a, x) : detail::gamma_q_continued_fraction(a, x);
}

/// Chi-square CDF with `dof` degrees of freedom: P(X <= x) = P(dof/2, x/2).
/// Preconditions: dof > 0, x >= 0 (std::invalid_argument).
inline double chi_square_cdf(double x, double dof) {
  if (!(dof > 0.0) || !std::isfinite(dof)) throw std::invalid_argument("chi_square_cdf: need 0 < dof < infinity");
  if (!(x >= 0.0)) throw std::invalid_argument("chi_square_cdf: need x >= 0");
  return regularized_gamma_p(0.5 * dof, 0.5 * x);
}

/// Chi-square survival function (upper tail, the p-value of a statistic x):
/// P(X > x) = Q(dof/2, x/2). Preconditions as chi_square_cdf.
inline double chi_square_sf(double x, double dof) {
  if (!(dof > 0.0) || !std::isfinite(dof)) throw std::invalid_argument("chi_square_sf: need 0 < dof < infinity");
  if (!(x >= 0.0)) throw std::invalid_argument("chi_square_sf: need x >= 0");
  return regularized_gamma_q(0.5 * dof, 0.5 * x);
}

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
inline Eigen::MatrixXd model_residuals(const StateSpace& sys, const Eigen::MatrixXd& K, const Experiment& data,
                                       CompareOptions options = {}) {
  options.predict_steps = K.size() == 0 ? 0 : 1;
  const CompareResult r = compare(sys, K, data, options);
  return data.y - r.y_hat;
}

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

namespace detail {

/// "3, 7" / "-2..4" / "1..3, 7": runs of three or more consecutive lags as ranges.
inline std::string format_lags(const std::vector<Eigen::Index>& lags) {
  std::string s;
  for (std::size_t i = 0; i < lags.size();) {
    std::size_t j = i;
    while (j + 1 < lags.size() && lags[j + 1] == lags[j] + 1) ++j;
    if (!s.empty()) s += ", ";
    if (j - i >= 2) {
      s += std::to_string(lags[i]) + ".." + std::to_string(lags[j]);
    } else {
      for (std::size_t k = i; k <= j; ++k) s += (k > i ? ", " : "") + std::to_string(lags[k]);
    }
    i = j + 1;
  }
  return s;
}

inline std::string lag_word(const std::vector<Eigen::Index>& lags) { return lags.size() == 1 ? "lag " : "lags "; }

inline std::string percent(double confidence) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g %%", 100.0 * confidence);
  return buf;
}

}  // namespace detail

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
template <class DE, class DU>
ResidualAnalysisResult analyze_residuals(const Eigen::MatrixBase<DE>& e_in, const Eigen::MatrixBase<DU>& u_in,
                                         const ResidualAnalysisOptions& options = {}) {
  const Eigen::MatrixXd e = e_in, u = u_in;
  const Eigen::Index N = e.rows(), l = e.cols(), m = u.cols(), M = options.max_lag;
  if (l < 1) throw std::invalid_argument("analyze_residuals: need at least 1 residual channel");
  if (u.rows() != N && !(m == 0))
    throw std::invalid_argument("analyze_residuals: need u.rows() == e.rows() (" + std::to_string(u.rows()) +
                                " != " + std::to_string(N) + ")");
  if (M < 1) throw std::invalid_argument("analyze_residuals: need max_lag >= 1");
  if (N <= M)
    throw std::invalid_argument("analyze_residuals: need samples > max_lag (" + std::to_string(N) +
                                " <= " + std::to_string(M) + ")");
  if (!(options.confidence > 0.0 && options.confidence < 1.0))
    throw std::invalid_argument("analyze_residuals: need 0 < confidence < 1");
  const Eigen::Index h = options.ljung_box_lags == 0 ? M : options.ljung_box_lags;
  if (h < 1 || h >= N) throw std::invalid_argument("analyze_residuals: need 1 <= ljung_box_lags < samples");
  if (options.noise_parameters < 0 || options.noise_parameters >= h)
    throw std::invalid_argument("analyze_residuals: need 0 <= noise_parameters < ljung_box_lags (" +
                                std::to_string(options.noise_parameters) + " vs " + std::to_string(h) + ")");
  if (options.variance_lags < 0 || options.variance_lags >= N)
    throw std::invalid_argument("analyze_residuals: need 0 <= variance_lags < samples");
  if (!options.output_names.empty() && static_cast<Eigen::Index>(options.output_names.size()) != l)
    throw std::invalid_argument("analyze_residuals: need output_names empty or of size " + std::to_string(l));
  if (!options.input_names.empty() && static_cast<Eigen::Index>(options.input_names.size()) != m)
    throw std::invalid_argument("analyze_residuals: need input_names empty or of size " + std::to_string(m));
  if (!e.allFinite()) throw std::invalid_argument("analyze_residuals: need finite residuals");
  if (!u.allFinite()) throw std::invalid_argument("analyze_residuals: need finite inputs");

  const double alpha = 1.0 - options.confidence;
  const double sqrt_n = std::sqrt(static_cast<double>(N));
  const Eigen::Index K = std::min<Eigen::Index>(options.variance_lags == 0 ? std::max<Eigen::Index>(M, 25)
                                                                           : options.variance_lags,
                                                N - 1);
  const Eigen::Index auto_lags = std::max({M, h, K});  // autocorrelations needed by any part

  auto out_name = [&](Eigen::Index i) {
    return options.output_names.empty() ? "y" + std::to_string(i + 1) : options.output_names[i];
  };
  auto in_name = [&](Eigen::Index j) {
    return options.input_names.empty() ? "u" + std::to_string(j + 1) : options.input_names[j];
  };

  ResidualAnalysisResult r;
  r.samples = N;
  r.max_lag = M;
  r.confidence = options.confidence;
  r.z = normal_quantile(1.0 - alpha / 2.0);
  r.autocorrelation_bound = r.z / sqrt_n;
  if (N < 10 * M)
    r.warnings.push_back("only " + std::to_string(N) + " samples for lags up to " + std::to_string(M) +
                         ": the bounds are asymptotic (N >> max_lag) and rough here");

  // Centred channels, and their full autocorrelations up to auto_lags.
  Eigen::MatrixXd ec = e, uc = u;
  r.mean = e.colwise().mean().transpose();
  ec.rowwise() -= r.mean.transpose();
  if (m > 0) uc.rowwise() -= u.colwise().mean();
  r.rms = (ec.colwise().squaredNorm() / static_cast<double>(N)).cwiseSqrt().transpose();
  Eigen::MatrixXd acf_e(auto_lags + 1, l), acf_u(auto_lags + 1, m);
  for (Eigen::Index i = 0; i < l; ++i) {
    acf_e.col(i) = sample_correlation(ec.col(i), ec.col(i), 0, auto_lags);
    if (!(r.rms(i) > 0.0)) {
      r.warnings.push_back("the residual of " + out_name(i) + " is constant: its correlations are undefined (reported as 0)");
    } else if (std::abs(r.mean(i)) > r.z * r.rms(i) / sqrt_n) {
      r.warnings.push_back("the residual of " + out_name(i) + " has a mean of " + format_number(r.mean(i), 2) +
                           " (" + format_number(r.mean(i) / r.rms(i), 2) +
                           " rms), outside its bound: an offset the model does not explain");
    }
  }
  for (Eigen::Index j = 0; j < m; ++j) {
    acf_u.col(j) = sample_correlation(uc.col(j), uc.col(j), 0, auto_lags);
    if (acf_u(0, j) == 0.0)
      r.warnings.push_back("input " + in_name(j) + " is constant: its cross-correlation is undefined (reported as 0)");
  }
  r.autocorrelation = acf_e.topRows(M + 1);

  // Residual correlations between outputs (the diagonal is the autocorrelation).
  r.output_correlation.assign(static_cast<std::size_t>(M + 1), Eigen::MatrixXd::Zero(l, l));
  for (Eigen::Index i = 0; i < l; ++i)
    for (Eigen::Index j = 0; j < l; ++j) {
      const Eigen::VectorXd c = i == j ? Eigen::VectorXd(acf_e.col(i).head(M + 1)) : sample_correlation(ec.col(i), ec.col(j), 0, M);
      for (Eigen::Index tau = 0; tau <= M; ++tau) r.output_correlation[static_cast<std::size_t>(tau)](i, j) = c(tau);
    }

  // Residual-input cross-correlations with Bartlett's variance factor.
  r.input_correlation.resize(2 * M + 1, l * m);
  r.input_correlation_bound.resize(l * m);
  r.input_variance_factor.resize(l * m);
  for (Eigen::Index i = 0; i < l; ++i)
    for (Eigen::Index j = 0; j < m; ++j) {
      const Eigen::Index col = i * m + j;
      r.input_correlation.col(col) = sample_correlation(ec.col(i), uc.col(j), -M, M);
      // P = sum_{|k|<=K} r_e(k) r_u(k) = 1 + 2 sum_{k=1}^K r_e(k) r_u(k).
      double P = 1.0 + 2.0 * acf_e.col(i).segment(1, K).dot(acf_u.col(j).segment(1, K));
      if (!(P > 0.0)) {
        // The truncated sum of sample products can dip below zero only when both
        // signals have large oscillating correlations; the Bartlett-weighted sum
        // (a spectral estimate at frequency 0, never negative) replaces it.
        double Pb = 1.0;
        for (Eigen::Index k = 1; k <= K; ++k)
          Pb += 2.0 * (1.0 - static_cast<double>(k) / static_cast<double>(K + 1)) * acf_e(k, i) * acf_u(k, j);
        r.warnings.push_back("variance factor for " + out_name(i) + " vs " + in_name(j) +
                             " was not positive with rectangular truncation; the Bartlett-weighted sum was used");
        P = Pb > 0.0 ? Pb : 1.0;
      }
      r.input_variance_factor(col) = P;
      r.input_correlation_bound(col) = r.z * std::sqrt(P) / sqrt_n;
    }

  // Ljung-Box.
  r.ljung_box_lags = h;
  r.ljung_box_dof = static_cast<double>(h - options.noise_parameters);
  r.ljung_box_q.resize(l);
  r.ljung_box_p.resize(l);
  const double nd = static_cast<double>(N);
  for (Eigen::Index i = 0; i < l; ++i) {
    double s = 0.0;
    for (Eigen::Index k = 1; k <= h; ++k) s += acf_e(k, i) * acf_e(k, i) / (nd - static_cast<double>(k));
    r.ljung_box_q(i) = nd * (nd + 2.0) * s;
    r.ljung_box_p(i) = chi_square_sf(r.ljung_box_q(i), r.ljung_box_dof);
  }

  // Verdicts.
  const double z_sim_auto = normal_quantile(1.0 - alpha / (2.0 * static_cast<double>(M)));
  const double z_sim_cross = normal_quantile(1.0 - alpha / (2.0 * static_cast<double>(2 * M + 1)));
  const std::string pct = detail::percent(options.confidence);
  r.verdicts.resize(static_cast<std::size_t>(l));
  for (Eigen::Index i = 0; i < l; ++i) {
    ResidualVerdict& v = r.verdicts[static_cast<std::size_t>(i)];
    bool strong = false;
    for (Eigen::Index tau = 1; tau <= M; ++tau) {
      const double a = std::abs(acf_e(tau, i));
      if (a > r.autocorrelation_bound) v.lags_outside.push_back(tau);
      if (a > z_sim_auto / sqrt_n) strong = true;
    }
    v.output_lags_outside.assign(static_cast<std::size_t>(l), {});
    bool strong_cross = false;
    for (Eigen::Index j = 0; j < l; ++j) {
      if (j == i) continue;
      for (Eigen::Index tau = 1; tau <= M; ++tau) {
        const double a = std::abs(r.output_correlation[static_cast<std::size_t>(tau)](i, j));
        if (a > r.autocorrelation_bound) v.output_lags_outside[static_cast<std::size_t>(j)].push_back(tau);
        if (a > z_sim_auto / sqrt_n) strong_cross = true;
      }
    }
    const bool lb_rejects = r.ljung_box_p(i) < alpha;
    v.white = !(lb_rejects || strong || strong_cross);
    const std::string lb_text = "Ljung-Box p = " + format_number(r.ljung_box_p(i), 2);
    if (v.white) {
      v.whiteness = "white";
      if (!v.lags_outside.empty())
        v.whiteness += " (autocorrelation outside the " + pct + " bound only at " + detail::lag_word(v.lags_outside) +
                       detail::format_lags(v.lags_outside) + ", as chance allows among " + std::to_string(M) + " lags)";
    } else {
      std::vector<std::string> why;
      if (!v.lags_outside.empty())
        why.push_back("autocorrelation outside the " + pct + " bound at " + detail::lag_word(v.lags_outside) +
                      detail::format_lags(v.lags_outside));
      if (lb_rejects) why.push_back(lb_text + " < " + format_number(alpha, 2));
      for (Eigen::Index j = 0; j < l; ++j) {
        const auto& lags = v.output_lags_outside[static_cast<std::size_t>(j)];
        if (!lags.empty())
          why.push_back("correlated with the earlier residual of " + out_name(j) + " at " + detail::lag_word(lags) +
                        detail::format_lags(lags));
      }
      v.whiteness = "not white: ";
      for (std::size_t k = 0; k < why.size(); ++k) v.whiteness += (k ? "; " : "") + why[k];
    }

    v.independent.assign(static_cast<std::size_t>(m), true);
    v.input_lags_outside.assign(static_cast<std::size_t>(m), {});
    v.independence.assign(static_cast<std::size_t>(m), "");
    for (Eigen::Index j = 0; j < m; ++j) {
      const Eigen::Index col = i * m + j;
      auto& lags = v.input_lags_outside[static_cast<std::size_t>(j)];
      const double sigma = std::sqrt(r.input_variance_factor(col)) / sqrt_n;
      bool dependent = false;
      for (Eigen::Index tau = -M; tau <= M; ++tau) {
        const double a = std::abs(r.input_correlation(tau + M, col));
        if (a > r.input_correlation_bound(col)) lags.push_back(tau);
        if (a > z_sim_cross * sigma) dependent = true;
      }
      v.independent[static_cast<std::size_t>(j)] = !dependent;
      std::string& text = v.independence[static_cast<std::size_t>(j)];
      if (acf_u(0, j) == 0.0) {
        text = "not tested against input " + in_name(j) + " (constant over the record)";
      } else if (!dependent) {
        text = "independent of input " + in_name(j);
        if (!lags.empty())
          text += " (outside the " + pct + " bound only at " + detail::lag_word(lags) + detail::format_lags(lags) +
                  ", as chance allows among " + std::to_string(2 * M + 1) + " lags)";
      } else {
        text = "correlated with input " + in_name(j) + " at " + detail::lag_word(lags) + detail::format_lags(lags);
        Eigen::Index peak = 0;
        r.input_correlation.col(col).cwiseAbs().maxCoeff(&peak);
        peak -= M;
        const bool negative = std::any_of(lags.begin(), lags.end(), [](Eigen::Index t) { return t < 0; });
        const bool positive = std::any_of(lags.begin(), lags.end(), [](Eigen::Index t) { return t >= 0; });
        // A coloured input spreads a correlation at one lag over its neighbours on
        // both sides (r_eu = g * r_uu), so negative lags next to a positive peak
        // are not by themselves evidence of feedback, and vice versa.
        text += " (peak at lag " + std::to_string(peak) + "; ";
        if (positive && !negative)
          text += "lags >= 0: input dynamics the model misses)";
        else if (negative && !positive)
          text += "lags < 0: the residual leads the input: feedback)";
        else if (peak >= 0)
          text += "lags >= 0: input dynamics the model misses; the negative lags may be its spread through a coloured "
                  "input, or feedback)";
        else
          text += "lags < 0: the residual leads the input: feedback; the lags >= 0 may be its spread through a coloured "
                  "input, or input dynamics the model misses)";
      }
    }
  }
  return r;
}

}  // namespace sysid
