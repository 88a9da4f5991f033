// Implementation of reduce/modal_truncation.hpp (method in the header). Compiled
// once into libsysid: the eigenvector solver and LU factorisations are heavy to
// instantiate.
#include "core/detail/modal_table.hpp"
#include <sysid/core/real_modal_form.hpp>
#include "reduce/detail/hankel_singular_values.hpp"
#include "reduce/detail/reduction_error.hpp"
#include <sysid/reduce/modal_truncation.hpp>

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

ReductionResult modal_truncation(const StateSpace& sys, const ModalTruncationOptions& options) {
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
  struct Block : RealModalBlock {
    Mode mode;
    double dominance = 0.0;
  };
  std::vector<Block> blocks;
  if (n > 0) {
    RealModalForm form;
    const RealModalStatus status = real_modal_form(g.A, form);
    if (status == RealModalStatus::no_convergence)
      throw NumericalError("modal_truncation: eigenvalue iteration did not converge");
    if (status == RealModalStatus::unpaired)
      throw NumericalError("modal_truncation: eigenvalues are not in conjugate pairs");
    Vr = form.T;
    for (const auto& b : form.blocks) {
      Block block;
      static_cast<RealModalBlock&>(block) = b;
      block.mode = detail::make_mode(b.lambda, g.Ts, b.size == 2);
      blocks.push_back(block);
    }
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

  // Selection.
  std::vector<bool> keep(blocks.size(), false);
  if (options.order >= 0) {
    for (Block& b : blocks) {
      const double arg = discrete ? std::abs(std::arg(b.lambda)) : std::abs(b.lambda.imag());
      const Complex at = discrete ? std::polar(1.0, arg) : Complex(0.0, arg);
      const StateSpace mode_sys(real_modal_block(b), Bm.middleRows(b.start, b.size), Cm.middleCols(b.start, b.size),
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
    const Eigen::MatrixXd a = real_modal_block(b);
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
