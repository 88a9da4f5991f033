// Implementation of core/levenberg_marquardt.hpp (method and references in the header).
#include <sysid/core/levenberg_marquardt.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace sysid {

LevenbergMarquardt::LevenbergMarquardt(Problem& problem, const Options& options)
    : m_problem(problem), m_options(options) {
  m_n = m_problem.parameter_count();
  m_residuals = m_problem.residual_count();
  m_summary.damping = m_options.initial_damping;
  m_cost = m_problem.cost();
  m_summary.initial_cost = m_cost;
  m_summary.cost_history.push_back(m_cost);
  m_eliminate = m_problem.eliminates_linear_part();
  if (m_eliminate) {
    m_cost = m_problem.eliminate_linear_part(m_cost);
    if (m_cost < m_summary.initial_cost) m_summary.cost_history.push_back(m_cost);
  }
  m_x = m_problem.parameters();
  m_summary.r = m_problem.jacobian_factor();
  m_summary.status = Status::max_iterations;
  m_summary.termination = "reached max_iterations (" + std::to_string(m_options.max_iterations) + ")";
}

LevenbergMarquardt::LevenbergMarquardt(Problem& problem) : LevenbergMarquardt(problem, Options{}) {}

bool LevenbergMarquardt::iterate() {
  if (m_ended) return false;
  const Eigen::Index p = m_n;
  double& lambda = m_summary.damping;
  if (m_need_factor) m_summary.r = m_problem.jacobian_factor();
  m_need_factor = false;
  const Eigen::MatrixXd& r = m_summary.r;
  const Eigen::MatrixXd r11 = r.topLeftCorner(p, p).triangularView<Eigen::Upper>();
  const Eigen::VectorXd r12 = r.col(p).head(p);
  const Eigen::VectorXd gradient = r11.transpose() * r12;  // J^T eps
  if (gradient.cwiseAbs().maxCoeff() <= m_options.gradient_tolerance * (1.0 + m_cost)) {
    m_summary.status = Status::converged;
    m_summary.termination = "gradient below tolerance";
    return end();
  }
  // The full Gauss-Newton step dtheta = -R11^-1 r12 has Mahalanobis length
  // ||r12|| / sigma in the metric of the parameter covariance sigma^2 (J^T J)^-1
  // (Ljung 1999, eq. 9.17): below a fraction of one standard deviation, further
  // iterations change nothing the data can distinguish.
  const double sigma2 = 2.0 * m_cost / std::max(1.0, static_cast<double>(m_residuals - p));
  // Rounding in an ill-conditioned or over-parametrised Jacobian can hide the
  // last decrease; it is "working precision" when the Gauss-Newton minimiser
  // lies inside the parameters' confidence region, ||r12||^2 / sigma^2 <= p
  // (the mean of the chi-square(p) that bounds it).
  const bool inside_confidence_region = r12.squaredNorm() <= static_cast<double>(p) * sigma2;
  if (m_options.step_significance_tolerance > 0 &&
      r12.squaredNorm() <= m_options.step_significance_tolerance * m_options.step_significance_tolerance * sigma2) {
    m_summary.status = Status::converged;
    std::ostringstream why;
    why << "Gauss-Newton step below " << m_options.step_significance_tolerance << " standard deviations of the parameters";
    m_summary.termination = why.str();
    return end();
  }
  ++m_iteration;
  // Marquardt scaling by the column norms of J (= those of R11).
  Eigen::VectorXd scale = r11.colwise().norm().transpose();
  for (Eigen::Index k = 0; k < p; ++k) scale(k) = std::max(scale(k), 1e-12 * std::max(1.0, scale.maxCoeff()));
  bool accepted = false;
  int rejected = 0;  // a step accepted only after rejections is short because of the damping, not convergence
  while (!accepted) {
    Eigen::MatrixXd stacked(2 * p, p);
    stacked << r11, std::sqrt(lambda) * scale.asDiagonal().toDenseMatrix();
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * p);
    rhs.head(p) = -r12;
    Eigen::VectorXd step = stacked.householderQr().solve(rhs);
    bool feasible = m_problem.set_candidate(m_x + step);
    // A step that leaves the feasible region (for pem: the stable one) is shortened
    // along its direction first (the quadratic model stays right; only the
    // constraint bites): cheaper than raising the damping, which turns the step
    // towards the gradient.
    double fraction = 1.0;
    while (!feasible && fraction > 0.1) {
      fraction *= 0.5;
      feasible = m_problem.set_candidate(m_x + fraction * step);
    }
    step *= fraction;
    const double predicted = 0.5 * (r12.squaredNorm() - (r11 * step + r12).squaredNorm());
    double trial_cost = std::numeric_limits<double>::infinity();
    if (feasible) trial_cost = m_problem.candidate_cost();
    const double rho = predicted > 0 ? (m_cost - trial_cost) / predicted : -1.0;
    if (std::isfinite(trial_cost) && rho > 0) {
      // The damping follows rho, the quality of the Gauss-Newton model for
      // the joint step; the projection's further gain is then taken on top.
      if (m_eliminate) {
        trial_cost = m_problem.eliminate_linear_part_of_candidate(trial_cost);
        step = m_problem.candidate_parameters() - m_x;
      }
      const double decrease = m_cost - trial_cost;
      const bool small_step = step.norm() <= m_options.parameter_tolerance * (m_x.norm() + m_options.parameter_tolerance);
      m_x += step;
      m_problem.accept_candidate();
      m_cost = trial_cost;
      m_summary.cost_history.push_back(m_cost);
      // Nielsen (1999), but a step the quadratic model predicted well (rho > 0.75)
      // shrinks the damping tenfold: on ill-conditioned problems the damped step
      // is otherwise tiny for dozens of iterations.
      // Consecutive such steps at the first try shrink it faster and faster
      // (0.1, 0.01, 1e-3, then 1e-4 each): the damping that suits an ill-conditioned
      // problem can lie ten decades below the start. A step shortened by
      // the stability constraint leaves the damping as it is.
      if (fraction < 1.0) {
      } else if (rho > 0.75) {
        lambda *= m_shrink;
        if (rejected == 0) m_shrink = std::max(m_shrink * 0.1, 1e-4);
      } else {
        lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
      }
      if (rejected > 0 || rho <= 0.75) m_shrink = 0.1;
      m_nu = 2.0;
      accepted = true;
      m_need_factor = true;
      // The decrease and step-length tests only mean convergence for a step
      // close to the Gauss-Newton one: a strongly damped step is short and
      // gains little because of the damping.
      // A step of relative length 1e-9 after rejections moves the parameters
      // by rounding only: what it "gains" is the cost's own rounding noise
      // (with C next to the unit circle, that noise is of the order of sigma^2).
      const bool rounding_step = step.norm() <= 1e-9 * (m_x.norm() + 1e-9);
      if (rejected > 0 && (decrease <= 1e-3 * sigma2 || rounding_step) && inside_confidence_region) {
        // Damping had to grow and the step gained nothing the data resolve.
        m_summary.status = Status::converged;
        m_summary.termination = "no step lowers the cost appreciably (minimum to working precision: the Gauss-Newton "
                                "minimiser lies inside the parameters' confidence region)";
      } else if (rejected > 0 || predicted < 0.25 * r12.squaredNorm()) {
      } else if (decrease <= m_options.function_tolerance * m_cost) {
        m_summary.status = Status::converged;
        m_summary.termination = "relative cost decrease below tolerance";
      } else if (small_step) {
        m_summary.status = Status::converged;
        m_summary.termination = "step below tolerance";
      }
    } else {
      lambda *= m_nu;
      m_nu *= 2.0;
      ++rejected;
      if (lambda > m_options.max_damping) break;
    }
  }
  if (m_summary.status == Status::converged) return end();
  if (!accepted) {
    // No damped step lowers the cost: at a minimum to working precision, or
    // stuck. Working precision when the Gauss-Newton minimiser lies inside the
    // parameters' confidence region, ||r12||^2 / sigma^2 <= p (the mean of the
    // chi-square(p) that bounds it): rounding in an ill-conditioned or
    // over-parametrised Jacobian then hides a decrease the data cannot resolve.
    const bool flat = gradient.cwiseAbs().maxCoeff() <= 1e-6 * (1.0 + m_cost) || inside_confidence_region;
    m_summary.status = flat ? Status::converged : Status::failed;
    m_summary.termination = flat ? "no step lowers the cost further (minimum to working precision: the Gauss-Newton "
                                   "minimiser lies inside the parameters' confidence region)"
                                 : "no step lowers the cost although the gradient is not small (damping limit reached)";
    return end();
  }
  return true;
}

void LevenbergMarquardt::iterate_up_to(int max_iterations) {
  while (m_iteration < max_iterations && iterate()) {
  }
}

LevenbergMarquardt::Summary LevenbergMarquardt::finish() {
  m_summary.iterations = m_iteration;
  m_summary.final_cost = m_cost;
  if (m_need_factor) m_summary.r = m_problem.jacobian_factor();
  m_need_factor = false;
  return m_summary;
}

LevenbergMarquardt::Summary LevenbergMarquardt::solve(Problem& problem, const Options& options) {
  LevenbergMarquardt lm(problem, options);
  lm.iterate_up_to(options.max_iterations);
  return lm.finish();
}

LevenbergMarquardt::Summary LevenbergMarquardt::solve(Problem& problem) { return solve(problem, Options{}); }

bool LevenbergMarquardt::end() {
  m_ended = true;
  return false;
}

std::string LevenbergMarquardt::Summary::brief_report() const {
  std::ostringstream s;
  s << (status == Status::converged ? "converged" : status == Status::max_iterations ? "max_iterations" : "failed") << " ("
    << termination << ") after " << iterations << " iterations, cost " << initial_cost << " -> " << final_cost;
  return s.str();
}

}  // namespace sysid
