// Order search (pem/order_search.hpp) and the structure dispatch
// (pem/polynomial_fit.hpp): BIC finds the true order of an AR(4) and an
// ARX(2,2) process; the grid enumerates every combination once; a validation
// fit criterion needs validation data; bad ranges are rejected.
#include <sysid/pem/order_search.hpp>
#include <sysid/signal/polynomial_filter.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "random_matrices.hpp"

namespace test_unit_pem_order_search {

using namespace sysid;

namespace {

/// AR(4) with two resonances: poles 0.95 e^{+-0.3j}, 0.9 e^{+-1.2j}.
IoData ar4_data(std::uint64_t seed) {
  Eigen::VectorXd a(5);
  const double r1 = 0.95, w1 = 0.3, r2 = 0.9, w2 = 1.2;
  const Eigen::Vector3d p1(1.0, -2 * r1 * std::cos(w1), r1 * r1), p2(1.0, -2 * r2 * std::cos(w2), r2 * r2);
  a << 1.0, p1(1) + p2(1), p1(2) + p1(1) * p2(1) + p2(2), p1(1) * p2(2) + p1(2) * p2(1), p1(2) * p2(2);
  const Eigen::Index n = 8000;
  const Eigen::VectorXd y = filter_polynomial(Eigen::VectorXd::Ones(1), a, sysid::test::white_noise(n, 1, seed)).col(0);
  return IoData(Eigen::MatrixXd(n, 0), y, 1.0);
}

/// ARX(2,2), nk 1: A = 1 - 1.5 q^-1 + 0.7 q^-2, B = 1 + 0.5 q^-1.
IoData arx_data(std::uint64_t seed) {
  const Eigen::Index n = 6000;
  const Eigen::VectorXd u = sysid::test::white_noise(n, 1, seed).col(0), e = sysid::test::white_noise(n, 1, seed + 1, 0.3).col(0);
  const Eigen::Vector3d a(1.0, -1.5, 0.7);
  const Eigen::VectorXd y = filter_polynomial(Eigen::Vector3d(0.0, 1.0, 0.5), a, u).col(0) +
                            filter_polynomial(Eigen::VectorXd::Ones(1), a, e).col(0);
  return IoData(u, y, 1.0);
}

}  // namespace

TEST(OrderSearch, BicFindsTheOrderOfAnAr4Process) {
  PolynomialOrderGrid grid;
  grid.na = {1, 10};
  OrderSearchOptions o;
  o.fit.structure = PolynomialStructure::ar;
  o.criterion = OrderCriterion::bic;
  const OrderSearchResult r = search_polynomial_orders(ar4_data(1), nullptr, grid, o);
  ASSERT_EQ(r.table.size(), 10u);
  EXPECT_EQ(r.table[r.best].orders.na, 4);
  EXPECT_EQ(r.best_fit.models.front().na(), 4);
  // Below the true order the loss falls steeply; above it BIC rises by about log N per parameter.
  EXPECT_GT(r.table[2].bic - r.table[3].bic, 100.0);
  EXPECT_GT(r.table[9].bic, r.table[3].bic);
  EXPECT_TRUE(std::isnan(r.table.front().validation_fit));
}

TEST(OrderSearch, ArxBicAndValidationFitPickTheTrueOrders) {
  PolynomialOrderGrid grid;
  grid.na = {1, 4};
  grid.nb = {{1, 4}};
  grid.nk = {1};
  OrderSearchOptions o;
  o.fit.structure = PolynomialStructure::arx;
  o.criterion = OrderCriterion::bic;
  const IoData est = arx_data(3), val = arx_data(30);
  const OrderSearchResult r = search_polynomial_orders(est, &val, grid, o);
  ASSERT_EQ(r.table.size(), 16u);
  EXPECT_EQ(r.table[r.best].orders.na, 2);
  EXPECT_EQ(r.table[r.best].orders.nb, std::vector<int>({2}));
  // Validation fit: the true orders are within 0.5 point of the best row (larger ones overfit only a little).
  double best_fit = -1e9;
  for (const auto& row : r.table) best_fit = std::max(best_fit, row.validation_fit);
  EXPECT_GT(r.table[r.best].validation_fit, best_fit - 0.5);
  EXPECT_LT(r.table.front().validation_fit, best_fit - 5.0);  // na = nb = 1 underfits
  const std::string text = format_order_table(r, PolynomialStructure::arx);
  EXPECT_NE(text.find("*     2       2"), std::string::npos) << text;
}

TEST(OrderSearch, GridEnumeratesEveryCombinationOnce) {
  PolynomialOrderGrid grid;
  grid.na = {2, 3};
  grid.nc = {1, 2};
  grid.nb = {{1, 3}, {0, 1}};
  grid.nk = {1, 1};
  const auto combos = order_combinations(grid, PolynomialStructure::armax);
  ASSERT_EQ(combos.size(), 2u * 2u * 3u * 2u);
  std::set<std::vector<int>> seen;
  for (const auto& c : combos) seen.insert({c.na, c.nc, c.nb[0], c.nb[1]});
  EXPECT_EQ(seen.size(), combos.size());
  // OE ignores na and nc; its F ranges vary instead.
  grid.nf = {{1, 2}, {1, 1}};
  EXPECT_EQ(order_combinations(grid, PolynomialStructure::oe).size(), 3u * 2u * 2u);
}

TEST(OrderSearch, BadRequestsAreRejected) {
  PolynomialOrderGrid grid;
  grid.na = {5, 2};
  OrderSearchOptions o;
  o.fit.structure = PolynomialStructure::ar;
  EXPECT_THROW(search_polynomial_orders(ar4_data(2), nullptr, grid, o), std::invalid_argument);
  grid.na = {1, 3};
  o.criterion = OrderCriterion::validation_fit;
  EXPECT_THROW(search_polynomial_orders(ar4_data(2), nullptr, grid, o), std::invalid_argument);
  o.criterion = OrderCriterion::aic;
  o.max_combinations = 2;
  EXPECT_THROW(search_polynomial_orders(ar4_data(2), nullptr, grid, o), std::invalid_argument);
}

}  // namespace test_unit_pem_order_search
