#pragma once
/// @file
/// Purpose: SISO transfer functions as polynomial ratios and in factored
/// zero-pole-gain form, and their conversion to and from state space.
///
///   G(z) = num(z) / den(z) = k prod(z - z_i) / prod(z - p_i)
///
/// with coefficients in descending powers of z (discrete, Ts > 0) or s
/// (continuous, Ts = 0).
///
/// References: K. Ogata, "Modern Control Engineering", observable canonical form;
/// A. Emami-Naeini, P. Van Dooren, Automatica 18(4), 1982 (zeros, see poles_zeros.hpp).
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <string>

namespace sysid {

/// A SISO transfer function num/den, coefficients in descending powers.
struct TransferFunction {
  Eigen::VectorXd num;  ///< b0 z^q + ... + bq
  Eigen::VectorXd den;  ///< a0 z^n + ... + an (a0 != 0; monic after normalisation)
  double Ts = 0;        ///< sample time in seconds; 0 means continuous (variable s)
};

/// Purpose: real polynomial with the given roots, leading coefficient 1,
/// coefficients in descending powers (size roots.size() + 1).
/// Preconditions: complex roots come in conjugate pairs (std::invalid_argument if
/// the product has an imaginary part above 1e-8 relative to the coefficient size).
/// Numerical aspects: O(r^2) complex multiplications; the imaginary parts of the
/// result cancel to rounding level and are dropped.
Eigen::VectorXd poly_from_roots(const Eigen::VectorXcd& roots);

/// Purpose: product of two polynomials (coefficient convolution); either order of
/// powers works as long as both use the same. Empty input gives an empty result.
Eigen::VectorXd poly_multiply(const Eigen::VectorXd& a, const Eigen::VectorXd& b);

/// Purpose: state-space realisation of a proper SISO transfer function, in
/// (shifted) observable canonical form:
///
///   A = sigma I + [0 ... 0 -c_n; 1 0 ... -c_{n-1}; ...; 0 ... 1 -c_1],
///   B = [d_n - c_n d_0; ...; d_1 - c_1 d_0],  C = [0 ... 0 1],  D = d_0,
///
/// where c and d are the coefficients of den(w + sigma) and num(w + sigma) in the
/// shifted variable w = x - sigma, after dividing by den's leading coefficient.
/// With sigma = 0 this is Ogata's observable canonical form; C (xI - A)^-1 B + D
/// = num(x)/den(x) for every sigma.
///
/// Method: for a discrete model sigma is the centroid of the poles, -a_1 / n
/// (so c_1 = 0); for a continuous model sigma = 0.
/// Why the shift: a sampled mechanical system has its poles clustered near z = 1,
/// and then the coefficients of den(z) are large alternating binomial-like sums
/// (up to ~C(n, n/2)) whose near-cancellation on the unit circle costs digits:
/// for the order-10 Par2 model a plain companion form gives an FRF only
/// ~1e-6 accurate near its 28.5 Hz resonance. In w = z - sigma the roots sit near
/// the origin, the coefficients are small and evaluating them on the unit circle
/// is well conditioned (measured error 3e-13 for the same model). The shifted
/// coefficients are computed in double-double arithmetic so the shift itself adds
/// no error beyond the final rounding.
/// Preconditions: den not all zero; deg num <= deg den (std::invalid_argument
/// otherwise); finite coefficients; Ts >= 0. Exact leading zeros are ignored.
/// Numerical aspects: O(n^2). A is upper Hessenberg, so frequency_response()
/// applies no reduction to it.
StateSpace to_state_space(const TransferFunction& tf);

/// Factored form G = gain * prod(x - zeros) / prod(x - poles), x = z or s.
struct ZeroPoleGain {
  Eigen::VectorXcd zeros, poles;
  double gain = 0.0;
  double Ts = 0.0;
};

/// Purpose: zeros, poles and gain of one channel (output <- input) of a model.
/// Method: poles = all eigenvalues of A (poles()); zeros = invariant zeros of the
/// channel realisation (channel_zeros' method), so that for any realisation
/// G(x) = gain prod(x - z_i) / prod(x - p_i) holds exactly (a mode the channel does
/// not see appears as both a zero and a pole). The gain is found by evaluating G
/// at x0 = R e^(j 1.1) with R = 2 max(1, |roots|), a point at distance >= R/2 from
/// every root, and dividing out the root factors (interleaved to avoid overflow).
/// An identically zero channel gives gain 0 and no zeros.
/// Preconditions: 0 <= output < l, 0 <= input < m.
ZeroPoleGain zero_pole_gain(const StateSpace& sys, Eigen::Index output = 0, Eigen::Index input = 0);

/// Purpose: ASCII factored form of a zero-pole-gain model, as in eqs. (5)-(6) of
/// the Par2 paper, e.g.
///   "-0.055 (z-1.003)(z-1.15)(z^2-1.993z+1.002)(z+1)^2 / [(z^2-1.985z+0.993)(z^2-1.561z+0.641)]"
/// Real roots print as (x-r), conjugate pairs as (x^2+ax+b), a root at 0 as x,
/// repeated factors as ^k; x is z for a discrete model (Ts > 0), s otherwise.
/// Factors are ordered by frequency (angle of the root for z, modulus for s).
/// Numbers have `digits` significant digits (digits >= 1).
std::string format_factored(const ZeroPoleGain& zpk, int digits = 4);

}  // namespace sysid
