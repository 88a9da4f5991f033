// Tests of pem/polynomial_fit.hpp's noise check: a time-series model whose
// one-step residual is not white warns, says what it means and what to fit
// instead (issue 34 item 7: least-squares AR under sensor noise), and stays
// quiet on records it describes.
#include <sysid/pem/polynomial_fit.hpp>
#include <sysid/signal/polynomial_filter.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "par2_disturbance_polynomial.hpp"
#include "random_systems.hpp"

namespace test_unit_pem_polynomial_fit {

using namespace sysid;

namespace {

/// The process and, when `noise_fraction` > 0, white sensor noise of that fraction of its RMS.
IoData record(unsigned seed, double noise_fraction) {
  const Eigen::Index n = 40000;
  Eigen::VectorXd y = filter_polynomial(Eigen::VectorXd::Ones(1), test::par2_disturbance_denominator(), test::white_noise(n, 1, seed)).col(0);
  const double rms = std::sqrt(y.squaredNorm() / static_cast<double>(n));
  if (noise_fraction > 0) y += noise_fraction * rms * test::white_noise(n, 1, seed + 1000).col(0);
  return IoData(Eigen::MatrixXd(n, 0), y, 5e-4);
}

PolynomialFit fit(const IoData& data, PolynomialStructure s, int na, int nc, ArMethod method = ArMethod::least_squares) {
  PolynomialFitOptions o;
  o.structure = s;
  o.orders.na = na;
  o.orders.nc = nc;
  o.ar_method = method;
  return fit_polynomial(data, o);
}

bool warns_of_residual_correlation(const PolynomialFit& f) {
  return std::any_of(f.warnings.begin(), f.warnings.end(),
                     [](const std::string& w) { return w.find("are not white") != std::string::npos; });
}

std::string all(const PolynomialFit& f) {
  std::string s;
  for (const auto& w : f.warnings) s += w + "\n";
  return s;
}

}  // namespace

TEST(PolynomialFitNoiseCheck, QuietOnRecordsTheModelDescribes) {
  for (unsigned seed = 1; seed <= 4; ++seed)
    for (int na : {4, 8, 16}) {
      const PolynomialFit f = fit(record(seed, 0.0), PolynomialStructure::ar, na, 0);
      EXPECT_FALSE(warns_of_residual_correlation(f)) << "seed " << seed << " na " << na << "\n" << all(f);
      ASSERT_EQ(f.residual_whiteness.size(), 1u);
      EXPECT_GT(f.residual_whiteness[0].lags, 0);
    }
}

TEST(PolynomialFitNoiseCheck, LeastSquaresArUnderSensorNoiseWarnsAndNamesTheRemedy) {
  const IoData noisy = record(11, 0.01);
  const PolynomialFit ls = fit(noisy, PolynomialStructure::ar, 8, 0);
  ASSERT_TRUE(warns_of_residual_correlation(ls)) << all(ls);
  const std::string text = all(ls);
  EXPECT_NE(text.find("AR(8)"), std::string::npos) << text;
  EXPECT_NE(text.find("myw"), std::string::npos) << text;
  EXPECT_NE(text.find("ARMA(8, 8)"), std::string::npos) << text;
  EXPECT_NE(text.find("least squares"), std::string::npos) << text;
  EXPECT_LT(ls.residual_whiteness[0].p_value, 1e-12);
  const PolynomialFit burg = fit(noisy, PolynomialStructure::ar, 8, 0, ArMethod::burg);
  EXPECT_NE(all(burg).find("Burg"), std::string::npos) << all(burg);
  // The modified Yule-Walker residual A(q) y is coloured by the noise by design: not a defect, no warning.
  EXPECT_FALSE(warns_of_residual_correlation(fit(noisy, PolynomialStructure::ar, 8, 0, ArMethod::modified_yule_walker)));
}

TEST(PolynomialFitNoiseCheck, ArmaWithEnoughNumeratorIsQuietAndWithTooLittleWarns) {
  const IoData noisy = record(21, 0.01);
  const PolynomialFit full = fit(noisy, PolynomialStructure::arma, 4, 4);
  EXPECT_FALSE(warns_of_residual_correlation(full)) << all(full);
  const PolynomialFit short_c = fit(noisy, PolynomialStructure::arma, 4, 1);
  ASSERT_TRUE(warns_of_residual_correlation(short_c)) << all(short_c);
  EXPECT_NE(all(short_c).find("nc >= na"), std::string::npos) << all(short_c);
}

}  // namespace test_unit_pem_polynomial_fit
