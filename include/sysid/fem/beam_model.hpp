#pragma once
/// @file
/// Purpose: small reference finite-element structures built in code — an
/// Euler-Bernoulli beam, optionally clamped at its left end, with point masses,
/// springs and dampers to ground and attached spring-mass resonators. They serve
/// the verification tests (a cantilever against the analytic eigenfrequencies),
/// the example data (a beam on an isolator) and the benchmarks (a model of any
/// size), and let a user build a quick model without an FE package.
///
/// Method: two-node Hermite cubic elements with two DOFs per node (transverse
/// displacement w, rotation theta), consistent mass matrix (Przemieniecki,
/// "Theory of Matrix Structural Analysis", 1968, eqs. 5.116 and 11.33):
///
///   K_e = EI/h^3 [ 12   6h   -12   6h  ;  6h  4h^2  -6h  2h^2 ;
///                 -12  -6h    12  -6h  ;  6h  2h^2  -6h  4h^2 ]
///   M_e = rhoA h/420 [ 156  22h   54  -13h ;  22h  4h^2  13h  -3h^2 ;
///                       54  13h  156  -22h ; -13h -3h^2 -22h  4h^2 ]
///
/// With consistent mass the eigenfrequencies converge from above as h^4; 20
/// elements already put the first five cantilever modes within 0.01 % of the
/// Euler-Bernoulli values.
///
/// DOF numbering: node i (0..elements) has w at 2i and theta at 2i+1, minus the
/// two DOFs of node 0 when the beam is clamped there; DOFs added later
/// (resonators) are appended at the end.
#include <Eigen/SparseCore>
#include <vector>

#include "sysid/fem/second_order_model.hpp"

namespace sysid::fem {

struct BeamOptions {
  int elements = 20;                 ///< number of equal elements, >= 1
  double length = 1.0;               ///< m
  double flexural_rigidity = 1.0;    ///< EI, N m^2
  double mass_per_length = 1.0;      ///< rho A, kg/m
  bool clamped_left = false;         ///< node 0 fixed (w = theta = 0): a cantilever
};

/// A structure under construction: triplets of M, K, C and the DOF map. finish()
/// turns it into a SecondOrderModel (damping kind matrix when a damper was added,
/// else none; the caller may set Rayleigh or modal damping afterwards).
class StructureBuilder {
 public:
  /// A beam per `options`. Throws std::invalid_argument for elements < 1 or a
  /// non-positive length, rigidity or mass.
  explicit StructureBuilder(const BeamOptions& options);

  /// DOF of the transverse displacement of beam node `node` (0..elements); throws
  /// std::invalid_argument for a node outside the beam or a clamped one.
  Eigen::Index translation_dof(int node) const;
  /// The beam node nearest to position x along the beam (0 <= x <= length).
  int node_at(double x) const;

  void add_point_mass(Eigen::Index dof, double mass);
  void add_spring_to_ground(Eigen::Index dof, double stiffness, double damping = 0.0);
  /// A spring-mass(-damper) attached at `dof`: appends one DOF (the mass) and
  /// returns it. Its uncoupled natural frequency is sqrt(stiffness / mass).
  Eigen::Index add_resonator(Eigen::Index dof, double mass, double stiffness, double damping = 0.0);

  Eigen::Index dofs() const { return m_dofs; }
  SecondOrderModel finish(std::vector<ForceInput> inputs, std::vector<DofOutput> outputs) const;

 private:
  void add(std::vector<Eigen::Triplet<double>>& target, Eigen::Index i, Eigen::Index j, double value);
  BeamOptions m_options;
  Eigen::Index m_dofs = 0;
  std::vector<Eigen::Triplet<double>> m_mass, m_stiffness, m_damping;
};

/// The natural frequencies (Hz) of a uniform Euler-Bernoulli cantilever, modes
/// 1..count, from the roots beta_i L of cos(bL) cosh(bL) = -1 (Blevins, "Formulas
/// for Natural Frequency and Mode Shape", table 8-1): f_i = (beta_i L)^2 /
/// (2 pi L^2) sqrt(EI / rhoA). The roots are found by Newton's method from the
/// asymptote (2i - 1) pi / 2.
Eigen::VectorXd cantilever_frequencies_hz(const BeamOptions& options, int count);

}  // namespace sysid::fem
