#pragma once
/// @file
/// Purpose: the steady-state Kalman filter of a discrete-time system with
/// process noise w, measurement noise v and E[[w;v][w;v]^T] = [Q S; S^T R]:
///
///   x[k+1] = A x[k] + B u[k] + K e[k],   y[k] = C x[k] + D u[k] + e[k],
///   cov(e) = C P C^T + R,   K = (A P C^T + S)(C P C^T + R)^-1,
///
/// where P >= 0 solves the filter algebraic Riccati equation
///   P = A P A^T - (A P C^T + S)(C P C^T + R)^-1 (A P C^T + S)^T + Q.
///
/// Method: the cross term is removed (A_s = A - S R^-1 C, Q_s = Q - S R^-1 S^T),
/// then the structure-preserving doubling algorithm solves the dual control-form
/// equation (E. K.-W. Chu, H.-Y. Fan, W.-W. Lin, "A structure-preserving doubling
/// algorithm for discrete-time algebraic Riccati equations", Linear Algebra
/// Appl. 396 (2005) 55-80, eqs. (2.3)-(2.5)). Quadratic convergence; each step
/// costs a few n x n solves.
///
/// Preconditions: R > 0 (positive definite), [Q S; S^T R] >= 0,
/// (A, C) detectable and (A_s, Q_s^1/2) stabilisable (no uncontrollable mode on
/// the unit circle). Violations show as non-convergence: status, not exception.
#include <Eigen/Dense>
#include <string>

namespace sysid {

struct KalmanFilterResult {
  enum class Status { converged, not_converged, failed };
  Status status = Status::failed;
  Eigen::MatrixXd P;                     ///< state error covariance (n x n)
  Eigen::MatrixXd K;                     ///< Kalman gain, innovation form (n x l)
  Eigen::MatrixXd innovation_covariance;  ///< C P C^T + R (l x l)
  int iterations = 0;
  std::string message;
};

struct KalmanFilterOptions {
  int max_iterations = 100;
  /// Stop when ||H_{k+1} - H_k||_F <= tolerance * ||H_{k+1}||_F (relative change of the iterate).
  double tolerance = 1e-13;
};

/// Purpose: the steady-state Kalman filter of (A, C) with noise covariances Q, R and
/// cross covariance S (file comment).
/// Preconditions: A n x n, C l x n, Q n x n, R l x l, S n x l (std::invalid_argument
/// otherwise); the rest as in the file comment (violations: status, not exception).
KalmanFilterResult steady_state_kalman_filter(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C,
                                              const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R,
                                              const Eigen::MatrixXd& S,
                                              const KalmanFilterOptions& options = {});

}  // namespace sysid
