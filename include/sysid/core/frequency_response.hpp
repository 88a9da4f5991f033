#pragma once
/// @file
/// Purpose: frequency response G(z) = C (zI - A)^-1 B + D of a state-space model,
/// with z = exp(j 2 pi f Ts) for a discrete model and s = j 2 pi f for a
/// continuous one (Ts = 0).
///
/// Method: Laub (1981): reduce A once to upper Hessenberg form H = Q^T A Q
/// (orthogonal Q, Householder), transform B~ = Q^T B and C~ = C Q, then for each
/// frequency solve the Hessenberg system (zI - H) X = B~ by Gaussian elimination
/// with partial pivoting between adjacent rows (the only candidates, as each
/// column has one subdiagonal entry), and form G = C~ X + D. The similarity leaves
/// G unchanged; each frequency costs O(n^2 m + l n m) instead of the O(n^3) of a
/// dense LU.
///
/// Preconditions: a valid StateSpace (validate()).
/// Numerical aspects: the reduction is backward stable; Gaussian elimination on a
/// Hessenberg matrix with adjacent-row pivoting has element growth at most n
/// (Wilkinson), so the result is the exact response of a model perturbed by
/// O(n eps ||A||). At a frequency that hits a pole exactly the response is not
/// finite (Inf/NaN entries), as the transfer function is.
///
/// References: A. J. Laub, "Efficient multivariable frequency response
/// computations", IEEE Trans. Automatic Control 26(2):407-408, 1981.
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <complex>
#include <vector>

namespace sysid {

/// Purpose: G(z) (l x m) at one complex point z (discrete) or s (continuous).
/// Method: dense complex LU of (zI - A), O(n^3); use frequency_response() for many
/// points.
/// Preconditions: a valid StateSpace. At a pole the result is not finite.
Eigen::MatrixXcd frequency_response_at(const StateSpace& sys, std::complex<double> z_or_s);

/// Purpose: frequency response at each frequency of freqs_hz (Hz), one l x m
/// complex matrix per frequency: z = exp(j 2 pi f Ts) if Ts > 0, s = j 2 pi f if
/// Ts = 0.
/// Method: Laub (1981) Hessenberg method, see the file comment.
/// Preconditions: a valid StateSpace; frequencies finite (any sign).
/// Numerical aspects: O(n^3) once plus O(n^2 m + l n m) per frequency.
/// Example: `auto G = frequency_response(model, Eigen::VectorXd::LinSpaced(500, 0, 1000));`
std::vector<Eigen::MatrixXcd> frequency_response(const StateSpace& sys, const Eigen::VectorXd& freqs_hz);

}  // namespace sysid
