// Implementation of core/frequency_response.hpp (method and references in the header).
// Compiled once into libsysid: the Hessenberg reduction and complex LU are heavy to
// instantiate.
#include <sysid/core/frequency_response.hpp>

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

namespace sysid {

namespace {

/// Solves M X = R in place for an upper Hessenberg M (overwritten by its U factor;
/// X overwrites R). Pivoting compares row k with row k+1 only, which is partial
/// pivoting for this structure.
void hessenberg_solve_in_place(Eigen::MatrixXcd& M, Eigen::MatrixXcd& R) {
  const Eigen::Index n = M.rows();
  for (Eigen::Index k = 0; k + 1 < n; ++k) {
    if (std::abs(M(k + 1, k)) > std::abs(M(k, k))) {
      M.row(k).tail(n - k).swap(M.row(k + 1).tail(n - k));
      R.row(k).swap(R.row(k + 1));
    }
    const std::complex<double> pivot = M(k, k);
    if (pivot == 0.0) continue;  // column already zero below the diagonal (M(k+1,k) = 0 too)
    const std::complex<double> factor = M(k + 1, k) / pivot;
    if (factor == 0.0) continue;
    M(k + 1, k) = 0.0;
    M.row(k + 1).tail(n - k - 1) -= factor * M.row(k).tail(n - k - 1);
    R.row(k + 1) -= factor * R.row(k);
  }
  M.triangularView<Eigen::Upper>().solveInPlace(R);
}

/// The point at which a model is evaluated at frequency f (Hz).
std::complex<double> frequency_point(const StateSpace& sys, double f_hz) {
  const double w = 2.0 * std::numbers::pi * f_hz;
  return sys.is_discrete() ? std::polar(1.0, w * sys.Ts) : std::complex<double>(0.0, w);
}

}  // namespace

Eigen::MatrixXcd frequency_response_at(const StateSpace& sys, std::complex<double> z_or_s) {
  sys.validate();
  const Eigen::Index n = sys.order();
  Eigen::MatrixXcd G = sys.D.cast<std::complex<double>>();
  if (n == 0) return G;
  Eigen::MatrixXcd M = -sys.A.cast<std::complex<double>>();
  M.diagonal().array() += z_or_s;
  const Eigen::MatrixXcd X = M.partialPivLu().solve(sys.B.cast<std::complex<double>>());
  G.noalias() += sys.C.cast<std::complex<double>>() * X;
  return G;
}

std::vector<Eigen::MatrixXcd> frequency_response(const StateSpace& sys, const Eigen::VectorXd& freqs_hz) {
  sys.validate();
  using Complex = std::complex<double>;
  const Eigen::Index n = sys.order(), m = sys.inputs();
  std::vector<Eigen::MatrixXcd> out;
  out.reserve(static_cast<std::size_t>(freqs_hz.size()));
  const Eigen::MatrixXcd D = sys.D.cast<Complex>();
  if (n == 0) {
    for (Eigen::Index i = 0; i < freqs_hz.size(); ++i) out.push_back(D);
    return out;
  }
  const Eigen::HessenbergDecomposition<Eigen::MatrixXd> hess(sys.A);
  const Eigen::MatrixXd Q = hess.matrixQ();
  const Eigen::MatrixXcd H = Eigen::MatrixXd(hess.matrixH()).cast<Complex>();
  const Eigen::MatrixXcd Bt = (Q.transpose() * sys.B).cast<Complex>();
  const Eigen::MatrixXcd Ct = (sys.C * Q).cast<Complex>();
  Eigen::MatrixXcd M(n, n), X(n, m);  // reused workspace
  for (Eigen::Index i = 0; i < freqs_hz.size(); ++i) {
    const Complex z = frequency_point(sys, freqs_hz[i]);
    M = -H;
    M.diagonal().array() += z;
    X = Bt;
    hessenberg_solve_in_place(M, X);
    Eigen::MatrixXcd G = D;
    G.noalias() += Ct * X;
    out.push_back(std::move(G));
  }
  return out;
}

}  // namespace sysid
