// ARX and AR estimation (pem/arx.hpp): exact recovery without noise,
// recovery within the reported standard errors with noise, the AR methods
// agreeing, the modified Yule-Walker method unbiased under sensor noise,
// experiments pooled, and bad orders rejected.
#include <sysid/pem/arx.hpp>
#include <sysid/signal/polynomial_filter.hpp>

#include <gtest/gtest.h>

#include "random_systems.hpp"

namespace test_unit_pem_arx {

using namespace sysid;

namespace {

/// y = B/A u(t-nk) + 1/A e.
Eigen::VectorXd arx_output(const Eigen::VectorXd& a, const Eigen::VectorXd& b, int nk, const Eigen::VectorXd& u,
                           const Eigen::VectorXd& e) {
  Eigen::VectorXd num = Eigen::VectorXd::Zero(b.size() + nk);
  num.tail(b.size()) = b;
  return filter_polynomial(num, a, u).col(0) + filter_polynomial(Eigen::VectorXd::Ones(1), a, e).col(0);
}

const Eigen::Vector3d kA(1.0, -1.5, 0.7);
const Eigen::Vector2d kB(1.0, 0.5);

}  // namespace

TEST(Arx, NoiseFreeDataGiveTheExactParameters) {
  const Eigen::VectorXd u = test::white_noise(400, 1, 1).col(0);
  const Eigen::VectorXd y = arx_output(kA, kB, 2, u, Eigen::VectorXd::Zero(400));
  const LinearPolynomialResult r = arx(IoData(u, y, 0.01), {.na = 2, .nb = {2}, .nk = {2}, .remove_means = false});
  ASSERT_EQ(r.models.size(), 1u);
  EXPECT_LT((r.models[0].A - kA).norm(), 1e-10);
  EXPECT_LT((r.models[0].B[0] - kB).norm(), 1e-10);
  EXPECT_EQ(r.models[0].nk[0], 2);
  EXPECT_NEAR(r.models[0].Ts, 0.01, 0.0);
}

TEST(Arx, ScalesOfNineDecadesGiveTheSameParameters) {
  // Hardening (issue 8): u x su, y x sy leaves A unchanged and scales B by sy / su;
  // the column-scaled QR must keep every digit it has at unit scale.
  const Eigen::VectorXd u = test::white_noise(400, 1, 3).col(0);
  const Eigen::VectorXd y = arx_output(kA, kB, 2, u, 0.01 * test::white_noise(400, 1, 4).col(0));
  const ArxOptions o{.na = 2, .nb = {2}, .nk = {2}, .remove_means = false};
  const LinearPolynomialResult reference = arx(IoData(u, y, 0.01), o);
  for (double su : {1e-9, 1e9})
    for (double sy : {1e-9, 1e9}) {
      const LinearPolynomialResult r = arx(IoData(Eigen::VectorXd(su * u), Eigen::VectorXd(sy * y), 0.01), o);
      EXPECT_LT((r.models[0].A - reference.models[0].A).norm(), 1e-9) << su << " " << sy;
      EXPECT_LT((r.models[0].B[0] * su / sy - reference.models[0].B[0]).norm(), 1e-9 * reference.models[0].B[0].norm())
          << su << " " << sy;
    }
}

TEST(Arx, NoisyDataWithinTheReportedStandardErrors) {
  const Eigen::Index n = 20000;
  const Eigen::VectorXd u = test::white_noise(n, 1, 2).col(0), e = test::white_noise(n, 1, 3, 0.3).col(0);
  const Eigen::VectorXd y = arx_output(kA, kB, 1, u, e);
  const LinearPolynomialResult r = arx(IoData(u, y, 1.0), {.na = 2, .nb = {2}, .nk = {1}});
  Eigen::VectorXd truth(4), theta(4);
  truth << kA.tail(2), kB;
  theta << r.models[0].A.tail(2), r.models[0].B[0];
  for (Eigen::Index k = 0; k < 4; ++k) {
    const double se = std::sqrt(r.covariance[0](k, k));
    EXPECT_GT(se, 0.0);
    EXPECT_LT(std::abs(theta(k) - truth(k)), 4.0 * se) << "parameter " << k;
  }
  EXPECT_NEAR(r.models[0].noise_variance, 0.09, 0.09 * 0.05);
}

TEST(Arx, TwoExperimentsArePooledWithoutASeam) {
  const Eigen::VectorXd u1 = test::white_noise(300, 1, 4).col(0), u2 = test::white_noise(300, 1, 5).col(0);
  IoData data(u1, arx_output(kA, kB, 1, u1, Eigen::VectorXd::Zero(300)), 1.0);
  data.add_experiment({u2, arx_output(kA, kB, 1, u2, Eigen::VectorXd::Zero(300)), ""});
  const LinearPolynomialResult r = arx(data, {.na = 2, .nb = {2}, .nk = {1}, .remove_means = false});
  // Exact only if no equation straddles the two records.
  EXPECT_LT((r.models[0].A - kA).norm(), 1e-10);
}

TEST(Ar, LeastSquaresYuleWalkerAndBurgAgree) {
  const Eigen::Index n = 50000;
  const Eigen::VectorXd y = filter_polynomial(Eigen::VectorXd::Ones(1), kA, test::white_noise(n, 1, 6)).col(0);
  IoData data(Eigen::MatrixXd(n, 0), y, 1.0);
  for (ArMethod method : {ArMethod::least_squares, ArMethod::yule_walker, ArMethod::burg}) {
    const LinearPolynomialResult r = ar(data, {.na = 2, .method = method});
    EXPECT_LT((r.models[0].A - kA).cwiseAbs().maxCoeff(), 0.02) << "method " << static_cast<int>(method) << ": " << r.models[0].A.transpose();
    EXPECT_NEAR(r.models[0].noise_variance, 1.0, 0.03);
  }
}

TEST(Ar, BurgAndYuleWalkerAreStableOnShortNoisyRecords) {
  // Near-unit-circle poles and 64 samples: least squares may go unstable, these two may not.
  const Eigen::Vector3d a(1.0, -1.9, 0.995);
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const Eigen::VectorXd y = filter_polynomial(Eigen::VectorXd::Ones(1), a, test::white_noise(64, 1, seed)).col(0);
    IoData data(Eigen::MatrixXd(64, 0), y, 1.0);
    for (ArMethod method : {ArMethod::yule_walker, ArMethod::burg}) {
      const Eigen::VectorXd est = ar(data, {.na = 2, .method = method}).models[0].A;
      Eigen::Matrix2d companion;
      companion << -est(1), -est(2), 1.0, 0.0;
      EXPECT_LT(companion.eigenvalues().cwiseAbs().maxCoeff(), 1.0) << "seed " << seed;
    }
  }
}

TEST(Ar, ModifiedYuleWalkerIsUnbiasedUnderWhiteSensorNoise) {
  // An AR(2) process seen through a sensor adding white noise of 30 % of its RMS
  // is ARMA(2, 2): least squares (and Yule-Walker, Burg) are biased towards the
  // noise floor, the modified Yule-Walker equations (lags >= na + 1) are not.
  const Eigen::Index n = 200000;
  const Eigen::VectorXd x = filter_polynomial(Eigen::VectorXd::Ones(1), kA, test::white_noise(n, 1, 8)).col(0);
  const double rms = std::sqrt(x.squaredNorm() / static_cast<double>(n));
  const Eigen::VectorXd y = x + 0.3 * rms * test::white_noise(n, 1, 9).col(0);
  IoData data(Eigen::MatrixXd(n, 0), y, 1.0);
  const Eigen::VectorXd ls = ar(data, {.na = 2, .method = ArMethod::least_squares}).models[0].A;
  const Eigen::VectorXd myw = ar(data, {.na = 2, .method = ArMethod::modified_yule_walker}).models[0].A;
  EXPECT_GT((ls - kA).cwiseAbs().maxCoeff(), 0.1) << "least squares should be visibly biased: " << ls.transpose();
  EXPECT_LT((myw - kA).cwiseAbs().maxCoeff(), 0.02) << myw.transpose();
  // Without sensor noise it agrees with the others.
  IoData clean(Eigen::MatrixXd(n, 0), x, 1.0);
  const LinearPolynomialResult r = ar(clean, {.na = 2, .method = ArMethod::modified_yule_walker});
  EXPECT_LT((r.models[0].A - kA).cwiseAbs().maxCoeff(), 0.02) << r.models[0].A.transpose();
  EXPECT_NEAR(r.models[0].noise_variance, 1.0, 0.03);
  // Too short for na + M lags: a clear error.
  IoData tiny(Eigen::MatrixXd(9, 0), y.head(9), 1.0);
  EXPECT_THROW(ar(tiny, {.na = 2, .method = ArMethod::modified_yule_walker}), std::invalid_argument);
}

TEST(Arx, BadOrdersAreRejected) {
  const IoData data(test::white_noise(100, 1, 1), test::white_noise(100, 1, 2), 1.0);
  EXPECT_THROW(arx(data, {.na = -1, .nb = {2}, .nk = {}}), std::invalid_argument);
  EXPECT_THROW(arx(data, {.na = 2, .nb = {2, 2}, .nk = {}}), std::invalid_argument);
  EXPECT_THROW(arx(data, {.na = 2, .nb = {2}, .nk = {-1}}), std::invalid_argument);
  EXPECT_THROW(arx(data, {.na = 60, .nb = {60}, .nk = {}}), std::invalid_argument);  // more parameters than equations
  EXPECT_THROW(ar(data, {.na = 0}), std::invalid_argument);
}

}  // namespace test_unit_pem_arx
