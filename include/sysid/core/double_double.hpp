#pragma once
/// @file
/// Purpose: double-double ("double-word") arithmetic: a value hi + lo held as
/// two doubles with |lo| <= ulp(hi) / 2, about 106 significant bits (unit
/// roundoff ~ 1e-32), for the few places where a Gram matrix must be formed
/// and factorised beyond double precision (hankel/block_hankel.hpp).
///
/// Method: the error-free transformations
///  - two_sum (Knuth): s + e = a + b exactly, s = fl(a + b);
///  - fast_two_sum (Dekker): the same when |a| >= |b|;
///  - two_prod: p + e = a * b exactly, p = fl(a * b), by one fused multiply-add
///    where the hardware has it (FP_FAST_FMA) and by Veltkamp's splitting and
///    Dekker's product otherwise (a software fma would be a slow library call);
/// and on them the double-word operations of M. Joldes, J.-M. Muller and
/// V. Popescu, "Tight and rigorous error bounds for basic building blocks of
/// double-word arithmetic", ACM TOMS 44 (2017) 15: addition Algorithm 6
/// (relative error <= 3u^2), multiplication in the form of their Algorithms
/// 10-12, division Algorithm 17 (<= 15u^2 + 56u^3), u = 2^-53: relative errors
/// of a few u^2 (the paper proves the bounds). The square root is
/// one Newton step on the double estimate (Karp & Markstein, "High-precision
/// division and square root", ACM TOMS 23 (1997) 561-589), error O(u^2).
///
/// Numerical aspects: correct only with IEEE double evaluation in round to
/// nearest and no value-changing optimisation (-ffast-math would fold the
/// error terms away). Contraction of a*b + c into an fma (GCC's default
/// -ffp-contract=fast) changes the rounded sums by at most O(u^2) relative and
/// keeps the bounds of order u^2. No overflow handling: operands are data
/// scaled to O(1).
#include <Eigen/Core>

#include <cmath>

namespace sysid {

struct DoubleDouble {
  double hi = 0.0;
  double lo = 0.0;
  DoubleDouble() = default;
  constexpr DoubleDouble(double h) : hi(h) {}  // NOLINT: implicit from double is the point
  constexpr DoubleDouble(double h, double l) : hi(h), lo(l) {}
  double to_double() const { return hi + lo; }
};

/// s + e == a + b exactly (Knuth's TwoSum, 6 flops, no condition on a, b).
inline DoubleDouble two_sum(double a, double b) {
  const double s = a + b;
  const double bb = s - a;
  return {s, (a - (s - bb)) + (b - bb)};
}

/// s + e == a + b exactly, provided |a| >= |b| or a == 0 (Dekker's FastTwoSum).
inline DoubleDouble fast_two_sum(double a, double b) {
  const double s = a + b;
  return {s, b - (s - a)};
}

/// p + e == a * b exactly (barring underflow), by one fused multiply-add.
inline DoubleDouble two_prod_fma(double a, double b) {
  const double p = a * b;
  return {p, std::fma(a, b, -p)};
}

/// p + e == a * b exactly (barring underflow and overflow of 2^27 a), without
/// an fma: Veltkamp's splitting into 26-bit halves, then Dekker's exact product.
inline DoubleDouble two_prod_dekker(double a, double b) {
  constexpr double split = 134217729.0;  // 2^27 + 1
  const double p = a * b;
  const double ta = split * a, tb = split * b;
  const double ah = ta - (ta - a), al = a - ah;
  const double bh = tb - (tb - b), bl = b - bh;
  return {p, ((ah * bh - p) + ah * bl + al * bh) + al * bl};
}

/// p + e == a * b exactly: the fma form where the hardware has one (a software
/// fma would be a slow library call), Dekker's otherwise.
inline DoubleDouble two_prod(double a, double b) {
#ifdef FP_FAST_FMA
  return two_prod_fma(a, b);
#else
  return two_prod_dekker(a, b);
#endif
}

/// Joldes-Muller-Popescu 2017, Algorithm 6 (AccurateDWPlusDW).
inline DoubleDouble operator+(const DoubleDouble& x, const DoubleDouble& y) {
  const DoubleDouble s = two_sum(x.hi, y.hi);
  const DoubleDouble t = two_sum(x.lo, y.lo);
  const DoubleDouble v = fast_two_sum(s.hi, s.lo + t.hi);
  return fast_two_sum(v.hi, t.lo + v.lo);
}

inline DoubleDouble operator-(const DoubleDouble& x) { return {-x.hi, -x.lo}; }
inline DoubleDouble operator-(const DoubleDouble& x, const DoubleDouble& y) { return x + (-y); }

/// Double-word product (Joldes-Muller-Popescu 2017, sec. 5): exact hi*hi, the
/// cross terms in double, one renormalisation.
inline DoubleDouble operator*(const DoubleDouble& x, const DoubleDouble& y) {
  const DoubleDouble c = two_prod(x.hi, y.hi);
  const double cross = x.lo * y.lo + (x.hi * y.lo + x.lo * y.hi);
  return fast_two_sum(c.hi, c.lo + cross);
}

/// Joldes-Muller-Popescu 2017, Algorithm 17 (DWDivDW2).
inline DoubleDouble operator/(const DoubleDouble& x, const DoubleDouble& y) {
  const double th = x.hi / y.hi;
  const DoubleDouble r = y * DoubleDouble(th);
  const double pi = x.hi - r.hi;
  const double delta = (pi + (x.lo - r.lo)) / y.hi;
  return fast_two_sum(th, delta);
}

inline DoubleDouble& operator+=(DoubleDouble& x, const DoubleDouble& y) { return x = x + y; }
inline DoubleDouble& operator-=(DoubleDouble& x, const DoubleDouble& y) { return x = x - y; }

/// sqrt(x) for x >= 0: s = fl(sqrt(hi)), then one Newton step s + (x - s^2) / (2 s)
/// with x - s^2 formed exactly enough by two_prod (Karp & Markstein 1997).
inline DoubleDouble sqrt(const DoubleDouble& x) {
  if (!(x.hi > 0.0)) return {x.hi == 0.0 ? 0.0 : std::sqrt(x.hi), 0.0};  // 0, or NaN for a negative argument
  const double s = std::sqrt(x.hi);
  const DoubleDouble s2 = two_prod(s, s);
  const double residual = ((x.hi - s2.hi) - s2.lo) + x.lo;
  return fast_two_sum(s, residual / (2.0 * s));
}

/// sum_p x[p] y[p] of double-double vectors, as a double-double.
///
/// Method: Ogita, Rump & Oishi's Dot2 (SIAM J. Sci. Comput. 26 (2005) 1955,
/// Algorithm 5.3) on the hi parts (exact products by two_prod, running sums by
/// two_sum, their errors summed in double), the cross terms x.hi y.lo + x.lo y.hi
/// added to the error sum (x.lo y.lo, ~u^2 of a term, is dropped); four
/// independent partial sums, joined at the end in double-double. Error about
/// (n + 4) u^2 sum |x_p y_p|, the order of n accumulating double-double
/// multiply-adds (3u^2 of the running sum each), but the partial sums carry no
/// renormalisation from one term to the next: the four chains overlap in the
/// pipeline where a double-double accumulation is one long dependency.
inline DoubleDouble dot(const DoubleDouble* x, const DoubleDouble* y, Eigen::Index n) {
  constexpr int lanes = 4;
  double hi[lanes] = {0.0, 0.0, 0.0, 0.0}, err[lanes] = {0.0, 0.0, 0.0, 0.0};
  auto term = [&](Eigen::Index p, int lane) {
    const DoubleDouble product = two_prod(x[p].hi, y[p].hi);
    const DoubleDouble sum = two_sum(hi[lane], product.hi);
    hi[lane] = sum.hi;
    err[lane] += (product.lo + sum.lo) + (x[p].hi * y[p].lo + x[p].lo * y[p].hi);
  };
  Eigen::Index p = 0;
  for (; p + lanes <= n; p += lanes)
    for (int lane = 0; lane < lanes; ++lane) term(p + lane, lane);
  for (int lane = 0; p < n; ++p, ++lane) term(p, lane);
  const DoubleDouble joined = (DoubleDouble(hi[0]) + DoubleDouble(hi[1])) + (DoubleDouble(hi[2]) + DoubleDouble(hi[3]));
  return joined + DoubleDouble((err[0] + err[1]) + (err[2] + err[3]));
}

/// A matrix of double-double values kept as two double matrices: value = hi + lo
/// (hi alone is the matrix rounded to double).
struct DoubleDoubleMatrix {
  Eigen::MatrixXd hi, lo;
  static DoubleDoubleMatrix zero(Eigen::Index rows, Eigen::Index cols) {
    return {Eigen::MatrixXd::Zero(rows, cols), Eigen::MatrixXd::Zero(rows, cols)};
  }
  DoubleDouble operator()(Eigen::Index r, Eigen::Index c) const { return {hi(r, c), lo(r, c)}; }
  void set(Eigen::Index r, Eigen::Index c, const DoubleDouble& v) {
    hi(r, c) = v.hi;
    lo(r, c) = v.lo;
  }
};

/// target(row.., col..) += block (or block^T), in double-double.
inline void add_block(DoubleDoubleMatrix& target, Eigen::Index row, Eigen::Index col, const DoubleDoubleMatrix& block,
                      bool transposed = false) {
  const Eigen::Index rows = transposed ? block.hi.cols() : block.hi.rows();
  const Eigen::Index cols = transposed ? block.hi.rows() : block.hi.cols();
  for (Eigen::Index c = 0; c < cols; ++c)
    for (Eigen::Index r = 0; r < rows; ++r)
      target.set(row + r, col + c, target(row + r, col + c) + (transposed ? block(c, r) : block(r, c)));
}

}  // namespace sysid
