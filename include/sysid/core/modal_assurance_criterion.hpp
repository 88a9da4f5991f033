#pragma once
/// @file
/// Purpose: the modal assurance criterion, the correlation of two mode shapes
/// (R. J. Allemang, "The modal assurance criterion - twenty years of use and
/// abuse", Sound and Vibration 37 (2003) 14-21):
///   MAC(a, b) = |a^H b|^2 / (|a|^2 |b|^2),
/// 1 for the same shape up to a complex factor, 0 for orthogonal shapes. One
/// definition for the stabilisation diagram (subspace/) and mode tracking over a
/// family of models (family/).
#include <Eigen/Dense>

namespace sysid {

/// MAC of two shapes of equal length; 0 if either is zero or the lengths differ.
double modal_assurance_criterion(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b);

}  // namespace sysid
