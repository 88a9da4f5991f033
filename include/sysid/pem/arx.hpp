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

enum class ArMethod { least_squares, yule_walker, burg };

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
