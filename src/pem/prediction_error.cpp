// Implementation of pem/prediction_error.hpp (method and references in the header).
#include <sysid/core/column_scaled_condition.hpp>
#include <sysid/core/detail/lagged_sums.hpp>
#include <sysid/core/double_double_cholesky.hpp>
#include <sysid/core/parallel_for.hpp>
#include <sysid/core/errors.hpp>
#include <sysid/core/streaming_qr.hpp>
#include <sysid/core/transfer_function.hpp>
#include <sysid/pem/arx.hpp>
#include <sysid/pem/lagged_regression.hpp>
#include <sysid/pem/prediction_error.hpp>
#include <sysid/signal/polynomial_filter.hpp>
#include <sysid/subspace/n4sid.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace sysid {

std::string structure_name(int na, const std::vector<int>& nb, int nc, int nd, const std::vector<int>& nf) {
  const bool inputs = std::any_of(nb.begin(), nb.end(), [](int k) { return k > 0; });
  const bool f = std::any_of(nf.begin(), nf.end(), [](int k) { return k > 0; });
  if (!inputs) return nc > 0 ? (nd > 0 ? "polynomial" : "arma") : (nd > 0 ? "polynomial" : "ar");
  if (f) return na == 0 && nc == 0 && nd == 0 ? "oe" : (na == 0 ? "bj" : "polynomial");
  if (nd > 0) return "polynomial";
  return nc > 0 ? "armax" : "arx";
}

Eigen::VectorXd pack_parameters(const PolynomialModel& model) {
  Eigen::Index p = model.na() + model.nc() + model.nd();
  for (Eigen::Index i = 0; i < model.inputs(); ++i) p += model.nb(i) + model.nf(i);
  Eigen::VectorXd theta(p);
  Eigen::Index at = 0;
  auto put = [&](const Eigen::VectorXd& v) {
    theta.segment(at, v.size()) = v;
    at += v.size();
  };
  put(model.A.tail(model.na()));
  for (const auto& b : model.B) put(b);
  put(model.C.tail(model.nc()));
  put(model.D.tail(model.nd()));
  for (const auto& f : model.F) put(f.tail(f.size() - 1));
  return theta;
}

void unpack_parameters(const Eigen::VectorXd& theta, PolynomialModel& model) {
  if (theta.size() != pack_parameters(model).size()) throw std::invalid_argument("pem: parameter vector of the wrong size");
  Eigen::Index at = 0;
  auto take = [&](Eigen::VectorXd& v, Eigen::Index first) {
    v.segment(first, v.size() - first) = theta.segment(at, v.size() - first);
    at += v.size() - first;
  };
  take(model.A, 1);
  for (auto& b : model.B) take(b, 0);
  take(model.C, 1);
  take(model.D, 1);
  for (auto& f : model.F) take(f, 1);
}

Eigen::VectorXcd polynomial_roots(const Eigen::VectorXd& monic) {
  const Eigen::Index n = monic.size() - 1;
  if (n <= 0) return Eigen::VectorXcd();
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  companion.row(0) = -monic.tail(n).transpose();
  if (n > 1) companion.bottomLeftCorner(n - 1, n - 1).setIdentity();
  return companion.eigenvalues();
}

Eigen::VectorXd reflect_into_unit_circle(const Eigen::VectorXd& monic) {
  Eigen::VectorXcd roots = polynomial_roots(monic);
  bool changed = false;
  for (auto& z : roots)
    if (std::abs(z) >= 1.0) {
      z = 1.0 / std::conj(z) * (std::abs(z) == 1.0 ? 0.999 : 1.0);  // a root on the circle is pulled just inside
      changed = true;
    }
  if (!changed) return monic;
  return poly_from_roots(roots);  // reflection keeps conjugate pairs: the result is real
}

namespace {

bool strictly_stable(const Eigen::VectorXd& monic) {
  if (monic.size() <= 1) return true;
  const Eigen::VectorXcd r = polynomial_roots(monic);
  return r.cwiseAbs().maxCoeff() < 1.0 - 1e-10;
}

bool denominators_stable(const PolynomialModel& m) {
  if (!strictly_stable(m.C) || !strictly_stable(m.D)) return false;
  for (const auto& f : m.F)
    if (!strictly_stable(f)) return false;
  return true;
}

/// Prediction errors and the filtered signals whose shifted copies are the
/// Jacobian's columns (header, eqs. 10.51-10.55): column j is
/// sign_j * signals[signal_j](t - shift_j), zero before the record starts.
/// Holding the few signals instead of the N x p Jacobian keeps the Gauss-Newton
/// factorisation at O(p^2) memory (rows are made chunk by chunk).
struct FilteredRegressors {
  using Column = detail::ShiftedColumn;
  Eigen::VectorXd eps;
  std::vector<Eigen::VectorXd> signals;
  std::vector<Column> columns;

  /// Rows [first, first + out.rows()) of the Jacobian into `out` (p columns).
  template <class Block>
  void rows(Eigen::Index first, Block&& out) const {
    const Eigen::Index count = out.rows();
    for (std::size_t j = 0; j < columns.size(); ++j) {
      const Column& c = columns[j];
      auto col = out.col(static_cast<Eigen::Index>(j));
      // Row t holds signal(t - shift): zero while t - shift < 0.
      const Eigen::Index zeros = std::clamp<Eigen::Index>(c.shift - first, 0, count);
      col.head(zeros).setZero();
      if (zeros < count) col.tail(count - zeros) = c.sign * signals[c.signal].segment(first + zeros - c.shift, count - zeros);
    }
  }
};

/// `by_c`, when given, holds y / C and every u_i / C at the model's C, and
/// `known_eps` the model's prediction errors (D = F = 1: the variable
/// projection's signals and the last cost's errors): taken instead of filtered again.
FilteredRegressors filtered_regressors(const PolynomialModel& model, const Eigen::MatrixXd& u, const Eigen::VectorXd& y,
                                       bool with_signals, const std::vector<Eigen::VectorXd>* by_c = nullptr,
                                       const Eigen::VectorXd* known_eps = nullptr) {
  const Eigen::Index m = model.inputs(), n = y.size();
  if (u.cols() != m || (m > 0 && u.rows() != n)) throw std::invalid_argument("pem: u and y do not match the model");
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(1);
  // w_i = B_i / F_i u_i(t - nk_i);  v = A y - sum w_i;  eps = D / C v. (v and w
  // are needed again only for the D and F columns, which known errors exclude.)
  std::vector<Eigen::VectorXd> w(static_cast<std::size_t>(m));
  Eigen::VectorXd v;
  FilteredRegressors out;
  if (known_eps) {
    out.eps = *known_eps;
  } else {
    v = filter_polynomial(model.A, one, y);
    for (Eigen::Index i = 0; i < m; ++i) {
      const auto k = static_cast<std::size_t>(i);
      if (model.nb(i) == 0) {
        w[k] = Eigen::VectorXd::Zero(n);
        continue;
      }
      w[k] = filter_polynomial(detail::delayed(model.B[k], model.nk[k]), model.F[k], u.col(i));
      v -= w[k];
    }
    out.eps = filter_polynomial(model.D, model.C, v);
  }
  if (!with_signals) return out;
  auto add = [&](Eigen::VectorXd signal, Eigen::Index first_shift, int count, double sign) {
    out.signals.push_back(std::move(signal));
    for (int j = 0; j < count; ++j) out.columns.push_back({out.signals.size() - 1, first_shift + j, sign});
  };
  if (model.na() > 0)
    add(by_c ? (*by_c)[0] : Eigen::VectorXd(filter_polynomial(model.D, model.C, y)), 1, model.na(), 1.0);
  std::vector<Eigen::VectorXd> cf(static_cast<std::size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto k = static_cast<std::size_t>(i);
    cf[k] = detail::polynomial_product(model.C, model.F[k]);
    if (model.nb(i) > 0)
      add(by_c ? (*by_c)[1 + k] : Eigen::VectorXd(filter_polynomial(model.D, cf[k], u.col(i))), model.nk[k],
          model.nb(i), -1.0);
  }
  if (model.nc() > 0) add(filter_polynomial(one, model.C, out.eps), 1, model.nc(), -1.0);
  if (model.nd() > 0) add(filter_polynomial(one, model.C, v), 1, model.nd(), 1.0);
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (model.nf(i) > 0) add(filter_polynomial(model.D, cf[k], w[k]), 1, model.nf(i), 1.0);
  }
  return out;
}

}  // namespace

PredictionErrors prediction_errors(const PolynomialModel& model, const Eigen::MatrixXd& u, const Eigen::VectorXd& y,
                                   bool with_jacobian) {
  FilteredRegressors fr = filtered_regressors(model, u, y, with_jacobian);
  PredictionErrors out;
  if (with_jacobian) {
    out.jacobian.resize(y.size(), static_cast<Eigen::Index>(fr.columns.size()));
    fr.rows(0, out.jacobian);
  }
  out.eps = std::move(fr.eps);
  return out;
}

namespace {

struct ScaledRecord {
  Eigen::MatrixXd u;
  Eigen::VectorXd y;
};

/// The cost 0.5 sum eps^2 over the records; `eps`, when given, receives each record's errors.
double cost_of(const PolynomialModel& model, const std::vector<ScaledRecord>& records,
               std::vector<Eigen::VectorXd>* eps = nullptr) {
  double v = 0;
  if (eps) eps->clear();
  for (const auto& r : records) {
    Eigen::VectorXd e = prediction_errors(model, r.u, r.y, false).eps;
    v += 0.5 * e.squaredNorm();
    if (eps) eps->push_back(std::move(e));
  }
  return v;
}

/// y / C and every u_i / C of each record at one C, with the table of their
/// lagged sums: what the variable projection forms, and what the Jacobian
/// factor at the same C (after a step, the projection's model) takes instead
/// of filtering and correlating them again (a quarter of its lags on the Par2
/// ARMAX(32,32,26)).
struct FilteredByC {
  Eigen::VectorXd c;
  std::vector<std::vector<Eigen::VectorXd>> signals;  ///< per record: y / C, then u_i / C
  std::vector<detail::LaggedSumsTable> tables;        ///< per record

  /// Whether these are the signals of the model's C and the model's Jacobian
  /// starts with them in the same order (y / C, then u_i / C for every input).
  bool serves(const PolynomialModel& m) const {
    if (c.size() != m.C.size() || c != m.C || m.na() == 0 || m.nd() > 0) return false;
    for (Eigen::Index i = 0; i < m.inputs(); ++i)
      if (m.nb(i) == 0 || m.nf(i) > 0) return false;
    return true;
  }
};

/// R factor of a matrix whose columns are shifted copies of each record's
/// signals (the same columns for every record, the records stacked), from
/// their double-double Gram matrix of lagged sums summed over the records
/// (core/detail/lagged_sums.hpp, core/double_double_cholesky.hpp). `known`
/// (one per record) holds lagged sums of the records' first signals already
/// formed; `tables` receives this call's. Empty when a record is not longer
/// than the largest shift or the factorisation is refused.
std::optional<Eigen::MatrixXd> shifted_columns_factor(const std::vector<std::vector<Eigen::VectorXd>>& record_signals,
                                                      const std::vector<detail::ShiftedColumn>& columns,
                                                      const std::vector<detail::LaggedSumsTable>* known = nullptr,
                                                      std::vector<detail::LaggedSumsTable>* tables = nullptr) {
  Eigen::Index max_shift = 0;
  for (const auto& c : columns) max_shift = std::max(max_shift, c.shift);
  const auto n = static_cast<Eigen::Index>(columns.size());
  DoubleDoubleMatrix gram = DoubleDoubleMatrix::zero(n, n);
  if (tables) tables->clear();
  for (std::size_t e = 0; e < record_signals.size(); ++e) {
    if (record_signals[e].front().size() <= max_shift) return std::nullopt;
    const detail::LaggedSumsTable* known_pairs = known ? &(*known)[e] : nullptr;
    detail::LaggedSumsTable table = detail::lagged_sums_table(record_signals[e], columns, known_pairs);
    add_block(gram, 0, 0, detail::shifted_columns_gram(table, columns));
    if (tables) tables->push_back(std::move(table));
  }
  return lagged_sums_gram_factor(gram);
}

/// R factor of [J eps] from its Gram matrix: the columns of J are shifted
/// copies of a few filtered signals, and eps is one more signal, so the Gram
/// matrix costs O(N L) for the L distinct lags (core/detail/lagged_sums.hpp)
/// instead of the QR's O(N p^2): about 19 ms against 45-70 ms for
/// ARMAX(32,32,26) on 40 000 samples. It is formed and factorised in
/// double-double, because J is ill-conditioned (scaled condition 5e15-2e16 on
/// that problem, whose orders are 3x the true ones: a double Gram matrix is
/// indefinite); the result is then at least as accurate as the Householder R.
/// Where [J eps] is rank deficient to double precision (near common factors, an
/// exact fit, a zero column) a Schur complement pivot can come out at or below
/// zero: the factorisation is then semidefinite (core/double_double_cholesky.hpp),
/// that row of R zero where a Householder R would hold rounding noise of the same
/// size; the damping alone sets the step along it. Before, those factorisations
/// went to the QR: a third of them on the Par2 ARMAX(32,32,26), whose time then
/// fell from 2.3 to 1.1 s. Empty when a pivot is negative beyond the errors
/// of G or a record is shorter than the lags: the QR decides.
std::optional<Eigen::MatrixXd> gram_jacobian_factor(const std::vector<FilteredRegressors>& regressors,
                                                    const std::vector<detail::LaggedSumsTable>* known) {
  std::vector<detail::ShiftedColumn> columns = regressors.front().columns;
  columns.push_back({regressors.front().signals.size(), 0, 1.0});  // eps, after the signals
  std::vector<std::vector<Eigen::VectorXd>> signals;
  for (const FilteredRegressors& fr : regressors) {
    signals.push_back(fr.signals);
    signals.back().push_back(fr.eps);
  }
  return shifted_columns_factor(signals, columns, known);
}

/// R factor of [J eps] over all records ((p+1) x (p+1), non-negative
/// diagonal): from the Gram matrix when that is accurate, else by a streaming
/// Householder QR whose rows are made in its own buffer, chunk by chunk
/// (O(p^2) memory). `by_c`, when it serves the model, supplies y / C, u / C and
/// their lagged sums, and `eps` (one per record) the model's prediction errors.
Eigen::MatrixXd jacobian_factor(const PolynomialModel& model, const std::vector<ScaledRecord>& records, Eigen::Index p,
                                const FilteredByC* by_c = nullptr, const std::vector<Eigen::VectorXd>* eps = nullptr) {
  const bool reuse = by_c && by_c->serves(model) && eps && eps->size() == records.size();
  std::vector<FilteredRegressors> regressors;
  regressors.reserve(records.size());
  for (std::size_t e = 0; e < records.size(); ++e) {
    const std::vector<Eigen::VectorXd>* filtered = reuse ? &by_c->signals[e] : nullptr;
    const Eigen::VectorXd* known_eps = reuse ? &(*eps)[e] : nullptr;
    regressors.push_back(filtered_regressors(model, records[e].u, records[e].y, true, filtered, known_eps));
  }
  // A record shorter than the lags has no Gram route: only the QR has rows for it.
  if (std::optional<Eigen::MatrixXd> r = gram_jacobian_factor(regressors, reuse ? &by_c->tables : nullptr))
    return std::move(*r);
  // Chunks of 1024 rows: about 15 % faster than the default 4 (p + 1) for p ~ 90
  // (the blocked Householder update works on taller panels), 0.75 MB at p = 90.
  StreamingQR qr(p + 1, 1024);
  for (const FilteredRegressors& fr : regressors) {
    const Eigen::Index n = fr.eps.size();
    for (Eigen::Index first = 0; first < n;) {
      const Eigen::Index count = std::min(qr.free_rows(), n - first);
      auto block = qr.next_rows(count);
      fr.rows(first, block.leftCols(p));
      block.col(p) = fr.eps.segment(first, count);
      qr.commit_rows(count);
      first += count;
    }
  }
  return qr.r();
}

/// ARX of the given orders on the scaled records (target y, inputs u), with optional extra noise regressors.
RegressionSolution arx_regression(const std::vector<ScaledRecord>& records, int na, const std::vector<int>& nb,
                                  const std::vector<int>& nk, const std::vector<Eigen::VectorXd>* noise, int nc) {
  const Eigen::Index m = static_cast<Eigen::Index>(nb.size());
  std::vector<Eigen::MatrixXd> signals;
  for (std::size_t e = 0; e < records.size(); ++e) {
    const auto& r = records[e];
    Eigen::MatrixXd s(r.y.size(), 1 + m + (noise ? 1 : 0));
    s.col(0) = r.y;
    if (m > 0) s.middleCols(1, m) = r.u;
    if (noise) s.col(1 + m) = (*noise)[e];
    signals.push_back(std::move(s));
  }
  std::vector<RegressionTerm> terms{{0, 1, na, -1.0}};
  for (Eigen::Index i = 0; i < m; ++i) terms.push_back({1 + i, nk[static_cast<std::size_t>(i)], nb[static_cast<std::size_t>(i)], 1.0});
  if (noise) terms.push_back({1 + m, 1, nc, 1.0});
  return lagged_least_squares(signals, 0, terms);
}

/// Hannan-Rissanen start of ARMA/ARMAX (scaled units).
void hannan_rissanen(PolynomialModel& model, const std::vector<ScaledRecord>& records, int high_order) {
  const Eigen::Index m = model.inputs();
  std::vector<int> nb_high(static_cast<std::size_t>(m), high_order);
  for (Eigen::Index i = 0; i < m; ++i)
    if (model.nb(i) == 0) nb_high[static_cast<std::size_t>(i)] = 0;
  const RegressionSolution high = arx_regression(records, high_order, nb_high, model.nk, nullptr, 0);
  PolynomialModel h = model;
  h.A = Eigen::VectorXd(high_order + 1);
  h.A << 1.0, high.theta.head(high_order);
  Eigen::Index at = high_order;
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto k = static_cast<std::size_t>(i);
    h.B[k] = high.theta.segment(at, nb_high[k]);
    at += nb_high[k];
  }
  h.C = Eigen::VectorXd::Ones(1);
  h.D = Eigen::VectorXd::Ones(1);
  std::vector<Eigen::VectorXd> residuals;
  for (const auto& r : records) residuals.push_back(prediction_errors(h, r.u, r.y, false).eps);
  std::vector<int> nb(static_cast<std::size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) nb[static_cast<std::size_t>(i)] = model.nb(i);
  const RegressionSolution sol = arx_regression(records, model.na(), nb, model.nk, &residuals, model.nc());
  Eigen::VectorXd theta = pack_parameters(model);
  // Same order as pack_parameters for ARMAX (a, b, c) since D and F are trivial here.
  theta.head(sol.theta.size()) = sol.theta;
  unpack_parameters(theta, model);
  model.C = reflect_into_unit_circle(model.C);
}

/// The OE start's ARX denominator has roots outside the unit circle: the plant is
/// likely unstable, which an output-error model (a simulation, kept stable during
/// the iterations) cannot represent.
constexpr const char* unstable_plant_warning =
    "pem: the ARX estimate of F is unstable: the plant itself may be unstable, which an output-error model "
    "cannot represent (its simulation diverges; F is kept stable); use arx, armax or n4sid for an unstable plant";

/// OE start: ARX for F and B, then Steiglitz-McBride passes (scaled units).
void output_error_start(PolynomialModel& model, const std::vector<ScaledRecord>& records, int passes,
                        std::vector<std::string>& warnings) {
  const Eigen::Index m = model.inputs();
  std::vector<int> nb(static_cast<std::size_t>(m));
  int nf_max = 0;
  bool equal = true;
  for (Eigen::Index i = 0; i < m; ++i) {
    nb[static_cast<std::size_t>(i)] = model.nb(i);
    if (i > 0 && model.nf(i) != model.nf(0)) equal = false;
    nf_max = std::max(nf_max, model.nf(i));
  }
  if (!equal) {
    // Different denominators: each input's F from its own single-input ARX (the others act as noise).
    for (Eigen::Index i = 0; i < m; ++i) {
      const auto k = static_cast<std::size_t>(i);
      std::vector<ScaledRecord> single;
      for (const auto& r : records) single.push_back({r.u.col(i), r.y});
      const RegressionSolution sol = arx_regression(single, model.nf(i), {model.nb(i)}, {model.nk[k]}, nullptr, 0);
      model.F[k] = Eigen::VectorXd(model.nf(i) + 1);
      model.F[k] << 1.0, sol.theta.head(model.nf(i));
      if (!strictly_stable(model.F[k])) warnings.push_back(unstable_plant_warning);
      model.F[k] = reflect_into_unit_circle(model.F[k]);
      model.B[k] = sol.theta.tail(model.nb(i));
    }
    warnings.push_back("pem: inputs with different nf: OE started from single-input ARX fits (no Steiglitz-McBride passes)");
    return;
  }
  Eigen::VectorXd f = Eigen::VectorXd::Ones(1);
  for (int pass = 0; pass <= passes; ++pass) {
    // Pass 0: plain ARX; later passes: the data filtered by 1 / F of the previous pass.
    std::vector<ScaledRecord> filtered;
    for (const auto& r : records)
      filtered.push_back({filter_polynomial(Eigen::VectorXd::Ones(1), f, r.u), filter_polynomial(Eigen::VectorXd::Ones(1), f, r.y)});
    const RegressionSolution sol = arx_regression(filtered, nf_max, nb, model.nk, nullptr, 0);
    f = Eigen::VectorXd(nf_max + 1);
    f << 1.0, sol.theta.head(nf_max);
    if (pass == 0 && !strictly_stable(f))
      warnings.push_back(unstable_plant_warning);
    f = reflect_into_unit_circle(f);
    Eigen::Index at = nf_max;
    for (Eigen::Index i = 0; i < m; ++i) {
      const auto k = static_cast<std::size_t>(i);
      model.B[k] = sol.theta.segment(at, model.nb(i));
      model.F[k] = f;
      at += model.nb(i);
    }
  }
}

/// Whether eps is linear in the A and B coefficients once C is fixed (no D, no
/// F, a C to eliminate them under, and something to eliminate): ARMA, ARMAX.
bool separable(const PolynomialModel& m) {
  if (m.nd() > 0 || m.nc() == 0) return false;
  bool linear = m.na() > 0;
  for (Eigen::Index i = 0; i < m.inputs(); ++i) {
    if (m.nf(i) > 0) return false;
    linear = linear || m.nb(i) > 0;
  }
  return linear;
}

/// A and B minimising the prediction-error cost for the model's C (variable
/// projection, header): eps = A (y / C) - sum_i B_i (u_i / C) is linear in
/// them, so they solve the least-squares regression of y / C on its own past
/// and on the past of each u_i / C, every column filtered from rest as in the
/// cost. Its columns are shifted copies of those 1 + m signals, so R comes from
/// their double-double Gram matrix of lagged sums (shifted_columns_factor, as
/// the Jacobian's) and the coefficients from a
/// complete orthogonal decomposition of R (minimum norm where the regression is
/// rank deficient to working precision: near common factors).
/// The model is changed only when its cost falls (the minimum-norm solution of
/// the rank that can be resolved can lie above the model's cost by rounding),
/// and left as it is when a record is shorter than the lags or the Gram
/// matrix is refused. `by_c` receives the filtered signals and their lagged
/// sums (they depend on C only), and `eps` (the model's prediction errors) the
/// projected model's when it is kept. Returns the model's cost afterwards.
double project_linear_part(PolynomialModel& model, const std::vector<ScaledRecord>& records, double cost,
                           FilteredByC& by_c, std::vector<Eigen::VectorXd>& eps) {
  const Eigen::Index m = model.inputs();
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(1);
  // Columns: -y_f(t - k), k = 1..na; u_if(t - nk_i - j), j < nb_i; then the target y_f(t).
  std::vector<detail::ShiftedColumn> columns;
  for (Eigen::Index k = 1; k <= model.na(); ++k) columns.push_back({0, k, -1.0});
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = 0; j < model.nb(i); ++j)
      columns.push_back({static_cast<std::size_t>(1 + i), model.nk[static_cast<std::size_t>(i)] + j, 1.0});
  columns.push_back({0, 0, 1.0});
  const Eigen::Index p = static_cast<Eigen::Index>(columns.size()) - 1;
  by_c.c = model.C;
  by_c.signals.clear();
  for (const auto& r : records) {
    by_c.signals.push_back({filter_polynomial(one, model.C, r.y)});
    for (Eigen::Index i = 0; i < m; ++i) by_c.signals.back().push_back(filter_polynomial(one, model.C, r.u.col(i)));
  }
  const std::optional<Eigen::MatrixXd> factor = shifted_columns_factor(by_c.signals, columns, nullptr, &by_c.tables);
  if (!factor) by_c = FilteredByC();
  if (!factor) return cost;
  const Eigen::MatrixXd r11 = factor->topLeftCorner(p, p).triangularView<Eigen::Upper>();
  const Eigen::VectorXd theta = r11.completeOrthogonalDecomposition().solve(factor->col(p).head(p));
  if (!theta.allFinite()) return cost;
  PolynomialModel projected = model;
  projected.A.tail(model.na()) = theta.head(model.na());
  Eigen::Index at = model.na();
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto k = static_cast<std::size_t>(i);
    projected.B[k] = theta.segment(at, model.nb(i));
    at += model.nb(i);
  }
  std::vector<Eigen::VectorXd> projected_eps;
  const double projected_cost = cost_of(projected, records, &projected_eps);
  if (!(projected_cost < cost)) return cost;
  model = std::move(projected);
  eps = std::move(projected_eps);
  return projected_cost;
}

/// The outcome of a Levenberg-Marquardt run (scaled units). `r` is the R
/// factor of [J eps] at the final model.
struct LmRun {
  PemResult::Status status = PemResult::Status::failed;
  std::string termination;
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
  std::vector<double> cost_history;
  Eigen::MatrixXd r;
  double lambda = 1e-3;  ///< Marquardt damping
};

/// Levenberg-Marquardt from a model (scaled units), one iteration at a time so
/// that several starts can be raced in step (pem's automatic ARMAX start); the
/// model is updated in place.
class LevenbergMarquardt {
 public:
  LevenbergMarquardt(PolynomialModel& start, const std::vector<ScaledRecord>& scaled_records, Eigen::Index parameters,
                     const PemOptions& pem_options)
      : model(start), records(scaled_records), p(parameters), options(pem_options) {
    for (const auto& r : records) samples += r.y.size();
    cost = cost_of(model, records, &eps);
    run.initial_cost = cost;
    run.cost_history.push_back(cost);
    project = options.variable_projection && separable(model);
    if (project) {
      cost = project_linear_part(model, records, cost, by_c, eps);
      if (cost < run.initial_cost) run.cost_history.push_back(cost);
    }
    theta = pack_parameters(model);
    run.r = jacobian_factor(model, records, p, &by_c, &eps);
    run.status = PemResult::Status::max_iterations;
    run.termination = "reached max_iterations (" + std::to_string(options.max_iterations) + ")";
  }

  /// One iteration (its first checks may find convergence without a step):
  /// false once the run has ended, converged or failed (then status says why).
  bool iterate() {
    if (ended_) return false;
    double& lambda = run.lambda;
    if (need_factor) run.r = jacobian_factor(model, records, p, &by_c, &eps);
    need_factor = false;
    const Eigen::MatrixXd& r = run.r;
    const Eigen::MatrixXd r11 = r.topLeftCorner(p, p).triangularView<Eigen::Upper>();
    const Eigen::VectorXd r12 = r.col(p).head(p);
    const Eigen::VectorXd gradient = r11.transpose() * r12;  // J^T eps
    if (gradient.cwiseAbs().maxCoeff() <= options.gradient_tolerance * (1.0 + cost)) {
      run.status = PemResult::Status::converged;
      run.termination = "gradient below tolerance";
      return end();
    }
    // The full Gauss-Newton step dtheta = -R11^-1 r12 has Mahalanobis length
    // ||r12|| / sigma in the metric of the parameter covariance sigma^2 (J^T J)^-1
    // (Ljung 1999, eq. 9.17): below a fraction of one standard deviation, further
    // iterations change nothing the data can distinguish.
    const double sigma2 = 2.0 * cost / std::max(1.0, static_cast<double>(samples - p));
    // Rounding in an ill-conditioned or over-parametrised Jacobian can hide the
    // last decrease; it is "working precision" when the Gauss-Newton minimiser
    // lies inside the parameters' confidence region, ||r12||^2 / sigma^2 <= p
    // (the mean of the chi-square(p) that bounds it).
    const bool inside_confidence_region = r12.squaredNorm() <= static_cast<double>(p) * sigma2;
    if (options.step_significance_tolerance > 0 &&
        r12.squaredNorm() <= options.step_significance_tolerance * options.step_significance_tolerance * sigma2) {
      run.status = PemResult::Status::converged;
      std::ostringstream why;
      why << "Gauss-Newton step below " << options.step_significance_tolerance << " standard deviations of the parameters";
      run.termination = why.str();
      return end();
    }
    ++iteration;
    // Marquardt scaling by the column norms of J (= those of R11).
    Eigen::VectorXd scale = r11.colwise().norm().transpose();
    for (Eigen::Index k = 0; k < p; ++k) scale(k) = std::max(scale(k), 1e-12 * std::max(1.0, scale.maxCoeff()));
    bool accepted = false;
    int rejected = 0;  // a step accepted only after rejections is short because of the damping, not convergence
    while (!accepted) {
      Eigen::MatrixXd stacked(2 * p, p);
      stacked << r11, std::sqrt(lambda) * scale.asDiagonal().toDenseMatrix();
      Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * p);
      rhs.head(p) = -r12;
      Eigen::VectorXd step = stacked.householderQr().solve(rhs);
      PolynomialModel trial = model;
      unpack_parameters(theta + step, trial);
      // A step that leaves the stable region is shortened along its direction
      // first (the quadratic model stays right; only the constraint bites):
      // cheaper than raising the damping, which turns the step towards the gradient.
      double fraction = 1.0;
      while (!denominators_stable(trial) && fraction > 0.1) {
        fraction *= 0.5;
        unpack_parameters(theta + fraction * step, trial);
      }
      step *= fraction;
      const double predicted = 0.5 * (r12.squaredNorm() - (r11 * step + r12).squaredNorm());
      double trial_cost = std::numeric_limits<double>::infinity();
      std::vector<Eigen::VectorXd> trial_eps;
      if (denominators_stable(trial)) trial_cost = cost_of(trial, records, &trial_eps);
      const double rho = predicted > 0 ? (cost - trial_cost) / predicted : -1.0;
      if (std::isfinite(trial_cost) && rho > 0) {
        // The damping follows rho, the quality of the Gauss-Newton model for
        // the joint step; the projection's further gain is then taken on top.
        if (project) {
          trial_cost = project_linear_part(trial, records, trial_cost, by_c, trial_eps);
          step = pack_parameters(trial) - theta;
        }
        const double decrease = cost - trial_cost;
        const bool small_step = step.norm() <= options.parameter_tolerance * (theta.norm() + options.parameter_tolerance);
        theta += step;
        model = trial;
        cost = trial_cost;
        eps = std::move(trial_eps);
        run.cost_history.push_back(cost);
        // Nielsen (1999), but a step the quadratic model predicted well (rho > 0.75)
        // shrinks the damping tenfold: on ill-conditioned problems the damped step
        // is otherwise tiny for dozens of iterations.
        // Consecutive such steps at the first try shrink it faster and faster
        // (0.1, 0.01, 1e-3, then 1e-4 each): the damping that suits an ill-conditioned
        // problem can lie ten decades below the start. A step shortened by
        // the stability constraint leaves the damping as it is.
        if (fraction < 1.0) {
        } else if (rho > 0.75) {
          lambda *= shrink;
          if (rejected == 0) shrink = std::max(shrink * 0.1, 1e-4);
        } else {
          lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
        }
        if (rejected > 0 || rho <= 0.75) shrink = 0.1;
        nu = 2.0;
        accepted = true;
        need_factor = true;
        // The decrease and step-length tests only mean convergence for a step
        // close to the Gauss-Newton one: a strongly damped step is short and
        // gains little because of the damping.
        // A step of relative length 1e-9 after rejections moves the parameters
        // by rounding only: what it "gains" is the cost's own rounding noise
        // (with C next to the unit circle, that noise is of the order of sigma^2).
        const bool rounding_step = step.norm() <= 1e-9 * (theta.norm() + 1e-9);
        if (rejected > 0 && (decrease <= 1e-3 * sigma2 || rounding_step) && inside_confidence_region) {
          // Damping had to grow and the step gained nothing the data resolve.
          run.status = PemResult::Status::converged;
          run.termination = "no step lowers the cost appreciably (minimum to working precision: the Gauss-Newton "
                            "minimiser lies inside the parameters' confidence region)";
        } else if (rejected > 0 || predicted < 0.25 * r12.squaredNorm()) {
        } else if (decrease <= options.function_tolerance * cost) {
          run.status = PemResult::Status::converged;
          run.termination = "relative cost decrease below tolerance";
        } else if (small_step) {
          run.status = PemResult::Status::converged;
          run.termination = "step below tolerance";
        }
      } else {
        lambda *= nu;
        nu *= 2.0;
        ++rejected;
        if (lambda > 1e16) break;
      }
    }
    if (run.status == PemResult::Status::converged) return end();
    if (!accepted) {
      // No damped step lowers the cost: at a minimum to working precision, or
      // stuck. Working precision when the Gauss-Newton minimiser lies inside the
      // parameters' confidence region, ||r12||^2 / sigma^2 <= p (the mean of the
      // chi-square(p) that bounds it): rounding in an ill-conditioned or
      // over-parametrised Jacobian then hides a decrease the data cannot resolve.
      const bool flat = gradient.cwiseAbs().maxCoeff() <= 1e-6 * (1.0 + cost) || inside_confidence_region;
      run.status = flat ? PemResult::Status::converged : PemResult::Status::failed;
      run.termination = flat ? "no step lowers the cost further (minimum to working precision: the Gauss-Newton "
                               "minimiser lies inside the parameters' confidence region)"
                             : "no step lowers the cost although the gradient is not small (damping limit reached)";
      return end();
    }
    return true;
  }

  /// The run as it stands: iterations, final cost and the factor at the final model.
  LmRun finish() {
    run.iterations = iteration;
    run.final_cost = cost;
    if (need_factor) run.r = jacobian_factor(model, records, p, &by_c, &eps);
    need_factor = false;
    return run;
  }

  /// Iterates until the run ends or has taken `max_iterations` in all.
  void iterate_up_to(int max_iterations) {
    while (iteration < max_iterations && iterate()) {
    }
  }

  bool ended() const { return ended_; }
  bool converged() const { return run.status == PemResult::Status::converged; }
  double current_cost() const { return cost; }

 private:
  bool end() {
    ended_ = true;
    return false;
  }

  PolynomialModel& model;
  const std::vector<ScaledRecord>& records;
  const Eigen::Index p;
  const PemOptions& options;
  Eigen::Index samples = 0;
  LmRun run;
  double cost = 0;
  bool project = false;
  FilteredByC by_c;  // the last projection's signals, for the Jacobian factor at the same C
  std::vector<Eigen::VectorXd> eps;  // the model's prediction errors, per record
  Eigen::VectorXd theta;
  double nu = 2.0;
  double shrink = 0.1;  // damping factor after a well-predicted step (see below)
  int iteration = 0;
  bool need_factor = false;
  bool ended_ = false;
};

/// One Levenberg-Marquardt run of at most `max_iterations` iterations.
LmRun levenberg_marquardt(PolynomialModel& model, const std::vector<ScaledRecord>& records, Eigen::Index p,
                          const PemOptions& options, int max_iterations) {
  LevenbergMarquardt lm(model, records, p, options);
  lm.iterate_up_to(max_iterations);
  return lm.finish();
}

/// Order of the high-order ARX in the Hannan-Rissanen start (PemOptions::initial_arx_order).
int hannan_rissanen_order(const PemOptions& options, double total) {
  int high = options.initial_arx_order;
  if (high == 0) {
    int max_nb = 0;
    for (int b : options.nb) max_nb = std::max(max_nb, b);
    high = std::max(3 * std::max({options.na, max_nb, options.nc}), 20);
    high = std::min<int>(high, static_cast<int>(total / 20.0));
  }
  if (high <= options.nc) throw std::invalid_argument("pem: too few samples for the Hannan-Rissanen start of these orders");
  return high;
}

IoData records_as_data(const std::vector<ScaledRecord>& records, double Ts) {
  IoData d;
  d.Ts = Ts;
  for (const auto& r : records) d.experiments.push_back({r.u, r.y, "scaled record"});
  return d;
}

/// ARMAX start from an output-error fit (scaled units): B and F of
/// OE(nb, nf = min(na, nc)) fitted by PEM, A = C = F zero-padded to na and nc.
/// The ARMAX predictor then is the OE one (white measurement noise,
/// y = B/F u + e), the start of highest likelihood when the noise is white
/// at the output. For lightly damped
/// plants sampled fast this starts next to the optimum where the
/// Hannan-Rissanen start stalls: its high-order ARX cannot whiten a noise
/// model with roots next to the unit circle. Returns false when the OE fit fails.
bool armax_output_error_start(PolynomialModel& model, const std::vector<ScaledRecord>& records, const PemOptions& options) {
  const Eigen::Index m = model.inputs();
  PemOptions oe;
  oe.nb = options.nb;
  oe.nk = model.nk;
  // F of order min(na, nc), zero-padded into both A and C: C / A = 1 exactly
  // (roots at the origin fill the higher order).
  const int nf = std::min(options.na, options.nc);
  oe.nf.assign(static_cast<std::size_t>(m), nf);
  oe.max_iterations = options.max_iterations;
  oe.steiglitz_mcbride_iterations = options.steiglitz_mcbride_iterations;
  oe.remove_means = false;
  const PemResult fit = pem(records_as_data(records, model.Ts), oe);
  if (fit.status == PemResult::Status::failed) return false;
  const Eigen::VectorXd& f = fit.model.F.front();
  model.A = Eigen::VectorXd::Zero(options.na + 1);
  model.A.head(f.size()) = f;
  model.C = Eigen::VectorXd::Zero(options.nc + 1);
  model.C.head(f.size()) = f;
  model.B = fit.model.B;
  return true;
}

/// [1, p_1..p_n] of det(zI - M), read as a polynomial in q^-1.
Eigen::VectorXd characteristic_polynomial(const Eigen::MatrixXd& M) {
  if (M.rows() == 0) return Eigen::VectorXd::Ones(1);
  return poly_from_roots(M.eigenvalues());
}

/// `p` cut or zero-padded to `size` coefficients.
Eigen::VectorXd resized(const Eigen::VectorXd& p, Eigen::Index size) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(size);
  const Eigen::Index n = std::min(size, p.size());
  out.head(n) = p.head(n);
  return out;
}

/// ARMAX start from a subspace model (scaled units): MOESP-weighted n4sid on
/// the records (order chosen by its SVC rule, at most min(na, 20)), then the polynomials of its
/// innovation form x+ = A x + B u + K e, y = C x + D u + e (single output):
///   A(q) = det(zI - A),   C(q) = det(zI - A + K C)   (A(q) when K is not available:
///   the output-error predictor), and per input, since for one output
///   det(zI - A + B_i C) = det(zI - A) (1 + C (zI - A)^-1 B_i),
///   N_i(q) = det(zI - A + B_i C) + (D_i - 1) det(zI - A),
/// B_i = N_i from lag nk_i. Each is cut or zero-padded to the model's orders and
/// C reflected into the unit circle. A subspace fit is consistent whatever the
/// noise colour, so it starts next to the optimum where the Hannan-Rissanen
/// start does not (lightly damped plants with white output noise), at the cost
/// of one n4sid. Returns false when n4sid fails.
bool armax_subspace_start(PolynomialModel& model, const std::vector<ScaledRecord>& records, const PemOptions& options) {
  N4sidOptions so;
  so.max_order = std::min(options.na, so.max_order);
  so.remove_means = false;
  // MOESP weighting: on the band-limited Par2 log its model is far closer to
  // the truth than the N4SID weighting's (bench/README.md: in-band fit 99.05 %
  // against 88.4 %), and the ARMAX iterations from it end in a better minimum.
  so.weighting = SubspaceWeighting::moesp;
  N4sidResult fit;
  try {
    fit = n4sid(records_as_data(records, model.Ts), so);
  } catch (const std::exception&) {
    return false;
  }
  const StateSpace& ss = fit.model;
  if (!ss.A.allFinite() || !ss.B.allFinite()) return false;
  const Eigen::VectorXd a = characteristic_polynomial(ss.A);
  model.A = resized(a, options.na + 1);
  const Eigen::VectorXd c = fit.K.size() > 0 ? characteristic_polynomial(ss.A - fit.K * ss.C) : a;
  model.C = reflect_into_unit_circle(resized(c, options.nc + 1));
  for (Eigen::Index i = 0; i < model.inputs(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (model.nb(i) == 0) continue;
    const Eigen::VectorXd numerator = characteristic_polynomial(ss.A - ss.B.col(i) * ss.C) + (ss.D(0, i) - 1.0) * a;
    model.B[k] = resized(numerator.tail(std::max<Eigen::Index>(0, numerator.size() - model.nk[k])), model.nb(i));
  }
  return model.A.allFinite() && model.C.allFinite();
}

}  // namespace

PemResult pem(IoData data, const PemOptions& options) {
  data.validate();
  const Eigen::Index m = data.inputs(), l = data.outputs();
  if (options.output < 0 || options.output >= l) throw std::invalid_argument("pem: output index out of range");
  if (options.na < 0 || options.nc < 0 || options.nd < 0) throw std::invalid_argument("pem: need na, nc, nd >= 0");
  if (static_cast<Eigen::Index>(options.nb.size()) != m)
    throw std::invalid_argument("pem: need one nb per input (" + std::to_string(options.nb.size()) + " given for " +
                                std::to_string(m) + " inputs)");
  std::vector<int> nf = options.nf.empty() ? std::vector<int>(static_cast<std::size_t>(m), 0) : options.nf;
  if (static_cast<Eigen::Index>(nf.size()) != m) throw std::invalid_argument("pem: need one nf per input");
  for (Eigen::Index i = 0; i < m; ++i)
    if (options.nb[static_cast<std::size_t>(i)] < 0 || nf[static_cast<std::size_t>(i)] < 0)
      throw std::invalid_argument("pem: need nb, nf >= 0");
  const std::vector<int> nk = detail::input_delays(options.nk, m);
  const bool has_f = std::any_of(nf.begin(), nf.end(), [](int k) { return k > 0; });
  if (has_f && options.na > 0) throw std::invalid_argument("pem: an A polynomial together with F is not supported (use na = 0)");
  if (options.max_iterations < 0) throw std::invalid_argument("pem: need max_iterations >= 0");

  PemResult res;
  res.structure = structure_name(options.na, options.nb, options.nc, options.nd, nf);
  std::tie(res.input_offset, res.output_offset) = detail::remove_means_if(data, options.remove_means);

  // Scaled records of the chosen output.
  const double total = static_cast<double>(data.total_samples());
  Eigen::VectorXd su = Eigen::VectorXd::Zero(m);
  double sy = 0;
  for (const auto& e : data.experiments) {
    su += e.u.colwise().squaredNorm().transpose();
    sy += e.y.col(options.output).squaredNorm();
  }
  su = (su / total).cwiseSqrt();
  sy = std::sqrt(sy / total);
  if (!(sy > 0)) throw DataError("pem: output '" + data.output_name(options.output) + "' is constant");
  for (Eigen::Index i = 0; i < m; ++i)
    if (!(su(i) > 0)) throw DataError("pem: input '" + data.input_name(i) + "' is constant: it does not excite the system");
  std::vector<ScaledRecord> records;
  for (const auto& e : data.experiments)
    records.push_back({e.u * su.cwiseInverse().asDiagonal(), e.y.col(options.output) / sy});

  PolynomialModel model;
  model.Ts = data.Ts;
  model.A = Eigen::VectorXd::Zero(options.na + 1);
  model.A(0) = 1.0;
  model.C = Eigen::VectorXd::Zero(options.nc + 1);
  model.C(0) = 1.0;
  model.D = Eigen::VectorXd::Zero(options.nd + 1);
  model.D(0) = 1.0;
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto k = static_cast<std::size_t>(i);
    model.B.push_back(Eigen::VectorXd::Zero(options.nb[k]));
    model.nk.push_back(nk[k]);
    model.F.push_back(Eigen::VectorXd::Zero(nf[k] + 1));
    model.F.back()(0) = 1.0;
  }
  const Eigen::Index p = pack_parameters(model).size();
  if (p == 0) throw std::invalid_argument("pem: need at least one parameter");
  if (static_cast<double>(p) >= total) throw std::invalid_argument("pem: more parameters than samples");

  // Initial values and Levenberg-Marquardt.
  LmRun run;
  if (has_f) {
    output_error_start(model, records, options.steiglitz_mcbride_iterations, res.warnings);
    run = levenberg_marquardt(model, records, p, options, options.max_iterations);
  } else if (options.nc > 0) {
    const bool armax = options.na > 0 && m > 0;
    if (!armax && options.start != PemStart::automatic && options.start != PemStart::hannan_rissanen)
      throw std::invalid_argument("pem: the output-error and subspace starts need an ARMAX structure (na > 0 and an input)");
    std::vector<PemStart> starts{options.start};
    if (options.start == PemStart::automatic)
      starts = armax ? std::vector<PemStart>{PemStart::subspace, PemStart::hannan_rissanen}
                     : std::vector<PemStart>{PemStart::hannan_rissanen};
    // Several starts are raced a few iterations each, in step: every round is
    // one iteration of each running start, the starts on the machine's cores,
    // so the outcome does not depend on timing. The race ends after `trial`
    // rounds, or earlier once a start has converged below every start still
    // running (it sits at a local minimum to working precision that the others
    // have not reached in as many iterations; with variable projection the
    // subspace start converges on the Par2 ARMAX in 6, while the
    // Hannan-Rissanen start, at twice its cost, would take 10 trial rounds).
    // The lowest cost (the first in start order at a tie) goes on to the full
    // iteration budget; a full run from each start would multiply the time.
    const int trial = starts.size() > 1 ? std::min(options.max_iterations, 10) : options.max_iterations;
    struct Racer {
      PolynomialModel model;
      std::string name;
      std::optional<LevenbergMarquardt> lm;  // holds a reference to `model`: racers never move
      bool running() const { return lm && !lm->ended(); }
    };
    std::vector<Racer> racers(starts.size());
    parallel_for(starts.size(), [&](std::size_t k) {
      Racer& o = racers[k];
      o.model = model;
      const PemStart start = starts[k];
      if (start == PemStart::hannan_rissanen) {
        hannan_rissanen(o.model, records, hannan_rissanen_order(options, total));
        o.name = "hannan-rissanen";
      } else if (start == PemStart::subspace && armax_subspace_start(o.model, records, options)) {
        o.name = "subspace";
      } else if ((start == PemStart::output_error || options.start == PemStart::automatic) &&
                 armax_output_error_start(o.model, records, options)) {
        // Under `automatic` the output-error start stands in for a failed subspace one.
        o.name = "output-error";
      } else {
        return;
      }
      o.lm.emplace(o.model, records, p, options);
    });
    for (int round = 0; round < trial; ++round) {
      std::vector<std::size_t> running;
      for (std::size_t k = 0; k < racers.size(); ++k)
        if (racers[k].running()) running.push_back(k);
      if (running.empty()) break;
      parallel_for(running.size(), [&](std::size_t j) { racers[running[j]].lm->iterate(); });
      double lowest_running = std::numeric_limits<double>::infinity(), lowest_converged = lowest_running;
      for (const Racer& o : racers) {
        if (!o.lm) continue;
        if (o.running()) lowest_running = std::min(lowest_running, o.lm->current_cost());
        else if (o.lm->converged()) lowest_converged = std::min(lowest_converged, o.lm->current_cost());
      }
      if (lowest_converged < lowest_running) break;
    }
    Racer* winner = nullptr;
    for (Racer& o : racers)
      if (o.lm && (!winner || o.lm->current_cost() < winner->lm->current_cost())) winner = &o;
    if (!winner)
      throw NumericalError(std::string("pem: the ") + (options.start == PemStart::subspace ? "subspace" : "output-error") +
                           " start of the ARMAX model failed (its sub-fit did not succeed)");
    winner->lm->iterate_up_to(options.max_iterations);
    run = winner->lm->finish();
    model = winner->model;
    res.start = winner->name;
  } else {
    std::vector<int> nb(options.nb.begin(), options.nb.end());
    const RegressionSolution sol = arx_regression(records, options.na, nb, nk, nullptr, 0);
    Eigen::VectorXd theta = pack_parameters(model);
    theta.head(sol.theta.size()) = sol.theta;
    unpack_parameters(theta, model);
    run = levenberg_marquardt(model, records, p, options, options.max_iterations);
  }
  res.status = run.status;
  res.termination = run.termination;
  res.iterations = run.iterations;
  res.initial_cost = run.initial_cost;
  res.final_cost = run.final_cost;
  res.cost_history = std::move(run.cost_history);
  const double cost = run.final_cost;
  const Eigen::MatrixXd& r = run.r;

  // Covariance sigma^2 (J^T J)^-1 and conditioning at the solution (scaled units).
  const Eigen::MatrixXd r11 = r.topLeftCorner(p, p).triangularView<Eigen::Upper>();
  res.condition = column_scaled_condition(r11);
  const double sigma2 = 2.0 * cost / std::max(1.0, total - static_cast<double>(p));
  const Eigen::MatrixXd r_inv = r11.completeOrthogonalDecomposition().pseudoInverse();
  Eigen::MatrixXd covariance = sigma2 * r_inv * r_inv.transpose();
  // Above ~1/u the SVD of a double R11 no longer measures the condition: the
  // semidefinite Gram factor's zero rows make it infinite, its rounding-level
  // pivots anything from 1e16 up.
  if (!(res.condition < 1e16)) {
    res.warnings.push_back("pem: the Jacobian is rank deficient to double precision at the solution: some parameters "
                           "are not determined by the data (orders too high, or common factors)");
  } else if (res.condition > 1e10) {
    std::ostringstream w;
    w << "pem: the Jacobian is ill-conditioned at the solution (condition " << std::setprecision(3) << res.condition
      << "): some parameters are poorly determined (orders too high, or common factors)";
    res.warnings.push_back(w.str());
  }

  // Back to original units: B_i scales by sy / su_i, the variance by sy^2.
  Eigen::VectorXd unit = Eigen::VectorXd::Ones(p);
  {
    Eigen::Index at = model.na();
    for (Eigen::Index i = 0; i < m; ++i) {
      const double s = sy / su(i);
      model.B[static_cast<std::size_t>(i)] *= s;
      unit.segment(at, model.nb(i)).setConstant(s);
      at += model.nb(i);
    }
  }
  res.covariance = unit.asDiagonal() * covariance * unit.asDiagonal();
  model.noise_variance = sigma2 * sy * sy;
  res.model = model;
  res.model.validate();
  return res;
}

}  // namespace sysid
