#pragma once
/// @file
/// Purpose: a large sparse second-order structural model, the finite-element side
/// of a comparison with measurements:
///
///   M q''(t) + C q'(t) + K q(t) = F u(t),     y(t) = one of q, q', q'' at chosen DOFs
///
/// with M, C, K real symmetric sparse n x n matrices (M positive definite, K
/// positive semi-definite: a free-floating structure has rigid-body modes), F the
/// n x m input map that puts each force input on one DOF, and each output one DOF
/// read as displacement, velocity or acceleration.
///
/// Damping is given one of three ways, as FE packages export it:
///   - an explicit matrix C;
///   - Rayleigh (proportional) damping C = alpha M + beta K;
///   - a modal damping ratio zeta, the same for every mode. It has no sparse
///     matrix: modal methods use it exactly (2 zeta omega_i per mode); direct
///     frequency-domain solves use the structural-damping equivalent
///     K (1 + 2 j zeta), which gives each mode the same damping at its resonance
///     (Ewins, "Modal Testing", 2nd ed., sec. 2.3) and says so in a warning.
#include <Eigen/SparseCore>
#include <complex>
#include <cstddef>
#include <string>
#include <vector>

namespace sysid::fem {

/// What an output reads at its DOF.
enum class Quantity { displacement, velocity, acceleration };

/// "displacement", "velocity", "acceleration"; the inverse throws
/// std::invalid_argument naming the accepted words.
const char* quantity_name(Quantity quantity);
Quantity quantity_from_name(const std::string& name);

/// The factor from displacement to `quantity` at angular frequency omega (rad/s):
/// 1, j omega or -omega^2.
inline std::complex<double> quantity_factor(Quantity quantity, double omega) {
  switch (quantity) {
    case Quantity::velocity: return {0.0, omega};
    case Quantity::acceleration: return {-omega * omega, 0.0};
    case Quantity::displacement: break;
  }
  return {1.0, 0.0};
}

enum class DampingKind { none, matrix, rayleigh, modal_ratio };

struct Damping {
  DampingKind kind = DampingKind::none;
  double alpha = 0.0;  ///< Rayleigh mass coefficient, 1/s (kind rayleigh)
  double beta = 0.0;   ///< Rayleigh stiffness coefficient, s (kind rayleigh)
  double ratio = 0.0;  ///< modal damping ratio, dimensionless (kind modal_ratio)
};

/// A force input acting on one DOF (0-based row of M, C, K).
struct ForceInput {
  std::string name;
  Eigen::Index dof = 0;
  std::string unit = "N";
};

/// An output reading one DOF (0-based) as displacement, velocity or acceleration.
struct DofOutput {
  std::string name;
  Eigen::Index dof = 0;
  Quantity quantity = Quantity::displacement;
  std::string unit;  ///< free text for plots and reports, e.g. "m/s^2"
};

struct SecondOrderModel {
  Eigen::SparseMatrix<double> mass;       ///< M, n x n, symmetric positive definite
  Eigen::SparseMatrix<double> stiffness;  ///< K, n x n, symmetric positive semi-definite
  Eigen::SparseMatrix<double> damping_matrix;  ///< C, n x n; used only when damping.kind == matrix
  Damping damping;
  std::vector<ForceInput> inputs;
  std::vector<DofOutput> outputs;

  Eigen::Index dofs() const { return mass.rows(); }

  /// The damping matrix the model implies: C itself, alpha M + beta K, or an empty
  /// (all-zero) matrix for none and modal_ratio.
  Eigen::SparseMatrix<double> effective_damping_matrix() const;

  /// The structural loss factor eta that stands in for a modal damping ratio in
  /// frequency-domain solves, Z = K (1 + j eta) - omega^2 M with eta = 2 zeta
  /// (file comment); 0 for the other damping kinds.
  double structural_loss_factor() const {
    return damping.kind == DampingKind::modal_ratio ? 2.0 * damping.ratio : 0.0;
  }

  /// Throws std::invalid_argument naming the first violation: matrix sizes differ
  /// or are not square, a matrix is not symmetric (relative tolerance 1e-10 of its
  /// largest entry), a non-finite entry, a DOF outside 0..n-1, no inputs or no
  /// outputs, duplicate names, negative damping coefficients.
  void validate() const;
};

}  // namespace sysid::fem
