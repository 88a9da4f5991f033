// Variable projection of the ARMA/ARMAX prediction-error cost: A and B re-solved
// by least squares for the model's C (src/pem/detail/variable_projection.hpp).
#include <sysid/core/detail/lagged_sums.hpp>
#include <sysid/signal/polynomial_filter.hpp>

#include <optional>
#include <utility>
#include <vector>

#include "pem/detail/variable_projection.hpp"

namespace sysid::detail::pem_impl {

bool separable(const PolynomialModel& m) {
  if (m.nd() > 0 || m.nc() == 0) return false;
  bool linear = m.na() > 0;
  for (Eigen::Index i = 0; i < m.inputs(); ++i) {
    if (m.nf(i) > 0) return false;
    linear = linear || m.nb(i) > 0;
  }
  return linear;
}

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

}  // namespace sysid::detail::pem_impl
