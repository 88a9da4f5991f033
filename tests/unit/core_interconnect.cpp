#include <sysid/core/frequency_response.hpp>
#include <sysid/core/interconnect.hpp>

#include <gtest/gtest.h>

#include "random_systems.hpp"

namespace test_unit_core_interconnect {

using namespace sysid;

TEST(Interconnect, SeriesResponseIsTheProduct) {
  const StateSpace g1 = test::random_modal_system(2, 2, 3, 1), g2 = test::random_modal_system(3, 3, 2, 2);
  const StateSpace s = series(g1, g2);
  EXPECT_EQ(s.order(), g1.order() + g2.order());
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(50, 0.01, 0.49);
  const auto h1 = frequency_response(g1, f), h2 = frequency_response(g2, f), hs = frequency_response(s, f);
  for (std::size_t k = 0; k < hs.size(); ++k) {
    const Eigen::MatrixXcd expected = h2[k] * h1[k];
    EXPECT_LT((hs[k] - expected).norm(), 1e-10 * (1 + expected.norm()));
  }
}

TEST(Interconnect, BlockDiagonalStacksChannels) {
  const StateSpace g1 = test::random_modal_system(1, 1, 2, 3), g2 = test::random_modal_system(2, 2, 1, 4);
  const StateSpace s = block_diagonal({g1, g2});
  ASSERT_EQ(s.inputs(), 3);
  ASSERT_EQ(s.outputs(), 3);
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(20, 0.01, 0.49);
  const auto h1 = frequency_response(g1, f), h2 = frequency_response(g2, f), hs = frequency_response(s, f);
  for (std::size_t k = 0; k < hs.size(); ++k) {
    EXPECT_LT((hs[k].topLeftCorner(2, 1) - h1[k]).norm(), 1e-10 * (1 + h1[k].norm()));
    EXPECT_LT((hs[k].bottomRightCorner(1, 2) - h2[k]).norm(), 1e-10 * (1 + h2[k].norm()));
    EXPECT_LT(hs[k].topRightCorner(2, 2).norm() + hs[k].bottomLeftCorner(1, 1).norm(), 1e-14);
  }
}

TEST(Interconnect, MismatchedModelsAreRejected) {
  const StateSpace g1 = test::random_modal_system(1, 1, 2, 3), g2 = test::random_modal_system(1, 1, 1, 4);
  EXPECT_THROW(series(g1, g2), std::invalid_argument);
  StateSpace g3 = g2;
  g3.Ts = 0.5;
  EXPECT_THROW(block_diagonal({g2, g3}), std::invalid_argument);
}

}  // namespace test_unit_core_interconnect
