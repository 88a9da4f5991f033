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
#include <stdexcept>
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

inline KalmanFilterResult steady_state_kalman_filter(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, const Eigen::MatrixXd& Q,
                                                     const Eigen::MatrixXd& R, const Eigen::MatrixXd& S,
                                                     const KalmanFilterOptions& options = {}) {
  const Eigen::Index n = A.rows(), l = C.rows();
  if (A.cols() != n || C.cols() != n || Q.rows() != n || Q.cols() != n || R.rows() != l || R.cols() != l || S.rows() != n ||
      S.cols() != l)
    throw std::invalid_argument("kalman: inconsistent dimensions of A, C, Q, R, S");
  KalmanFilterResult out;
  Eigen::LLT<Eigen::MatrixXd> r_llt(0.5 * (R + R.transpose()));
  if (r_llt.info() != Eigen::Success) {
    out.message = "measurement noise covariance R is not positive definite";
    return out;
  }
  const Eigen::MatrixXd s_rinv = r_llt.solve(S.transpose()).transpose();  // S R^-1
  // Dual (control-form) data: A_c = A_s^T, G = C^T R^-1 C, H = Q_s.
  Eigen::MatrixXd a = (A - s_rinv * C).transpose();
  Eigen::MatrixXd g = C.transpose() * r_llt.solve(C);
  Eigen::MatrixXd h = Q - s_rinv * S.transpose();
  h = 0.5 * (h + h.transpose());
  g = 0.5 * (g + g.transpose());
  const Eigen::MatrixXd eye = Eigen::MatrixXd::Identity(n, n);
  out.status = KalmanFilterResult::Status::not_converged;
  for (int it = 1; it <= options.max_iterations; ++it) {
    Eigen::PartialPivLU<Eigen::MatrixXd> w(eye + g * h);
    const Eigen::MatrixXd w_a = w.solve(a);  // (I + G H)^-1 A
    const Eigen::MatrixXd w_g = w.solve(g);  // (I + G H)^-1 G
    Eigen::MatrixXd h_next = h + a.transpose() * h * w_a;
    Eigen::MatrixXd g_next = g + a * w_g * a.transpose();
    a = a * w_a;
    h_next = 0.5 * (h_next + h_next.transpose());
    g = 0.5 * (g_next + g_next.transpose());
    const double change = (h_next - h).norm(), size = h_next.norm();
    h = std::move(h_next);
    out.iterations = it;
    if (!h.allFinite()) {
      out.status = KalmanFilterResult::Status::failed;
      out.message = "doubling iteration diverged (system not detectable/stabilisable?)";
      return out;
    }
    if (change <= options.tolerance * std::max(size, 1e-300)) {
      out.status = KalmanFilterResult::Status::converged;
      break;
    }
  }
  out.P = h;
  const Eigen::MatrixXd cp = C * out.P;
  out.innovation_covariance = cp * C.transpose() + R;
  out.innovation_covariance = 0.5 * (out.innovation_covariance + out.innovation_covariance.transpose());
  out.K = (A * cp.transpose() + S) * out.innovation_covariance.inverse();
  if (out.status != KalmanFilterResult::Status::converged)
    out.message = "Riccati doubling did not converge in " + std::to_string(options.max_iterations) + " iterations";
  return out;
}

}  // namespace sysid
