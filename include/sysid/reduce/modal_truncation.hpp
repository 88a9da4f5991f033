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
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

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
inline ReductionResult modal_truncation(const StateSpace& sys, const ModalTruncationOptions& options) {
  using Complex = std::complex<double>;
  sys.validate();
  if (options.order < 0 && !(options.f_lo_hz <= options.f_hi_hz))
    throw std::invalid_argument("modal_truncation: need f_lo_hz <= f_hi_hz");
  ReductionResult res;
  res.method = "modal truncation";
  res.original_order = sys.order();
  const StateSpace g = detail::balanced_realisation(sys);
  const Eigen::Index n = g.order(), m = g.inputs(), l = g.outputs();
  const bool discrete = g.is_discrete();

  // Real modal form.
  Eigen::MatrixXd Vr(n, n);
  struct Block {
    Eigen::Index start, size;
    Complex lambda;
    Mode mode;
    double dominance = 0.0;
  };
  std::vector<Block> blocks;
  if (n > 0) {
    const Eigen::EigenSolver<Eigen::MatrixXd> es(g.A, true);
    if (es.info() != Eigen::Success) throw NumericalError("modal_truncation: eigenvalue iteration did not converge");
    const Eigen::VectorXcd lam = es.eigenvalues();
    const Eigen::MatrixXcd V = es.eigenvectors();
    Eigen::Index col = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (lam(i).imag() == 0.0) {
        Vr.col(col) = V.col(i).real();
        blocks.push_back({col, 1, lam(i), detail::make_mode(lam(i), g.Ts, false)});
        col += 1;
      } else if (lam(i).imag() > 0.0) {
        Vr.col(col) = V.col(i).real();
        Vr.col(col + 1) = V.col(i).imag();
        blocks.push_back({col, 2, lam(i), detail::make_mode(lam(i), g.Ts, true)});
        col += 2;
      }
    }
    if (col != n) throw NumericalError("modal_truncation: eigenvalues are not in conjugate pairs");
  }
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(Vr);
  const double rcond = n > 0 ? lu.rcond() : 1.0;
  if (!(rcond >= 1e-13))
    throw NumericalError("modal_truncation: A is defective or nearly so (reciprocal condition of the modal basis " +
                         std::to_string(rcond) + " < 1e-13): no modal form");
  if (rcond < 1e-8) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "modal basis is ill conditioned (1/cond ~ %.3g): close or repeated poles", rcond);
    res.warnings.emplace_back(buf);
  }
  const Eigen::MatrixXd Bm = n > 0 ? Eigen::MatrixXd(lu.solve(g.B)) : Eigen::MatrixXd(0, m);
  const Eigen::MatrixXd Cm = g.C * Vr;
  auto block_A = [](const Block& b) {
    Eigen::MatrixXd a(b.size, b.size);
    if (b.size == 1) a(0, 0) = b.lambda.real();
    else a << b.lambda.real(), b.lambda.imag(), -b.lambda.imag(), b.lambda.real();
    return a;
  };

  // Selection.
  std::vector<bool> keep(blocks.size(), false);
  if (options.order >= 0) {
    for (Block& b : blocks) {
      const double arg = discrete ? std::abs(std::arg(b.lambda)) : std::abs(b.lambda.imag());
      const Complex at = discrete ? std::polar(1.0, arg) : Complex(0.0, arg);
      const StateSpace mode_sys(block_A(b), Bm.middleRows(b.start, b.size), Cm.middleCols(b.start, b.size),
                                Eigen::MatrixXd::Zero(l, m), g.Ts);
      const double peak = detail::max_singular_value(frequency_response_at(mode_sys, at));
      b.dominance = std::isfinite(peak) ? peak : std::numeric_limits<double>::infinity();
    }
    std::vector<std::size_t> order_idx(blocks.size());
    std::iota(order_idx.begin(), order_idx.end(), std::size_t{0});
    std::stable_sort(order_idx.begin(), order_idx.end(),
                     [&](std::size_t a, std::size_t b) { return blocks[a].dominance > blocks[b].dominance; });
    Eigen::Index used = 0;
    for (std::size_t i : order_idx)
      if (used + blocks[i].size <= options.order) {
        keep[i] = true;
        used += blocks[i].size;
      }
  } else {
    for (std::size_t i = 0; i < blocks.size(); ++i)
      keep[i] = blocks[i].mode.freq_hz >= options.f_lo_hz && blocks[i].mode.freq_hz <= options.f_hi_hz;
  }

  Eigen::Index nk = 0, nx = 0;
  for (std::size_t i = 0; i < blocks.size(); ++i) (keep[i] ? nk : nx) += blocks[i].size;
  Eigen::MatrixXd Ar = Eigen::MatrixXd::Zero(nk, nk), Br(nk, m), Cr(l, nk);
  Eigen::MatrixXd Ax = Eigen::MatrixXd::Zero(nx, nx), Bx(nx, m), Cx(l, nx);
  Eigen::MatrixXd Dr = g.D;
  Eigen::Index ik = 0, ix = 0;
  bool dc_skipped = false;
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const Block& b = blocks[i];
    const Eigen::MatrixXd a = block_A(b);
    const auto bb = Bm.middleRows(b.start, b.size);
    const auto cc = Cm.middleCols(b.start, b.size);
    if (keep[i]) {
      Ar.block(ik, ik, b.size, b.size) = a;
      Br.middleRows(ik, b.size) = bb;
      Cr.middleCols(ik, b.size) = cc;
      ik += b.size;
      res.kept_modes.push_back(b.mode);
      if (!b.mode.stable) res.unstable_states += b.size;
    } else {
      Ax.block(ix, ix, b.size, b.size) = a;
      Bx.middleRows(ix, b.size) = bb;
      Cx.middleCols(ix, b.size) = cc;
      ix += b.size;
      res.removed_modes.push_back(b.mode);
      if (options.keep_dc_gain) {
        // Static gain of the block: C (I - A)^-1 B (discrete), -C A^-1 B (continuous).
        Eigen::MatrixXd M = discrete ? Eigen::MatrixXd(Eigen::MatrixXd::Identity(b.size, b.size) - a) : Eigen::MatrixXd(-a);
        const Eigen::FullPivLU<Eigen::MatrixXd> blu(M);
        if (!blu.isInvertible()) {
          dc_skipped = true;
          continue;
        }
        Dr.noalias() += cc * blu.solve(Eigen::MatrixXd(bb));
      }
    }
  }
  if (dc_skipped)
    res.warnings.emplace_back("a removed mode is an integrator (pole at DC): its static gain is infinite and was not "
                              "added to D; the DC gain is not kept");
  auto by_freq = [](const Mode& a, const Mode& b) { return a.freq_hz < b.freq_hz; };
  std::stable_sort(res.kept_modes.begin(), res.kept_modes.end(), by_freq);
  std::stable_sort(res.removed_modes.begin(), res.removed_modes.end(), by_freq);

  res.model = StateSpace(Ar, Br, Cr, Dr, g.Ts);
  res.model.input_names = sys.input_names;
  res.model.output_names = sys.output_names;
  res.order = nk;
  if (options.measure_error) {
    // G - G_r = removed modes + (D - D_r): measured on that system's own poles.
    const StateSpace err(Ax, Bx, Cx, g.D - Dr, g.Ts);
    const HinfErrorEstimate e = hinf_norm_estimate(err, options.grid);
    res.hinf_error = e.value;
    res.hinf_error_freq_hz = e.freq_hz;
    res.dc_error = e.dc;
    res.grid_points = e.grid_points;
  }
  return res;
}

}  // namespace sysid
