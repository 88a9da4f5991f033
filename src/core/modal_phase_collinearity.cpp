// Implementation of core/modal_phase_collinearity.hpp (formulas in the header).
#include <sysid/core/modal_phase_collinearity.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>

namespace sysid {

double modal_phase_collinearity(const Eigen::VectorXcd& shape) {
  const double energy = shape.squaredNorm();
  if (!(energy > 0.0)) return 0.0;
  return std::norm(shape.cwiseProduct(shape).sum()) / (energy * energy);  // |phi^T phi|^2 / (phi^H phi)^2
}

double quadrature_tolerant_collinearity(const Eigen::VectorXcd& shape) {
  // phi_j^2 / |phi_j| keeps each entry's magnitude and doubles its phase.
  Eigen::VectorXcd doubled(shape.size());
  for (Eigen::Index j = 0; j < shape.size(); ++j) {
    const double magnitude = std::abs(shape(j));
    doubled(j) = magnitude > 0.0 ? shape(j) * shape(j) / magnitude : std::complex<double>(0.0);
  }
  return std::max(modal_phase_collinearity(shape), modal_phase_collinearity(doubled));
}

double shape_effective_outputs(const Eigen::VectorXcd& shape) {
  const Eigen::VectorXd power = shape.cwiseAbs2();
  const double fourth = power.squaredNorm();
  if (!(fourth > 0.0)) return 0.0;
  return std::min(static_cast<double>(shape.size()), 2.0 * power.sum() * power.sum() / fourth);
}

double random_shape_collinearity_quantile(double outputs, double level) {
  if (!(outputs > 1.0)) throw std::invalid_argument("random_shape_collinearity_quantile: need more than one output");
  if (!(level > 0.0 && level < 1.0)) throw std::invalid_argument("random_shape_collinearity_quantile: need 0 < level < 1");
  // Two statistics (MPC and the phase-doubled MPC), each P(> x) = (1 - x)^((m - 1) / 2):
  // the union bound gives level / 2 to each.
  return 1.0 - std::pow(0.5 * level, 2.0 / (outputs - 1.0));
}

}  // namespace sysid
