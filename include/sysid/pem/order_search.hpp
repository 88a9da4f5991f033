#pragma once
/// @file
/// Purpose: choose polynomial model orders from ranges (`--na 8:32`): every
/// combination is fitted and scored by Akaike's information criterion, the
/// Bayesian (Schwarz) criterion, Akaike's final prediction error and, when
/// validation data are given, the simulation fit on them; the best by the
/// chosen criterion is returned with the whole table.
///
/// Method (Ljung 1999, sec. 16.4, eqs. 16.33-16.35; N estimation samples, p_r
/// coefficients and loss V_r = mean squared prediction error of output r):
///   AIC = sum_r N log V_r + 2 p_r
///   BIC = sum_r N log V_r + p_r log N
///   FPE = sum_r V_r (1 + p_r / N) / (1 - p_r / N)
/// (constant terms dropped; only differences between rows matter).
/// A combination whose minimisation does not converge is kept in the table,
/// marked, and never chosen.
#include <sysid/core/io_data.hpp>
#include <sysid/pem/polynomial_fit.hpp>

#include <Eigen/Dense>
#include <optional>
#include <string>
#include <vector>

namespace sysid {

/// Inclusive integer range lo..hi (a single order is lo = hi).
struct OrderRange {
  int lo = 0, hi = 0;
};

struct PolynomialOrderGrid {
  OrderRange na, nc;
  std::vector<OrderRange> nb, nf;  ///< per input
  std::vector<int> nk;             ///< per input delays (fixed)
};

enum class OrderCriterion { validation_fit, aic, bic, fpe };

/// "fit", "aic", "bic", "fpe".
const char* to_string(OrderCriterion c);

struct OrderSearchOptions {
  PolynomialFitOptions fit;  ///< structure, AR method, iterations (orders come from the grid)
  /// How the best row is chosen; validation_fit needs validation data.
  OrderCriterion criterion = OrderCriterion::aic;
  /// Refuse grids larger than this (each row is a full identification).
  std::size_t max_combinations = 2000;
};

struct OrderScore {
  PolynomialOrders orders;
  Eigen::Index parameters = 0;
  double aic = 0, bic = 0, fpe = 0;
  double validation_fit = 0;  ///< mean over outputs, % (NaN without validation data)
  bool converged = true;
};

struct OrderSearchResult {
  std::vector<OrderScore> table;  ///< in grid order
  std::size_t best = 0;           ///< row of the chosen model
  OrderCriterion criterion = OrderCriterion::aic;
  PolynomialFit best_fit;  ///< the chosen model, as fitted
  std::vector<std::string> warnings;
};

/// Every combination of the grid's ranges (na, nc, each nb, each nf), in order.
std::vector<PolynomialOrders> order_combinations(const PolynomialOrderGrid& grid, PolynomialStructure structure);

/// Throws std::invalid_argument for an empty or oversized grid, or for
/// criterion validation_fit without validation data; NumericalError when no
/// combination converges.
OrderSearchResult search_polynomial_orders(const IoData& estimation, const IoData* validation,
                                           const PolynomialOrderGrid& grid, const OrderSearchOptions& options);

/// The table as aligned text: orders, parameters, AIC, BIC, FPE, validation fit,
/// a '*' on the chosen row and a '!' on rows that did not converge.
std::string format_order_table(const OrderSearchResult& result, PolynomialStructure structure);

}  // namespace sysid
