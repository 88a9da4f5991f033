// Implementation of reduce/hankel_singular_values.hpp (method and references in the
// header). Compiled once into libsysid: the Schur reordering, Sylvester solve,
// QR, symmetric eigensolver and SVD are heavy to instantiate.
#include "core/detail/poles_zeros.hpp"
#include <sysid/core/format_number.hpp>
#include "reduce/detail/gramians.hpp"
#include "reduce/detail/hankel_singular_values.hpp"
#include <sysid/reduce/hankel_singular_values.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

namespace {

bool is_stable_pole(std::complex<double> p, bool discrete, double tol) {
  if (discrete) return std::abs(p) < 1.0 - tol;
  const double a = std::abs(p);
  return a > 0.0 && -p.real() > tol * a;
}

/// Swaps the adjacent diagonal entries p, p+1 of the triangular T (and updates U).
void swap_schur_entries(Eigen::MatrixXcd& T, Eigen::MatrixXcd& U, Eigen::Index p) {
  using Complex = std::complex<double>;
  const Eigen::Index n = T.rows();
  const Complex t11 = T(p, p), t22 = T(p + 1, p + 1);
  // First column of the rotation: eigenvector of [t11 t12; 0 t22] for t22.
  Complex v1 = T(p, p + 1), v2 = t22 - t11;
  const double nv = std::sqrt(std::norm(v1) + std::norm(v2));
  if (nv == 0.0) return;
  v1 /= nv;
  v2 /= nv;
  Eigen::Matrix2cd G;
  G << v1, -std::conj(v2), v2, std::conj(v1);
  T.middleRows(p, 2).rightCols(n - p) = (G.adjoint() * T.middleRows(p, 2).rightCols(n - p)).eval();
  T.middleCols(p, 2).topRows(p + 2) = (T.middleCols(p, 2).topRows(p + 2) * G).eval();
  U.middleCols(p, 2) = (U.middleCols(p, 2) * G).eval();
  T(p + 1, p) = 0.0;
  T(p, p) = t22;
  T(p + 1, p + 1) = t11;
}

/// Solves T11 Z - Z T22 = F for upper triangular T11, T22 (column by column).
Eigen::MatrixXcd triangular_sylvester(const Eigen::MatrixXcd& T11, const Eigen::MatrixXcd& T22,
                                      Eigen::MatrixXcd F) {
  const Eigen::Index k = T11.rows(), q = T22.rows();
  for (Eigen::Index j = 0; j < q; ++j) {
    if (j > 0) F.col(j).noalias() += F.leftCols(j) * T22.col(j).head(j);
    Eigen::MatrixXcd M = T11;
    M.diagonal().array() -= T22(j, j);
    M.triangularView<Eigen::Upper>().solveInPlace(F.col(j));
    (void)k;
  }
  return F;
}

}  // namespace

namespace detail {

StateSpace balanced_realisation(const StateSpace& sys) {
  StateSpace b = sys;
  if (sys.order() == 0) return b;
  const Eigen::VectorXd d = balance_in_place(b.A);
  b.B = d.cwiseInverse().asDiagonal() * sys.B;
  b.C = sys.C * d.asDiagonal();
  return b;
}

SquareRootBalancing square_root_balancing(const StateSpace& stable, const ComplexSchurForm& schur,
                                          bool vectors) {
  SquareRootBalancing s;
  GramianFactors f;
  f.controllability = controllability_factor_from_schur(schur, stable.B, stable.is_discrete());
  f.observability = observability_factor_from_schur(schur, stable.C, stable.is_discrete());
  s.Lc = f.controllability;
  s.Lo = f.observability;
  const Eigen::MatrixXd M = s.Lo.transpose() * s.Lc;
  const Eigen::Index n = M.rows();
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(n, n);
  S.selfadjointView<Eigen::Lower>().rankUpdate(M.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S);
  if (es.info() == Eigen::Success && n > 0 && es.eigenvalues()(n - 1) > 0.0 &&
      es.eigenvalues()(0) >= 1e-10 * es.eigenvalues()(n - 1)) {
    const Eigen::MatrixXd V = es.eigenvectors().rowwise().reverse();  // descending
    const Eigen::MatrixXd W = M * V;
    const Eigen::VectorXd norms = W.colwise().norm().transpose();
    // The norms may reorder near-equal values: sort descending.
    std::vector<Eigen::Index> idx(static_cast<std::size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) idx[static_cast<std::size_t>(i)] = i;
    std::stable_sort(idx.begin(), idx.end(), [&](Eigen::Index a, Eigen::Index b) { return norms(a) > norms(b); });
    s.hsv.resize(n);
    if (vectors) {
      s.U.resize(n, n);
      s.V.resize(n, n);
    }
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Index j = idx[static_cast<std::size_t>(i)];
      s.hsv(i) = norms(j);
      if (vectors) {
        s.V.col(i) = V.col(j);
        s.U.col(i) = W.col(j) / norms(j);
      }
    }
    return s;
  }
  if (vectors) {
    const Eigen::BDCSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeThinU | Eigen::ComputeThinV);
    s.hsv = svd.singularValues();
    s.U = svd.matrixU();
    s.V = svd.matrixV();
  } else {
    const Eigen::BDCSVD<Eigen::MatrixXd> svd(M);
    s.hsv = svd.singularValues();
  }
  return s;
}

StabilitySplit stable_unstable_split(const StateSpace& sys, double tol, ComplexSchurForm& stable_schur) {
  using Complex = std::complex<double>;
  sys.validate();
  if (!(tol >= 0.0 && tol < 1.0)) throw std::invalid_argument("stable_unstable_split: need 0 <= tol < 1");
  const Eigen::Index n = sys.order(), m = sys.inputs(), l = sys.outputs();
  const bool discrete = sys.is_discrete();
  auto empty = [&](Eigen::MatrixXd D) {
    StateSpace e(Eigen::MatrixXd(0, 0), Eigen::MatrixXd(0, m), Eigen::MatrixXd(l, 0), std::move(D), sys.Ts);
    e.input_names = sys.input_names;
    e.output_names = sys.output_names;
    return e;
  };
  StabilitySplit out;
  detail::ComplexSchurForm cs = detail::complex_schur_from_real(sys.A);
  Eigen::Index k = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!is_stable_pole(cs.T(i, i), discrete, tol)) continue;
    for (Eigen::Index p = i - 1; p >= k; --p) swap_schur_entries(cs.T, cs.U, p);
    ++k;
  }
  if (k == n) {
    out.stable = sys;
    out.unstable = empty(Eigen::MatrixXd::Zero(l, m));
    stable_schur = std::move(cs);
    return out;
  }
  if (k == 0) {
    stable_schur = ComplexSchurForm{Eigen::MatrixXcd(0, 0), Eigen::MatrixXcd(0, 0)};
    out.stable = empty(sys.D);
    out.unstable = sys;
    out.unstable.D.setZero();
    return out;
  }
  // Real orthogonal basis of the (conjugation-closed) stable invariant subspace.
  Eigen::MatrixXd F(n, 2 * k);
  F.leftCols(k) = cs.U.leftCols(k).real();
  F.rightCols(k) = cs.U.leftCols(k).imag();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(F);
  const Eigen::MatrixXd Q = qr.householderQ();
  const Eigen::MatrixXd At = Q.transpose() * sys.A * Q;
  const double a21 = At.bottomLeftCorner(n - k, k).norm();
  if (a21 > 1e3 * static_cast<double>(n) * std::numeric_limits<double>::epsilon() * sys.A.norm())
    throw NumericalError("stable_unstable_split: the stable subspace is not invariant (||A21|| = " +
                         format_number(a21) + "): poles too close to the stability boundary to separate");
  const Eigen::MatrixXd Bt = Q.transpose() * sys.B, Ct = sys.C * Q;
  // Sylvester A11 X - X A22 + A12 = 0 on the triangular factors:
  // A11 = W1 T11 W1^H, A22 = W2 T22 W2^H with W1 = Qs^T U1, W2 = Qu^T U2 (unitary).
  const Eigen::MatrixXcd W1 = Q.leftCols(k).transpose().cast<Complex>() * cs.U.leftCols(k);
  const Eigen::MatrixXcd W2 = Q.rightCols(n - k).transpose().cast<Complex>() * cs.U.rightCols(n - k);
  const Eigen::MatrixXcd Fz = -(W1.adjoint() * At.topRightCorner(k, n - k).cast<Complex>() * W2);
  const Eigen::MatrixXcd Z =
      triangular_sylvester(cs.T.topLeftCorner(k, k), cs.T.bottomRightCorner(n - k, n - k), Fz);
  const Eigen::MatrixXd X = (W1 * Z * W2.adjoint()).real();
  out.decoupling_norm = X.norm();
  out.stable = StateSpace(At.topLeftCorner(k, k), Bt.topRows(k) - X * Bt.bottomRows(n - k), Ct.leftCols(k), sys.D,
                          sys.Ts);
  out.unstable = StateSpace(At.bottomRightCorner(n - k, n - k), Bt.bottomRows(n - k),
                            Ct.leftCols(k) * X + Ct.rightCols(n - k), Eigen::MatrixXd::Zero(l, m), sys.Ts);
  for (StateSpace* s : {&out.stable, &out.unstable}) {
    s->input_names = sys.input_names;
    s->output_names = sys.output_names;
  }
  // A11 = W1 T11 W1^H: the Schur form of the stable part comes for free.
  stable_schur = ComplexSchurForm{cs.T.topLeftCorner(k, k), W1};
  return out;
}

}  // namespace detail

StabilitySplit stable_unstable_split(const StateSpace& sys, double tol) {
  detail::ComplexSchurForm unused;
  return detail::stable_unstable_split(sys, tol, unused);
}

HankelSingularValuesResult hankel_singular_values(const StateSpace& sys,
                                                  const HankelSingularValuesOptions& options) {
  sys.validate();
  HankelSingularValuesResult r;
  detail::ComplexSchurForm schur;
  const StabilitySplit split =
      detail::stable_unstable_split(detail::balanced_realisation(sys), options.stability_tolerance, schur);
  r.unstable_states = split.unstable.order();
  if (split.decoupling_norm > 1e8)
    r.warnings.push_back("stable and unstable poles are poorly separated (||X|| = " +
                         std::to_string(split.decoupling_norm) + "): the stable part is inaccurate");
  if (split.stable.order() == 0) {
    r.values.resize(0);
    return r;
  }
  r.values = detail::square_root_balancing(split.stable, schur, false).hsv;
  return r;
}

}  // namespace sysid
