// Reduced state-space models of FE models from their modes (see modal_model.hpp).
#include "sysid/fem/modal_model.hpp"

#include <Eigen/CholmodSupport>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "sysid/core/discretize.hpp"
#include "sysid/core/errors.hpp"
#include "sysid/core/format_number.hpp"

namespace sysid::fem {

ModalModelResult modal_model(const SecondOrderModel& model, const ModalAnalysisResult& modes,
                             const ModalModelOptions& options) {
  model.validate();
  const Eigen::Index n = model.dofs(), r = modes.mode_shapes.cols(), m = static_cast<Eigen::Index>(model.inputs.size()),
                     l = static_cast<Eigen::Index>(model.outputs.size());
  if (modes.mode_shapes.rows() != n || r == 0 || modes.eigenvalues.size() != r || modes.modal_damping.rows() != r)
    throw std::invalid_argument("modal_model: the modes were not computed on this model (" +
                                std::to_string(modes.mode_shapes.rows()) + " DOFs vs " + std::to_string(n) + ")");
  if (!(options.Ts >= 0.0)) throw std::invalid_argument("modal_model: need Ts >= 0");
  if (options.static_correction && modes.rigid_body_modes > 0)
    throw std::invalid_argument("modal_model: static correction needs a structure fixed to ground (" +
                                std::to_string(modes.rigid_body_modes) + " rigid-body modes found, K is singular)");

  ModalModelResult result;
  result.modes = modes;
  const Eigen::MatrixXd& phi = modes.mode_shapes;
  const Eigen::VectorXd omega2 = modes.eigenvalues.cwiseMax(0.0);
  // Phi^T F: the rows of Phi at the input DOFs, transposed.
  Eigen::MatrixXd modal_input(r, m);
  for (Eigen::Index j = 0; j < m; ++j) modal_input.col(j) = phi.row(model.inputs[static_cast<std::size_t>(j)].dof).transpose();

  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * r, 2 * r), b = Eigen::MatrixXd::Zero(2 * r, m);
  a.topRightCorner(r, r).setIdentity();
  a.bottomLeftCorner(r, r) = -Eigen::MatrixXd(omega2.asDiagonal());
  a.bottomRightCorner(r, r) = -modes.modal_damping;
  b.bottomRows(r) = modal_input;
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(l, 2 * r), d = Eigen::MatrixXd::Zero(l, m);
  bool displacement_outputs = false, other_outputs = false;
  for (Eigen::Index i = 0; i < l; ++i) {
    const DofOutput& out = model.outputs[static_cast<std::size_t>(i)];
    const Eigen::RowVectorXd shape = phi.row(out.dof);
    switch (out.quantity) {
      case Quantity::displacement:
        c.block(i, 0, 1, r) = shape;
        displacement_outputs = true;
        break;
      case Quantity::velocity:
        c.block(i, r, 1, r) = shape;
        other_outputs = true;
        break;
      case Quantity::acceleration:
        // q'' = Phi eta'' = Phi (-Omega^2 eta - D_m eta' + Phi^T F u).
        c.row(i) = shape * a.bottomRows(r);
        d.row(i) = shape * modal_input;
        other_outputs = true;
        break;
    }
  }

  if (options.static_correction && displacement_outputs) {
    Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> k_factor;
    k_factor.cholmod().print = 0;
    k_factor.compute(model.stiffness);
    if (k_factor.info() != Eigen::Success)
      throw NumericalError("modal_model: K is not positive definite, so the static correction is undefined");
    Eigen::MatrixXd f = Eigen::MatrixXd::Zero(n, m);
    for (Eigen::Index j = 0; j < m; ++j) f(model.inputs[static_cast<std::size_t>(j)].dof, j) = 1.0;
    const Eigen::MatrixXd full_static = k_factor.solve(f);
    const Eigen::MatrixXd kept_static = phi * (omega2.cwiseInverse().asDiagonal() * modal_input);
    for (Eigen::Index i = 0; i < l; ++i) {
      const DofOutput& out = model.outputs[static_cast<std::size_t>(i)];
      if (out.quantity == Quantity::displacement) d.row(i) += full_static.row(out.dof) - kept_static.row(out.dof);
    }
  }
  if (options.static_correction && other_outputs)
    result.warnings.push_back("static correction applied to displacement outputs only (velocity and acceleration "
                              "outputs keep the truncated modes' contribution out)");

  StateSpace continuous(a, b, c, d, 0.0);
  for (const auto& in : model.inputs) continuous.input_names.push_back(in.name);
  for (const auto& out : model.outputs) continuous.output_names.push_back(out.name);
  result.model = options.Ts > 0.0 ? c2d(continuous, options.Ts, options.hold) : continuous;
  if (options.Ts > 0.0) {
    result.model.input_names = continuous.input_names;
    result.model.output_names = continuous.output_names;
    const double f_max = std::sqrt(omega2.maxCoeff()) / (2.0 * std::numbers::pi);
    if (f_max > 0.5 / options.Ts)
      result.warnings.push_back("the highest retained mode (" + format_number(f_max) +
                                " Hz) lies above the Nyquist frequency of Ts (" + format_number(0.5 / options.Ts) +
                                " Hz): it aliases in the sampled model");
  }
  result.warnings.insert(result.warnings.begin(), modes.warnings.begin(), modes.warnings.end());
  return result;
}

ModalModelResult modal_model(const SecondOrderModel& model, const ModalAnalysisOptions& analysis,
                             const ModalModelOptions& options) {
  return modal_model(model, modal_analysis(model, analysis), options);
}

}  // namespace sysid::fem
