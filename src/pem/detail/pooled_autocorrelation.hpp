#pragma once
// Internal to src/pem: the sample autocovariance pooled over experiments, shared
// by the Yule-Walker-type AR methods (arx.cpp) and the residual whiteness test
// (residual_whiteness.cpp).
#include <Eigen/Dense>

#include <vector>

namespace sysid::detail {

/// Biased sample autocovariance r(0..max_lag) pooled over experiments: each lag's
/// products summed inside every series, divided by the total samples. The
/// series are taken as given (the caller removes their mean).
inline Eigen::VectorXd pooled_autocorrelation(const std::vector<Eigen::VectorXd>& series, Eigen::Index max_lag) {
  Eigen::VectorXd acf = Eigen::VectorXd::Zero(max_lag + 1);
  double count = 0;
  for (const auto& x : series) {
    for (Eigen::Index k = 0; k <= max_lag && k < x.size(); ++k) acf(k) += x.head(x.size() - k).dot(x.tail(x.size() - k));
    count += static_cast<double>(x.size());
  }
  return acf / count;
}

}  // namespace sysid::detail
