#include <sysid/core/column_scaled_condition.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "random_matrices.hpp"

namespace test_unit_core_column_scaled_condition {

using namespace sysid;

TEST(ColumnScaledCondition, IgnoresColumnUnitsAndMeasuresCollinearity) {
  // Two unit columns at angle phi: singular values sqrt(1 +- cos phi).
  const double phi = 1e-3;
  Eigen::MatrixXd h(3, 2);
  h << 1, std::cos(phi), 0, std::sin(phi), 0, 0;
  const double expected = std::sqrt((1 + std::cos(phi)) / (1 - std::cos(phi)));
  EXPECT_NEAR(column_scaled_condition(h), expected, 1e-9 * expected);
  // Units do not matter: column scales of 1e6 and 1e-6 give the same number.
  const Eigen::MatrixXd scaled = h * Eigen::Vector2d(1e6, 1e-6).asDiagonal();
  EXPECT_NEAR(column_scaled_condition(scaled), expected, 1e-9 * expected);
}

TEST(ColumnScaledCondition, AgreesWithTheJacobiSvdOnALargeTriangularFactor) {
  // 192 columns, the size of the Hannan-Rissanen regression on the Par2 ARMAX.
  const Eigen::MatrixXd h = test::white_noise(400, 192, 3) * Eigen::VectorXd::LinSpaced(192, 1, 1e3).asDiagonal();
  const Eigen::MatrixXd r = h.householderQr().matrixQR().topRows(192).triangularView<Eigen::Upper>();
  Eigen::VectorXd norms = r.colwise().norm().transpose();
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(r * norms.cwiseInverse().asDiagonal()).singularValues();
  const double reference = sv(0) / sv(sv.size() - 1);
  EXPECT_NEAR(column_scaled_condition(r), reference, 1e-8 * reference);
}

TEST(ColumnScaledCondition, ZeroColumnIsInfiniteAndEmptyIsOne) {
  Eigen::MatrixXd h = test::white_noise(10, 3, 4);
  h.col(1).setZero();
  EXPECT_EQ(column_scaled_condition(h), std::numeric_limits<double>::infinity());
  EXPECT_EQ(column_scaled_condition(Eigen::MatrixXd(5, 0)), 1.0);
}

}  // namespace test_unit_core_column_scaled_condition
