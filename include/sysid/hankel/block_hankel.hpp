#pragma once
/// @file
/// Purpose: the block-Hankel data matrix of subspace identification, compressed
/// to its square-root Gram factor without ever being formed.
///
/// For horizon i (i past and i future block rows), the data matrix of one
/// experiment with N samples has j = N - 2i + 1 columns
///
///   H = [ U_{0|2i-1} ]   U_{0|2i-1} has block rows u(t), u(t+1), ..., u(t+2i-1)
///       [ Y_{0|2i-1} ]   Y_{0|2i-1} likewise for y,           t = 0..j-1
///
/// (Van Overschee & De Moor, "Subspace Identification for Linear Systems", 1996,
/// sec. 1.3.2; k = 2i(m+l) rows). What the algorithms need is an upper-triangular
/// R (k x k) with R^T R = H H^T, i.e. H = R^T Q^T with orthonormal Q (the LQ
/// factorisation of the book, L = R^T). Every later projection is a product of
/// rows of R^T, because Q drops out of all norms and projections.
///
/// Method, three routes (the first two as SLICOT IB01MD documents):
///  - qr: H^T is produced in chunks of rows and folded into a StreamingQR.
///    Accurate (backward stable); ~2 j k^2 flops.
///  - cholesky: the Gram matrix G = H H^T is built from the block-Toeplitz
///    structure of the data: block (0,q) is a lagged correlation sum, and block
///    (p,q) follows from block (p-1,q-1) by adding the one sample product that
///    enters the window and removing the one that leaves it; ~2i j (m+l)^2 flops
///    instead of j k^2. Then R = chol(G). Squares the condition number: the
///    rounding of G (u ||H||^2) swamps its small eigenvalues once cond(H) > 1e8.
///  - cholesky_double_double: the same structured Gram matrix accumulated and
///    factorised in double-double arithmetic (core/detail/lagged_sums.hpp,
///    core/double_double_cholesky.hpp). Its error, ~1e-30 ||H||^2, is below
///    that of Householder's R (u ||H|| sigma_min(H)) for cond(H) up to ~1e15,
///    so R is at least as accurate as on the qr route, at a cost that still
///    grows like j (m+l)^2 i rather than j k^2. This is the route band-limited
///    data take: a chirp or multisine that leaves part of the Nyquist band
///    empty makes H ill-conditioned (cond 5e11 on the Par2 log decimated by 5,
///    where this route is 5x faster than qr and its R 800x closer to a
///    long-double reference).
///  automatic: cholesky when it succeeds with an estimated cond(G) within
///  `max_gram_condition` (not tried when `double_gram_first` is off), else
///  cholesky_double_double when G is positive definite in double-double with
///  every pivot ratio >= `min_pivot_ratio`, else qr (data rank deficient to
///  double precision, where the QR's R is still well defined).
/// Several experiments add their Gram matrices (resp. continue the QR): no block
/// column ever straddles two experiments, so there is no seam.
///
/// Preconditions: horizon >= 1; every experiment has N >= 2i samples; the total
/// number of columns j >= k (otherwise R is rank deficient: std::invalid_argument).
#include <Eigen/Dense>
#include <sysid/core/io_data.hpp>
#include <sysid/core/detail/lagged_sums.hpp>
#include <sysid/core/double_double_cholesky.hpp>
#include <sysid/core/parallel_for.hpp>
#include <sysid/core/format_number.hpp>
#include <sysid/core/streaming_qr.hpp>
#include <algorithm>
#include <limits>
#include <string>
#include <vector>

namespace sysid {

enum class HankelRoute { automatic, qr, cholesky, cholesky_double_double };

inline const char* to_string(HankelRoute r) {
  switch (r) {
    case HankelRoute::automatic: return "automatic";
    case HankelRoute::qr: return "qr";
    case HankelRoute::cholesky: return "cholesky";
    case HankelRoute::cholesky_double_double: return "cholesky_double_double";
  }
  return "?";
}

/// The route named `name`: to_string's names, with "auto" for automatic (the
/// command line's --hankel, Python's hankel=); std::invalid_argument otherwise.
inline HankelRoute hankel_route_from_name(const std::string& name) {
  if (name == "auto") return HankelRoute::automatic;
  for (const HankelRoute r : {HankelRoute::automatic, HankelRoute::qr, HankelRoute::cholesky, HankelRoute::cholesky_double_double})
    if (name == to_string(r)) return r;
  throw std::invalid_argument("hankel: expected 'auto', 'qr', 'cholesky' or 'cholesky_double_double', found '" + name + "'");
}

struct BlockHankelOptions {
  int horizon = 10;                           ///< i: number of past (and of future) block rows
  HankelRoute route = HankelRoute::automatic;  ///< automatic = cholesky, then cholesky_double_double, then qr
  /// Largest acceptable estimated condition number of the Gram matrix on the
  /// cholesky route. 1e12 keeps about 4 significant digits in R in the worst
  /// case (relative error ~ eps * cond(G)); beyond that the automatic route
  /// forms G in double-double.
  double max_gram_condition = 1e12;
  /// The double-double route is taken only when every pivot ratio R_jj / sqrt(G_jj)
  /// (the sine of the angle between row j of H and the rows before it) is at
  /// least this: a smaller one proves cond(H) > 1 / ratio, i.e. data rank
  /// deficient to double precision, which the qr route handles as before.
  double min_pivot_ratio = kRankDeficientPivotRatio;
  /// automatic route: try the Gram matrix in double first. false starts at the
  /// double-double Gram matrix: for data the caller knows to be band-limited
  /// (low-passed before decimation, the upper part of the band empty), where
  /// cond(G) is far beyond max_gram_condition and the double attempt is refused
  /// anyway (Par2 decimated by 5: its Cholesky fails; forming it costs a fifth of
  /// the compression). Only the time changes: the double-double R is at least as accurate.
  bool double_gram_first = true;
};

/// Row ranges of the partitions of H, in rows of H (= columns of R).
struct HankelLayout {
  Eigen::Index horizon = 0, inputs = 0, outputs = 0;
  Eigen::Index size() const { return 2 * horizon * (inputs + outputs); }
  /// First row of u(t + block) within H.
  Eigen::Index u_row(Eigen::Index block) const { return block * inputs; }
  /// First row of y(t + block) within H.
  Eigen::Index y_row(Eigen::Index block) const { return 2 * horizon * inputs + block * outputs; }
  /// Rows of U_{first|last} or Y_{first|last} (block rows first..last inclusive).
  std::vector<Eigen::Index> u_rows(Eigen::Index first, Eigen::Index last) const { return rows(u_row(first), (last - first + 1) * inputs); }
  std::vector<Eigen::Index> y_rows(Eigen::Index first, Eigen::Index last) const { return rows(y_row(first), (last - first + 1) * outputs); }

 private:
  static std::vector<Eigen::Index> rows(Eigen::Index start, Eigen::Index count) {
    std::vector<Eigen::Index> r(static_cast<std::size_t>(count));
    for (Eigen::Index k = 0; k < count; ++k) r[static_cast<std::size_t>(k)] = start + k;
    return r;
  }
};

struct BlockHankelCompression {
  Eigen::MatrixXd R;        ///< k x k upper triangular, R^T R = H H^T
  HankelLayout layout;
  Eigen::Index columns = 0;  ///< j, summed over experiments
  HankelRoute route_used = HankelRoute::qr;
  double gram_condition_estimate = 0;  ///< (max R_ii / min R_ii)^2, a cheap lower bound on cond(G)
  std::vector<std::string> warnings;

  /// Rows of L = R^T selected by H-row indices: the coefficients of those data
  /// rows in the orthonormal basis Q^T.
  Eigen::MatrixXd l_rows(const std::vector<Eigen::Index>& rows) const {
    Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), R.rows());
    for (std::size_t k = 0; k < rows.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = R.col(rows[k]).transpose();
    return out;
  }
};

namespace detail {

/// Adds H H^T of one experiment to G (in H layout). With the layout
/// [U_{0|2i-1}; Y_{0|2i-1}] the four quadrants of G are exactly the lagged-sum
/// matrices of (u,u), (u,y), (y,u) and (y,y). The three products run on the
/// cores (core/parallel_for.hpp): (u,y) has no symmetry to exploit and costs
/// about what (u,u) and (y,y) cost together for one input and one output.
inline void add_gram(const Experiment& e, const HankelLayout& lay, Eigen::MatrixXd& gram) {
  const Eigen::Index i2 = 2 * lay.horizon, j = e.samples() - i2 + 1;
  const Eigen::Index nu = i2 * lay.inputs, ny = i2 * lay.outputs;
  Eigen::MatrixXd uu, uy, yy;
  parallel_invoke([&] { uu = lagged_sums(e.u, e.u, i2, j, true); }, [&] { uy = lagged_sums(e.u, e.y, i2, j, false); },
                  [&] { yy = lagged_sums(e.y, e.y, i2, j, true); });
  gram.topLeftCorner(nu, nu) += uu;
  gram.topRightCorner(nu, ny) += uy;
  gram.bottomLeftCorner(ny, nu) += uy.transpose();
  gram.bottomRightCorner(ny, ny) += yy;
}

/// add_gram in double-double.
inline void add_gram_double_double(const Experiment& e, const HankelLayout& lay, DoubleDoubleMatrix& gram) {
  const Eigen::Index i2 = 2 * lay.horizon, j = e.samples() - i2 + 1, nu = i2 * lay.inputs;
  DoubleDoubleMatrix uu, uy, yy;
  parallel_invoke([&] { uu = lagged_sums_double_double(e.u, e.u, i2, j, true); },
                  [&] { uy = lagged_sums_double_double(e.u, e.y, i2, j, false); },
                  [&] { yy = lagged_sums_double_double(e.y, e.y, i2, j, true); });
  add_block(gram, 0, 0, uu);
  add_block(gram, 0, nu, uy);
  add_block(gram, nu, 0, uy, /*transposed=*/true);
  add_block(gram, nu, nu, yy);
}

/// Folds the rows of H^T of one experiment into the streaming QR.
inline void add_qr_rows(const Experiment& e, const HankelLayout& lay, StreamingQR& qr) {
  const Eigen::Index i2 = 2 * lay.horizon;
  const Eigen::Index j = e.samples() - i2 + 1;
  Eigen::Index t0 = 0;
  while (t0 < j) {
    const Eigen::Index c = std::min(qr.free_rows(), j - t0);
    auto block = qr.next_rows(c);
    for (Eigen::Index t = 0; t < i2; ++t) {
      block.middleCols(lay.u_row(t), lay.inputs) = e.u.middleRows(t0 + t, c);
      block.middleCols(lay.y_row(t), lay.outputs) = e.y.middleRows(t0 + t, c);
    }
    qr.commit_rows(c);
    t0 += c;
  }
}

inline double diag_condition(const Eigen::MatrixXd& r) {
  const Eigen::VectorXd d = r.diagonal().cwiseAbs();
  const double lo = d.minCoeff(), hi = d.maxCoeff();
  return lo > 0 ? (hi / lo) * (hi / lo) : std::numeric_limits<double>::infinity();
}

}  // namespace detail

/// Compresses the block-Hankel matrix of `data` (all experiments) into R.
inline BlockHankelCompression compress_block_hankel(const IoData& data, const BlockHankelOptions& options = {}) {
  if (options.horizon < 1) throw std::invalid_argument("block-hankel: need horizon >= 1");
  BlockHankelCompression out;
  out.layout = {options.horizon, data.inputs(), data.outputs()};
  const Eigen::Index k = out.layout.size();
  for (const auto& e : data.experiments) {
    if (e.samples() < 2 * options.horizon)
      throw std::invalid_argument("block-hankel: experiment " + e.source + " has " + std::to_string(e.samples()) +
                                  " samples, need at least 2*horizon = " + std::to_string(2 * options.horizon));
    out.columns += e.samples() - 2 * options.horizon + 1;
  }
  if (out.columns < k)
    throw std::invalid_argument("block-hankel: too few samples for horizon " + std::to_string(options.horizon) + ": " +
                                std::to_string(out.columns) + " Hankel columns, need at least 2*horizon*(inputs+outputs) = " +
                                std::to_string(k) + " (about " + std::to_string(k + 2 * options.horizon - 1) +
                                " samples); use a shorter horizon or more data");

  if ((options.route == HankelRoute::automatic && options.double_gram_first) || options.route == HankelRoute::cholesky) {
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(k, k);
    for (const auto& e : data.experiments) detail::add_gram(e, out.layout, gram);
    Eigen::LLT<Eigen::MatrixXd> llt(gram);
    if (llt.info() == Eigen::Success) {
      out.R = llt.matrixU();
      out.gram_condition_estimate = detail::diag_condition(out.R);
      out.route_used = HankelRoute::cholesky;
      if (out.gram_condition_estimate <= options.max_gram_condition || options.route == HankelRoute::cholesky) {
        if (out.gram_condition_estimate > options.max_gram_condition)
          out.warnings.push_back("block-hankel: Gram matrix condition ~" + format_number(out.gram_condition_estimate) +
                                 " on the forced cholesky route; R may be inaccurate");
        return out;
      }
    } else if (options.route == HankelRoute::cholesky) {
      throw std::invalid_argument("block-hankel: Cholesky factorisation of the Gram matrix failed (data rank deficient)");
    }
  }
  if (options.route == HankelRoute::automatic || options.route == HankelRoute::cholesky_double_double) {
    DoubleDoubleMatrix gram = DoubleDoubleMatrix::zero(k, k);
    for (const auto& e : data.experiments) detail::add_gram_double_double(e, out.layout, gram);
    DoubleDoubleCholeskyResult chol = double_double_cholesky(gram);
    const bool forced = options.route == HankelRoute::cholesky_double_double;
    if (chol.positive_definite && (chol.smallest_pivot_ratio >= options.min_pivot_ratio || forced)) {
      if (chol.smallest_pivot_ratio < options.min_pivot_ratio)
        out.warnings.push_back("block-hankel: smallest Cholesky pivot ratio " + format_number(chol.smallest_pivot_ratio) +
                               " on the forced cholesky_double_double route: the data are rank deficient to double "
                               "precision");
      out.R = std::move(chol.R);
      out.gram_condition_estimate = detail::diag_condition(out.R);
      out.route_used = HankelRoute::cholesky_double_double;
      return out;
    }
    if (forced)
      throw std::invalid_argument(
          "block-hankel: double-double Cholesky factorisation of the Gram matrix failed (data rank deficient)");
    out.warnings.push_back("block-hankel: the data are rank deficient to double precision (" +
                           (chol.positive_definite ? "smallest Cholesky pivot ratio " + format_number(chol.smallest_pivot_ratio)
                                                   : std::string("Gram matrix not positive definite in double-double")) +
                           "): R by QR");
  }
  StreamingQR qr(k);
  for (const auto& e : data.experiments) detail::add_qr_rows(e, out.layout, qr);
  out.R = qr.r();
  out.gram_condition_estimate = detail::diag_condition(out.R);
  out.route_used = HankelRoute::qr;
  return out;
}

}  // namespace sysid
