#pragma once
/// @file
/// Purpose: exact zero-order-hold conversion between continuous- and discrete-time
/// state-space models.
///
/// Method: with the input held constant over each sample interval,
///
///   expm([A B; 0 0] Ts) = [Ad Bd; 0 I],   Ad = e^(A Ts),  Bd = int_0^Ts e^(A t) dt B,
///
/// (Van Loan 1978), C and D unchanged. The inverse takes the principal matrix
/// logarithm of the same block matrix: logm([Ad Bd; 0 I]) / Ts = [A B; 0 0]. The
/// block form needs no inverse of A (integrators are fine) nor of Ad - I.
/// Eigen's MatrixFunctions module evaluates expm by scaling and squaring with Pade
/// approximants (Higham 2005) and logm by Schur-Parlett with inverse scaling and
/// squaring atoms (Higham 2008).
///
/// Numerical aspects: O((n+m)^3). d2c_zoh inverts c2d_zoh only for continuous
/// poles with |Im s| < pi / Ts (no aliasing); a discrete pole on the closed
/// negative real axis (or at 0) has no real logarithm and is refused.
///
/// References: C. F. Van Loan, "Computing integrals involving the matrix
/// exponential", IEEE TAC 23(3):395-404, 1978. N. J. Higham, "The scaling and
/// squaring method for the matrix exponential revisited", SIMAX 26(4), 2005.
#include <sysid/core/errors.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/state_space.hpp>

namespace sysid {

/// Purpose: exact ZOH discretisation of a continuous model with sample time Ts.
/// Preconditions: continuous.Ts == 0 and Ts > 0 finite (std::invalid_argument).
/// Numerical aspects: one (n+m)-square matrix exponential. Names are kept.
StateSpace c2d_zoh(const StateSpace& continuous, double Ts);

/// Purpose: the continuous model whose exact ZOH discretisation is `discrete`.
/// Preconditions: discrete.Ts > 0 (std::invalid_argument).
/// Throws NumericalError if a pole lies on the closed negative real axis (or at
/// 0), where no real logarithm exists; a real pole counts as on the axis when
/// |Im z| <= sqrt(eps) |z| (a pair split by rounding would give a logarithm that
/// is real only by accident).
StateSpace d2c_zoh(const StateSpace& discrete);

}  // namespace sysid
