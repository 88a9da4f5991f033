// Prediction-error identification (pem/prediction_error.hpp): the analytic
// Jacobian against central finite differences for every structure; ARMAX,
// ARMA and OE recover their parameters within the reported standard errors;
// the subspace start of ARMAX (MISO) is near the truth before any iteration;
// the stability helpers; bad orders rejected.
#include <sysid/pem/prediction_error.hpp>
#include <sysid/signal/polynomial_filter.hpp>

#include <gtest/gtest.h>

#include <iostream>

#include "random_systems.hpp"

namespace test_unit_pem_prediction_error {

using namespace sysid;

namespace {

PolynomialModel make_model(Eigen::VectorXd a, std::vector<Eigen::VectorXd> b, std::vector<int> nk, std::vector<Eigen::VectorXd> f,
                           Eigen::VectorXd c, Eigen::VectorXd d) {
  PolynomialModel pm;
  pm.A = std::move(a);
  pm.B = std::move(b);
  pm.nk = std::move(nk);
  pm.F = std::move(f);
  pm.C = std::move(c);
  pm.D = std::move(d);
  return pm;
}

/// y from the model's defining equation with white e (filtered from rest).
Eigen::VectorXd simulate_polynomial(const PolynomialModel& pm, const Eigen::MatrixXd& u, const Eigen::VectorXd& e) {
  Eigen::VectorXd rhs = filter_polynomial(pm.C, pm.D, e).col(0);
  for (Eigen::Index i = 0; i < pm.inputs(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    Eigen::VectorXd num = Eigen::VectorXd::Zero(pm.B[k].size() + pm.nk[k]);
    num.tail(pm.B[k].size()) = pm.B[k];
    rhs += filter_polynomial(num, pm.F[k], u.col(i)).col(0);
  }
  return filter_polynomial(Eigen::VectorXd::Ones(1), pm.A, rhs).col(0);
}

const Eigen::VectorXd kOne = Eigen::VectorXd::Ones(1);

void expect_jacobian_matches_finite_differences(const PolynomialModel& pm) {
  const Eigen::MatrixXd u = test::white_noise(300, pm.inputs(), 7);
  const Eigen::VectorXd y = test::white_noise(300, 1, 8).col(0) + simulate_polynomial(pm, u, Eigen::VectorXd::Zero(300));
  const PredictionErrors pe = prediction_errors(pm, u, y, true);
  const Eigen::VectorXd theta = pack_parameters(pm);
  ASSERT_EQ(pe.jacobian.cols(), theta.size());
  for (Eigen::Index k = 0; k < theta.size(); ++k) {
    const double h = 1e-6;
    PolynomialModel plus = pm, minus = pm;
    Eigen::VectorXd tp = theta, tm = theta;
    tp(k) += h;
    tm(k) -= h;
    unpack_parameters(tp, plus);
    unpack_parameters(tm, minus);
    const Eigen::VectorXd fd = (prediction_errors(plus, u, y, false).eps - prediction_errors(minus, u, y, false).eps) / (2 * h);
    // Central differences: truncation O(h^2), rounding O(eps / h) relative to the signal size.
    EXPECT_LT((fd - pe.jacobian.col(k)).norm(), 1e-6 * (1.0 + fd.norm())) << "parameter " << k;
  }
}

}  // namespace

TEST(PredictionError, JacobianOfArmaxMatchesFiniteDifferences) {
  expect_jacobian_matches_finite_differences(make_model(Eigen::Vector3d(1.0, -1.5, 0.7), {Eigen::Vector2d(1.0, 0.5), Eigen::Vector2d(-0.3, 0.2)},
                                                       {1, 0}, {kOne, kOne}, Eigen::Vector2d(1.0, 0.4), kOne));
}

TEST(PredictionError, JacobianOfOutputErrorAndBoxJenkinsMatchesFiniteDifferences) {
  expect_jacobian_matches_finite_differences(
      make_model(kOne, {Eigen::Vector2d(1.0, 0.5)}, {2}, {Eigen::Vector3d(1.0, -1.2, 0.6)}, kOne, kOne));
  expect_jacobian_matches_finite_differences(make_model(kOne, {Eigen::Vector2d(1.0, 0.5), Eigen::Vector3d(0.1, 0.2, 0.3)}, {1, 1},
                                                       {Eigen::Vector3d(1.0, -1.2, 0.6), Eigen::Vector2d(1.0, -0.5)},
                                                       Eigen::Vector2d(1.0, 0.3), Eigen::Vector3d(1.0, -0.9, 0.2)));
}

TEST(PredictionError, JacobianOfArmaMatchesFiniteDifferences) {
  expect_jacobian_matches_finite_differences(make_model(Eigen::Vector3d(1.0, -0.9, 0.5), {}, {}, {}, Eigen::Vector3d(1.0, 0.5, 0.2), kOne));
}

TEST(PredictionError, ArmaxRecoversItsParameters) {
  const PolynomialModel truth = make_model(Eigen::Vector3d(1.0, -1.5, 0.7), {Eigen::Vector2d(1.0, 0.5)}, {1}, {kOne},
                                           Eigen::Vector3d(1.0, -0.6, 0.2), kOne);
  const Eigen::Index n = 20000;
  const Eigen::MatrixXd u = test::white_noise(n, 1, 11);
  const Eigen::VectorXd y = simulate_polynomial(truth, u, test::white_noise(n, 1, 12, 0.5).col(0));
  PemOptions opt;
  opt.na = 2;
  opt.nb = {2};
  opt.nc = 2;
  opt.nk = {1};
  const PemResult r = pem(IoData(u, y, 1.0), opt);
  ASSERT_EQ(r.status, PemResult::Status::converged) << r.termination;
  EXPECT_EQ(r.structure, "armax");
  EXPECT_LE(r.final_cost, r.initial_cost);
  const Eigen::VectorXd err = pack_parameters(r.model) - pack_parameters(truth);
  for (Eigen::Index k = 0; k < err.size(); ++k) EXPECT_LT(std::abs(err(k)), 4.0 * std::sqrt(r.covariance(k, k))) << "parameter " << k;
  EXPECT_NEAR(r.model.noise_variance, 0.25, 0.25 * 0.05);
}

TEST(PredictionError, SubspaceStartAloneIsNearTheTruthForEachInput) {
  // Two inputs: each B_i comes from its own rank-one determinant identity, C from
  // det(zI - A + KC). No iterations: this is the start itself.
  const PolynomialModel truth = make_model(Eigen::Vector3d(1.0, -1.5, 0.7), {Eigen::Vector2d(1.0, 0.5), Eigen::Vector2d(0.3, -0.2)},
                                           {1, 1}, {kOne, kOne}, Eigen::Vector3d(1.0, -0.6, 0.2), kOne);
  const Eigen::Index n = 20000;
  const Eigen::MatrixXd u = test::white_noise(n, 2, 21);
  const Eigen::VectorXd y = simulate_polynomial(truth, u, test::white_noise(n, 1, 22, 0.5).col(0));
  PemOptions opt;
  opt.na = 2;
  opt.nb = {2, 2};
  opt.nc = 2;
  opt.nk = {1, 1};
  opt.start = PemStart::subspace;
  opt.max_iterations = 0;
  const PemResult start = pem(IoData(u, y, 1.0), opt);
  EXPECT_EQ(start.start, "subspace");
  EXPECT_EQ(start.iterations, 0);
  const Eigen::VectorXd err = pack_parameters(start.model) - pack_parameters(truth);
  for (Eigen::Index k = 0; k < err.size(); ++k) EXPECT_LT(std::abs(err(k)), 0.05) << "parameter " << k;
  std::cout << "subspace start: largest parameter error " << err.cwiseAbs().maxCoeff() << "\n";
  // Iterated from there, the minimum is the truth within the standard errors.
  opt.max_iterations = 100;
  const PemResult r = pem(IoData(u, y, 1.0), opt);
  ASSERT_EQ(r.status, PemResult::Status::converged) << r.termination;
  EXPECT_LE(r.final_cost, r.initial_cost);
  const Eigen::VectorXd final_err = pack_parameters(r.model) - pack_parameters(truth);
  for (Eigen::Index k = 0; k < final_err.size(); ++k)
    EXPECT_LT(std::abs(final_err(k)), 4.0 * std::sqrt(r.covariance(k, k))) << "parameter " << k;
}

TEST(PredictionError, VariableProjectionPutsAAndBAtTheirOptimumForTheStartsC) {
  // With C fixed, eps = (A y - B u) / C is linear in A and B: after the
  // projection the cost's gradient in them is zero (to rounding), and the cost
  // is below the start's own. Without it the Hannan-Rissanen start's A and B
  // (fitted to its high-order ARX residuals) are not optimal for its C.
  const PolynomialModel truth = make_model(Eigen::Vector3d(1.0, -1.5, 0.7), {Eigen::Vector2d(1.0, 0.5)}, {1}, {kOne},
                                           Eigen::Vector3d(1.0, -0.6, 0.2), kOne);
  const Eigen::Index n = 5000;
  const Eigen::MatrixXd u = test::white_noise(n, 1, 31);
  const Eigen::VectorXd y = simulate_polynomial(truth, u, test::white_noise(n, 1, 32, 0.5).col(0));
  PemOptions opt;
  opt.na = 2;
  opt.nb = {2};
  opt.nc = 2;
  opt.nk = {1};
  opt.start = PemStart::hannan_rissanen;
  opt.max_iterations = 0;
  opt.remove_means = false;
  auto largest_ab_gradient = [&](const PemResult& r) {
    const PredictionErrors pe = prediction_errors(r.model, u, y, true);
    double worst = 0;
    for (Eigen::Index k = 0; k < 4; ++k)  // a_1, a_2, b_1, b_2 (pack_parameters order)
      worst = std::max(worst, std::abs(pe.jacobian.col(k).dot(pe.eps)) / (pe.jacobian.col(k).norm() * pe.eps.norm()));
    return worst;
  };
  const PemResult projected = pem(IoData(u, y, 1.0), opt);
  opt.variable_projection = false;
  const PemResult plain = pem(IoData(u, y, 1.0), opt);
  std::cout << "relative A, B gradient: projected " << largest_ab_gradient(projected) << ", plain "
            << largest_ab_gradient(plain) << "\n";
  EXPECT_LT(largest_ab_gradient(projected), 1e-10);
  EXPECT_GT(largest_ab_gradient(plain), 1e-4);
  EXPECT_LT(projected.final_cost, plain.final_cost);
  EXPECT_EQ(projected.initial_cost, plain.initial_cost);  // the same start, reported before the projection
  // C is the start's in both.
  EXPECT_EQ((projected.model.C - plain.model.C).cwiseAbs().maxCoeff(), 0.0);
}

TEST(PredictionError, ArmaRecoversItsParameters) {
  const PolynomialModel truth = make_model(Eigen::Vector3d(1.0, -0.9, 0.5), {}, {}, {}, Eigen::Vector2d(1.0, 0.7), kOne);
  const Eigen::Index n = 20000;
  const Eigen::VectorXd y = simulate_polynomial(truth, Eigen::MatrixXd(n, 0), test::white_noise(n, 1, 13).col(0));
  PemOptions opt;
  opt.na = 2;
  opt.nc = 1;
  const PemResult r = pem(IoData(Eigen::MatrixXd(n, 0), y, 1.0), opt);
  ASSERT_EQ(r.status, PemResult::Status::converged) << r.termination;
  EXPECT_EQ(r.structure, "arma");
  const Eigen::VectorXd err = pack_parameters(r.model) - pack_parameters(truth);
  for (Eigen::Index k = 0; k < err.size(); ++k) EXPECT_LT(std::abs(err(k)), 4.0 * std::sqrt(r.covariance(k, k))) << "parameter " << k;
}

TEST(PredictionError, OutputErrorRecoversItsParametersFromColouredInput) {
  // OE with a lightly damped F and a low-pass input: the ARX start is biased,
  // the prediction-error minimum is not.
  const PolynomialModel truth = make_model(kOne, {Eigen::Vector2d(0.5, 0.3)}, {1}, {Eigen::Vector3d(1.0, -1.6, 0.9)}, kOne, kOne);
  const Eigen::Index n = 10000;
  const Eigen::MatrixXd u = filter_polynomial(Eigen::VectorXd::Ones(1), Eigen::Vector2d(1.0, -0.7), test::white_noise(n, 1, 14));
  const Eigen::VectorXd y = simulate_polynomial(truth, u, test::white_noise(n, 1, 15, 0.5).col(0));
  PemOptions opt;
  opt.nb = {2};
  opt.nf = {2};
  opt.nk = {1};
  const PemResult r = pem(IoData(u, y, 1.0), opt);
  ASSERT_EQ(r.status, PemResult::Status::converged) << r.termination;
  EXPECT_EQ(r.structure, "oe");
  const Eigen::VectorXd err = pack_parameters(r.model) - pack_parameters(truth);
  for (Eigen::Index k = 0; k < err.size(); ++k) EXPECT_LT(std::abs(err(k)), 4.0 * std::sqrt(r.covariance(k, k))) << "parameter " << k;
  // Without the statistical stop the iterations go on to the tolerances of
  // cost and gradient: they must lower the cost, yet move no parameter by more
  // than a fraction of its standard deviation (what the stop claims).
  opt.step_significance_tolerance = 0.0;
  const PemResult strict = pem(IoData(u, y, 1.0), opt);
  ASSERT_EQ(strict.status, PemResult::Status::converged) << strict.termination;
  EXPECT_GT(strict.iterations, r.iterations);
  EXPECT_LE(strict.final_cost, r.final_cost);
  const Eigen::VectorXd moved = pack_parameters(strict.model) - pack_parameters(r.model);
  for (Eigen::Index k = 0; k < moved.size(); ++k)
    EXPECT_LT(std::abs(moved(k)), 0.1 * std::sqrt(r.covariance(k, k))) << "parameter " << k;
}

TEST(PredictionError, ReflectionKeepsTheMagnitudeShape) {
  // 1 + 2.5 q^-1 has its root at -2.5; its spectral factor 1 + 0.4 q^-1 has the
  // same |.| up to the constant 2.5.
  const Eigen::VectorXd reflected = reflect_into_unit_circle(Eigen::Vector2d(1.0, 2.5));
  EXPECT_NEAR(reflected(1), 0.4, 1e-12);
  EXPECT_LT(polynomial_roots(reflected).cwiseAbs().maxCoeff(), 1.0);
  const Eigen::Vector3d stable(1.0, -0.5, 0.06);
  EXPECT_LT((reflect_into_unit_circle(stable) - stable).norm(), 1e-15);
}

TEST(PredictionError, BadOrdersAreRejected) {
  const IoData data(test::white_noise(200, 1, 1), test::white_noise(200, 1, 2), 1.0);
  PemOptions opt;
  opt.na = 2;
  opt.nb = {2, 2};
  EXPECT_THROW(pem(data, opt), std::invalid_argument);  // one nb per input
  opt.nb = {2};
  opt.nk = {-1};
  EXPECT_THROW(pem(data, opt), std::invalid_argument);  // negative delay
  opt.nk = {1};
  opt.nc = -1;
  EXPECT_THROW(pem(data, opt), std::invalid_argument);
  opt.nc = 1;
  opt.nf = {2};
  EXPECT_THROW(pem(data, opt), std::invalid_argument);  // A together with F
  opt = PemOptions{};
  opt.na = 2;
  opt.nc = 1;
  opt.start = PemStart::subspace;
  const IoData series(Eigen::MatrixXd(200, 0), test::white_noise(200, 1, 2), 1.0);
  EXPECT_THROW(pem(series, opt), std::invalid_argument);  // the subspace start needs an input (ARMA)
  opt.start = PemStart::output_error;
  EXPECT_THROW(pem(series, opt), std::invalid_argument);  // so does the output-error start
  opt = PemOptions{};
  opt.na = 150;
  opt.nb = {150};
  EXPECT_THROW(pem(data, opt), std::invalid_argument);  // more parameters than the data support
}

}  // namespace test_unit_pem_prediction_error
