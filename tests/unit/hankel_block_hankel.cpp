#include <sysid/hankel/block_hankel.hpp>

#include <gtest/gtest.h>

#include "random_systems.hpp"

namespace test_unit_hankel_block_hankel {

using namespace sysid;

namespace {

/// The explicit block-Hankel matrix H (k x j) of one experiment, for reference.
Eigen::MatrixXd explicit_hankel(const Experiment& e, const HankelLayout& lay) {
  const Eigen::Index j = e.samples() - 2 * lay.horizon + 1;
  Eigen::MatrixXd h(lay.size(), j);
  for (Eigen::Index t = 0; t < 2 * lay.horizon; ++t) {
    h.middleRows(lay.u_row(t), lay.inputs) = e.u.middleRows(t, j).transpose();
    h.middleRows(lay.y_row(t), lay.outputs) = e.y.middleRows(t, j).transpose();
  }
  return h;
}

IoData noise_data(Eigen::Index n, int m, int l, std::uint64_t seed) {
  return IoData(test::white_noise(n, m, seed), test::white_noise(n, l, seed + 1), 0.01);
}

}  // namespace

TEST(BlockHankel, BothRoutesReproduceTheGramMatrix) {
  for (auto [m, l, i] : {std::tuple{1, 1, 5}, std::tuple{2, 3, 4}, std::tuple{3, 2, 7}}) {
    const IoData data = noise_data(900, m, l, 11 + i);
    BlockHankelOptions opt;
    opt.horizon = i;
    const HankelLayout lay{i, m, l};
    const Eigen::MatrixXd h = explicit_hankel(data.experiments[0], lay);
    const Eigen::MatrixXd g = h * h.transpose();
    for (HankelRoute route : {HankelRoute::qr, HankelRoute::cholesky}) {
      opt.route = route;
      const BlockHankelCompression c = compress_block_hankel(data, opt);
      EXPECT_EQ(c.route_used, route);
      EXPECT_EQ(c.columns, h.cols());
      EXPECT_LT((c.R.transpose() * c.R - g).norm(), 1e-11 * g.norm()) << to_string(route);
      EXPECT_TRUE(c.R.isUpperTriangular());
    }
  }
}

TEST(BlockHankel, ExperimentsJoinWithoutASeam) {
  // Two experiments: the Gram matrix is the sum of the two, and no column mixes them.
  IoData data = noise_data(400, 2, 2, 5);
  data.add_experiment({test::white_noise(300, 2, 8), test::white_noise(300, 2, 9), "second"});
  BlockHankelOptions opt;
  opt.horizon = 3;
  const HankelLayout lay{3, 2, 2};
  const Eigen::MatrixXd h1 = explicit_hankel(data.experiments[0], lay), h2 = explicit_hankel(data.experiments[1], lay);
  const Eigen::MatrixXd g = h1 * h1.transpose() + h2 * h2.transpose();
  for (HankelRoute route : {HankelRoute::qr, HankelRoute::cholesky}) {
    opt.route = route;
    const BlockHankelCompression c = compress_block_hankel(data, opt);
    EXPECT_EQ(c.columns, h1.cols() + h2.cols());
    EXPECT_LT((c.R.transpose() * c.R - g).norm(), 1e-11 * g.norm());
  }
}

TEST(BlockHankel, AutomaticRouteFallsBackToQrOnRankDeficientData) {
  // Two identical inputs: the Gram matrix is singular, Cholesky must not be trusted.
  IoData data = noise_data(600, 2, 1, 3);
  data.experiments[0].u.col(1) = data.experiments[0].u.col(0);
  BlockHankelOptions opt;
  opt.horizon = 4;
  const BlockHankelCompression c = compress_block_hankel(data, opt);
  EXPECT_EQ(c.route_used, HankelRoute::qr);
  ASSERT_FALSE(c.warnings.empty());
  const HankelLayout lay{4, 2, 1};
  const Eigen::MatrixXd h = explicit_hankel(data.experiments[0], lay);
  const Eigen::MatrixXd g = h * h.transpose();
  EXPECT_LT((c.R.transpose() * c.R - g).norm(), 1e-11 * g.norm());
}

TEST(BlockHankel, TooFewSamplesIsAPreconditionError) {
  const IoData data = noise_data(30, 1, 1, 1);
  BlockHankelOptions opt;
  opt.horizon = 10;  // k = 40 rows, only 11 columns
  try {
    compress_block_hankel(data, opt);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("too few samples"), std::string::npos) << e.what();
  }
}

}  // namespace test_unit_hankel_block_hankel
