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

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <string>

namespace sysid {

/// Purpose: exact ZOH discretisation of a continuous model with sample time Ts.
/// Preconditions: continuous.Ts == 0 and Ts > 0 finite (std::invalid_argument).
/// Numerical aspects: one (n+m)-square matrix exponential. Names are kept.
inline StateSpace c2d_zoh(const StateSpace& continuous, double Ts) {
  continuous.validate();
  if (continuous.Ts != 0.0) throw std::invalid_argument("c2d_zoh: need a continuous model (Ts == 0)");
  if (!(Ts > 0.0) || !std::isfinite(Ts)) throw std::invalid_argument("c2d_zoh: need sample time Ts > 0");
  const Eigen::Index n = continuous.order(), m = continuous.inputs();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + m, n + m);
  M.topLeftCorner(n, n) = continuous.A * Ts;
  M.topRightCorner(n, m) = continuous.B * Ts;
  const Eigen::MatrixXd E = M.exp();
  if (!E.allFinite()) throw NumericalError("c2d_zoh: matrix exponential overflowed (A Ts too large)");
  StateSpace d(E.topLeftCorner(n, n), E.topRightCorner(n, m), continuous.C, continuous.D, Ts);
  d.input_names = continuous.input_names;
  d.output_names = continuous.output_names;
  return d;
}

/// Purpose: the continuous model whose exact ZOH discretisation is `discrete`.
/// Preconditions: discrete.Ts > 0 (std::invalid_argument).
/// Throws NumericalError if a pole lies on the closed negative real axis (or at
/// 0), where no real logarithm exists; a real pole counts as on the axis when
/// |Im z| <= sqrt(eps) |z| (a pair split by rounding would give a logarithm that
/// is real only by accident).
inline StateSpace d2c_zoh(const StateSpace& discrete) {
  discrete.validate();
  if (!discrete.is_discrete()) throw std::invalid_argument("d2c_zoh: need a discrete model (Ts > 0)");
  const Eigen::Index n = discrete.order(), m = discrete.inputs();
  const double Ts = discrete.Ts;
  const Eigen::VectorXcd p = poles(discrete);
  const double eps = std::numeric_limits<double>::epsilon();
  const double scale = n > 0 ? discrete.A.cwiseAbs().maxCoeff() : 0.0;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    const bool at_zero = std::abs(p[i]) <= static_cast<double>(n) * eps * scale;
    const bool negative_real = p[i].real() < 0.0 && std::abs(p[i].imag()) <= std::sqrt(eps) * std::abs(p[i]);
    if (at_zero || negative_real)
      throw NumericalError("d2c_zoh: discrete pole " + std::to_string(p[i].real()) + (p[i].imag() >= 0 ? "+" : "") +
                           std::to_string(p[i].imag()) +
                           "j is on the negative real axis or at 0: no continuous-time ZOH equivalent");
  }
  Eigen::MatrixXd M = Eigen::MatrixXd::Identity(n + m, n + m);
  M.topLeftCorner(n, n) = discrete.A;
  M.topRightCorner(n, m) = discrete.B;
  const Eigen::MatrixXd L = M.log();
  if (!L.allFinite()) throw NumericalError("d2c_zoh: matrix logarithm failed");
  StateSpace c(L.topLeftCorner(n, n) / Ts, L.topRightCorner(n, m) / Ts, discrete.C, discrete.D, 0.0);
  c.input_names = discrete.input_names;
  c.output_names = discrete.output_names;
  return c;
}

}  // namespace sysid
