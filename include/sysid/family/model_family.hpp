#pragma once
/// @file
/// Purpose: from one identified model per operating condition to what a robust
/// controller design needs (the Par2 workflow): the modes followed across the
/// members with their spread, a nominal model, the uncertainty bound over the band
/// and a low-order weight that covers it.
///
/// Method (each step in its own header):
///  1. The band: as given, else the band every member's log excites (the
///     intersection of their excited bands, family/estimation_error.hpp).
///  2. Modes in the band followed across the members (family/mode_tracking.hpp).
///  3. The grid over the band, denser at the members' resonances, the members'
///     responses and standard deviations on it, the nominal and the bound
///     (family/uncertainty_bound.hpp).
///  4. The weight W fitted over the bound (family/uncertainty_weight.hpp): stable,
///     minimum-phase, |W| >= bound at every grid frequency.
///
/// Preconditions (std::invalid_argument): at least one member; all members
/// discrete with the same Ts, inputs and outputs. With one member there is no
/// spread: no bound or weight (a warning says so).
#include <sysid/core/state_space.hpp>
#include <sysid/family/estimation_error.hpp>
#include <sysid/family/mode_tracking.hpp>
#include <sysid/family/uncertainty_bound.hpp>
#include <sysid/family/uncertainty_weight.hpp>

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sysid {

/// One member as the family sees it: its model and, when its log was at hand, the
/// standard deviation of its response (empty error: no allowance for it).
struct FamilyMemberModel {
  StateSpace model;
  FrequencyResponseError error;
};

struct ModelFamilyOptions {
  std::optional<std::pair<double, double>> band_hz;  ///< default: the band every member's log excites
  UncertaintyBoundOptions bound;                     ///< form, allowance, nominal
  int weight_order = 4;                              ///< poles of W (1..6)
  int grid_points = 200;                             ///< logarithmic base grid (resonance points added)
  double max_mode_damping = 0.3;                     ///< modes more damped than this are not followed
  ModeTrackingOptions tracking;
};

struct ModelFamilyResult {
  double band_lo_hz = 0.0, band_hi_hz = 0.0;
  std::string band_source;  ///< "as given" or how it was found
  ModeTrackingResult modes;
  Eigen::VectorXd frequency_hz;
  std::optional<UncertaintyBound> bound;    ///< absent with one member
  std::optional<UncertaintyWeightResult> weight;
  std::vector<std::string> warnings;
};

/// Purpose: the model a family compares for one member: the model itself, or for
/// a time series (no inputs: a disturbance record's AR, ARMA or n4sid model) its
/// unit-noise innovation form (core/assemble.hpp disturbance_input_model), the
/// spectral factor whose deviations are the disturbance's uncertainty.
/// Preconditions (std::invalid_argument): a time series carries K and the
/// innovation covariance.
StateSpace family_member_model(const StateSpace& model, const Eigen::MatrixXd& K, const Eigen::MatrixXd& noise_covariance);

/// Purpose: the family's modes, nominal, bound and weight (file comment).
ModelFamilyResult analyse_model_family(const std::vector<FamilyMemberModel>& members, const ModelFamilyOptions& options = {});

}  // namespace sysid
