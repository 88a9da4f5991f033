// Implementation of core/discrete_riccati.hpp (method and references in the header).
#include <sysid/core/discrete_riccati.hpp>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace sysid {

KalmanFilterResult steady_state_kalman_filter(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, const Eigen::MatrixXd& Q,
                                              const Eigen::MatrixXd& R, const Eigen::MatrixXd& S,
                                              const KalmanFilterOptions& options) {
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
