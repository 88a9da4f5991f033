#pragma once
// Internal to src/pem: the initial values of the iterations (src/pem/pem_starts.cpp):
// least-squares ARX, Hannan-Rissanen, the output-error start with
// Steiglitz-McBride passes, and the ARMAX starts from an OE fit and from a
// subspace model (method in include/sysid/pem/prediction_error.hpp).
#include <sysid/pem/lagged_regression.hpp>
#include <sysid/pem/polynomial_model.hpp>
#include <sysid/pem/prediction_error.hpp>

#include <Eigen/Dense>

#include <string>
#include <vector>

#include "pem/detail/pem_jacobian.hpp"

namespace sysid::detail::pem_impl {

/// ARX of the given orders on the scaled records (target y, inputs u), with optional extra noise regressors.
RegressionSolution arx_regression(const std::vector<ScaledRecord>& records, int na, const std::vector<int>& nb,
                                  const std::vector<int>& nk, const std::vector<Eigen::VectorXd>* noise, int nc);

/// Hannan-Rissanen start of ARMA/ARMAX (scaled units).
void hannan_rissanen(PolynomialModel& model, const std::vector<ScaledRecord>& records, int high_order);

/// Order of the high-order ARX in the Hannan-Rissanen start (PemOptions::initial_arx_order).
int hannan_rissanen_order(const PemOptions& options, double total);

/// OE start: ARX for F and B, then Steiglitz-McBride passes (scaled units).
void output_error_start(PolynomialModel& model, const std::vector<ScaledRecord>& records, int passes,
                        std::vector<std::string>& warnings);

/// ARMAX start from an output-error fit (scaled units): B and F of
/// OE(nb, nf = min(na, nc)) fitted by PEM, A = C = F zero-padded to na and nc.
/// The ARMAX predictor then is the OE one (white measurement noise,
/// y = B/F u + e), the start of highest likelihood when the noise is white
/// at the output. For lightly damped
/// plants sampled fast this starts next to the optimum where the
/// Hannan-Rissanen start stalls: its high-order ARX cannot whiten a noise
/// model with roots next to the unit circle. Returns false when the OE fit fails.
bool armax_output_error_start(PolynomialModel& model, const std::vector<ScaledRecord>& records, const PemOptions& options);

/// ARMAX start from a subspace model (scaled units): MOESP-weighted n4sid on
/// the records (order chosen by its SVC rule, at most min(na, 20)), then the polynomials of its
/// innovation form x+ = A x + B u + K e, y = C x + D u + e (single output):
///   A(q) = det(zI - A),   C(q) = det(zI - A + K C)   (A(q) when K is not available:
///   the output-error predictor), and per input, since for one output
///   det(zI - A + B_i C) = det(zI - A) (1 + C (zI - A)^-1 B_i),
///   N_i(q) = det(zI - A + B_i C) + (D_i - 1) det(zI - A),
/// B_i = N_i from lag nk_i. Each is cut or zero-padded to the model's orders and
/// C reflected into the unit circle. A subspace fit is consistent whatever the
/// noise colour, so it starts next to the optimum where the Hannan-Rissanen
/// start does not (lightly damped plants with white output noise), at the cost
/// of one n4sid. Returns false when n4sid fails.
bool armax_subspace_start(PolynomialModel& model, const std::vector<ScaledRecord>& records, const PemOptions& options);

}  // namespace sysid::detail::pem_impl
