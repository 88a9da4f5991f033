#pragma once
// Internal to src/pem: the prediction-error cost of a polynomial model as a
// LevenbergMarquardt::Problem (core/levenberg_marquardt.hpp), in scaled units
// (src/pem/pem_problem.cpp). The solver steps in the packed parameter vector
// (pack_parameters); the problem keeps the model, its prediction errors and the
// variable projection's filtered signals, which the Jacobian factor at the same
// C reuses.
#include <sysid/core/levenberg_marquardt.hpp>
#include <sysid/pem/polynomial_model.hpp>
#include <sysid/pem/prediction_error.hpp>

#include <Eigen/Dense>

#include <vector>

#include "pem/detail/pem_jacobian.hpp"

namespace sysid::detail::pem_impl {

/// F(theta) = 1/2 sum over the records of eps(t, theta)^2, the model's one-step
/// prediction errors. The domain: C, D and every F_i strictly stable (a step that
/// leaves it is shortened by the solver). With variable projection (ARMA/ARMAX,
/// PemOptions::variable_projection) A and B are re-solved by least squares for
/// the current C at the start and after every accepted step.
class PemProblem final : public LevenbergMarquardt::Problem {
 public:
  /// `model` (the current point, updated in place) and `records` must outlive the
  /// problem; `parameters` = pack_parameters(model).size().
  PemProblem(PolynomialModel& model, const std::vector<ScaledRecord>& records, Eigen::Index parameters,
             bool variable_projection);

  Eigen::Index residual_count() const override { return m_samples; }
  Eigen::Index parameter_count() const override { return m_p; }
  Eigen::VectorXd parameters() const override;
  double cost() override;
  Eigen::MatrixXd jacobian_factor() override;
  bool set_candidate(const Eigen::VectorXd& theta) override;
  double candidate_cost() override;
  void accept_candidate() override;
  bool eliminates_linear_part() const override { return m_project; }
  double eliminate_linear_part(double cost) override;
  double eliminate_linear_part_of_candidate(double cost) override;
  Eigen::VectorXd candidate_parameters() const override;

 private:
  PolynomialModel& m_model;
  const std::vector<ScaledRecord>& m_records;
  const Eigen::Index m_p;
  Eigen::Index m_samples = 0;
  bool m_project = false;
  FilteredByC m_by_c;                      // the last projection's signals, for the Jacobian factor at the same C
  std::vector<Eigen::VectorXd> m_eps;      // the model's prediction errors, per record
  PolynomialModel m_trial;                 // the candidate
  std::vector<Eigen::VectorXd> m_trial_eps;  // the candidate's prediction errors, per record
};

/// The solver's options from pem's: the iteration budget and the four tolerances.
LevenbergMarquardt::Options levenberg_marquardt_options(const PemOptions& options);

/// pem's status of a solver run.
PemResult::Status pem_status(LevenbergMarquardt::Status status);

/// One Levenberg-Marquardt run from `model` (updated in place) of at most
/// options.max_iterations iterations.
LevenbergMarquardt::Summary levenberg_marquardt(PolynomialModel& model, const std::vector<ScaledRecord>& records,
                                                Eigen::Index p, const PemOptions& options);

}  // namespace sysid::detail::pem_impl
