#pragma once
/// @file
/// Purpose: Hankel singular values (HSV) of a model, sigma_i = sqrt(lambda_i(Wc Wo)),
/// which measure how much each state of a balanced realisation contributes to the
/// input-output behaviour; for a model with unstable poles, the HSV of its stable
/// part and the number of unstable states (which no reduction may remove).
///
/// Method:
///  1. A power-of-two diagonal similarity balances A (Parlett & Reinsch 1969,
///     detail::balance_in_place): exact, and it keeps the Schur form of
///     companion-form realisations (polynomial models) accurate.
///  2. Stable/unstable split (stable_unstable_split): complex Schur form A = U T U^H
///     (gramians.hpp) reordered by adjacent unitary swaps of diagonal entries
///     (the complex analogue of LAPACK ZTREXC / the ordered real Schur form of
///     SLICOT TB01KD) so the k stable poles come first. The stable invariant
///     subspace span(U1) is closed under conjugation, so [Re U1, Im U1] has rank
///     exactly k (its nonzero singular values are all 1); a column-pivoted QR of it
///     gives a real orthogonal Q = [Qs Qu] with A~ = Q^T A Q = [A11 A12; 0 A22].
///     The Sylvester equation A11 X - X A22 + A12 = 0 (solved on the triangular
///     factors T11, T22 already at hand, Bartels & Stewart 1972) decouples the two:
///     with S = [I X; 0 I], S^-1 A~ S = diag(A11, A22), so
///       G = (A11, B1 - X B2, C1, D) + (A22, B2, C1 X + C2, 0) = G_s + G_u.
///     A pole counts as unstable when |z| >= 1 - tol (discrete) or when its damping
///     ratio -Re(s)/|s| <= tol (continuous; s = 0 included): marginal poles make the
///     Gramians infinite.
///  3. HSV of G_s: Gramian factors Lc, Lo (Hammarling, gramians.hpp), then the
///     singular values of Lo^T Lc (square-root method: Laub, Heath, Paige & Ward,
///     IEEE TAC 32(2):115-122, 1987), which avoids forming Wc Wo.
///
/// Preconditions: a valid StateSpace; tol in [0, 1).
/// Numerical aspects: O(n^3). HSV have absolute accuracy ~ n eps sigma_1 (more
/// for badly conditioned Gramian factors). The decoupling is ill conditioned when
/// stable and unstable poles are close (||X|| large): reported in the warnings.
#include <sysid/core/errors.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/reduce/gramians.hpp>

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace sysid {

/// G = stable + unstable, with D carried by the stable part.
struct StabilitySplit {
  StateSpace stable;
  StateSpace unstable;  ///< D = 0; order 0 when the model is stable
  double decoupling_norm = 0.0;  ///< ||X||_F of the Sylvester solution (large: poorly separated)
};

struct HankelSingularValuesOptions {
  /// A pole is unstable when |z| >= 1 - stability_tolerance (discrete) or its damping
  /// ratio is <= stability_tolerance (continuous).
  double stability_tolerance = 1e-8;
};

struct HankelSingularValuesResult {
  Eigen::VectorXd values;            ///< HSV of the stable part, descending
  Eigen::Index unstable_states = 0;  ///< states of the unstable (incl. marginal) part
  std::vector<std::string> warnings;
};

/// Purpose: additive decomposition G = G_s + G_u into a strictly stable part and an
/// unstable (incl. marginal) part; see the file comment, step 2.
/// Preconditions: a valid StateSpace; 0 <= tol < 1.
/// Throws NumericalError if the Schur iteration fails or the reordered Schur form
/// does not give an invariant subspace (rounding-level check).
StabilitySplit stable_unstable_split(const StateSpace& sys, double tol = 1e-8);

/// Purpose: Hankel singular values of the stable part of a model, and the number of
/// unstable states (see the file comment).
/// Preconditions: a valid StateSpace; 0 <= options.stability_tolerance < 1.
/// Example: `auto h = hankel_singular_values(model); // h.values(0) >= h.values(1) ...`
HankelSingularValuesResult hankel_singular_values(const StateSpace& sys,
                                                  const HankelSingularValuesOptions& options = {});

}  // namespace sysid
