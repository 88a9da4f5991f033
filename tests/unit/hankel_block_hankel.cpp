#include <sysid/hankel/block_hankel.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/signal/butterworth.hpp>
#include <sysid/signal/sos_filter.hpp>

#include <gtest/gtest.h>

#include <iostream>

#include "checks.hpp"
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

TEST(BlockHankel, EveryRouteReproducesTheGramMatrix) {
  for (auto [m, l, i] : {std::tuple{1, 1, 5}, std::tuple{2, 3, 4}, std::tuple{3, 2, 7}}) {
    const IoData data = noise_data(900, m, l, 11 + i);
    BlockHankelOptions opt;
    opt.horizon = i;
    const HankelLayout lay{i, m, l};
    const Eigen::MatrixXd h = explicit_hankel(data.experiments[0], lay);
    const Eigen::MatrixXd g = h * h.transpose();
    for (HankelRoute route : {HankelRoute::qr, HankelRoute::cholesky, HankelRoute::cholesky_double_double}) {
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
  for (HankelRoute route : {HankelRoute::qr, HankelRoute::cholesky, HankelRoute::cholesky_double_double}) {
    opt.route = route;
    const BlockHankelCompression c = compress_block_hankel(data, opt);
    EXPECT_EQ(c.route_used, route);
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
  EXPECT_TRUE(test::has_warning(c.warnings, "rank deficient to double precision")) << c.warnings.size();
  const HankelLayout lay{4, 2, 1};
  const Eigen::MatrixXd h = explicit_hankel(data.experiments[0], lay);
  const Eigen::MatrixXd g = h * h.transpose();
  EXPECT_LT((c.R.transpose() * c.R - g).norm(), 1e-11 * g.norm());
}

TEST(BlockHankel, ForcedCholeskyRoutesRefuseOrFlagRankDeficientData) {
  IoData data = noise_data(600, 2, 1, 3);
  data.experiments[0].u.col(1) = data.experiments[0].u.col(0);
  BlockHankelOptions opt;
  opt.horizon = 4;
  opt.route = HankelRoute::cholesky;
  EXPECT_THROW(compress_block_hankel(data, opt), std::invalid_argument);
  // In double-double the pivot of the repeated input is rounding of either
  // sign: an error when negative, a warning when positive, never silence.
  opt.route = HankelRoute::cholesky_double_double;
  try {
    const BlockHankelCompression c = compress_block_hankel(data, opt);
    EXPECT_EQ(c.route_used, HankelRoute::cholesky_double_double);
    EXPECT_TRUE(test::has_warning(c.warnings, "rank deficient to double precision"));
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("rank deficient"), std::string::npos) << e.what();
  }
}

TEST(BlockHankel, BandLimitedDataTakeTheDoubleDoubleRouteAndBeatQrAgainstAReference) {
  // A lightly damped plant driven by noise low-passed at 5 % of the sample
  // rate (8th-order Butterworth), as a chirp below 100 Hz at 2 kHz would be:
  // H is so ill-conditioned that the double Gram matrix is refused. The
  // reference R is a Householder QR of the explicit H in long double.
  const Eigen::Index n = 6000;
  const SecondOrderSections lowpass = butterworth(8, BandType::lowpass, 0.05, 0.0, 1.0);
  const Eigen::MatrixXd u = sos_filter(lowpass, test::white_noise(n, 1, 21));
  const StateSpace plant = test::random_modal_system(2, 1, 1, 4, 0.02);
  const Eigen::MatrixXd y = simulate(plant, u) + 1e-5 * test::white_noise(n, 1, 22);
  const IoData data(u, y, 1.0);
  BlockHankelOptions opt;
  opt.horizon = 8;
  const HankelLayout lay{8, 1, 1};
  const BlockHankelCompression automatic = compress_block_hankel(data, opt);
  EXPECT_EQ(automatic.route_used, HankelRoute::cholesky_double_double);
  opt.route = HankelRoute::qr;
  const BlockHankelCompression qr = compress_block_hankel(data, opt);

  using LongMatrix = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
  const LongMatrix h = explicit_hankel(data.experiments[0], lay).transpose().cast<long double>();
  const Eigen::HouseholderQR<LongMatrix> reference_qr(h);
  LongMatrix reference = reference_qr.matrixQR().topRows(lay.size()).triangularView<Eigen::Upper>();
  for (Eigen::Index i = 0; i < reference.rows(); ++i)
    if (reference(i, i) < 0) reference.row(i) *= -1;
  const Eigen::MatrixXd r_ref = reference.cast<double>();
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(r_ref).singularValues();
  const double cond_h = sv(0) / sv(sv.size() - 1);
  EXPECT_GT(cond_h, 1e9) << "the case must be ill-conditioned beyond the double Gram route";
  const double error_dd = (automatic.R - r_ref).norm() / r_ref.norm();
  const double error_qr = (qr.R - r_ref).norm() / r_ref.norm();
  EXPECT_LT(error_dd, 0.1 * error_qr) << "cond(H) " << cond_h;
  EXPECT_LT(error_dd, 1e-9) << "cond(H) " << cond_h;
  std::cout << "cond(H) " << cond_h << ": relative error of R against the long-double reference " << error_dd
            << " (double-double Gram), " << error_qr << " (Householder QR)\n";
  // Told the data are band-limited, the automatic route skips the double
  // attempt: same route, same R (the double-double Gram matrix is formed the same way).
  opt.route = HankelRoute::automatic;
  opt.double_gram_first = false;
  const BlockHankelCompression skipped = compress_block_hankel(data, opt);
  EXPECT_EQ(skipped.route_used, HankelRoute::cholesky_double_double);
  EXPECT_EQ(skipped.R, automatic.R);
}

TEST(BlockHankel, WithoutTheDoubleAttemptWellConditionedDataStillGetAnAccurateR) {
  // White-noise data, where the automatic route takes the double Gram matrix:
  // with double_gram_first off they go to double-double, whose R is at least as
  // close to the QR's.
  const IoData data = noise_data(2000, 2, 1, 31);
  BlockHankelOptions opt;
  opt.horizon = 6;
  const BlockHankelCompression first = compress_block_hankel(data, opt);
  ASSERT_EQ(first.route_used, HankelRoute::cholesky);
  opt.double_gram_first = false;
  const BlockHankelCompression skipped = compress_block_hankel(data, opt);
  EXPECT_EQ(skipped.route_used, HankelRoute::cholesky_double_double);
  opt.route = HankelRoute::qr;
  const BlockHankelCompression qr = compress_block_hankel(data, opt);
  const double error_skipped = (skipped.R - qr.R).norm() / qr.R.norm();
  const double error_first = (first.R - qr.R).norm() / qr.R.norm();
  EXPECT_LT(error_skipped, 1e-13);
  EXPECT_LE(error_skipped, 2 * error_first + 1e-15);
  // A forced route ignores the flag.
  opt.route = HankelRoute::cholesky;
  EXPECT_EQ(compress_block_hankel(data, opt).route_used, HankelRoute::cholesky);
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
