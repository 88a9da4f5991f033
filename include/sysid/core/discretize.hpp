#pragma once
/// @file
/// Purpose: exact zero-order-hold conversion between continuous- and discrete-time
/// state-space models, and the first-order-hold (triangle-hold) discretisation.
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
/// First-order hold (Franklin, Powell & Workman, Digital Control of Dynamic Systems,
/// 3rd ed., sec. 6.3.2): the input is the straight line through its samples, the
/// right model for smooth signals that were merely sampled (a measured force, an
/// oversampled and decimated simulation), where ZOH lags by half a sample. With
///
///   expm([A Ts, B Ts, 0; 0, 0, I; 0, 0, 0]) = [Phi, G1, G2; 0, I, I; 0, 0, I],
///
/// the model in the state xi = x - G2 u is
///
///   xi+ = Phi xi + (G1 + (Phi - I) G2) u,   y = C xi + (D + C G2) u
///
/// (the same as MATLAB's c2d 'foh' and SciPy's cont2discrete 'foh'). A strictly
/// proper plant gets a direct term: the hold looks half a sample ahead.
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

#include <stdexcept>
#include <string>

namespace sysid {

/// Purpose: exact ZOH discretisation of a continuous model with sample time Ts.
/// Preconditions: continuous.Ts == 0 and Ts > 0 finite (std::invalid_argument).
/// Numerical aspects: one (n+m)-square matrix exponential. Names are kept.
StateSpace c2d_zoh(const StateSpace& continuous, double Ts);

/// Purpose: first-order-hold (triangle-hold) discretisation with sample time Ts;
/// see the file comment. The state is xi = x - G2 u, not x.
/// Preconditions: continuous.Ts == 0 and Ts > 0 finite (std::invalid_argument).
/// Numerical aspects: one (n+2m)-square matrix exponential. Names are kept.
StateSpace c2d_foh(const StateSpace& continuous, double Ts);

/// The holds a continuous model can be sampled with.
enum class Hold { zoh, foh };

/// "zoh" or "foh"; std::invalid_argument otherwise.
inline Hold hold_from_name(const std::string& name) {
  if (name == "zoh") return Hold::zoh;
  if (name == "foh") return Hold::foh;
  throw std::invalid_argument("hold: expected 'zoh' or 'foh', found '" + name + "'");
}

/// c2d_zoh or c2d_foh.
StateSpace c2d(const StateSpace& continuous, double Ts, Hold hold);

/// Purpose: `model` ready to run on data sampled every `Ts` seconds, as every verb
/// that runs a model file on a log (and Python's diagnose) takes it: a continuous
/// model is discretised with `hold` (names kept); a discrete model whose sample
/// time differs from Ts by more than 1e-6 relative is sysid::DataError naming
/// `source` (a model runs only at its own rate).
StateSpace model_at_sample_time(const StateSpace& model, double Ts, Hold hold, const std::string& source);

/// Purpose: the continuous model whose exact ZOH discretisation is `discrete`.
/// Preconditions: discrete.Ts > 0 (std::invalid_argument).
/// Throws NumericalError if a pole lies on the closed negative real axis (or at
/// 0), where no real logarithm exists; a real pole counts as on the axis when
/// |Im z| <= sqrt(eps) |z| (a pair split by rounding would give a logarithm that
/// is real only by accident).
StateSpace d2c_zoh(const StateSpace& discrete);

}  // namespace sysid
