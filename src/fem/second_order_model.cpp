#include "sysid/fem/second_order_model.hpp"

#include <cmath>
#include <set>
#include <stdexcept>

namespace sysid::fem {

const char* quantity_name(Quantity quantity) {
  switch (quantity) {
    case Quantity::displacement: return "displacement";
    case Quantity::velocity: return "velocity";
    case Quantity::acceleration: return "acceleration";
  }
  return "displacement";
}

Quantity quantity_from_name(const std::string& name) {
  if (name == "displacement") return Quantity::displacement;
  if (name == "velocity") return Quantity::velocity;
  if (name == "acceleration") return Quantity::acceleration;
  throw std::invalid_argument("unknown output quantity '" + name +
                              "' (expected displacement, velocity or acceleration)");
}

Eigen::SparseMatrix<double> SecondOrderModel::effective_damping_matrix() const {
  switch (damping.kind) {
    case DampingKind::matrix: return damping_matrix;
    case DampingKind::rayleigh: {
      Eigen::SparseMatrix<double> c = damping.alpha * mass + damping.beta * stiffness;
      c.makeCompressed();
      return c;
    }
    case DampingKind::none:
    case DampingKind::modal_ratio: break;
  }
  return Eigen::SparseMatrix<double>(mass.rows(), mass.cols());
}

namespace {

void check_symmetric_finite(const Eigen::SparseMatrix<double>& matrix, const char* name) {
  double largest = 0.0;
  for (Eigen::Index k = 0; k < matrix.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(matrix, k); it; ++it) {
      if (!std::isfinite(it.value()))
        throw std::invalid_argument(std::string("FE model: ") + name + " has a non-finite entry at (" +
                                    std::to_string(it.row()) + ", " + std::to_string(it.col()) + ")");
      largest = std::max(largest, std::abs(it.value()));
    }
  const Eigen::SparseMatrix<double> transposed = matrix.transpose();
  const Eigen::SparseMatrix<double> difference = matrix - transposed;
  const double asymmetry = difference.nonZeros() > 0 ? difference.coeffs().cwiseAbs().maxCoeff() : 0.0;
  if (matrix.nonZeros() > 0 && asymmetry > 1e-10 * largest)
    throw std::invalid_argument(std::string("FE model: ") + name + " is not symmetric (largest |A - A^T| = " +
                                std::to_string(asymmetry) + ", largest entry " + std::to_string(largest) + ")");
}

}  // namespace

void SecondOrderModel::validate() const {
  const Eigen::Index n = mass.rows();
  if (n == 0 || mass.cols() != n) throw std::invalid_argument("FE model: M must be square and non-empty");
  if (stiffness.rows() != n || stiffness.cols() != n)
    throw std::invalid_argument("FE model: K must be " + std::to_string(n) + " x " + std::to_string(n) +
                                " like M, is " + std::to_string(stiffness.rows()) + " x " +
                                std::to_string(stiffness.cols()));
  check_symmetric_finite(mass, "M");
  check_symmetric_finite(stiffness, "K");
  if (damping.kind == DampingKind::matrix) {
    if (damping_matrix.rows() != n || damping_matrix.cols() != n)
      throw std::invalid_argument("FE model: C must be " + std::to_string(n) + " x " + std::to_string(n) +
                                  " like M");
    check_symmetric_finite(damping_matrix, "C");
  }
  if (!(damping.alpha >= 0.0) || !(damping.beta >= 0.0) || !(damping.ratio >= 0.0) ||
      !std::isfinite(damping.alpha + damping.beta + damping.ratio))
    throw std::invalid_argument("FE model: damping coefficients must be finite and >= 0");
  if (inputs.empty()) throw std::invalid_argument("FE model: needs at least one input");
  if (outputs.empty()) throw std::invalid_argument("FE model: needs at least one output");
  std::set<std::string> names;
  auto check_name_dof = [&](const std::string& name, Eigen::Index dof) {
    if (name.empty()) throw std::invalid_argument("FE model: an input or output has no name");
    if (!names.insert(name).second) throw std::invalid_argument("FE model: duplicate signal name '" + name + "'");
    if (dof < 0 || dof >= n)
      throw std::invalid_argument("FE model: '" + name + "' is on DOF " + std::to_string(dof) +
                                  ", outside 0.." + std::to_string(n - 1));
  };
  for (const ForceInput& input : inputs) check_name_dof(input.name, input.dof);
  for (const DofOutput& output : outputs) check_name_dof(output.name, output.dof);
}

}  // namespace sysid::fem
