#pragma once
/// @file
/// Purpose: controllability and observability Gramians of a stable linear system,
/// returned as square-root (Cholesky-like) factors, which is what balanced
/// truncation and the Hankel singular values need:
///
///   discrete (Ts > 0):   A Wc A^T - Wc + B B^T = 0,    A^T Wo A - Wo + C^T C = 0
///   continuous (Ts = 0): A Wc + Wc A^T + B B^T = 0,    A^T Wo + Wo A + C^T C = 0
///
/// with Wc = Lc Lc^T and Wo = Lo Lo^T, Lc and Lo real, n x n, lower triangular.
///
/// Method: Hammarling's method (S. J. Hammarling, "Numerical solution of the stable,
/// non-negative definite Lyapunov equation", IMA J. Numer. Anal. 2:303-323, 1982),
/// in its complex triangular form:
///  1. A = U T U^H with T upper triangular (complex Schur form), obtained from the
///     real Schur form (Eigen::RealSchur: Hessenberg reduction + Francis QR) by one
///     2x2 unitary rotation per 2x2 diagonal block (the first column of the rotation
///     is the block's eigenvector), which is cheaper than a complex QR iteration.
///  2. With B~ = U^H B the factor X = R R^H of T X + X T^H + B~ B~^H = 0 (or
///     T X T^H - X + B~ B~^H = 0) is computed column by column from the bottom
///     right: partition T = [T1 t; 0 tau], R = [R1 r; 0 rho], B~ = [B1; b]; then
///       continuous: rho = |b| / sqrt(-2 Re tau),
///                   (T1 + conj(tau) I) r = -(rho t + B1 b^H / rho),
///                   B1 <- B1 - r b / rho                  (Hammarling sec. 5),
///       discrete:   rho = |b| / sqrt(1 - |tau|^2),
///                   (conj(tau) T1 - I) r = -(conj(tau) rho t + B1 b^H / rho),
///                   v = T1 r + rho t,  q = b^H / |b|,
///                   B1 <- B1 (I - (1 - |tau|) q q^H) + c v q^H,
///                   c = -(conj(tau) / |tau|) sqrt(1 - |tau|^2)   (Hammarling sec. 6),
///     and the recursion continues on (T1, B1); the updated B1 satisfies
///     B1 B1^H = (the right-hand side of the leading block's equation), so the
///     factor never goes through the Gramian itself and stays accurate when the
///     Gramian is nearly singular (small Hankel singular values) or, for lightly
///     damped systems, very ill conditioned.
///  3. The observability Gramian uses the same Schur form: A^T = (U J)(J T^H J)(U J)^H
///     with J the reversal permutation, and J T^H J is upper triangular.
///  4. The complex factor L = U R has L L^H = W real, so the real n x 2n matrix
///     [Re L, Im L] is a real factor of W; a Householder QR of its transpose
///     compresses it to the n x n lower triangular factor returned.
///
/// Preconditions: A square (n x n), B with n rows (C with n columns), all poles
/// strictly stable (|z| < 1 discrete, Re s < 0 continuous): violations throw
/// std::invalid_argument. Use stable_unstable_split() (hankel_singular_values.hpp)
/// first for a model with unstable poles.
///
/// Numerical aspects: O(n^3): one real Schur decomposition (~25 n^3 flops) shared by
/// both Gramians, two triangular recursions of ~n^3/6 complex multiply-adds each,
/// two n x n complex products and two 2n x n QR compressions. Backward stable as
/// the Schur decomposition; the relative accuracy of each factor degrades only
/// with the separation of the spectrum from the stability boundary (1 - |z| or
/// -Re s), which is intrinsic to the Gramian.
///
/// References: Hammarling 1982 (above); SLICOT SB03OD/SB03OU documentation (the
/// real-arithmetic implementation of the same method).
#include <sysid/core/errors.hpp>
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>

namespace sysid {

namespace detail {

/// A = U T U^H, T upper triangular (complex Schur form).
struct ComplexSchurForm {
  Eigen::MatrixXcd T;
  Eigen::MatrixXcd U;
};

/// Complex Schur form of a real matrix: real Schur form, then one unitary 2x2
/// rotation per 2x2 diagonal block (see the file comment, step 1).
/// Throws NumericalError if the QR iteration does not converge.
inline ComplexSchurForm complex_schur_from_real(const Eigen::MatrixXd& A) {
  using Complex = std::complex<double>;
  const Eigen::Index n = A.rows();
  ComplexSchurForm out;
  if (n == 0) {
    out.T.resize(0, 0);
    out.U.resize(0, 0);
    return out;
  }
  const Eigen::RealSchur<Eigen::MatrixXd> rs(A, true);
  if (rs.info() != Eigen::Success) throw NumericalError("Schur decomposition: QR iteration did not converge");
  out.T = rs.matrixT().cast<Complex>();
  out.U = rs.matrixU().cast<Complex>();
  Eigen::MatrixXcd& T = out.T;
  Eigen::MatrixXcd& U = out.U;
  for (Eigen::Index k = 0; k + 1 < n; ++k) {
    if (T(k + 1, k) == 0.0) continue;
    const double a = T(k, k).real(), b = T(k, k + 1).real(), c = T(k + 1, k).real(), d = T(k + 1, k + 1).real();
    const double mean = 0.5 * (a + d), half = 0.5 * (a - d);
    const double disc = half * half + b * c;
    // A real Schur 2x2 block has complex eigenvalues (disc < 0); guard anyway.
    const Complex lambda = disc < 0.0 ? Complex(mean, std::sqrt(-disc)) : Complex(mean + std::sqrt(disc), 0.0);
    // Eigenvector from the second row: c v1 + (d - lambda) v2 = 0.
    Complex v1 = lambda - d, v2 = c;
    const double nv = std::sqrt(std::norm(v1) + std::norm(v2));
    v1 /= nv;
    v2 /= nv;
    Eigen::Matrix2cd G;
    G << v1, -std::conj(v2), v2, std::conj(v1);
    T.middleRows(k, 2).rightCols(n - k) = (G.adjoint() * T.middleRows(k, 2).rightCols(n - k)).eval();
    T.middleCols(k, 2).topRows(k + 2) = (T.middleCols(k, 2).topRows(k + 2) * G).eval();
    U.middleCols(k, 2) = (U.middleCols(k, 2) * G).eval();
    T(k + 1, k) = 0.0;
    ++k;  // the block is done; the next one starts two rows down
  }
  return out;
}

/// y[0..len) += a x[0..len), written on the real and imaginary parts (std::complex
/// products check for NaN, which stops vectorisation).
inline void complex_axpy(std::complex<double> a, const std::complex<double>* x, std::complex<double>* y,
                         Eigen::Index len) {
  const double ar = a.real(), ai = a.imag();
  const double* xd = reinterpret_cast<const double*>(x);
  double* yd = reinterpret_cast<double*>(y);
  for (Eigen::Index i = 0; i < len; ++i) {
    const double xr = xd[2 * i], xi = xd[2 * i + 1];
    yd[2 * i] += ar * xr - ai * xi;
    yd[2 * i + 1] += ar * xi + ai * xr;
  }
}

/// Hammarling's recursion on an upper triangular T (file comment, step 2): returns
/// the upper triangular R with R R^H = X, where T X + X T^H + B B^H = 0
/// (continuous) or T X T^H - X + B B^H = 0 (discrete).
/// Throws std::invalid_argument if a diagonal entry of T is not strictly stable.
inline Eigen::MatrixXcd hammarling_triangular(const Eigen::MatrixXcd& T, Eigen::MatrixXcd B, bool discrete) {
  using Complex = std::complex<double>;
  const Eigen::Index n = T.rows();
  Eigen::MatrixXcd R = Eigen::MatrixXcd::Zero(n, n);
  Eigen::VectorXcd r(n), v(n), Bq(n);
  for (Eigen::Index j = n - 1; j >= 0; --j) {
    const Complex tau = T(j, j);
    const double denom = discrete ? 1.0 - std::norm(tau) : -2.0 * tau.real();
    if (!(denom > 0.0))
      throw std::invalid_argument(discrete ? "gramian: need every pole |z| < 1 (stable discrete system)"
                                           : "gramian: need every pole Re(s) < 0 (stable continuous system)");
    const double beta = B.row(j).norm();
    const double rho = beta / std::sqrt(denom);
    R(j, j) = rho;
    // rho = 0: b = 0, so r = 0 and B1 is unchanged (both right-hand sides vanish).
    if (j == 0 || rho == 0.0) continue;
    auto rj = r.head(j);
    rj.noalias() = -(B.topRows(j) * B.row(j).adjoint()) / rho;
    const Complex ct = std::conj(tau);
    rj -= (discrete ? ct * rho : Complex(rho)) * T.col(j).head(j);
    // Back substitution with the shifted triangular matrix, column oriented so
    // every update is a contiguous axpy on a column of T (raw loops: the vectors
    // are short and an expression per column would cost more than the arithmetic).
    const Complex* Td = T.data();
    Complex* rd = r.data();
    for (Eigen::Index k = j - 1; k >= 0; --k) {
      const Complex* Tk = Td + k * n;
      const Complex diag = discrete ? ct * Tk[k] - 1.0 : Tk[k] + ct;
      const Complex rk = rd[k] / diag;
      rd[k] = rk;
      const Complex f = discrete ? ct * rk : rk;
      if (f == 0.0) continue;
      complex_axpy(-f, Tk, rd, k);
    }
    R.col(j).head(j) = rj;
    if (!discrete) {
      B.topRows(j).noalias() -= (rj / rho) * B.row(j);
    } else {
      auto vj = v.head(j);
      // v = T1 r + rho t (upper triangular T1), column by column.
      vj = rho * T.col(j).head(j);
      Complex* vd = v.data();
      for (Eigen::Index k = 0; k < j; ++k) {
        const Complex rk = rd[k];
        if (rk == 0.0) continue;
        const Complex* Tk = Td + k * n;
        complex_axpy(rk, Tk, vd, k + 1);
      }
      const Eigen::RowVectorXcd qh = B.row(j) / beta;  // q^H
      const double at = std::abs(tau);
      const Complex c = at > 0.0 ? -(ct / at) * std::sqrt(denom) : Complex(-1.0);
      auto bq = Bq.head(j);
      bq.noalias() = B.topRows(j) * qh.adjoint();
      bq *= -(1.0 - at);
      bq += c * vj;
      B.topRows(j).noalias() += bq * qh;
    }
  }
  return R;
}

/// Real n x n lower triangular F with F F^T = L L^H, for a complex L whose Gram
/// matrix L L^H is real (file comment, step 4).
inline Eigen::MatrixXd real_lower_factor(const Eigen::MatrixXcd& L) {
  const Eigen::Index n = L.rows(), k = L.cols();
  Eigen::MatrixXd F(2 * k, n);
  F.topRows(k) = L.real().transpose();
  F.bottomRows(k) = L.imag().transpose();
  Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(F);  // in place
  const Eigen::Index p = std::min<Eigen::Index>(2 * k, n);
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, n);
  out.leftCols(p) = qr.matrixQR().topRows(p).triangularView<Eigen::Upper>().transpose();
  return out;
}

/// Reduces a real n x m input matrix with m > n to n columns with the same B B^T
/// (QR of B^T), so the recursion's cost stays O(n^3).
inline Eigen::MatrixXd compress_columns(const Eigen::MatrixXd& B) {
  const Eigen::Index n = B.rows();
  if (B.cols() <= n) return B;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(B.transpose());
  return qr.matrixQR().topRows(n).triangularView<Eigen::Upper>().transpose();
}

inline Eigen::MatrixXd controllability_factor_from_schur(const ComplexSchurForm& s, const Eigen::MatrixXd& B,
                                                         bool discrete) {
  const Eigen::MatrixXd Bc = compress_columns(B);
  const Eigen::MatrixXcd Bt = s.U.adjoint() * Bc.cast<std::complex<double>>();
  const Eigen::MatrixXcd R = hammarling_triangular(s.T, Bt, discrete);
  const Eigen::MatrixXcd L = s.U * R.triangularView<Eigen::Upper>();
  return real_lower_factor(L);
}

inline Eigen::MatrixXd observability_factor_from_schur(const ComplexSchurForm& s, const Eigen::MatrixXd& C,
                                                       bool discrete) {
  // A^T = (U J)(J T^H J)(U J)^H with J the reversal: J T^H J is upper triangular.
  const Eigen::MatrixXd Ct = compress_columns(C.transpose());
  const Eigen::MatrixXcd Tf = s.T.adjoint().reverse();
  const Eigen::MatrixXcd UJ = s.U.rowwise().reverse();
  const Eigen::MatrixXcd Bt = UJ.adjoint() * Ct.cast<std::complex<double>>();
  const Eigen::MatrixXcd R = hammarling_triangular(Tf, Bt, discrete);
  const Eigen::MatrixXcd L = UJ * R.triangularView<Eigen::Upper>();
  return real_lower_factor(L);
}

}  // namespace detail

/// Square-root factors of both Gramians: Wc = controllability * controllability^T,
/// Wo = observability * observability^T (each n x n, lower triangular).
struct GramianFactors {
  Eigen::MatrixXd controllability;  ///< Lc
  Eigen::MatrixXd observability;    ///< Lo
};

/// Purpose: factor Lc (n x n, lower triangular) of the controllability Gramian of
/// (A, B): A Wc A^T - Wc + B B^T = 0 if discrete, A Wc + Wc A^T + B B^T = 0 if not,
/// Wc = Lc Lc^T.
/// Method / Numerical aspects: see the file comment (Hammarling 1982).
/// Preconditions: A n x n, B n x m, A strictly stable; std::invalid_argument otherwise.
template <class DerivedA, class DerivedB>
Eigen::MatrixXd controllability_gramian_factor(const Eigen::MatrixBase<DerivedA>& A,
                                               const Eigen::MatrixBase<DerivedB>& B, bool discrete) {
  if (A.rows() != A.cols()) throw std::invalid_argument("controllability_gramian_factor: need A square");
  if (B.rows() != A.rows()) throw std::invalid_argument("controllability_gramian_factor: need rows(B) == rows(A)");
  const detail::ComplexSchurForm s = detail::complex_schur_from_real(A.eval());
  return detail::controllability_factor_from_schur(s, B.eval(), discrete);
}

/// Purpose: factor Lo (n x n, lower triangular) of the observability Gramian of
/// (A, C): A^T Wo A - Wo + C^T C = 0 if discrete, A^T Wo + Wo A + C^T C = 0 if not,
/// Wo = Lo Lo^T.
/// Preconditions: A n x n, C l x n, A strictly stable; std::invalid_argument otherwise.
template <class DerivedA, class DerivedC>
Eigen::MatrixXd observability_gramian_factor(const Eigen::MatrixBase<DerivedA>& A,
                                             const Eigen::MatrixBase<DerivedC>& C, bool discrete) {
  if (A.rows() != A.cols()) throw std::invalid_argument("observability_gramian_factor: need A square");
  if (C.cols() != A.rows()) throw std::invalid_argument("observability_gramian_factor: need cols(C) == rows(A)");
  const detail::ComplexSchurForm s = detail::complex_schur_from_real(A.eval());
  return detail::observability_factor_from_schur(s, C.eval(), discrete);
}

/// Purpose: both Gramian factors of a model (discrete if Ts > 0), sharing one Schur
/// decomposition.
/// Preconditions: a valid, strictly stable StateSpace (std::invalid_argument otherwise).
inline GramianFactors gramian_factors(const StateSpace& sys) {
  sys.validate();
  const detail::ComplexSchurForm s = detail::complex_schur_from_real(sys.A);
  GramianFactors g;
  g.controllability = detail::controllability_factor_from_schur(s, sys.B, sys.is_discrete());
  g.observability = detail::observability_factor_from_schur(s, sys.C, sys.is_discrete());
  return g;
}

/// Purpose: the Gramian W = L L^T itself, from a factor (convenience).
inline Eigen::MatrixXd gramian_from_factor(const Eigen::MatrixXd& L) { return L * L.transpose(); }

}  // namespace sysid
