#pragma once
/// @file
/// Purpose: how many parameters of a linear model an input can determine — its
/// order of persistent excitation — so that an identification that asks for more
/// says so instead of returning a model shaped by noise and regularisation.
///
/// Method: an input is persistently exciting of order n when the n x n covariance
/// matrix of (u(t-1) .. u(t-n)) is non-singular (L. Ljung, "System Identification",
/// 2nd ed., def. 13.2). The singular values of the mean-removed data Hankel matrix
/// with n columns (rows from every experiment stacked) are scanned for the first
/// "cliff": a value below
/// `tolerance` times the largest and 40 dB below its predecessor. The order is the
/// count before the cliff: a single sine gives 2, a sum of k sines 2k, white noise
/// every n. A band-limited continuous spectrum (a chirp over part of the band,
/// filtered noise) has smoothly decaying singular values — an ill-conditioned but
/// exciting input — and counts as n.
///
/// Numerical aspects: the singular values are the square roots of the
/// eigenvalues of the Hankel matrix's Gram matrix, accumulated from correlation
/// sums (core/detail/lagged_sums.hpp) in O(N n) rather than by a QR in O(N n^2):
/// inside n4sid on the Par2 log this check took a fifth of the time. These are
/// normal equations, acceptable here because only the decision matters: rounding
/// leaves a floor of about 3 sqrt(n eps) (1e-7 to 7e-7 for n = 10..256) under
/// the relative singular values, four decades below `tolerance`. A cliff is
/// looked for only from values 100 times above that floor (1e-5 to 7e-5): an
/// input whose last excited direction is weaker than that counts as exciting
/// there (the test against a direct SVD is in
/// tests/unit/core_persistent_excitation.cpp).
///
/// What each model needs (Söderström & Stoica, "System Identification", 1989,
/// sec. 5.4 and complement C5.1; Ljung thm. 13.1): ARX(na, nb) and FIR-like
/// structures na + nb; OE / ARMAX / Box-Jenkins the numerator plus denominator
/// orders; a state-space model of order n (subspace methods, ERA from OKID) 2n; an
/// FIR of L taps (LMS) L.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "sysid/core/io_data.hpp"

namespace sysid {

struct ExcitationOrderOptions {
  Eigen::Index max_order = 60;       ///< Hankel columns: the largest order tested
  double tolerance = 1e-3;           ///< singular values below this times the largest count as zero (60 dB)
  Eigen::Index max_samples = 20000;  ///< Hankel rows used at most, over all experiments (from the start of each)
};

struct ExcitationOrder {
  /// Order of persistent excitation, capped at max_order (0: the input is constant).
  Eigen::Index order = 0;
  /// The Hankel singular values relative to the largest (empty for a constant input).
  Eigen::VectorXd singular_values;
};

/// Purpose: the order of persistent excitation of input `input` of `data` (file comment).
/// Preconditions (std::invalid_argument): 0 <= input < data.inputs(), max_order >= 1,
/// and at least max_order samples in some experiment (shorter experiments are skipped).
ExcitationOrder excitation_order(const IoData& data, Eigen::Index input, const ExcitationOrderOptions& options = {});

/// Purpose: one warning per input whose excitation order is below `required_order`,
/// naming the model (`model`, e.g. "ARX(8, 8)") and what the input supports. `who`
/// prefixes the message ("arx: ..."; empty: no prefix). Experiments shorter than the
/// required order are skipped; an input that is constant over all experiments is
/// left to the algorithms (they refuse it with their own error). Orders above 256
/// are not tested (cost O(samples n^2)): an input exciting 256 orders passes.
std::vector<std::string> insufficient_excitation_warnings(const IoData& data, Eigen::Index required_order,
                                                          const std::string& model, const std::string& who);

/// Purpose: refuse an input that is constant over all experiments (its range at
/// most 1e-12 of its magnitude, so the check does not depend on units): no model
/// of its effect can be identified, and a least-squares fit would return noise.
/// Errors: sysid::DataError "<who>: input 'u' is constant: it does not excite the system".
void require_varying_inputs(const IoData& data, const std::string& who);

}  // namespace sysid
