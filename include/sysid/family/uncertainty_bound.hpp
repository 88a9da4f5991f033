#pragma once
/// @file
/// Purpose: how far the members of a model family are from a nominal model, as the
/// frequency-wise bound an H-infinity or mu design takes (Skogestad and
/// Postlethwaite, Multivariable Feedback Control, 2nd ed., sec. 7.4, 8.2), and which
/// member to take as that nominal.
///
/// Method:
///  - Deviation of member P from the nominal P0 at one frequency (DESIGN.md "Model
///    families"): multiplicative output sigma_max((P - P0) P0^+), multiplicative
///    input sigma_max(P0^+ (P - P0)), additive sigma_max(P - P0); P0^+ the
///    Moore-Penrose inverse (SVD; singular values below 1e-12 sigma_max dropped).
///  - Allowance for estimation error: the members are estimates, so the bound adds,
///    per member, coverage * sqrt(s_P^2 + s_P0^2) * g, with s the standard deviation
///    of each model's sigma_max (family/estimation_error.hpp) and g = sigma_max(P0^+)
///    for the multiplicative forms, 1 for additive. coverage = sqrt(-ln 0.01) = 2.15:
///    the 99 % point of the modulus of a circular complex Gaussian error.
///  - Bound = the largest over the members of deviation + allowance.
///  - Nominal (default criterion): the member whose bound, with every member taken
///    in turn as the nominal, has the smallest peak over the grid.
///  - Grid (family_frequency_grid): `points` logarithmically spaced over the band
///    (from band_hi / 1000 when the band starts at 0), plus 13 points across each
///    member's resonance f (1 + k zeta / 2), k = -6..6, where the deviation changes
///    fastest; a resonance point within zeta / 4 (relative) of the point before it
///    is dropped, so members with nearly the same resonance add it once.
///  - Cost: choosing the nominal evaluates every member against every candidate,
///    O(N^2 K) deviations for N members and K frequencies (single-input
///    single-output: a division each), the candidates on the cores.
#include <sysid/family/mode_tracking.hpp>

#include <Eigen/Dense>
#include <optional>
#include <string>
#include <vector>

namespace sysid {

enum class UncertaintyForm { multiplicative_output, multiplicative_input, additive };

/// "multiplicative-output", "multiplicative-input", "additive".
const char* to_string(UncertaintyForm form);
/// Inverse of to_string; std::invalid_argument naming the choices otherwise.
UncertaintyForm uncertainty_form_from_name(const std::string& name);

/// Purpose: the frequency grid of a family's bound (file comment), increasing, unique.
Eigen::VectorXd family_frequency_grid(double band_lo_hz, double band_hi_hz,
                                      const std::vector<std::vector<ModeEstimate>>& member_modes, int points = 200);

/// Deviation of P from P0 in the given form (file comment).
double deviation_from_nominal(const Eigen::MatrixXcd& P, const Eigen::MatrixXcd& P0, UncertaintyForm form);

struct UncertaintyBoundOptions {
  UncertaintyForm form = UncertaintyForm::multiplicative_output;
  double coverage = 2.15;             ///< allowance in standard deviations (99 % for a circular Gaussian error)
  std::optional<int> nominal_member;  ///< fixed nominal; default: the smallest peak bound
};

struct UncertaintyBound {
  int nominal_member = 0;
  std::string criterion;            ///< how the nominal was chosen, in words
  Eigen::VectorXd bound;            ///< per grid frequency: max over members of deviation + allowance
  Eigen::VectorXd spread;           ///< per grid frequency: max over members of the deviation alone
  Eigen::VectorXd peak_by_nominal;  ///< per member: the bound's peak were it the nominal
  bool with_allowance = false;      ///< the members carried standard deviations
};

/// Purpose: the bound and the nominal. `frf[i][k]` is member i's response at grid
/// frequency k; `standard_deviation[i]` its standard deviation on the grid (or
/// empty: no allowance for that member).
/// Preconditions (std::invalid_argument): at least one member, equal grid sizes
/// and channel counts; nominal_member in range.
UncertaintyBound uncertainty_bound(const std::vector<std::vector<Eigen::MatrixXcd>>& frf,
                                   const std::vector<Eigen::VectorXd>& standard_deviation,
                                   const UncertaintyBoundOptions& options = {});

}  // namespace sysid
