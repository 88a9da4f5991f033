#pragma once
// Internal to src/pem: stability tests of the polynomial model's monic
// denominators (src/pem/polynomial_utilities.cpp), used by the iterations (a
// step must keep the predictor stable) and the output-error start.
#include <sysid/pem/polynomial_model.hpp>

#include <Eigen/Dense>

namespace sysid::detail::pem_impl {

/// Whether every root of the monic polynomial [1, a_1..a_n] (in q^-1) lies inside
/// the unit circle with a margin of 1e-10 (a constant polynomial is stable).
bool strictly_stable(const Eigen::VectorXd& monic);

/// Whether C, D and every F_i are strictly stable: the predictor's filters 1 / C,
/// 1 / F_i and the noise model's inverse are then stable.
bool denominators_stable(const PolynomialModel& m);

}  // namespace sysid::detail::pem_impl
