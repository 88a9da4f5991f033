// Implementation of core/poles_zeros.hpp (method and references in the header).
// Compiled once into libsysid: the eigenvalue, SVD and QZ solvers below are heavy
// to instantiate.
#include "core/detail/poles_zeros.hpp"
#include <sysid/core/errors.hpp>
#include <sysid/core/poles_zeros.hpp>

#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

namespace {

/// Number of singular values above tol.
Eigen::Index numerical_rank(const Eigen::VectorXd& singular_values, double tol) {
  Eigen::Index r = 0;
  for (Eigen::Index i = 0; i < singular_values.size(); ++i)
    if (singular_values[i] > tol) ++r;
  return r;
}

/// A system with the same finite invariant zeros as the input and D of full row
/// rank (Emami-Naeini & Van Dooren 1982, procedure "reduce"). The number of rows
/// of D at the end equals the normal rank of the transfer matrix.
struct ZeroReducedSystem {
  Eigen::MatrixXd A, B, C, D;
};

ZeroReducedSystem reduce_for_zeros(Eigen::MatrixXd A, Eigen::MatrixXd B, Eigen::MatrixXd C, Eigen::MatrixXd D,
                                   double tol) {
  for (;;) {
    const Eigen::Index n = A.rows(), m = B.cols(), p = C.rows();
    if (p == 0) break;
    // 1. Row compression of D: U^T D = [D1; 0] with D1 (sigma x m) of full row rank.
    Eigen::JacobiSVD<Eigen::MatrixXd> svd_d(D, Eigen::ComputeFullU);
    const Eigen::Index sigma = numerical_rank(svd_d.singularValues(), tol);
    const Eigen::Index tau = p - sigma;
    if (tau == 0) break;  // D has full row rank: done
    const Eigen::MatrixXd& U = svd_d.matrixU();
    const Eigen::MatrixXd Cu = U.transpose() * C;
    const Eigen::MatrixXd D1 = (U.transpose() * D).topRows(sigma);
    const Eigen::MatrixXd C1 = Cu.topRows(sigma);
    if (n == 0) {  // the tau rows [C2 0] are empty: those outputs are identically zero
      C = C1;
      D = D1;
      continue;
    }
    // 2. Column compression of C2 (the rows D cannot see): C2 V = [0 C~] with
    // C~ of full column rank rho; rows of C2 beyond its rank are zero outputs.
    const Eigen::MatrixXd C2 = Cu.bottomRows(tau);
    Eigen::JacobiSVD<Eigen::MatrixXd> svd_c(C2, Eigen::ComputeFullV);
    const Eigen::Index rho = numerical_rank(svd_c.singularValues(), tol);
    if (rho == 0) {
      C = C1;
      D = D1;
      continue;
    }
    // V = [null space of C2, row space of C2], so the last rho states are the ones
    // C2 measures.
    const Eigen::Index nr = n - rho;
    Eigen::MatrixXd V(n, n);
    V << svd_c.matrixV().rightCols(nr), svd_c.matrixV().leftCols(rho);
    const Eigen::MatrixXd Av = V.transpose() * A * V;
    const Eigen::MatrixXd Bv = V.transpose() * B;
    const Eigen::MatrixXd C1v = C1 * V;
    // 3. In the transformed pencil the rows [0 C~ 0] have a constant invertible
    // block in the columns of the last rho states: unimodular row operations
    // clear those columns, and deleting them with the rows [0 C~ 0] leaves the
    // pencil of the system (A11, B1, [A21; C11], [B2; D1]) with the same finite zeros.
    Eigen::MatrixXd An = Av.topLeftCorner(nr, nr);
    Eigen::MatrixXd Bn = Bv.topRows(nr);
    Eigen::MatrixXd Cn(rho + sigma, nr), Dn(rho + sigma, m);
    // With no state left (nr = 0) Cn is empty: filling it by blocks would offset
    // its null data pointer (undefined behaviour, found by UBSan).
    if (nr > 0) Cn << Av.bottomLeftCorner(rho, nr), C1v.leftCols(nr);
    Dn << Bv.bottomRows(rho), D1;
    A = std::move(An);
    B = std::move(Bn);
    C = std::move(Cn);
    D = std::move(Dn);
  }
  return {std::move(A), std::move(B), std::move(C), std::move(D)};
}

}  // namespace

namespace detail {

Eigen::VectorXd balance_in_place(Eigen::MatrixXd& A) {
  const Eigen::Index n = A.rows();
  Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
  bool changed = true;
  // Each accepted step lowers sum(c_i + r_i) by >= 5 %, so the loop ends; the
  // iteration cap is a guard against pathological Inf/NaN-free overflow cycles.
  for (int sweep = 0; changed && sweep < 100; ++sweep) {
    changed = false;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double c = A.col(i).cwiseAbs().sum() - std::abs(A(i, i));
      const double r = A.row(i).cwiseAbs().sum() - std::abs(A(i, i));
      if (c == 0.0 || r == 0.0) continue;
      // f = 2^e with e the integer nearest to log2(sqrt(r / c)) makes c f ~ r / f.
      const int e = static_cast<int>(std::lround(0.5 * std::log2(r / c)));
      if (e == 0) continue;
      const double f = std::ldexp(1.0, e);
      if (c * f + r / f >= 0.95 * (c + r)) continue;
      A.col(i) *= f;
      A.row(i) /= f;
      d[i] *= f;
      changed = true;
    }
  }
  return d;
}

InvariantZeros invariant_zeros(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& C,
                               const Eigen::MatrixXd& D) {
  const Eigen::Index n = A.rows(), m = B.cols(), p = C.rows();
  Eigen::MatrixXd S(n + p, n + m);
  S << A, B, C, D;
  if (p == m) {
    // Balance the square system matrix: diag(d)^-1 S diag(d) is a state similarity
    // on the first n indices and a row (output) / column (input) scaling on the
    // last m, none of which moves a zero. Companion-form realisations of
    // polynomial models have entries spanning many decades; unbalanced, their
    // zeros lose several digits (e.g. 3e-5 absolute for an order-6 continuous
    // numerator with roots of size 10).
    balance_in_place(S);
  }
  const double eps = std::numeric_limits<double>::epsilon();
  const double norm = S.norm();
  // Rank decisions relative to the whole system matrix (SLICOT AB08ND default).
  const double tol = static_cast<double>((n + p) * (n + m)) * eps * (norm > 0.0 ? norm : 1.0);
  ZeroReducedSystem r = reduce_for_zeros(S.topLeftCorner(n, n), S.topRightCorner(n, m), S.bottomLeftCorner(p, n),
                                         S.bottomRightCorner(p, m), tol);
  InvariantZeros out;
  out.normal_rank = r.D.rows();
  const Eigen::Index nr = r.A.rows();
  if (out.normal_rank != m || nr == 0) return out;
  // 4. Column compression [C_r D_r] W = [0 D~]: W = [null space, row space] of
  // [C_r D_r] from a full QR of its transpose.
  Eigen::MatrixXd CD(m, nr + m);
  CD << r.C, r.D;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(CD.transpose());
  const Eigen::MatrixXd Qfull = qr.householderQ();
  const Eigen::MatrixXd W1 = Qfull.rightCols(nr);  // spans the null space of [C_r D_r]
  Eigen::MatrixXd AB(nr, nr + m);
  AB << r.A, r.B;
  const Eigen::MatrixXd Af = AB * W1;
  const Eigen::MatrixXd Ef = W1.topRows(nr);
  Eigen::GeneralizedEigenSolver<Eigen::MatrixXd> ges(Af, Ef, false);
  if (ges.info() != Eigen::Success) throw NumericalError("zeros: QZ iteration did not converge");
  const Eigen::VectorXcd alpha = ges.alphas();
  const Eigen::VectorXd beta = ges.betas();
  // E_f is nonsingular in exact arithmetic (det S(lambda) has degree n_r), so an
  // eigenvalue is treated as infinite only when |beta| is at rounding level
  // relative to |alpha| and the norms of the pencil.
  const double scale_a = Af.norm(), scale_e = Ef.norm();
  std::vector<std::complex<double>> z;
  for (Eigen::Index i = 0; i < nr; ++i) {
    if (std::abs(beta[i]) * scale_a <= static_cast<double>(nr) * eps * std::abs(alpha[i]) * scale_e) continue;
    z.push_back(alpha[i] / beta[i]);
  }
  out.zeros = Eigen::Map<const Eigen::VectorXcd>(z.data(), static_cast<Eigen::Index>(z.size()));
  return out;
}

}  // namespace detail

Eigen::VectorXcd poles(const StateSpace& sys) {
  sys.validate();
  if (sys.order() == 0) return Eigen::VectorXcd();
  Eigen::MatrixXd A = sys.A;
  detail::balance_in_place(A);
  Eigen::EigenSolver<Eigen::MatrixXd> es(A, false);
  if (es.info() != Eigen::Success) throw NumericalError("poles: eigenvalue iteration did not converge");
  return es.eigenvalues();
}

Eigen::VectorXcd transmission_zeros(const StateSpace& sys) {
  sys.validate();
  if (sys.outputs() != sys.inputs())
    throw std::invalid_argument("transmission_zeros: need outputs == inputs (" + std::to_string(sys.outputs()) +
                                " != " + std::to_string(sys.inputs()) + ")");
  detail::InvariantZeros z = detail::invariant_zeros(sys.A, sys.B, sys.C, sys.D);
  if (z.normal_rank != sys.inputs())
    throw NumericalError("transmission_zeros: transfer matrix has normal rank " + std::to_string(z.normal_rank) + " < " +
                         std::to_string(sys.inputs()) + "; zeros are undefined");
  return z.zeros;
}

Eigen::VectorXcd channel_zeros(const StateSpace& sys, Eigen::Index output, Eigen::Index input) {
  sys.validate();
  if (output < 0 || output >= sys.outputs() || input < 0 || input >= sys.inputs())
    throw std::invalid_argument("channel_zeros: need 0 <= output < " + std::to_string(sys.outputs()) +
                                " and 0 <= input < " + std::to_string(sys.inputs()));
  detail::InvariantZeros z = detail::invariant_zeros(sys.A, sys.B.col(input), sys.C.row(output),
                                                     sys.D.block(output, input, 1, 1));
  if (z.normal_rank != 1)
    throw NumericalError("channel_zeros: channel " + sys.output_name(output) + " <- " + sys.input_name(input) +
                         " is identically zero; zeros are undefined");
  return z.zeros;
}

}  // namespace sysid
