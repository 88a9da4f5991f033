#pragma once
/// @file
/// Purpose: the Gram matrix of a block-Hankel matrix of one record without
/// forming the Hankel matrix: O(N i2) work instead of O(N i2^2). Used by the
/// block-Hankel compression's correlation route (hankel/block_hankel.hpp) and
/// by the order of persistent excitation (core/persistent_excitation.hpp).
/// lagged_sums_double_double forms the same sums to about 1e-30 relative, for
/// Gram matrices whose condition number exceeds 1 / (double's unit roundoff);
/// shifted_columns_gram_double_double the Gram matrix of any set of columns
/// that are shifted copies of a few signals (a prediction-error Jacobian).
#include <Eigen/Dense>
#include <sysid/core/double_double.hpp>
#include <sysid/core/parallel_for.hpp>

#include <algorithm>
#include <stdexcept>
#include <utility>
#include <vector>

namespace sysid::detail {

/// Lagged sums S(p,q) = sum_{t=0}^{j-1} x(t+p) y(t+q)^T for p, q = 0..i2-1,
/// written as an (i2*mx) x (i2*my) block matrix. The first block row and column
/// are correlation sums over the whole record, computed in chunks of rows with
/// one GEMM per chunk (BLAS-3 shape, no copy of the record); every other block
/// follows from its upper-left neighbour by adding the product that enters the
/// window and removing the one that leaves it.
template <class MX, class MY>
Eigen::MatrixXd lagged_sums(const MX& x, const MY& y, Eigen::Index i2, Eigen::Index j, bool symmetric) {
  const Eigen::Index mx = x.cols(), my = y.cols();
  Eigen::MatrixXd s = Eigen::MatrixXd::Zero(i2 * mx, i2 * my);
  Eigen::MatrixXd first_row = Eigen::MatrixXd::Zero(mx, i2 * my);  // S(0,q)
  Eigen::MatrixXd first_col = Eigen::MatrixXd::Zero(my, i2 * mx);  // S(p,0)^T
  constexpr Eigen::Index chunk = 4096;
  Eigen::MatrixXd shifted_y(chunk, i2 * my), shifted_x;
  if (!symmetric) shifted_x.resize(chunk, i2 * mx);
  for (Eigen::Index t0 = 0; t0 < j; t0 += chunk) {
    const Eigen::Index c = std::min(chunk, j - t0);
    for (Eigen::Index q = 0; q < i2; ++q) shifted_y.block(0, q * my, c, my) = y.middleRows(t0 + q, c);
    first_row.noalias() += x.middleRows(t0, c).transpose() * shifted_y.topRows(c);
    if (!symmetric) {
      for (Eigen::Index p = 0; p < i2; ++p) shifted_x.block(0, p * mx, c, mx) = x.middleRows(t0 + p, c);
      first_col.noalias() += y.middleRows(t0, c).transpose() * shifted_x.topRows(c);
    }
  }
  s.topRows(mx) = first_row;
  for (Eigen::Index p = 1; p < i2; ++p)
    s.block(p * mx, 0, mx, my) = symmetric ? Eigen::MatrixXd(first_row.middleCols(p * my, my).transpose())
                                           : Eigen::MatrixXd(first_col.middleCols(p * mx, mx).transpose());
  for (Eigen::Index p = 1; p < i2; ++p)
    for (Eigen::Index q = 1; q < i2; ++q)
      s.block(p * mx, q * my, mx, my) = s.block((p - 1) * mx, (q - 1) * my, mx, my) +
                                        x.row(p - 1 + j).transpose() * y.row(q - 1 + j) -
                                        x.row(p - 1).transpose() * y.row(q - 1);
  return s;
}

/// out[q] += sum_{t < count} a[t] * b[t + q] for q < lags, in double-double.
///
/// Method: Ogita, Rump & Oishi's Dot2 ("Accurate sum and dot product", SIAM J.
/// Sci. Comput. 26 (2005) 1955-1988, Algorithm 5.3) within blocks of `block`
/// terms: the products are split exactly by two_prod, the running sum by
/// two_sum, and every error term is summed in double. Dot2's error bound grows
/// like (n u)^2 with the number of terms n; restarting it every block and adding
/// the block results in double-double keeps the error near block * u^2 relative
/// to sum |a b| (about 3e-30 for block = 256) however long the record. The lags
/// carry no dependency on each other: tiles of up to 16 of them keep their
/// partial sums in vector registers over a block. The portable build also holds
/// the kernel compiled for AVX2 + FMA and for AVX-512, chosen at run time by the
/// processor's features (src/core/lagged_sums.cpp); every kernel returns the same bits.
void correlate_double_double(const double* a, const double* b, Eigen::Index count, Eigen::Index lags,
                             DoubleDouble* out);
/// The same sums by the kernel without FMA (Dekker's product), whatever the
/// processor: for the test that every kernel returns the same bits.
void correlate_double_double_without_fma(const double* a, const double* b, Eigen::Index count, Eigen::Index lags,
                                         DoubleDouble* out);

/// lagged_sums in double-double (same layout and arguments): the first block row
/// and column by correlate_double_double, the window updates with exact
/// products and double-double additions. Cost about 10x the double version's
/// flops (no BLAS-3): worth it only when the double Gram matrix is too
/// inaccurate to factorise.
template <class MX, class MY>
DoubleDoubleMatrix lagged_sums_double_double(const MX& x_in, const MY& y_in, Eigen::Index i2, Eigen::Index j,
                                             bool symmetric) {
  // Contiguous columns for the kernel: a view of a plain matrix, a copy only of an expression.
  const Eigen::Ref<const Eigen::MatrixXd> x(x_in), y(y_in);
  const Eigen::Index mx = x.cols(), my = y.cols();
  DoubleDoubleMatrix s = DoubleDoubleMatrix::zero(i2 * mx, i2 * my);
  std::vector<DoubleDouble> lagged(static_cast<std::size_t>(i2));
  for (Eigen::Index a = 0; a < mx; ++a)
    for (Eigen::Index b = 0; b < my; ++b) {
      // S(0,q)(a,b) = sum_t x(t,a) y(t+q,b)
      std::fill(lagged.begin(), lagged.end(), DoubleDouble());
      correlate_double_double(x.col(a).data(), y.col(b).data(), j, i2, lagged.data());
      for (Eigen::Index q = 0; q < i2; ++q) s.set(a, q * my + b, lagged[static_cast<std::size_t>(q)]);
      if (symmetric) continue;
      // S(p,0)(a,b) = sum_t x(t+p,a) y(t,b)
      std::fill(lagged.begin(), lagged.end(), DoubleDouble());
      correlate_double_double(y.col(b).data(), x.col(a).data(), j, i2, lagged.data());
      for (Eigen::Index p = 1; p < i2; ++p) s.set(p * mx + a, b, lagged[static_cast<std::size_t>(p)]);
    }
  if (symmetric)
    for (Eigen::Index p = 1; p < i2; ++p)
      for (Eigen::Index a = 0; a < mx; ++a)
        for (Eigen::Index b = 0; b < my; ++b) s.set(p * mx + a, b, s(b, p * my + a));
  for (Eigen::Index p = 1; p < i2; ++p)
    for (Eigen::Index q = 1; q < i2; ++q)
      for (Eigen::Index a = 0; a < mx; ++a)
        for (Eigen::Index b = 0; b < my; ++b)
          s.set(p * mx + a, q * my + b,
                s((p - 1) * mx + a, (q - 1) * my + b) + two_prod(x(p - 1 + j, a), y(q - 1 + j, b)) -
                    two_prod(x(p - 1, a), y(q - 1, b)));
  return s;
}

/// Column `sign * signals[signal](t - shift)` of a matrix with one row per
/// sample t = 0..n-1, zero for t < shift (a regressor filtered from rest).
struct ShiftedColumn {
  std::size_t signal = 0;
  Eigen::Index shift = 0;
  double sign = 1.0;
};

/// The lagged sums S_ab(i, j) = sum_{t<n} x_a(t - i) x_b(t - j) of signals
/// (zero before t = 0) that a set of ShiftedColumns needs, per pair a <= b, in
/// double-double: the intermediate of shifted_columns_gram_double_double. A
/// caller that forms Gram matrices of several column sets over the same signals
/// keeps it and passes it as `known` to the next table (PEM's projection and
/// Jacobian share y / C and u / C).
struct LaggedSumsTable {
  std::size_t count = 0;                  ///< signals
  std::vector<Eigen::Index> lo, hi;       ///< shift range used per signal (hi = -1: unused)
  std::vector<DoubleDoubleMatrix> pairs;  ///< pairs[a * count + b] (a <= b): S_ab(i, j), i <= hi[a], j <= hi[b]

  /// The Gram entry of two columns: sign_u sign_v S(shift_u, shift_v).
  DoubleDouble entry(const ShiftedColumn& u, const ShiftedColumn& v) const {
    const bool ordered = u.signal <= v.signal;
    const DoubleDoubleMatrix& s = ordered ? pairs[u.signal * count + v.signal] : pairs[v.signal * count + u.signal];
    const DoubleDouble value = ordered ? s(u.shift, v.shift) : s(v.shift, u.shift);
    const double sign = u.sign * v.sign;
    return {sign * value.hi, sign * value.lo};
  }

  /// Whether pair (a, b) holds every S_ab the shift ranges [lo_a, hi_a] x [lo_b, hi_b] need.
  bool covers(std::size_t a, std::size_t b, Eigen::Index lo_a, Eigen::Index hi_a, Eigen::Index lo_b,
              Eigen::Index hi_b) const {
    return a < count && b < count && hi[a] >= 0 && hi[b] >= 0 && lo[a] <= lo_a && hi[a] >= hi_a && lo[b] <= lo_b &&
           hi[b] >= hi_b;
  }
};

/// The table of lagged sums that `columns` need, in O(n L) work for the L
/// distinct lags between the signals' shift ranges.
///
/// Method: let S(i, j) = sum_{t<n} x(t - i) y(t - j). Shifting both by one
/// drops the last sample:
///   S(i, j) = S(i - 1, j - 1) - x(n - i) y(n - j),
/// so every S on a diagonal i - j = L follows from its start, a correlation
/// sum at lag L: S(L, 0) = sum_s x(s) y(s + L) and S(0, L) = sum_s y(s) x(s + L)
/// (correlate_double_double, on copies zero-padded at the end). Only the lags
/// between the shift ranges that columns actually use are summed. A pair that
/// `known` covers (a table of the same first known->count signals, bit for
/// bit: the caller's promise) is copied from it instead.
///
/// Preconditions: every signal has the same length n, and n > every shift
/// (std::invalid_argument otherwise).
inline LaggedSumsTable lagged_sums_table(const std::vector<Eigen::VectorXd>& signals,
                                         const std::vector<ShiftedColumn>& columns,
                                         const LaggedSumsTable* known = nullptr) {
  const std::size_t count = signals.size();
  const Eigen::Index n = count > 0 ? signals.front().size() : 0;
  LaggedSumsTable table;
  table.count = count;
  table.lo.assign(count, n);
  table.hi.assign(count, -1);
  std::vector<Eigen::Index>&lo = table.lo, &hi = table.hi;
  Eigen::Index max_shift = 0;
  for (const ShiftedColumn& c : columns) {
    if (c.signal >= count || c.shift < 0) throw std::invalid_argument("shifted_columns_gram: column refers to no signal");
    lo[c.signal] = std::min(lo[c.signal], c.shift);
    hi[c.signal] = std::max(hi[c.signal], c.shift);
    max_shift = std::max(max_shift, c.shift);
  }
  for (const auto& x : signals)
    if (x.size() != n || n <= max_shift)
      throw std::invalid_argument("shifted_columns_gram: signals of unequal length or not longer than the largest shift");
  table.pairs.resize(count * count);
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t a = 0; a < count; ++a)
    for (std::size_t b = a; b < count; ++b) {
      if (hi[a] < 0 || hi[b] < 0) continue;
      if (known && known->covers(a, b, lo[a], hi[a], lo[b], hi[b]))
        table.pairs[a * count + b] = known->pairs[a * known->count + b];
      else
        pairs.emplace_back(a, b);
    }
  std::vector<Eigen::VectorXd> padded(count);
  for (const auto& [a, b] : pairs)
    for (const std::size_t k : {a, b})
      if (padded[k].size() == 0) {
        padded[k] = Eigen::VectorXd::Zero(n + max_shift + 1);
        padded[k].head(n) = signals[k];
      }
  // The pairs are independent: one per core at a time (core/parallel_for.hpp).
  parallel_for(pairs.size(), [&](std::size_t k) {
    const auto [a, b] = pairs[k];
    const Eigen::VectorXd &x = padded[a], &y = padded[b];
    DoubleDoubleMatrix& s = table.pairs[a * count + b];
    s = DoubleDoubleMatrix::zero(hi[a] + 1, hi[b] + 1);
    std::vector<DoubleDouble> base;
    // Diagonals i - j = L >= 0 start at S(L, 0); those with j - i = L > 0 at S(0, L).
    const Eigen::Index below = hi[a] - lo[b], above = hi[b] - lo[a];
    if (below >= 0) {
      base.assign(static_cast<std::size_t>(below + 1), DoubleDouble());
      correlate_double_double(x.data(), y.data(), n, below + 1, base.data());
      for (Eigen::Index lag = 0; lag <= std::min(below, hi[a]); ++lag) s.set(lag, 0, base[static_cast<std::size_t>(lag)]);
    }
    if (a == b) {
      // S(0, L) = S(L, 0) for a signal with itself: no second correlation.
      for (Eigen::Index lag = 1; lag <= std::min(below, hi[a]); ++lag) s.set(0, lag, s(lag, 0));
    } else if (above >= 1) {
      base.assign(static_cast<std::size_t>(above + 1), DoubleDouble());
      correlate_double_double(y.data(), x.data(), n, above + 1, base.data());
      for (Eigen::Index lag = 1; lag <= std::min(above, hi[b]); ++lag) s.set(0, lag, base[static_cast<std::size_t>(lag)]);
    }
    for (Eigen::Index i = 1; i <= hi[a]; ++i)
      for (Eigen::Index j = 1; j <= hi[b]; ++j) s.set(i, j, s(i - 1, j - 1) - two_prod(x(n - i), y(n - j)));
  });
  return table;
}

/// Gram matrix G(r, c) = entry(columns[r], columns[c]) of a table that covers the columns.
inline DoubleDoubleMatrix shifted_columns_gram(const LaggedSumsTable& table, const std::vector<ShiftedColumn>& columns) {
  const auto p = static_cast<Eigen::Index>(columns.size());
  DoubleDoubleMatrix gram{Eigen::MatrixXd(p, p), Eigen::MatrixXd(p, p)};
  for (Eigen::Index r = 0; r < p; ++r)
    for (Eigen::Index c = 0; c < p; ++c)
      gram.set(r, c, table.entry(columns[static_cast<std::size_t>(r)], columns[static_cast<std::size_t>(c)]));
  return gram;
}

/// Gram matrix G(a, b) = sum_{t<n} c_a(t) c_b(t) of ShiftedColumns, in
/// double-double, without forming the n x p matrix: O(n L) work for the L
/// distinct lags between the signals' shift ranges instead of O(n p^2)
/// (lagged_sums_table, then shifted_columns_gram).
///
/// Preconditions: every signal has the same length n, and n > every shift
/// (std::invalid_argument otherwise).
inline DoubleDoubleMatrix shifted_columns_gram_double_double(const std::vector<Eigen::VectorXd>& signals,
                                                             const std::vector<ShiftedColumn>& columns) {
  return shifted_columns_gram(lagged_sums_table(signals, columns), columns);
}

}  // namespace sysid::detail
