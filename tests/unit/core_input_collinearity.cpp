// Tests for sysid::collinear_input_warnings (include/sysid/core/input_collinearity.hpp).
#include <sysid/core/input_collinearity.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/subspace/n4sid.hpp>

#include <gtest/gtest.h>

#include "random_systems.hpp"

namespace test_unit_core_input_collinearity {


TEST(InputCollinearity, NamesTheCollinearPairOnly) {
  Eigen::MatrixXd u = sysid::test::white_noise(2000, 3, 1);
  u.col(2) = -3.0 * u.col(0).array() + 7.0;  // c = -3 a + 7: collinear despite scale, sign and offset
  sysid::IoData d(u, u.col(1), 1e-3);
  d.input_names = {"a", "b", "c"};
  const auto w = sysid::collinear_input_warnings(d, "n4sid");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("n4sid: inputs a and c are collinear"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("-1.0000"), std::string::npos) << w[0];
}

TEST(InputCollinearity, IndependentInputsAndOneInputGiveNothing) {
  const Eigen::MatrixXd u = sysid::test::white_noise(2000, 3, 2);
  EXPECT_TRUE(sysid::collinear_input_warnings(sysid::IoData(u, u.col(0), 1e-3), "x").empty());
  EXPECT_TRUE(sysid::collinear_input_warnings(sysid::IoData(u.col(0), u.col(0), 1e-3), "x").empty());
}

TEST(InputCollinearity, N4sidWarnsOnTwinInputs) {
  const sysid::StateSpace truth = sysid::test::random_modal_system(1, 2, 1, 5);
  Eigen::MatrixXd u = sysid::test::white_noise(3000, 2, 6);
  u.col(1) = u.col(0);
  const Eigen::MatrixXd y = sysid::simulate(truth, u);
  sysid::N4sidOptions o;
  o.order = 2;
  const auto r = sysid::n4sid(sysid::IoData(u, y, truth.Ts), o);
  bool named = false;
  for (const auto& w : r.warnings) named |= w.find("inputs u1 and u2 are collinear") != std::string::npos;
  EXPECT_TRUE(named);
}

}  // namespace test_unit_core_input_collinearity
