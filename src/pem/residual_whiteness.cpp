// Implementation of pem/residual_whiteness.hpp (method and references in the header).
#include <sysid/pem/prediction_error.hpp>
#include <sysid/pem/residual_whiteness.hpp>
#include <sysid/signal/polynomial_filter.hpp>

#include "pem/detail/pooled_autocorrelation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sysid {

namespace {

/// Samples until the start-up of 1/C(q) has decayed to 1e-3 of its size (the
/// slowest root of C sets it); na at least, the regression's own start.
Eigen::Index start_up_samples(const PolynomialModel& model) {
  Eigen::Index settle = std::max(model.na(), model.nc());
  if (model.nc() > 0) {
    const double radius = polynomial_roots(model.C).cwiseAbs().maxCoeff();
    if (radius > 0.0 && radius < 1.0)
      settle = std::max(settle, static_cast<Eigen::Index>(std::ceil(std::log(1e-3) / std::log(radius))));
  }
  return settle;
}

}  // namespace

Eigen::Index default_whiteness_lags(const PolynomialModel& model, Eigen::Index samples) {
  const Eigen::Index parameters = model.na() + model.nc();
  return std::min<Eigen::Index>(std::max<Eigen::Index>(50, 4 * parameters), samples / 5);
}

std::optional<LjungBoxTest> one_step_residual_whiteness(const PolynomialModel& model, const IoData& data, Eigen::Index output,
                                         double output_offset, Eigen::Index lags) {
  if (model.inputs() != 0) throw std::invalid_argument("one_step_residual_whiteness: need a time-series model (no inputs)");
  if (output < 0 || output >= data.outputs()) throw std::invalid_argument("one_step_residual_whiteness: no such output");
  const Eigen::Index settle = start_up_samples(model);
  // The residual of every record after its start-up, centred on the pooled mean.
  std::vector<Eigen::VectorXd> residuals;
  Eigen::Index samples = 0;
  double sum = 0.0;
  for (const auto& e : data.experiments) {
    if (e.samples() <= settle) continue;
    const Eigen::VectorXd y = e.y.col(output).array() - output_offset;
    Eigen::VectorXd r = filter_polynomial(model.A, model.C, y).col(0).tail(e.samples() - settle);
    samples += r.size();
    sum += r.sum();
    residuals.push_back(std::move(r));
  }
  if (lags == 0) lags = default_whiteness_lags(model, samples);
  const Eigen::Index parameters = model.na() + model.nc();
  if (lags <= parameters || samples <= 5 * lags) return std::nullopt;
  const double mean = sum / static_cast<double>(samples);
  for (auto& r : residuals) r.array() -= mean;
  Eigen::VectorXd acf = detail::pooled_autocorrelation(residuals, lags);
  if (!(acf(0) > 0.0)) return LjungBoxTest{samples, lags, 0.0, static_cast<double>(lags - parameters), 1.0};
  acf /= acf(0);
  return ljung_box_test(acf, samples, lags, parameters);
}

}  // namespace sysid
