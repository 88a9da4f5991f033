#pragma once
// Internal to src/pem: variable projection for ARMA/ARMAX (src/pem/variable_projection.cpp;
// G. H. Golub & V. Pereyra, SIAM J. Numer. Anal. 10 (1973) 413-432; method in
// include/sysid/pem/prediction_error.hpp).
#include <sysid/pem/polynomial_model.hpp>

#include <Eigen/Dense>

#include <vector>

#include "pem/detail/pem_jacobian.hpp"

namespace sysid::detail::pem_impl {

/// Whether eps is linear in the A and B coefficients once C is fixed (no D, no
/// F, a C to eliminate them under, and something to eliminate): ARMA, ARMAX.
bool separable(const PolynomialModel& m);

/// A and B minimising the prediction-error cost for the model's C (variable
/// projection, header): eps = A (y / C) - sum_i B_i (u_i / C) is linear in
/// them, so they solve the least-squares regression of y / C on its own past
/// and on the past of each u_i / C, every column filtered from rest as in the
/// cost. Its columns are shifted copies of those 1 + m signals, so R comes from
/// their double-double Gram matrix of lagged sums (shifted_columns_factor, as
/// the Jacobian's) and the coefficients from a
/// complete orthogonal decomposition of R (minimum norm where the regression is
/// rank deficient to working precision: near common factors).
/// The model is changed only when its cost falls (the minimum-norm solution of
/// the rank that can be resolved can lie above the model's cost by rounding),
/// and left as it is when a record is shorter than the lags or the Gram
/// matrix is refused. `by_c` receives the filtered signals and their lagged
/// sums (they depend on C only), and `eps` (the model's prediction errors) the
/// projected model's when it is kept. Returns the model's cost afterwards.
double project_linear_part(PolynomialModel& model, const std::vector<ScaledRecord>& records, double cost,
                           FilteredByC& by_c, std::vector<Eigen::VectorXd>& eps);

}  // namespace sysid::detail::pem_impl
