#pragma once
/// @file
/// Purpose: the Kalman gain K and innovation covariance of a model whose A and C
/// are known, from the residuals v = y - G u of its deterministic part: the
/// forward innovation model
///
///   x[k+1] = A x[k] + K e[k],   v[k] = C x[k] + e[k],   cov(e) = Lambda0 - C P C^T,
///
/// that reproduces the sample covariances of v. Used where the projections of
/// the subspace step do not give K at the model's own rate (n4sid on a
/// decimated grid) and wherever a deterministic model needs a noise model.
///
/// Method: covariance-based stochastic realisation (P. Faurre, "Stochastic
/// realization algorithms", in System Identification: Advances and Case
/// Studies, 1976; Van Overschee & De Moor 1996, sec. 3.1.2):
///  1. sample covariances Lambda_k = E[v(t+k) v(t)^T], k = 0..lags;
///  2. Lambda_k = C A^{k-1} G for k >= 1: G = E[x(t+1) v(t)^T] by least squares
///     on the stacked [C; C A; ...; C A^{lags-1}] G = [Lambda_1; ...; Lambda_lags]
///     (complete orthogonal decomposition, not normal equations);
///  3. the forward Riccati iteration from P_0 = 0,
///       P_{j+1} = A P_j A^T + (G - A P_j C^T)(Lambda0 - C P_j C^T)^{-1}(G - A P_j C^T)^T,
///     increases monotonically to the minimal solution when the covariance
///     sequence is positive real (Faurre 1976); then
///       K = (G - A P C^T)(Lambda0 - C P C^T)^{-1},  cov(e) = Lambda0 - C P C^T.
///     Sample covariances need not be positive real: when Lambda0 - C P C^T
///     stops being positive definite, residuals that look white (every
///     normalised lag covariance below 3/sqrt(N)) get K = 0; otherwise the
///     result says so and carries no K.
///
/// Preconditions: A n x n stable, C l x n, every residual block l columns with
/// more rows than lags; violations throw std::invalid_argument.
/// Numerical aspects: O(N l^2 lags) for the covariances, O(iterations n^3) for
/// the iteration, which converges like rho(A - K C)^{2j}: slow for lightly
/// damped noise models, hence the generous default cap.
#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

struct InnovationModelOptions {
  /// Covariance lags used to estimate G; 0 = max(10, 2 ceil(n / l)).
  int lags = 0;
  int max_iterations = 200000;
  /// Stop when ||P_{j+1} - P_j||_F <= tolerance * max(||P_{j+1}||_F, ||Lambda0||_F).
  double tolerance = 1e-12;
};

struct InnovationModelResult {
  enum class Status { converged, not_converged, not_positive_real };
  Status status = Status::not_converged;
  Eigen::MatrixXd K;                      ///< n x l (empty unless converged)
  Eigen::MatrixXd innovation_covariance;  ///< l x l, Lambda0 - C P C^T (Lambda0 unless converged)
  Eigen::MatrixXd G;                      ///< E[x(t+1) v(t)^T], n x l
  Eigen::MatrixXd P;                      ///< state covariance of the innovation model
  Eigen::MatrixXd lambda0;                ///< sample covariance of the residuals
  int iterations = 0;
  int lags = 0;
  std::string message;
};

/// Sample covariances Lambda_k = sum over blocks and t of v(t+k) v(t)^T / (total rows), k = 0..lags.
inline std::vector<Eigen::MatrixXd> residual_covariances(const std::vector<Eigen::MatrixXd>& residuals, int lags) {
  if (residuals.empty()) throw std::invalid_argument("innovation model: need at least one residual block");
  const Eigen::Index l = residuals.front().cols();
  std::vector<Eigen::MatrixXd> lambda(static_cast<std::size_t>(lags) + 1, Eigen::MatrixXd::Zero(l, l));
  double count = 0;
  for (const Eigen::MatrixXd& v : residuals) {
    if (v.cols() != l) throw std::invalid_argument("innovation model: residual blocks differ in their number of columns");
    if (v.rows() <= lags) throw std::invalid_argument("innovation model: need more residual samples than lags in every block");
    count += static_cast<double>(v.rows());
    for (int k = 0; k <= lags; ++k)
      lambda[static_cast<std::size_t>(k)] += v.bottomRows(v.rows() - k).transpose() * v.topRows(v.rows() - k);
  }
  for (auto& c : lambda) c /= count;
  return lambda;
}

/// True when every normalised lag covariance Lambda_k(i,j) / sqrt(Lambda_0(i,i) Lambda_0(j,j)),
/// k >= 1, is below 3 / sqrt(N): the residuals look white (Ljung 1999, sec. 16.6).
inline bool white_residuals(const std::vector<Eigen::MatrixXd>& lambda, Eigen::Index samples) {
  const Eigen::VectorXd scale = lambda[0].diagonal().cwiseMax(1e-300).cwiseSqrt();
  const double bound = 3.0 / std::sqrt(static_cast<double>(samples));
  for (std::size_t k = 1; k < lambda.size(); ++k) {
    const Eigen::MatrixXd normalised = scale.cwiseInverse().asDiagonal() * lambda[k] * scale.cwiseInverse().asDiagonal();
    if (normalised.cwiseAbs().maxCoeff() >= bound) return false;
  }
  return true;
}

/// Purpose: the innovation model described in the file comment.
/// Example: `auto nm = innovation_model(A, C, {y - y_sim});  if (nm.status == ...converged) K = nm.K;`
inline InnovationModelResult innovation_model(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C,
                                              const std::vector<Eigen::MatrixXd>& residuals,
                                              const InnovationModelOptions& options = {}) {
  const Eigen::Index n = A.rows(), l = C.rows();
  if (A.cols() != n || C.cols() != n || n < 1 || l < 1)
    throw std::invalid_argument("innovation model: need A n x n and C l x n with n, l >= 1");
  if (!residuals.empty() && residuals.front().cols() != l)
    throw std::invalid_argument("innovation model: residuals have " + std::to_string(residuals.front().cols()) +
                                " columns, C has " + std::to_string(l) + " rows");
  InnovationModelResult out;
  out.lags = options.lags > 0 ? options.lags : std::max(10, 2 * static_cast<int>((n + l - 1) / l));
  const std::vector<Eigen::MatrixXd> lambda = residual_covariances(residuals, out.lags);
  Eigen::Index total_samples = 0;
  for (const auto& v : residuals) total_samples += v.rows();
  out.lambda0 = 0.5 * (lambda[0] + lambda[0].transpose());
  out.innovation_covariance = out.lambda0;

  // Step 2: G from Lambda_k = C A^{k-1} G.
  Eigen::MatrixXd observability(out.lags * l, n), stacked(out.lags * l, l);
  Eigen::MatrixXd ca = C;
  for (int k = 0; k < out.lags; ++k) {
    observability.middleRows(k * l, l) = ca;
    stacked.middleRows(k * l, l) = lambda[static_cast<std::size_t>(k) + 1];
    ca = ca * A;
  }
  out.G = observability.completeOrthogonalDecomposition().solve(stacked);

  // Step 3: forward Riccati iteration from P = 0.
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(n, n);
  const double scale = std::max(out.lambda0.norm(), 1e-300);
  for (int j = 1; j <= options.max_iterations; ++j) {
    const Eigen::MatrixXd cov = out.lambda0 - C * P * C.transpose();
    Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (cov + cov.transpose()));
    if (llt.info() != Eigen::Success) {
      out.iterations = j;
      if (white_residuals(lambda, total_samples)) {
        // Sample covariances of white residuals often miss positive realness by
        // sampling error alone; their innovation model is K = 0, cov(e) = Lambda0.
        out.status = InnovationModelResult::Status::converged;
        out.K = Eigen::MatrixXd::Zero(n, l);
        out.P = Eigen::MatrixXd::Zero(n, n);
        out.message = "residuals white within 3/sqrt(N) at every lag: K = 0";
        return out;
      }
      out.status = InnovationModelResult::Status::not_positive_real;
      out.message = "the residual covariances are not positive real for this (A, C): no innovation model";
      return out;
    }
    const Eigen::MatrixXd gain_num = out.G - A * P * C.transpose();
    const Eigen::MatrixXd next = A * P * A.transpose() + gain_num * llt.solve(gain_num.transpose());
    const double change = (next - P).norm();
    P = 0.5 * (next + next.transpose());
    if (change <= options.tolerance * std::max(P.norm(), scale)) {
      const Eigen::MatrixXd final_cov = out.lambda0 - C * P * C.transpose();
      Eigen::LLT<Eigen::MatrixXd> final_llt(0.5 * (final_cov + final_cov.transpose()));
      if (final_llt.info() != Eigen::Success) break;
      out.status = InnovationModelResult::Status::converged;
      out.iterations = j;
      out.P = P;
      out.innovation_covariance = 0.5 * (final_cov + final_cov.transpose());
      out.K = final_llt.solve((out.G - A * P * C.transpose()).transpose()).transpose();
      return out;
    }
  }
  out.iterations = options.max_iterations;
  out.message = "the Riccati iteration did not converge in " + std::to_string(options.max_iterations) + " iterations";
  return out;
}

}  // namespace sysid
