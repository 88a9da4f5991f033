#pragma once
/// @file
/// Purpose: reduce a model by keeping some of its modes: those whose natural
/// frequency lies in a band [f_lo, f_hi] (e.g. an AR(16) model of which only the two
/// in-band resonances matter, as in the Par2 paper: order 16 -> 4), or the most
/// dominant ones. The kept poles are exactly poles of the full model.
///
/// Method:
///  1. A balanced by a power-of-two diagonal similarity (exact; keeps the
///     eigenvectors of companion-form realisations accurate).
///  2. Eigen-decomposition A V = V Lambda (Hessenberg QR, Eigen::EigenSolver). Real
///     modal (block-diagonal) form: a real eigenvalue lambda with eigenvector v
///     contributes the column v and the 1x1 block [lambda]; a pair sigma +- j omega
///     with eigenvector vr + j vi contributes the columns [vr vi] and the 2x2 block
///     [sigma omega; -omega sigma] (A [vr vi] = [vr vi] [sigma omega; -omega sigma]).
///     With V_r the real basis, B_m = V_r^-1 B (LU) and C_m = C V_r. Each block is
///     built from the eigenvalue itself, so a kept mode keeps its pole.
///  3. Each mode (pair or real pole) is described as in core/modal_table.hpp
///     (natural frequency |s|/(2 pi), s = log(z)/Ts if discrete) and selected:
///     band: f_lo_hz <= freq_hz <= f_hi_hz;
///     dominant (order >= 0): by the peak gain of the mode alone, sigma_max of its
///     own response C_i (e^{j arg z} I - A_i)^-1 B_i (continuous: at s = j Im(s)),
///     i.e. at its damped frequency, which for a light damping is
///     ~ |residue| / (1 - |z|) (continuous: |residue| / |Re s|); modes are taken in
///     decreasing order while their states fit in `order` (a pair that does not fit
///     is skipped for a smaller real mode).
///  4. keep_dc_gain: the static contribution of the removed modes is added to D,
///     D_r = D + C_x (I - A_x)^-1 B_x (discrete) or D - C_x A_x^-1 B_x (continuous), so
///     G_r(z = 1) = G(z = 1) (G_r(0) = G(0)); block by block.
///  5. The error G - G_r = (A_x, B_x, C_x, D - D_r) (the removed modes) is measured
///     on the grid of reduction_error.hpp.
///
/// Preconditions: a valid StateSpace; band f_lo_hz <= f_hi_hz when order < 0.
/// Throws NumericalError if A is defective or nearly so (reciprocal condition of
/// the modal basis < 1e-13): the modal form does not exist then.
/// Numerical aspects: O(n^3). The modal basis has condition kappa(V_r); B_m, C_m
/// and the kept part lose ~log10(kappa) digits (reported in the warnings when
/// kappa > 1e8). There is no a-priori error bound (unlike balanced truncation).
#include <sysid/core/errors.hpp>
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/modal_table.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/reduce/hankel_singular_values.hpp>
#include <sysid/reduce/reduction_error.hpp>

#include <Eigen/Dense>
#include <limits>

namespace sysid {

struct ModalTruncationOptions {
  double f_lo_hz = 0.0;  ///< band: keep modes with f_lo_hz <= natural frequency <= f_hi_hz
  double f_hi_hz = std::numeric_limits<double>::infinity();
  /// >= 0: ignore the band and keep the `order` states of the most dominant modes
  /// (peak gain of the mode alone, see the file comment).
  Eigen::Index order = -1;
  bool keep_dc_gain = false;  ///< add the removed modes' static gain to D
  bool measure_error = true;  ///< measure ||G - G_r||_inf on the grid (reduction_error.hpp)
  ErrorGridOptions grid;
};

/// Purpose: modal truncation, see the file comment. The result lists the kept and
/// removed modes (ReductionResult::kept_modes / removed_modes, sorted by frequency).
/// Example: `ModalTruncationOptions o; o.f_lo_hz = 10; o.f_hi_hz = 60; auto r = modal_truncation(ar_model, o);`
ReductionResult modal_truncation(const StateSpace& sys, const ModalTruncationOptions& options);

}  // namespace sysid
