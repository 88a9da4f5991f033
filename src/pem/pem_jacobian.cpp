// The prediction errors of a polynomial model, their cost over scaled records and
// the R factor of [J eps] (method and references in pem/prediction_error.hpp: the
// Jacobian's columns are filtered signals, Ljung 1999 eqs. 10.51-10.55).
#include <sysid/core/detail/lagged_sums.hpp>
#include <sysid/core/double_double_cholesky.hpp>
#include <sysid/core/streaming_qr.hpp>
#include <sysid/pem/lagged_regression.hpp>
#include <sysid/pem/prediction_error.hpp>
#include <sysid/signal/polynomial_filter.hpp>

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <vector>

#include "pem/detail/pem_jacobian.hpp"

namespace sysid {

namespace detail::pem_impl {

namespace {

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

}  // namespace

double cost_of(const PolynomialModel& model, const std::vector<ScaledRecord>& records,
               std::vector<Eigen::VectorXd>* eps) {
  double v = 0;
  if (eps) eps->clear();
  for (const auto& r : records) {
    Eigen::VectorXd e = prediction_errors(model, r.u, r.y, false).eps;
    v += 0.5 * e.squaredNorm();
    if (eps) eps->push_back(std::move(e));
  }
  return v;
}

std::optional<Eigen::MatrixXd> shifted_columns_factor(const std::vector<std::vector<Eigen::VectorXd>>& record_signals,
                                                      const std::vector<detail::ShiftedColumn>& columns,
                                                      const std::vector<detail::LaggedSumsTable>* known,
                                                      std::vector<detail::LaggedSumsTable>* tables) {
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

Eigen::MatrixXd jacobian_factor(const PolynomialModel& model, const std::vector<ScaledRecord>& records, Eigen::Index p,
                                const FilteredByC* by_c, const std::vector<Eigen::VectorXd>* eps) {
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

}  // namespace detail::pem_impl

PredictionErrors prediction_errors(const PolynomialModel& model, const Eigen::MatrixXd& u, const Eigen::VectorXd& y,
                                   bool with_jacobian) {
  detail::pem_impl::FilteredRegressors fr = detail::pem_impl::filtered_regressors(model, u, y, with_jacobian);
  PredictionErrors out;
  if (with_jacobian) {
    out.jacobian.resize(y.size(), static_cast<Eigen::Index>(fr.columns.size()));
    fr.rows(0, out.jacobian);
  }
  out.eps = std::move(fr.eps);
  return out;
}

}  // namespace sysid
