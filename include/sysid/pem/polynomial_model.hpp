#pragma once
/// @file
/// Purpose: the single-output polynomial (transfer-function) model family of
/// prediction-error identification,
///
///   A(q) y(t) = sum_i B_i(q) / F_i(q) u_i(t - nk_i) + C(q) / D(q) e(t),
///
/// with q^-1 the backward shift, A, C, D, F_i monic polynomials in q^-1
/// (coefficient vectors [1, a_1, ..., a_na]) and B_i = b_i0 + b_i1 q^-1 + ...
/// (nb_i coefficients, acting on u_i delayed by nk_i samples). AR, ARMA, ARX,
/// ARMAX and OE are the special cases (L. Ljung, System Identification: Theory
/// for the User, 2nd ed., 1999, sec. 4.2, eq. 4.33); e is white with variance
/// noise_variance. A model with several outputs is a list of these (one per
/// output, "stacked MISO").
///
/// Its equivalent innovation-form state space
///   x[k+1] = A x[k] + B u[k] + K e[k],   y[k] = C x[k] + D u[k] + e[k]
/// is what simulate/compare/show and the model file's "state_space" use:
///  - when every F_i = 1 and D = 1 (AR, ARMA, ARX, ARMAX): one observer
///    canonical form over the common denominator A (max degree states), in
///    which the numerator of input i is q^-nk_i B_i and that of the noise is C;
///  - otherwise (OE, Box-Jenkins): one observer form per input for B_i/(A F_i)
///    and one for C/(A D), side by side (their states are not shared).
/// Observer canonical form of N(q)/A(q), n = max degree (Kailath, Linear
/// Systems, 1980, sec. 2.1): first column of A_ss = -[a_1..a_n], ones on the
/// superdiagonal, C_ss = e_1^T, D_ss = n_0, B_ss(k) = n_k - n_0 a_k.
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

struct PolynomialModel {
  Eigen::VectorXd A = Eigen::VectorXd::Ones(1);  ///< [1, a_1 .. a_na]
  std::vector<Eigen::VectorXd> B;                ///< per input, [b_0 .. b_{nb-1}] (empty vector: input not used)
  std::vector<int> nk;                           ///< per input, input delay in samples (>= 0)
  std::vector<Eigen::VectorXd> F;                ///< per input, [1, f_1 .. f_nf]
  Eigen::VectorXd C = Eigen::VectorXd::Ones(1);  ///< [1, c_1 .. c_nc]
  Eigen::VectorXd D = Eigen::VectorXd::Ones(1);  ///< [1, d_1 .. d_nd]
  double noise_variance = 0;                     ///< variance of e
  double Ts = 1;                                 ///< sample time in seconds (> 0)

  Eigen::Index inputs() const { return static_cast<Eigen::Index>(B.size()); }
  int na() const { return static_cast<int>(A.size()) - 1; }
  int nc() const { return static_cast<int>(C.size()) - 1; }
  int nd() const { return static_cast<int>(D.size()) - 1; }
  int nb(Eigen::Index i) const { return static_cast<int>(B[static_cast<std::size_t>(i)].size()); }
  int nf(Eigen::Index i) const { return static_cast<int>(F[static_cast<std::size_t>(i)].size()) - 1; }
  /// True when every F_i and D is 1: the ARMAX family with one common denominator.
  bool common_denominator() const {
    for (const auto& f : F)
      if (f.size() > 1) return false;
    return D.size() == 1;
  }

  /// Throws std::invalid_argument naming what is inconsistent.
  void validate() const {
    auto monic = [](const Eigen::VectorXd& p, const char* name) {
      if (p.size() < 1 || p(0) != 1.0) throw std::invalid_argument(std::string("polynomial model: ") + name + " must be monic ([1, ...])");
      if (!p.allFinite()) throw std::invalid_argument(std::string("polynomial model: ") + name + " has NaN or Inf");
    };
    monic(A, "A");
    monic(C, "C");
    monic(D, "D");
    if (nk.size() != B.size() || F.size() != B.size())
      throw std::invalid_argument("polynomial model: need one B, nk and F per input");
    for (std::size_t i = 0; i < B.size(); ++i) {
      if (nk[i] < 0) throw std::invalid_argument("polynomial model: need nk >= 0");
      if (!B[i].allFinite()) throw std::invalid_argument("polynomial model: B has NaN or Inf");
      monic(F[i], "F");
    }
    if (!(Ts > 0)) throw std::invalid_argument("polynomial model: need Ts > 0");
    if (!(noise_variance >= 0)) throw std::invalid_argument("polynomial model: need noise_variance >= 0");
  }
};

/// Innovation-form state space of a polynomial model (see the file comment).
struct InnovationStateSpace {
  StateSpace model;  ///< A, B, C, D (inputs: the model's inputs; may be 0 for AR/ARMA)
  Eigen::MatrixXd K;  ///< n x 1
};

namespace detail {

/// q^-shift p(q): the coefficient vector with `shift` leading zeros.
inline Eigen::VectorXd delayed(const Eigen::VectorXd& p, int shift) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(p.size() + shift);
  out.tail(p.size()) = p;
  return out;
}

/// Coefficients of the product of two polynomials in q^-1.
inline Eigen::VectorXd polynomial_product(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() == 0 || b.size() == 0) return Eigen::VectorXd();
  Eigen::VectorXd c = Eigen::VectorXd::Zero(a.size() + b.size() - 1);
  for (Eigen::Index i = 0; i < a.size(); ++i) c.segment(i, b.size()) += a(i) * b;
  return c;
}

/// Observer canonical realisation of numerators N_j(q) (columns) over a monic
/// denominator `den`, all in q^-1: returns (A_ss, B_ss, C_ss, D_ss) with n =
/// max(deg den, max deg N_j) states (n may be 0).
inline StateSpace observer_form(const Eigen::VectorXd& den, const std::vector<Eigen::VectorXd>& numerators, double ts) {
  Eigen::Index n = den.size() - 1;
  for (const auto& num : numerators) n = std::max<Eigen::Index>(n, num.size() - 1);
  const auto m = static_cast<Eigen::Index>(numerators.size());
  Eigen::VectorXd a = Eigen::VectorXd::Zero(n + 1);
  a.head(den.size()) = den;
  StateSpace s;
  s.Ts = ts;
  s.A = Eigen::MatrixXd::Zero(n, n);
  if (n > 0) {
    s.A.col(0) = -a.tail(n);
    s.A.topRightCorner(n - 1, n - 1).setIdentity();
  }
  s.B = Eigen::MatrixXd::Zero(n, m);
  s.C = Eigen::MatrixXd::Zero(1, n);
  if (n > 0) s.C(0, 0) = 1.0;
  s.D = Eigen::MatrixXd::Zero(1, m);
  for (Eigen::Index j = 0; j < m; ++j) {
    Eigen::VectorXd num = Eigen::VectorXd::Zero(n + 1);
    const Eigen::VectorXd& given = numerators[static_cast<std::size_t>(j)];
    num.head(given.size()) = given;
    s.D(0, j) = num(0);
    if (n > 0) s.B.col(j) = num.tail(n) - num(0) * a.tail(n);
  }
  return s;
}

}  // namespace detail

/// Purpose: the innovation-form state space of `model` (file comment).
/// Preconditions: model.validate() passes.
inline InnovationStateSpace to_innovation_state_space(const PolynomialModel& model) {
  model.validate();
  const Eigen::Index m = model.inputs();
  InnovationStateSpace out;
  if (model.common_denominator()) {
    std::vector<Eigen::VectorXd> numerators;
    for (Eigen::Index i = 0; i < m; ++i)
      numerators.push_back(model.nb(i) > 0 ? detail::delayed(model.B[static_cast<std::size_t>(i)], model.nk[static_cast<std::size_t>(i)])
                                           : Eigen::VectorXd::Zero(1));
    numerators.push_back(model.C);
    const StateSpace joint = detail::observer_form(model.A, numerators, model.Ts);
    out.model.A = joint.A;
    out.model.B = joint.B.leftCols(m);
    out.model.C = joint.C;
    out.model.D = joint.D.leftCols(m);
    out.model.Ts = model.Ts;
    out.K = joint.B.col(m);
    return out;
  }
  // Separate blocks: B_i / (A F_i) per input, then C / (A D) with unit feedthrough.
  std::vector<StateSpace> blocks;
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Eigen::VectorXd num = model.nb(i) > 0 ? detail::delayed(model.B[k], model.nk[k]) : Eigen::VectorXd::Zero(1);
    blocks.push_back(detail::observer_form(detail::polynomial_product(model.A, model.F[k]), {num}, model.Ts));
  }
  const StateSpace noise = detail::observer_form(detail::polynomial_product(model.A, model.D), {model.C}, model.Ts);
  Eigen::Index n = noise.A.rows();
  for (const auto& b : blocks) n += b.A.rows();
  out.model.Ts = model.Ts;
  out.model.A = Eigen::MatrixXd::Zero(n, n);
  out.model.B = Eigen::MatrixXd::Zero(n, m);
  out.model.C = Eigen::MatrixXd::Zero(1, n);
  out.model.D = Eigen::MatrixXd::Zero(1, m);
  out.K = Eigen::MatrixXd::Zero(n, 1);
  Eigen::Index at = 0;
  for (Eigen::Index i = 0; i < m; ++i) {
    const StateSpace& b = blocks[static_cast<std::size_t>(i)];
    const Eigen::Index ni = b.A.rows();
    out.model.A.block(at, at, ni, ni) = b.A;
    out.model.B.block(at, i, ni, 1) = b.B;
    out.model.C.middleCols(at, ni) = b.C;
    out.model.D(0, i) = b.D(0, 0);
    at += ni;
  }
  const Eigen::Index ne = noise.A.rows();
  out.model.A.block(at, at, ne, ne) = noise.A;
  out.model.C.middleCols(at, ne) = noise.C;
  out.K.middleRows(at, ne) = noise.B;  // noise feedthrough C(0)/(A D)(0) = 1: the innovation form's e
  return out;
}

/// Purpose: one innovation-form model for several outputs, each with its own
/// polynomial model over the same inputs ("stacked MISO"): block-diagonal
/// states, B and D stacked, K block-diagonal (output r's innovation drives only
/// its own states). Preconditions: at least one model, equal inputs and Ts.
inline InnovationStateSpace to_innovation_state_space(const std::vector<PolynomialModel>& models) {
  if (models.empty()) throw std::invalid_argument("polynomial model: need at least one output model");
  std::vector<InnovationStateSpace> parts;
  Eigen::Index n = 0;
  for (const auto& pm : models) {
    if (pm.inputs() != models.front().inputs() || pm.Ts != models.front().Ts)
      throw std::invalid_argument("polynomial model: the output models differ in inputs or Ts");
    parts.push_back(to_innovation_state_space(pm));
    n += parts.back().model.order();
  }
  const Eigen::Index m = models.front().inputs(), l = static_cast<Eigen::Index>(models.size());
  InnovationStateSpace out;
  out.model.Ts = models.front().Ts;
  out.model.A = Eigen::MatrixXd::Zero(n, n);
  out.model.B = Eigen::MatrixXd::Zero(n, m);
  out.model.C = Eigen::MatrixXd::Zero(l, n);
  out.model.D = Eigen::MatrixXd::Zero(l, m);
  out.K = Eigen::MatrixXd::Zero(n, l);
  Eigen::Index at = 0;
  for (Eigen::Index r = 0; r < l; ++r) {
    const InnovationStateSpace& p = parts[static_cast<std::size_t>(r)];
    const Eigen::Index nr = p.model.order();
    out.model.A.block(at, at, nr, nr) = p.model.A;
    out.model.B.middleRows(at, nr) = p.model.B;
    out.model.C.block(r, at, 1, nr) = p.model.C;
    out.model.D.row(r) = p.model.D;
    out.K.block(at, r, nr, 1) = p.K;
    at += nr;
  }
  return out;
}

}  // namespace sysid
