// Residual analysis: sample correlations, bounds valid for coloured signals,
// Ljung-Box, verdicts, and the residuals of a model (the chi-square distribution
// behind the p-values is tested in core_distributions.cpp).
#include <sysid/core/discrete_riccati.hpp>
#include <sysid/core/distributions.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/validate/residual_analysis.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "random_systems.hpp"

namespace test_unit_validate_residual_analysis {

using namespace sysid;

namespace {

/// AR(1) signal x(t) = a x(t-1) + w(t), w ~ N(0, 1), started from its stationary
/// distribution (x(0) ~ N(0, 1/(1-a^2))), so there is no start-up transient.
Eigen::VectorXd ar1(Eigen::Index N, double a, std::uint64_t seed) {
  const Eigen::VectorXd w = test::white_noise(N, 1, seed).col(0);
  Eigen::VectorXd x(N);
  x(0) = w(0) / std::sqrt(1.0 - a * a);
  for (Eigen::Index t = 1; t < N; ++t) x(t) = a * x(t - 1) + w(t);
  return x;
}

}  // namespace

// ---- sample correlations ------------------------------------------------------

TEST(SampleCorrelation, HandComputedAndSymmetric) {
  // x = [1 2 3 4]: centred [-1.5 -0.5 0.5 1.5], R(0) = 5/4, R(1) = (0.75 - 0.25 + 0.75)/4,
  // so r(1) = 1.25/5 = 0.25; R(2) = (-0.75 - 0.75)/4 -> r(2) = -0.3; R(3) -> r(3) = -2.25/5.
  Eigen::Vector4d x(1, 2, 3, 4);
  const Eigen::VectorXd r = sample_correlation(x, x, 0, 3);
  EXPECT_NEAR(r(0), 1.0, 1e-15);
  EXPECT_NEAR(r(1), 0.25, 1e-15);
  EXPECT_NEAR(r(2), -0.3, 1e-15);
  EXPECT_NEAR(r(3), -0.45, 1e-15);
  // r_xy(-tau) = r_yx(tau).
  const Eigen::VectorXd a = test::white_noise(300, 1, 5).col(0), b = test::white_noise(300, 1, 6).col(0);
  const Eigen::VectorXd rab = sample_correlation(a, b, -7, 7), rba = sample_correlation(b, a, -7, 7);
  for (int k = 0; k < 15; ++k) EXPECT_NEAR(rab(k), rba(14 - k), 1e-15);
  // A constant signal correlates with nothing (reported as 0, not NaN).
  EXPECT_TRUE(sample_correlation(Eigen::VectorXd::Constant(10, 3.0), a.head(10), -2, 2).isZero(0.0));
  EXPECT_THROW(sample_correlation(a, b.head(299), 0, 3), std::invalid_argument);
  EXPECT_THROW(sample_correlation(a, b, 3, 2), std::invalid_argument);
  EXPECT_THROW(sample_correlation(a, b, -300, 0), std::invalid_argument);
}

// ---- whiteness ----------------------------------------------------------------

TEST(ResidualAnalysis, WhiteNoiseIsWhiteAndLjungBoxPValuesAreUniform) {
  // Under whiteness Q ~ chi2(25), so p is uniform: the rejection count at 1 % over
  // 200 seeds is Binomial(200, 0.01) (mean 2; P(count >= 7) = 0.5 %), and the count
  // with p < 0.5 is Binomial(200, 0.5) (P(outside 80..120) = 0.4 %). The verdict
  // rejects by Ljung-Box or a lag beyond the Bonferroni bound, each at level 1 %,
  // so at most ~2 % of white records are judged not white: Binomial(200, 0.02)
  // exceeds 12 with probability < 0.5 %.
  int lb_rejections = 0, below_half = 0, judged_not_white = 0, judged_dependent = 0;
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    const Eigen::MatrixXd e = test::white_noise(2000, 1, 1000 + seed);
    const Eigen::MatrixXd u = test::white_noise(2000, 1, 5000 + seed);
    const ResidualAnalysisResult r = analyze_residuals(e, u);
    ASSERT_EQ(r.ljung_box_lags, 25);
    EXPECT_EQ(r.ljung_box_dof, 25.0);
    if (r.ljung_box_p(0) < 0.01) ++lb_rejections;
    if (r.ljung_box_p(0) < 0.5) ++below_half;
    if (!r.verdicts[0].white) ++judged_not_white;
    if (!r.verdicts[0].independent[0]) ++judged_dependent;
  }
  EXPECT_LE(lb_rejections, 6);
  EXPECT_GE(below_half, 80);
  EXPECT_LE(below_half, 120);
  EXPECT_LE(judged_not_white, 12);
  EXPECT_LE(judged_dependent, 12);

  // One record in detail.
  const Eigen::MatrixXd e = test::white_noise(4000, 1, 77);
  ResidualAnalysisOptions o;
  o.output_names = {"y"};
  const ResidualAnalysisResult r = analyze_residuals(e, Eigen::MatrixXd(4000, 0), o);
  EXPECT_TRUE(r.verdicts[0].white) << r.verdicts[0].whiteness;
  EXPECT_EQ(r.verdicts[0].whiteness.rfind("white", 0), 0u) << r.verdicts[0].whiteness;
  EXPECT_NEAR(r.z, 2.5758293035489, 1e-9);
  EXPECT_NEAR(r.autocorrelation_bound, r.z / std::sqrt(4000.0), 1e-15);
  EXPECT_EQ(r.autocorrelation.rows(), 26);
  EXPECT_EQ(r.autocorrelation(0, 0), 1.0);
  EXPECT_EQ(r.input_correlation.cols(), 0);
  EXPECT_TRUE(r.warnings.empty());
}

TEST(ResidualAnalysis, Ar1ResidualIsNotWhite) {
  // r(1) = 0.5 against a bound of 2.58 / sqrt(2000) = 0.058: far outside, and
  // r(k) = 0.5^k stays outside up to k = 4 (0.0625).
  const Eigen::VectorXd e = ar1(2000, 0.5, 11);
  ResidualAnalysisOptions o;
  o.output_names = {"y"};
  const ResidualAnalysisResult r = analyze_residuals(e, Eigen::MatrixXd(2000, 0), o);
  const ResidualVerdict& v = r.verdicts[0];
  EXPECT_FALSE(v.white);
  ASSERT_FALSE(v.lags_outside.empty());
  EXPECT_EQ(v.lags_outside.front(), 1);
  EXPECT_NEAR(r.autocorrelation(1, 0), 0.5, 4.0 / std::sqrt(2000.0));  // 4 sigma of the estimate
  EXPECT_LT(r.ljung_box_p(0), 1e-20);
  EXPECT_EQ(v.whiteness.rfind("not white: autocorrelation outside the 99 % bound at lag", 0), 0u) << v.whiteness;
}

TEST(ResidualAnalysis, NoiseParametersReduceTheDegreesOfFreedom) {
  const Eigen::MatrixXd e = test::white_noise(1000, 1, 3);
  ResidualAnalysisOptions o;
  o.ljung_box_lags = 20;
  const ResidualAnalysisResult r0 = analyze_residuals(e, Eigen::MatrixXd(1000, 0), o);
  o.noise_parameters = 4;
  const ResidualAnalysisResult r4 = analyze_residuals(e, Eigen::MatrixXd(1000, 0), o);
  EXPECT_EQ(r4.ljung_box_dof, 16.0);
  EXPECT_EQ(r4.ljung_box_q(0), r0.ljung_box_q(0));  // Q itself does not depend on p
  EXPECT_NEAR(r4.ljung_box_p(0), chi_square_sf(r0.ljung_box_q(0), 16.0), 1e-15);
  EXPECT_LT(r4.ljung_box_p(0), r0.ljung_box_p(0));  // fewer dof: the same Q is less likely
}

TEST(ResidualAnalysis, MimoCrossCorrelationBetweenOutputs) {
  // e1 white; e2(t) = w2(t) + 0.5 e1(t-2) is white by itself (a sum of independent
  // white sequences), but predictable from the past of e1: r_{e2 e1}(2) =
  // 0.5 / sqrt(1.25) = 0.447, far outside 2.58 / sqrt(3000) = 0.047.
  const Eigen::Index N = 3000;
  const Eigen::MatrixXd w = test::white_noise(N, 2, 21);
  Eigen::MatrixXd e = w;
  for (Eigen::Index t = 2; t < N; ++t) e(t, 1) += 0.5 * w(t - 2, 0);
  const ResidualAnalysisResult r = analyze_residuals(e, Eigen::MatrixXd(N, 0));
  ASSERT_EQ(r.output_correlation.size(), 26u);
  EXPECT_NEAR(r.output_correlation[2](1, 0), 0.5 / std::sqrt(1.25), 4.0 / std::sqrt(double(N)));
  EXPECT_NEAR(r.output_correlation[0](0, 0), 1.0, 1e-15);
  EXPECT_NEAR(r.output_correlation[5](1, 1), r.autocorrelation(5, 1), 1e-15);
  EXPECT_TRUE(r.verdicts[0].white) << r.verdicts[0].whiteness;
  EXPECT_FALSE(r.verdicts[1].white) << r.verdicts[1].whiteness;
  EXPECT_NE(std::find(r.verdicts[1].output_lags_outside[0].begin(), r.verdicts[1].output_lags_outside[0].end(), 2),
            r.verdicts[1].output_lags_outside[0].end());
  EXPECT_NE(r.verdicts[1].whiteness.find("earlier residual of y1 at lag"), std::string::npos) << r.verdicts[1].whiteness;
}

// ---- residual-input cross-correlation ----------------------------------------

TEST(ResidualAnalysis, CorrelationWithColouredInputIsFlaggedAtItsLag) {
  // e(t) = w(t) + 0.15 u(t - 4), u AR(1) with pole 0.9 (std 2.3): the residual
  // carries input dynamics the model missed, delayed 4 samples. r_eu(tau) is
  // proportional to r_uu(tau - 4) = 0.9^|tau - 4|, largest at tau = 4.
  const Eigen::Index N = 4000, d = 4;
  const Eigen::VectorXd u = ar1(N, 0.9, 31);
  Eigen::VectorXd e = test::white_noise(N, 1, 32).col(0);
  for (Eigen::Index t = d; t < N; ++t) e(t) += 0.15 * u(t - d);
  ResidualAnalysisOptions o;
  o.output_names = {"y"};
  o.input_names = {"u"};
  const ResidualAnalysisResult r = analyze_residuals(e, u, o);
  const ResidualVerdict& v = r.verdicts[0];
  EXPECT_FALSE(v.independent[0]) << v.independence[0];
  const auto& lags = v.input_lags_outside[0];
  EXPECT_NE(std::find(lags.begin(), lags.end(), d), lags.end());
  Eigen::Index peak = 0;
  r.input_correlation.col(0).cwiseAbs().maxCoeff(&peak);
  EXPECT_EQ(peak - r.max_lag, d);
  EXPECT_EQ(v.independence[0].rfind("correlated with input u at lags", 0), 0u) << v.independence[0];
  // The coloured input smears the lag-4 correlation to negative lags (0.9^|tau - 4|:
  // still 0.25 of the peak at tau = -9); the words attribute them to the peak's side.
  EXPECT_NE(v.independence[0].find("(peak at lag 4; lags >= 0: input dynamics the model misses"), std::string::npos)
      << v.independence[0];
  EXPECT_EQ(v.independence[0].find("the residual leads the input: feedback"), std::string::npos) << v.independence[0];
}

TEST(ResidualAnalysis, FeedbackShowsAtNegativeLags) {
  // u(t) = v(t) - 0.4 e(t - 3): a controller feeding the output error back into
  // the input. Then e(t + tau) u(t) correlates at tau = -3 (the residual leads).
  const Eigen::Index N = 4000;
  const Eigen::VectorXd e = test::white_noise(N, 1, 41).col(0);
  Eigen::VectorXd u = test::white_noise(N, 1, 42).col(0);
  for (Eigen::Index t = 3; t < N; ++t) u(t) -= 0.4 * e(t - 3);
  ResidualAnalysisOptions o;
  o.input_names = {"u"};
  const ResidualAnalysisResult r = analyze_residuals(e, u, o);
  const ResidualVerdict& v = r.verdicts[0];
  EXPECT_FALSE(v.independent[0]);
  const auto& lags = v.input_lags_outside[0];
  EXPECT_NE(std::find(lags.begin(), lags.end(), -3), lags.end()) << v.independence[0];
  Eigen::Index peak = 0;
  r.input_correlation.col(0).cwiseAbs().maxCoeff(&peak);
  EXPECT_EQ(peak - r.max_lag, -3);
  // r_eu(-3) = -0.4 / sqrt(1.16) = -0.37 (4 sigma of the estimate: 4 / sqrt(N)).
  EXPECT_NEAR(r.input_correlation(r.max_lag - 3, 0), -0.4 / std::sqrt(1.16), 4.0 / std::sqrt(double(N)));
  EXPECT_NE(v.independence[0].find("(peak at lag -3; lags < 0: the residual leads the input: feedback)"), std::string::npos)
      << v.independence[0];
  EXPECT_TRUE(v.white);
}

TEST(ResidualAnalysis, IndependentColouredSignalsStayWithinTheColouredBound) {
  // e and u independent AR(1) with pole 0.9. Bartlett's factor is
  // P = sum_k 0.81^|k| = 1.81 / 0.19 = 9.53: the true standard deviation of r_eu is
  // 3.09 / sqrt(N), so the naive bound z / sqrt(N) sits at 0.83 true sigma and is
  // exceeded at P(|Z| > 0.83) = 40 % of lags, while the coloured bound is exceeded
  // at 1 %. Exceedances cluster (neighbouring lags are correlated over ~10 lags),
  // so the fractions are pooled over 50 records: 2550 lags, ~2.5 clusters expected
  // outside the coloured bound; the 3 % limit (76 lags, ~7 clusters) is crossed
  // with probability well under 1 %.
  const Eigen::Index N = 2000;
  int lags_total = 0, outside_coloured = 0, outside_naive = 0, dependent = 0;
  double factor_sum = 0.0;
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    const Eigen::VectorXd e = ar1(N, 0.9, 100 + seed), u = ar1(N, 0.9, 900 + seed);
    const ResidualAnalysisResult r = analyze_residuals(e, u);
    const double naive = r.z / std::sqrt(double(N));
    for (Eigen::Index k = 0; k < r.input_correlation.rows(); ++k) {
      const double a = std::abs(r.input_correlation(k, 0));
      ++lags_total;
      if (a > r.input_correlation_bound(0)) ++outside_coloured;
      if (a > naive) ++outside_naive;
    }
    if (!r.verdicts[0].independent[0]) ++dependent;
    factor_sum += r.input_variance_factor(0);
  }
  EXPECT_LE(outside_coloured, 0.03 * lags_total) << outside_coloured << " of " << lags_total;
  EXPECT_GE(outside_naive, 0.20 * lags_total) << outside_naive << " of " << lags_total;
  // The estimated factor: sample autocorrelations of a pole-0.9 AR(1) over 2000
  // samples are biased low by ~(1 + a)/((1 - a) N) = 1 % each, so P^ ~ 8.5-9.5.
  EXPECT_NEAR(factor_sum / 50.0, 1.81 / 0.19, 0.15 * 1.81 / 0.19);
  EXPECT_LE(dependent, 3);
}

// ---- the residuals of a model --------------------------------------------------

TEST(ModelResiduals, InnovationPredictorRecoversTheInnovationsAndSimulationErrorWithoutK) {
  const StateSpace sys = test::random_modal_system(2, 1, 2, 7);
  const Eigen::Index n = sys.order(), l = sys.outputs(), N = 1500;
  const KalmanFilterResult kf = steady_state_kalman_filter(sys.A, sys.C, 0.1 * Eigen::MatrixXd::Identity(n, n),
                                                           Eigen::MatrixXd::Identity(l, l), Eigen::MatrixXd::Zero(n, l));
  ASSERT_EQ(kf.status, KalmanFilterResult::Status::converged);
  const Eigen::MatrixXd u = test::white_noise(N, 1, 8), e = test::white_noise(N, l, 9, 0.3);
  Eigen::MatrixXd Bx(n, 1 + l), Dx(l, 1 + l), ue(N, 1 + l);
  Bx << sys.B, kf.K;
  Dx << sys.D, Eigen::MatrixXd::Identity(l, l);
  ue << u, e;
  const Eigen::MatrixXd y = simulate(StateSpace(sys.A, Bx, sys.C, Dx, sys.Ts), ue);
  const Experiment data{u, y, "test"};
  CompareOptions o;
  o.estimate_x0 = false;  // the true x0 = 0: the predictor reproduces e exactly
  const Eigen::MatrixXd res = model_residuals(sys, kf.K, data, o);
  // Rounding only: the predictor recursion is stable (A - K C), errors do not grow.
  EXPECT_LT((res - e).cwiseAbs().maxCoeff(), 1e-10 * y.cwiseAbs().maxCoeff());
  const ResidualAnalysisResult r = analyze_residuals(res, u);
  EXPECT_TRUE(r.verdicts[0].white && r.verdicts[1].white) << r.verdicts[0].whiteness << " / " << r.verdicts[1].whiteness;
  // Without K: the simulation error y - G u = H e, coloured by the noise model.
  const Eigen::MatrixXd sim_err = model_residuals(sys, Eigen::MatrixXd(), data, o);
  EXPECT_LT((sim_err - (y - simulate(sys, u))).cwiseAbs().maxCoeff(), 1e-12 * y.cwiseAbs().maxCoeff());
  EXPECT_FALSE(analyze_residuals(sim_err, u).verdicts[0].white);
}

// ---- preconditions ------------------------------------------------------------

TEST(ResidualAnalysis, BadArgumentsThrow) {
  const Eigen::MatrixXd e = test::white_noise(100, 1, 1), u = test::white_noise(100, 1, 2);
  auto with = [](auto change) {
    ResidualAnalysisOptions o;
    change(o);
    return o;
  };
  EXPECT_THROW(analyze_residuals(e, u, with([](auto& o) { o.max_lag = 0; })), std::invalid_argument);
  EXPECT_THROW(analyze_residuals(e, u, with([](auto& o) { o.max_lag = 100; })), std::invalid_argument);
  EXPECT_THROW(analyze_residuals(e, u, with([](auto& o) { o.confidence = 1.0; })), std::invalid_argument);
  EXPECT_THROW(analyze_residuals(e, u, with([](auto& o) { o.confidence = 0.0; })), std::invalid_argument);
  EXPECT_THROW(analyze_residuals(e, u, with([](auto& o) { o.noise_parameters = 25; })), std::invalid_argument);
  EXPECT_THROW(analyze_residuals(e, u, with([](auto& o) { o.noise_parameters = -1; })), std::invalid_argument);
  EXPECT_THROW(analyze_residuals(e, u, with([](auto& o) { o.ljung_box_lags = 100; })), std::invalid_argument);
  EXPECT_THROW(analyze_residuals(e, u, with([](auto& o) { o.variance_lags = -1; })), std::invalid_argument);
  EXPECT_THROW(analyze_residuals(e, u, with([](auto& o) { o.output_names = {"a", "b"}; })), std::invalid_argument);
  EXPECT_THROW(analyze_residuals(e, u, with([](auto& o) { o.input_names = {"a", "b"}; })), std::invalid_argument);
  EXPECT_THROW(analyze_residuals(e, u.topRows(99)), std::invalid_argument);
  EXPECT_THROW(analyze_residuals(Eigen::MatrixXd(100, 0), u), std::invalid_argument);
  Eigen::MatrixXd bad = e;
  bad(5, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(analyze_residuals(bad, u), std::invalid_argument);
  bad = u;
  bad(7, 0) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(analyze_residuals(e, bad), std::invalid_argument);
  try {
    analyze_residuals(e, u, with([](auto& o) { o.max_lag = 100; }));
  } catch (const std::invalid_argument& ex) {
    EXPECT_NE(std::string(ex.what()).find("samples > max_lag"), std::string::npos) << ex.what();
  }
}

TEST(ResidualAnalysis, ConstantSignalsAreWarnedNotNaN) {
  const Eigen::MatrixXd e = test::white_noise(500, 1, 1);
  const Eigen::MatrixXd u = Eigen::MatrixXd::Constant(500, 1, 2.0);
  ResidualAnalysisOptions o;
  o.input_names = {"u"};
  const ResidualAnalysisResult r = analyze_residuals(e, u, o);
  EXPECT_TRUE(r.input_correlation.allFinite());
  EXPECT_TRUE(r.verdicts[0].independent[0]);
  EXPECT_NE(r.verdicts[0].independence[0].find("not tested"), std::string::npos);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings.back().find("input u is constant"), std::string::npos) << r.warnings.back();
  // A residual with an offset is warned about.
  const ResidualAnalysisResult off = analyze_residuals((e.array() + 0.5).matrix(), test::white_noise(500, 1, 2));
  ASSERT_FALSE(off.warnings.empty());
  EXPECT_NE(off.warnings.front().find("offset"), std::string::npos) << off.warnings.front();
}

}  // namespace test_unit_validate_residual_analysis
