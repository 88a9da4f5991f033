#pragma once
/// @file
/// Purpose: the linear least-squares problem behind ARX, AR and the
/// Hannan-Rissanen initialisation of ARMAX,
///
///   s_target(t) = sum_terms sign * sum_{k=0}^{count-1} theta_{term,k} s_signal(t - first_lag - k) + e(t),
///
/// over one or several experiments (rows start where every lag exists, so no
/// initial condition is assumed and experiments never see each other's samples).
///
/// Method: the regressor rows are streamed through a Householder QR
/// (core/streaming_qr.hpp) with the target as an extra column; theta solves the
/// triangular system (complete orthogonal decomposition of R when it is
/// rank-deficient), never the normal equations. Memory O(p^2) for p parameters,
/// whatever the number of samples.
///
/// Diagnostics: the residual variance ||e||^2 / (rows - p), the parameter
/// covariance sigma^2 (R^T R)^-1 (Ljung 1999, eq. 7.34 / II.33), and the
/// condition number of R after scaling its columns to unit norm (so it measures
/// collinearity of the regressors, not their units).
#include <Eigen/Dense>
#include <string>
#include <vector>

namespace sysid {

struct RegressionTerm {
  Eigen::Index signal = 0;  ///< column of the signal matrices
  int first_lag = 1;        ///< lag of the first coefficient (>= 0; 0 only for a signal other than the target)
  int count = 0;            ///< number of coefficients (>= 0)
  double sign = 1.0;        ///< -1 for the A-polynomial convention A(q) y = ...
};

struct RegressionSolution {
  Eigen::VectorXd theta;         ///< coefficients in the order of the terms, then lags
  Eigen::MatrixXd covariance;    ///< p x p
  double residual_variance = 0;  ///< ||e||^2 / (rows - p)
  double residual_sum_of_squares = 0;
  Eigen::Index rows = 0;         ///< equations used
  double condition = 0;          ///< of the column-scaled R
  bool rank_deficient = false;
};

/// Purpose: the regression of the file comment; signals[e] is experiment e's
/// N_e x s matrix of signals, `target` the column to explain.
/// Preconditions (std::invalid_argument): at least one term with count > 0;
/// signal indices in range; first_lag >= 1 for the target signal; more
/// equations than parameters in total.
RegressionSolution lagged_least_squares(const std::vector<Eigen::MatrixXd>& signals, Eigen::Index target,
                                        const std::vector<RegressionTerm>& terms);

}  // namespace sysid
