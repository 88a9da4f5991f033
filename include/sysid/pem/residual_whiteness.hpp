#pragma once
/// @file
/// Purpose: is the one-step prediction error of a time-series model (AR, ARMA)
/// white on the record it was fitted to? A least-squares (or Yule-Walker, or
/// Burg) AR model of a record that carries measurement noise is not: y = x + v
/// with x an AR(p) process and v white is an ARMA(p, p) process (Stoica & Moses,
/// Spectral Analysis of Signals, 2005, sec. 3.7), whose innovations a finite AR
/// cannot reach when the noise sits near the poles' innovation level; the poles
/// then come out biased (resonances too lightly damped, weak modes lost). The
/// residual's remaining correlation is what shows it (and an order too low
/// shows the same way), so the polynomial fits test it and say so.
///
/// Method: e = (A(q) / C(q)) (y - offset) per experiment, the first samples
/// (the start-up of 1/C) dropped; the normalised autocorrelation pooled over
/// experiments (each lag's products summed inside every record, divided by the
/// total samples); the Ljung-Box test (core/ljung_box.hpp) over h lags with
/// na + nc fitted parameters.
#include <sysid/core/io_data.hpp>
#include <sysid/core/ljung_box.hpp>
#include <sysid/pem/polynomial_model.hpp>

#include <optional>

namespace sysid {

/// Lags the test uses when none are given: 4 (na + nc), at least 50 (lightly
/// damped modes keep the residual's correlation for many samples), at most a
/// fifth of the samples the test sees.
Eigen::Index default_whiteness_lags(const PolynomialModel& model, Eigen::Index samples);

/// The test on output `output` of `data` (channel means `output_offset` removed).
/// `lags` 0 = default_whiteness_lags. Empty when the records hold too few
/// samples after their start-ups to test (at most 5 lags, or lags <= na + nc).
/// Precondition: a model without inputs (std::invalid_argument).
std::optional<LjungBoxTest> one_step_residual_whiteness(const PolynomialModel& model, const IoData& data, Eigen::Index output,
                                         double output_offset, Eigen::Index lags = 0);

}  // namespace sysid
