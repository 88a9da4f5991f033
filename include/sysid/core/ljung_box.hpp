#pragma once
/// @file
/// Purpose: the Ljung-Box portmanteau test of whiteness (G. M. Ljung & G. E. P.
/// Box, "On a measure of lack of fit in time series models", Biometrika 65
/// (1978) 297-303): Q = N (N + 2) sum_{k=1}^{h} r(k)^2 / (N - k) over the
/// normalised autocorrelation r of a residual; for the residual of a fitted
/// model with p noise-model parameters, Q ~ chi2(h - p) under whiteness.
/// One formula for every caller: residual analysis (validate/) and the noise
/// checks of the polynomial fits (pem/).
#include <Eigen/Dense>

namespace sysid {

struct LjungBoxTest {
  Eigen::Index samples = 0;       ///< N
  Eigen::Index lags = 0;          ///< h
  double statistic = 0;           ///< Q
  double degrees_of_freedom = 0;  ///< h - p
  double p_value = 1;             ///< P(chi2(h - p) > Q)
};

/// `autocorrelation`: r(0..>=h) normalised (r(0) = 1), from `samples` samples;
/// `lags` h >= 1; `fitted_parameters` p, 0 <= p < h. std::invalid_argument
/// otherwise (h beyond the vector or >= samples).
LjungBoxTest ljung_box_test(const Eigen::Ref<const Eigen::VectorXd>& autocorrelation, Eigen::Index samples, Eigen::Index lags,
                            Eigen::Index fitted_parameters);

}  // namespace sysid
