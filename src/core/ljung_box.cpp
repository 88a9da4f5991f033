// Implementation of core/ljung_box.hpp (method and reference in the header).
#include <sysid/core/distributions.hpp>
#include <sysid/core/ljung_box.hpp>

#include <stdexcept>
#include <string>

namespace sysid {

LjungBoxTest ljung_box_test(const Eigen::Ref<const Eigen::VectorXd>& autocorrelation, Eigen::Index samples, Eigen::Index lags,
                            Eigen::Index fitted_parameters) {
  if (lags < 1 || lags > autocorrelation.size() - 1)
    throw std::invalid_argument("ljung_box_test: need 1 <= lags <= " + std::to_string(autocorrelation.size() - 1));
  if (lags >= samples) throw std::invalid_argument("ljung_box_test: need lags < samples");
  if (fitted_parameters < 0 || fitted_parameters >= lags)
    throw std::invalid_argument("ljung_box_test: need 0 <= fitted_parameters < lags");
  const double n = static_cast<double>(samples);
  double sum = 0.0;
  for (Eigen::Index k = 1; k <= lags; ++k) sum += autocorrelation(k) * autocorrelation(k) / (n - static_cast<double>(k));
  LjungBoxTest t;
  t.samples = samples;
  t.lags = lags;
  t.statistic = n * (n + 2.0) * sum;
  t.degrees_of_freedom = static_cast<double>(lags - fitted_parameters);
  t.p_value = chi_square_sf(t.statistic, t.degrees_of_freedom);
  return t;
}

}  // namespace sysid
