#pragma once
/// @file
/// Purpose: how real a mode shape is, and how real a noise shape is by chance.
///
/// The modal phase collinearity (R. S. Pappa, K. B. Elliott & A. Schenk, "A
/// consistent-mode indicator for the eigensystem realization algorithm", J.
/// Guidance, Control, and Dynamics 16 (1993) 852-858):
///   MPC(phi) = |phi^T phi|^2 / (phi^H phi)^2,
/// the squared ratio (l1 - l2) / (l1 + l2) of the eigenvalues of the Gram matrix
/// of Re phi and Im phi. It is 1 when every entry lies on one line through the
/// origin (a mode of a lightly, classically damped structure seen by sensors of
/// one kind, whatever the shape's complex scaling) and near 0 when the phases
/// scatter. Non-proportional damping makes physical modes complex too: a chain
/// of 28 masses with two dashpots giving 5-12 % damping has modes down to MPC 0.7,
/// with 25 % damping down to 0.1.
///
/// Sensors of different kinds: a velocity sensor sees a lightly damped mode in
/// quadrature (s = i w) with displacement, strain and acceleration sensors, so a
/// real mode seen by a mix lies on two perpendicular lines and has a low MPC.
/// quadrature_tolerant_collinearity is the larger of MPC(phi) and MPC of phi with
/// every entry's phase doubled (doubling maps perpendicular lines onto one).
///
/// Chance: a shape of m independent circular complex Gaussian entries of equal
/// variance (a noise mode's shape) has Re phi, Im phi with a 2 x 2 Wishart Gram
/// matrix W, MPC = 1 - 4 det W / (tr W)^2 one minus Mauchly's sphericity statistic,
/// whose distribution in two dimensions is P(MPC > x) = (1 - x)^((m - 1) / 2)
/// (J. W. Mauchly, "Significance test for sphericity of a normal n-variate
/// distribution", Ann. Math. Statist. 11 (1940) 204-209; checked by simulation in
/// tests/unit/core_modal_phase_collinearity.cpp). Doubling the phases leaves such a
/// shape's distribution unchanged, so the quadrature-tolerant value exceeds x with
/// probability at most 2 (1 - x)^((m - 1) / 2).
#include <Eigen/Dense>

namespace sysid {

/// MPC of `shape` (file comment); 0 for an empty or zero shape.
double modal_phase_collinearity(const Eigen::VectorXcd& shape);

/// max(MPC(phi), MPC(phi with every entry's phase doubled)) (file comment).
double quadrature_tolerant_collinearity(const Eigen::VectorXcd& shape);

/// The number of outputs a shape effectively spreads over, as a noise shape's
/// equal-variance count: 2 (sum |phi_j|^2)^2 / sum |phi_j|^4 (for m equal-variance
/// Gaussian entries the ratio is about m / 2), at most the shape's length; 0 for a
/// zero shape. A noise shape dominated by a few noisy sensors counts as few.
double shape_effective_outputs(const Eigen::VectorXcd& shape);

/// The value a random shape of `outputs` effective entries exceeds in
/// quadrature_tolerant_collinearity with probability at most `level`:
/// 1 - (level / 2)^(2 / (outputs - 1)). Preconditions (std::invalid_argument):
/// outputs > 1, 0 < level < 1.
double random_shape_collinearity_quantile(double outputs, double level);

}  // namespace sysid
