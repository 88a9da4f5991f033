// pem's prediction-error cost as a LevenbergMarquardt::Problem (src/pem/detail/pem_problem.hpp).
#include <sysid/core/levenberg_marquardt.hpp>
#include <sysid/pem/prediction_error.hpp>

#include <utility>
#include <vector>

#include "pem/detail/pem_jacobian.hpp"
#include "pem/detail/pem_problem.hpp"
#include "pem/detail/polynomial_utilities.hpp"
#include "pem/detail/variable_projection.hpp"

namespace sysid::detail::pem_impl {

PemProblem::PemProblem(PolynomialModel& model, const std::vector<ScaledRecord>& records, Eigen::Index parameters,
                       bool variable_projection)
    : m_model(model), m_records(records), m_p(parameters) {
  for (const auto& r : m_records) m_samples += r.y.size();
  m_project = variable_projection && separable(m_model);
}

Eigen::VectorXd PemProblem::parameters() const { return pack_parameters(m_model); }

double PemProblem::cost() { return cost_of(m_model, m_records, &m_eps); }

Eigen::MatrixXd PemProblem::jacobian_factor() {
  return pem_impl::jacobian_factor(m_model, m_records, m_p, &m_by_c, &m_eps);
}

bool PemProblem::set_candidate(const Eigen::VectorXd& theta) {
  m_trial = m_model;
  unpack_parameters(theta, m_trial);
  return denominators_stable(m_trial);
}

double PemProblem::candidate_cost() { return cost_of(m_trial, m_records, &m_trial_eps); }

void PemProblem::accept_candidate() {
  m_model = m_trial;
  m_eps = std::move(m_trial_eps);
}

double PemProblem::eliminate_linear_part(double cost) {
  return project_linear_part(m_model, m_records, cost, m_by_c, m_eps);
}

double PemProblem::eliminate_linear_part_of_candidate(double cost) {
  return project_linear_part(m_trial, m_records, cost, m_by_c, m_trial_eps);
}

Eigen::VectorXd PemProblem::candidate_parameters() const { return pack_parameters(m_trial); }

LevenbergMarquardt::Options levenberg_marquardt_options(const PemOptions& options) {
  LevenbergMarquardt::Options o;
  o.max_iterations = options.max_iterations;
  o.gradient_tolerance = options.gradient_tolerance;
  o.step_significance_tolerance = options.step_significance_tolerance;
  o.function_tolerance = options.function_tolerance;
  o.parameter_tolerance = options.parameter_tolerance;
  return o;
}

PemResult::Status pem_status(LevenbergMarquardt::Status status) {
  switch (status) {
    case LevenbergMarquardt::Status::converged: return PemResult::Status::converged;
    case LevenbergMarquardt::Status::max_iterations: return PemResult::Status::max_iterations;
    case LevenbergMarquardt::Status::failed: return PemResult::Status::failed;
  }
  return PemResult::Status::failed;
}

LevenbergMarquardt::Summary levenberg_marquardt(PolynomialModel& model, const std::vector<ScaledRecord>& records,
                                                Eigen::Index p, const PemOptions& options) {
  PemProblem problem(model, records, p, options.variable_projection);
  return LevenbergMarquardt::solve(problem, levenberg_marquardt_options(options));
}

}  // namespace sysid::detail::pem_impl
