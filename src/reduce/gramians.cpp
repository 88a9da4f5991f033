// Implementation of reduce/gramians.hpp (Hammarling's method; details and
// references in the header). Compiled once into libsysid: the real Schur form,
// QR and complex triangular kernels are heavy to instantiate.
#include "reduce/detail/gramians.hpp"
#include <sysid/reduce/gramians.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>

namespace sysid {

namespace {

/// y[0..len) += a x[0..len), written on the real and imaginary parts (std::complex
/// products check for NaN, which stops vectorisation).
void complex_axpy(std::complex<double> a, const std::complex<double>* x, std::complex<double>* y,
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
Eigen::MatrixXcd hammarling_triangular(const Eigen::MatrixXcd& T, Eigen::MatrixXcd B, bool discrete) {
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
Eigen::MatrixXd real_lower_factor(const Eigen::MatrixXcd& L) {
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
Eigen::MatrixXd compress_columns(const Eigen::MatrixXd& B) {
  const Eigen::Index n = B.rows();
  if (B.cols() <= n) return B;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(B.transpose());
  return qr.matrixQR().topRows(n).triangularView<Eigen::Upper>().transpose();
}

}  // namespace

namespace detail {

ComplexSchurForm complex_schur_from_real(const Eigen::MatrixXd& A) {
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

Eigen::MatrixXd controllability_factor_from_schur(const ComplexSchurForm& s, const Eigen::MatrixXd& B,
                                                  bool discrete) {
  const Eigen::MatrixXd Bc = compress_columns(B);
  const Eigen::MatrixXcd Bt = s.U.adjoint() * Bc.cast<std::complex<double>>();
  const Eigen::MatrixXcd R = hammarling_triangular(s.T, Bt, discrete);
  const Eigen::MatrixXcd L = s.U * R.triangularView<Eigen::Upper>();
  return real_lower_factor(L);
}

Eigen::MatrixXd observability_factor_from_schur(const ComplexSchurForm& s, const Eigen::MatrixXd& C,
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

Eigen::MatrixXd controllability_gramian_factor_impl(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, bool discrete) {
  if (A.rows() != A.cols()) throw std::invalid_argument("controllability_gramian_factor: need A square");
  if (B.rows() != A.rows()) throw std::invalid_argument("controllability_gramian_factor: need rows(B) == rows(A)");
  const detail::ComplexSchurForm s = detail::complex_schur_from_real(A);
  return detail::controllability_factor_from_schur(s, B, discrete);
}

Eigen::MatrixXd observability_gramian_factor_impl(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, bool discrete) {
  if (A.rows() != A.cols()) throw std::invalid_argument("observability_gramian_factor: need A square");
  if (C.cols() != A.rows()) throw std::invalid_argument("observability_gramian_factor: need cols(C) == rows(A)");
  const detail::ComplexSchurForm s = detail::complex_schur_from_real(A);
  return detail::observability_factor_from_schur(s, C, discrete);
}

}  // namespace detail

GramianFactors gramian_factors(const StateSpace& sys) {
  sys.validate();
  const detail::ComplexSchurForm s = detail::complex_schur_from_real(sys.A);
  GramianFactors g;
  g.controllability = detail::controllability_factor_from_schur(s, sys.B, sys.is_discrete());
  g.observability = detail::observability_factor_from_schur(s, sys.C, sys.is_discrete());
  return g;
}

Eigen::MatrixXd gramian_from_factor(const Eigen::MatrixXd& L) { return L * L.transpose(); }

}  // namespace sysid
