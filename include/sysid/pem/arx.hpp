#pragma once
/// @file
/// Purpose: ARX models A(q) y(t) = sum_i B_i(q) u_i(t - nk_i) + e(t) and AR
/// models A(q) y(t) = e(t) (no inputs), one per output ("stacked MISO": each
/// output has its own A and uses its own past only).
///
/// Method:
///  - ARX and AR "least_squares": linear least squares by Householder QR of the
///    regressors (pem/lagged_regression.hpp; Ljung 1999, sec. 7.3), rows where
///    every lag exists;
///  - AR "yule_walker": Levinson-Durbin recursion on the biased sample
///    autocorrelation (Ljung 1999, sec. 7.3; always gives a stable A);
///  - AR "burg": Burg's method, reflection coefficients minimising forward plus
///    backward prediction errors (J. P. Burg 1975; S. Kay, Modern Spectral
///    Estimation, 1988, sec. 7.3; always stable; several experiments pool the
///    numerator and denominator of each reflection coefficient).
///  - AR "modified_yule_walker": the overdetermined modified Yule-Walker
///    equations r(k) + sum_j a_j r(k - j) = 0 for k = na+1 .. na+M, solved by
///    least squares (QR) (P. Stoica & R. Moses, Spectral Analysis of Signals,
///    2005, sec. 3.7.2; Cadzow 1980). They use autocorrelation lags >= 1 only,
///    which white measurement noise on y does not touch: the AR part of "AR
///    process plus sensor noise" (an ARMA(na, na) process) comes out unbiased,
///    where least squares, Burg and Yule-Walker spend their poles on the noise
///    floor. Not guaranteed stable (checked by the caller's unstable-model
///    warning); noise_variance is the variance of A(q) y.
///
/// Data are mean-removed first (offsets in the result) unless told otherwise.
/// Preconditions (std::invalid_argument): na >= 0, nb_i >= 0, nk_i >= 0, one nb
/// and nk per input (an empty nk means 1 for every input), at least one
/// parameter, more equations than parameters.
#include <sysid/core/io_data.hpp>
#include <sysid/pem/polynomial_model.hpp>

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace sysid {

enum class ArMethod { least_squares, yule_walker, burg, modified_yule_walker };

/// The AR method named `name`: "ls", "yw", "burg", "myw" (the command line's
/// --method of `sysid ar`, Python's method=); std::invalid_argument otherwise.
inline ArMethod ar_method_from_name(const std::string& name) {
  if (name == "ls") return ArMethod::least_squares;
  if (name == "yw") return ArMethod::yule_walker;
  if (name == "burg") return ArMethod::burg;
  if (name == "myw") return ArMethod::modified_yule_walker;
  throw std::invalid_argument("method: expected 'ls', 'yw', 'burg' or 'myw', found '" + name + "'");
}

/// The command line's name of an AR method (inverse of ar_method_from_name).
inline const char* to_string(ArMethod method) {
  switch (method) {
    case ArMethod::least_squares: return "ls";
    case ArMethod::yule_walker: return "yw";
    case ArMethod::burg: return "burg";
    case ArMethod::modified_yule_walker: return "myw";
  }
  return "?";
}

struct ArxOptions {
  int na = 2;
  std::vector<int> nb;  ///< per input; must have one entry per input
  std::vector<int> nk;  ///< per input; empty = 1 for every input
  bool remove_means = true;
};

struct ArOptions {
  int na = 2;
  ArMethod method = ArMethod::least_squares;
  bool remove_means = true;
  /// modified_yule_walker: equations M (lags na+1 .. na+M); 0 = 4 na, "a few
  /// times the order" (Stoica & Moses sec. 3.7.2: more equations average more
  /// lags, but far lags of a biased autocorrelation estimate carry mostly noise).
  int modified_yule_walker_equations = 0;
};

/// One model per output.
struct LinearPolynomialResult {
  std::vector<PolynomialModel> models;
  std::vector<Eigen::MatrixXd> covariance;  ///< per output, of [a; b_1; ...] (empty for Burg / Yule-Walker)
  std::vector<double> condition;            ///< per output, of the column-scaled regressors (0 when not applicable)
  Eigen::VectorXd input_offset, output_offset;
  std::vector<std::string> warnings;
};

LinearPolynomialResult arx(IoData data, const ArxOptions& options);

/// Time series: the inputs of `data` are ignored (it may have none).
LinearPolynomialResult ar(IoData data, const ArOptions& options);

namespace detail {
/// Subtracts channel means over all experiments when asked; returns (input, output) offsets.
std::pair<Eigen::VectorXd, Eigen::VectorXd> remove_means_if(IoData& data, bool remove);
/// Per input delays with the default (empty = 1 each), checked.
std::vector<int> input_delays(const std::vector<int>& nk, Eigen::Index inputs);
}  // namespace detail

}  // namespace sysid
