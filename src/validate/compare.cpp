// Implementation of validate/compare.hpp (methods and references are in the header).
// Compiled once into libsysid: the complete orthogonal decomposition and the eigenvalue
// solver used here are heavy to instantiate in every file that includes the header.
#include <sysid/validate/compare.hpp>

#include <sysid/core/flush_subnormals.hpp>
#include <sysid/core/simulate.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sysid {

namespace {

/// compare()'s checks of its options against the model.
void check_offsets(const StateSpace& sys, const CompareOptions& o) {
  if (o.input_offset.size() != 0 && o.input_offset.size() != sys.inputs())
    throw std::invalid_argument("compare: need input_offset of size " + std::to_string(sys.inputs()) + " or empty");
  if (o.output_offset.size() != 0 && o.output_offset.size() != sys.outputs())
    throw std::invalid_argument("compare: need output_offset of size " + std::to_string(sys.outputs()) + " or empty");
  if (o.predict_steps < 0) throw std::invalid_argument("compare: need predict_steps >= 0");
}

}  // namespace

Eigen::VectorXd estimate_initial_state(const StateSpace& sys, const Eigen::MatrixXd& u, const Eigen::MatrixXd& y,
                                       Eigen::Index max_samples) {
  if (max_samples < 1) throw std::invalid_argument("estimate_initial_state: need max_samples >= 1");
  if (u.rows() != y.rows())
    throw std::invalid_argument("estimate_initial_state: need u.rows() == y.rows() (" + std::to_string(u.rows()) +
                                " != " + std::to_string(y.rows()) + ")");
  if (y.cols() != sys.outputs())
    throw std::invalid_argument("estimate_initial_state: need y.cols() == outputs (" + std::to_string(y.cols()) +
                                " != " + std::to_string(sys.outputs()) + ")");
  if (y.rows() < 1) throw std::invalid_argument("estimate_initial_state: need at least 1 sample");
  const Eigen::Index n = sys.order(), l = sys.outputs();
  if (n == 0) return Eigen::VectorXd();
  const Eigen::Index samples = std::min(y.rows(), max_samples);
  const Eigen::MatrixXd y0 = simulate(sys, u.topRows(samples));
  Eigen::MatrixXd obs(samples * l, n);
  Eigen::VectorXd rhs(samples * l);
  // C A^t decays through the subnormal range over a long record (core/flush_subnormals.hpp).
  const ScopedFlushSubnormals flush;
  Eigen::MatrixXd lambda = sys.C;  // C A^t
  for (Eigen::Index t = 0; t < samples; ++t) {
    obs.middleRows(t * l, l) = lambda;
    rhs.segment(t * l, l) = (y.row(t) - y0.row(t)).transpose();
    lambda = lambda * sys.A;
  }
  Eigen::VectorXd scale = obs.colwise().norm().transpose();
  for (Eigen::Index c = 0; c < n; ++c)
    if (!(scale(c) > 0) || !std::isfinite(scale(c))) scale(c) = 1.0;
  obs = obs * scale.cwiseInverse().asDiagonal();
  const Eigen::VectorXd z = obs.completeOrthogonalDecomposition().solve(rhs);
  return z.cwiseQuotient(scale);
}

Eigen::MatrixXd predict_k_step(const StateSpace& sys, const Eigen::MatrixXd& K, const Eigen::MatrixXd& u,
                               const Eigen::MatrixXd& y, int k, const Eigen::VectorXd& x0) {
  detail::check_simulation_args(sys, u.cols(), x0, "predict_k_step");
  const Eigen::Index n = sys.order(), l = sys.outputs(), N = u.rows();
  if (k < 1) throw std::invalid_argument("predict_k_step: need k >= 1");
  if (y.rows() != N || y.cols() != l)
    throw std::invalid_argument("predict_k_step: need y to be " + std::to_string(N) + " x " + std::to_string(l) + ", is " +
                                std::to_string(y.rows()) + " x " + std::to_string(y.cols()));
  if (K.rows() != n || K.cols() != l)
    throw std::invalid_argument("predict_k_step: need K to be " + std::to_string(n) + " x " + std::to_string(l) + ", is " +
                                std::to_string(K.rows()) + " x " + std::to_string(K.cols()));
  const Eigen::VectorXd x_init = x0.size() == 0 ? Eigen::VectorXd(Eigen::VectorXd::Zero(n)) : x0;
  if (static_cast<Eigen::Index>(k) >= N) return simulate(sys, u, x_init);

  // Filter states xf[s] = x^[s|s-1], s = 0..N-1, as columns (n x N).
  Eigen::MatrixXd xf(n, N);
  const ScopedFlushSubnormals flush;  // the filter's state decays where u and y are zero (core/flush_subnormals.hpp)
  {
    const Eigen::MatrixXd F = sys.A - K * sys.C;
    const Eigen::MatrixXd G = sys.B - K * sys.D;
    Eigen::MatrixXd drive(n, N);  // (B - K D) u[s] + K y[s]
    drive.noalias() = G * u.transpose();
    drive.noalias() += K * y.transpose();
    xf.col(0) = x_init;
    for (Eigen::Index s = 0; s + 1 < N; ++s) xf.col(s + 1).noalias() = F * xf.col(s) + drive.col(s);
  }
  if (k == 1) {
    Eigen::MatrixXd yhat = xf.transpose() * sys.C.transpose();
    yhat.noalias() += u * sys.D.transpose();
    return yhat;
  }

  const Eigen::Index kk = k;
  Eigen::MatrixXd xp(n, N);  // x^[t|t-k]
  // t < k: open-loop from x0 (no measurement old enough to use).
  xp.leftCols(kk) = simulate_states(sys, u.topRows(kk), x_init).transpose();
  const double radius = n > 0 ? sys.A.eigenvalues().cwiseAbs().maxCoeff() : 0.0;
  if (radius < 1.0) {
    const Eigen::MatrixXd z = simulate_states(sys, u).transpose();  // n x N, zero initial state
    Eigen::MatrixXd ak = Eigen::MatrixXd::Identity(n, n);
    for (int p = 0; p < k - 1; ++p) ak = ak * sys.A;
    // Columns t = k..N-1 start from s = t-k+1 = 1..N-k.
    const Eigen::MatrixXd dev = xf.middleCols(1, N - kk) - z.middleCols(1, N - kk);
    xp.rightCols(N - kk).noalias() = ak * dev;
    xp.rightCols(N - kk) += z.rightCols(N - kk);
  } else {
    const Eigen::MatrixXd Bu = sys.B * u.transpose();  // n x N
    Eigen::VectorXd x(n);
    for (Eigen::Index t = kk; t < N; ++t) {
      x = xf.col(t - kk + 1);
      for (Eigen::Index j = t - kk + 1; j < t; ++j) x = sys.A * x + Bu.col(j);
      xp.col(t) = x;
    }
  }
  Eigen::MatrixXd yhat = xp.transpose() * sys.C.transpose();
  yhat.noalias() += u * sys.D.transpose();
  return yhat;
}

CompareResult compare(const StateSpace& sys, const Eigen::MatrixXd& K, const Experiment& data, const CompareOptions& options) {
  check_offsets(sys, options);
  if (data.u.rows() != data.y.rows()) throw std::invalid_argument("compare: u and y differ in length");
  if (data.u.cols() != sys.inputs() || data.y.cols() != sys.outputs())
    throw std::invalid_argument("compare: data has " + std::to_string(data.u.cols()) + " input(s) and " +
                                std::to_string(data.y.cols()) + " output(s), the model " + std::to_string(sys.inputs()) +
                                " and " + std::to_string(sys.outputs()));
  if (options.predict_steps > 0 && K.size() == 0)
    throw std::invalid_argument("compare: k-step prediction needs the Kalman gain K (the model has none)");
  Eigen::MatrixXd u = data.u, y = data.y;
  if (options.input_offset.size() != 0) u.rowwise() -= options.input_offset.transpose();
  if (options.output_offset.size() != 0) y.rowwise() -= options.output_offset.transpose();

  CompareResult r;
  if (options.estimate_x0)
    r.x0 = estimate_initial_state(sys, u, y, options.x0_max_samples);
  else
    r.x0 = options.x0.size() == 0 ? Eigen::VectorXd(Eigen::VectorXd::Zero(sys.order())) : options.x0;
  r.y_hat = options.predict_steps == 0 ? simulate(sys, u, r.x0) : predict_k_step(sys, K, u, y, options.predict_steps, r.x0);
  r.fit_percent = fit_percent(y, r.y_hat);
  if (options.output_offset.size() != 0) r.y_hat.rowwise() += options.output_offset.transpose();
  return r;
}

Eigen::VectorXd compare_fit(const StateSpace& sys, const Eigen::MatrixXd& K, const IoData& data,
                            const CompareOptions& options) {
  data.validate();
  FitAccumulator fit(data.outputs());
  for (const Experiment& e : data.experiments) fit.add_residual(e.y, e.y - compare(sys, K, e, options).y_hat);
  return fit.fit_percent();
}

}  // namespace sysid
