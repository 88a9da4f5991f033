// Implementation of reduce/balanced_truncation.hpp (method and references in the
// header). Compiled once into libsysid with the Schur, Gramian and SVD kernels it uses.
#include <sysid/core/errors.hpp>
#include <sysid/reduce/balanced_truncation.hpp>
#include "reduce/detail/hankel_singular_values.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

namespace sysid {

namespace {

/// Block-diagonal sum of two models with the same Ts, inputs and outputs.
StateSpace parallel_sum(const StateSpace& a, const StateSpace& b) {
  const Eigen::Index na = a.order(), nb = b.order();
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(na + nb, na + nb), B(na + nb, a.inputs()), C(a.outputs(), na + nb);
  A.topLeftCorner(na, na) = a.A;
  A.bottomRightCorner(nb, nb) = b.A;
  B << a.B, b.B;
  C << a.C, b.C;
  StateSpace s(A, B, C, a.D + b.D, a.Ts);
  s.input_names = a.input_names;
  s.output_names = a.output_names;
  return s;
}

}  // namespace

ReductionResult balanced_truncation(const StateSpace& sys, const BalancedTruncationOptions& options) {
  sys.validate();
  if (options.order < 0 && !(options.max_error_ratio > 0.0) && !(options.max_hinf_bound > 0.0))
    throw std::invalid_argument("balanced_truncation: need order >= 0, max_error_ratio > 0 or max_hinf_bound > 0");
  if (options.order < 0 && options.max_error_ratio > 0.0 && !(options.max_error_ratio < 1.0))
    throw std::invalid_argument("balanced_truncation: need max_error_ratio < 1");
  ReductionResult res;
  res.method = options.method == BalancedMethod::truncation ? "balanced truncation" : "singular perturbation";
  res.original_order = sys.order();
  detail::ComplexSchurForm schur;
  const StabilitySplit split =
      detail::stable_unstable_split(detail::balanced_realisation(sys), options.stability_tolerance, schur);
  const Eigen::Index nu = split.unstable.order(), ns = split.stable.order();
  res.unstable_states = nu;
  if (options.order >= 0 && options.order < nu)
    throw std::invalid_argument("balanced_truncation: need order >= unstable states (" + std::to_string(options.order) +
                                " < " + std::to_string(nu) + ")");
  if (split.decoupling_norm > 1e8)
    res.warnings.push_back("stable and unstable poles are poorly separated (||X|| = " +
                           std::to_string(split.decoupling_norm) + ")");

  StateSpace reduced_stable = split.stable;
  if (ns > 0) {
    const detail::SquareRootBalancing srb = detail::square_root_balancing(split.stable, schur, true);
    const Eigen::VectorXd& hsv = srb.hsv;
    res.hsv = hsv;
    // tail(i) = sum_{j >= i} sigma_j, summed from the smallest so small tails are exact.
    Eigen::VectorXd tail(ns + 1);
    tail(ns) = 0.0;
    for (Eigen::Index i = ns - 1; i >= 0; --i) tail(i) = tail(i + 1) + hsv(i);
    const double total = tail(0);
    const double eps = std::numeric_limits<double>::epsilon();
    Eigen::Index n_min = 0;
    while (n_min < ns && hsv(n_min) > static_cast<double>(ns) * eps * hsv(0)) ++n_min;

    Eigen::Index r = 0;
    if (options.order >= 0) {
      r = std::min<Eigen::Index>(options.order - nu, ns);
    } else if (options.max_error_ratio > 0.0) {
      while (r < ns && tail(r) > options.max_error_ratio * total) ++r;
    } else {
      while (r < ns && 2.0 * tail(r) > options.max_hinf_bound) ++r;
    }
    if (r > n_min) {
      res.warnings.push_back("order reduced from " + std::to_string(r + nu) + " to " + std::to_string(n_min + nu) +
                             ": the remaining Hankel singular values are at rounding level (non-minimal model)");
      r = n_min;
    }
    if (r > 0 && r < ns && hsv(r - 1) > 0.0 && (hsv(r - 1) - hsv(r)) / hsv(r - 1) < options.pair_gap_warning) {
      char buf[256];
      std::snprintf(buf, sizeof buf,
                    "the cut splits near-equal Hankel singular values sigma_%ld = %.6g and sigma_%ld = %.6g "
                    "(probably the two states of one lightly damped mode); consider order %ld or %ld",
                    static_cast<long>(r), hsv(r - 1), static_cast<long>(r + 1), hsv(r), static_cast<long>(r - 1 + nu),
                    static_cast<long>(r + 1 + nu));
      res.warnings.emplace_back(buf);
    }
    res.error_ratio = total > 0.0 ? tail(r) / total : 0.0;
    res.hinf_bound = 2.0 * tail(r);

    const bool spa = options.method == BalancedMethod::singular_perturbation;
    const Eigen::Index k = spa ? n_min : r;
    const Eigen::VectorXd s_isqrt = hsv.head(k).cwiseSqrt().cwiseInverse();
    const Eigen::MatrixXd Tr = srb.Lc * srb.V.leftCols(k) * s_isqrt.asDiagonal();
    const Eigen::MatrixXd Tl = s_isqrt.asDiagonal() * srb.U.leftCols(k).transpose() * srb.Lo.transpose();
    const StateSpace& g = split.stable;
    Eigen::MatrixXd Ab = Tl * g.A * Tr, Bb = Tl * g.B, Cb = g.C * Tr, Db = g.D;
    if (spa && r < k) {
      const Eigen::Index q = k - r;
      // Discrete: x2 = (I - A22)^-1 (A21 x1 + B2 u); continuous: x2 = -A22^-1 (A21 x1 + B2 u).
      Eigen::MatrixXd M = -Ab.bottomRightCorner(q, q);
      if (g.is_discrete()) M.diagonal().array() += 1.0;
      const Eigen::PartialPivLU<Eigen::MatrixXd> lu(M);
      Eigen::MatrixXd rhs(q, r + g.inputs());
      rhs << Ab.bottomLeftCorner(q, r), Bb.bottomRows(q);
      const Eigen::MatrixXd Y = lu.solve(rhs);  // [X21 XB]: x2 = X21 x1 + XB u
      if (!Y.allFinite()) throw NumericalError("balanced_truncation: singular perturbation system is singular");
      const Eigen::MatrixXd A11 = Ab.topLeftCorner(r, r) + Ab.topRightCorner(r, q) * Y.leftCols(r);
      const Eigen::MatrixXd B1 = Bb.topRows(r) + Ab.topRightCorner(r, q) * Y.rightCols(g.inputs());
      const Eigen::MatrixXd C1 = Cb.leftCols(r) + Cb.rightCols(q) * Y.leftCols(r);
      const Eigen::MatrixXd D1 = Db + Cb.rightCols(q) * Y.rightCols(g.inputs());
      Ab = A11;
      Bb = B1;
      Cb = C1;
      Db = D1;
    }
    reduced_stable = StateSpace(Ab, Bb, Cb, Db, g.Ts);
    reduced_stable.input_names = sys.input_names;
    reduced_stable.output_names = sys.output_names;
    if (options.measure_error) {
      // G - G_r = G_s - G_sr: the unstable part cancels exactly, so measure on the stable parts.
      const HinfErrorEstimate e = reduction_error(split.stable, reduced_stable, options.grid);
      res.hinf_error = e.value;
      res.hinf_error_freq_hz = e.freq_hz;
      res.dc_error = e.dc;
      res.grid_points = e.grid_points;
    }
  } else {
    res.error_ratio = 0.0;
    res.hinf_bound = 0.0;
    if (options.measure_error) {
      res.hinf_error = 0.0;
      res.dc_error = 0.0;
    }
  }
  res.model = nu > 0 ? parallel_sum(reduced_stable, split.unstable) : reduced_stable;
  res.model.input_names = sys.input_names;
  res.model.output_names = sys.output_names;
  res.order = res.model.order();
  return res;
}

}  // namespace sysid
