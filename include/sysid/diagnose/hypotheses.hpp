#pragma once
/// @file
/// Purpose: the detectors of `sysid diagnose` (issue 6, scope 2): for every kind
/// of physics (physics_kind.hpp; each kind's detector is in its own file,
/// src/diagnose/kinds/<kind>.cpp), a detector that scores how much of the
/// current simulation residual the effect could explain and proposes start values
/// and bounds for the fit.
///
/// Method: most effects vanish at a known parameter value p0 (zero friction, zero
/// delay, unit gain); near p0 the augmented output is linear in p - p0, so the
/// sensitivity g = (sim(p0 + delta) - sim(p0)) / delta, computed by simulation,
/// is the effect's signature. Least squares of the residual r on g gives the start
/// p0 + <g, r>/<g, g> and the score <g, r>^2 / (<g, g> <r, r>): the fraction of
/// the residual energy the linearised effect explains (a Gauss-Newton step from
/// the nominal model, Ljung, System Identification, 2nd ed., sec. 10.2). Effects
/// that are not smooth at p0 (saturation, hysteresis) or that have a frequency
/// to find (missing mode, periodic disturbance) are scored on a small grid of
/// their nonlinear parameters, the frequencies taken from the mismatch location
/// (model-error bands and residual peaks).
/// Outputs are weighted by 1/std(y_i) so channels count alike.
/// Channels: sensor kinds on every output; actuator kinds on every input (seen
/// at output j, or the only output); the plant's forces collocated (input j acts
/// where output j is measured, or on the only output), once per reading of the
/// outputs when diagnose tries several (an output's quantity unknown); modal
/// terms on every path of a single input or onto a single output, collocated
/// paths otherwise (bounding the candidates of square MIMO); couplings from
/// input j to every other output i.
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "sysid/diagnose/augmented_model.hpp"
#include "sysid/diagnose/candidate_fit.hpp"

namespace sysid {

struct DetectionOptions {
  /// Simulation steps per sample for forces inside the plant; 0 = automatic:
  /// 4 for a nominal without direct feedthrough (D = 0: a sampled physical plant,
  /// whose force is better resolved within the sample), 1 when D != 0 (an
  /// identified discrete model: the force sequence goes through the model like
  /// the input sequence, with the feedthrough solved implicitly — on Silverbox
  /// this gives a test RMSE of 0.45 mV against 3.9 mV with 4 substeps).
  int feedback_substeps = 0;
  double friction_velocity_fraction = 0.005;  ///< friction's tanh velocity scale, as a fraction of the velocity RMS
  double max_delay_samples = 8.0;   ///< upper bound of time_delay
};

/// What the detectors look at. Rows [0, rows) of u, y (deviation coordinates) are
/// the detection and fitting data; `current` is the present model's simulation on them.
struct DetectionData {
  const AugmentedSimulator* simulator = nullptr;  ///< substeps >= feedback_substeps when the plant has feedback candidates
  /// Simulators differing only in how they read the outputs (their output
  /// quantities), one per reading to try for the plant's forces that read the
  /// motion; empty: `simulator`'s reading only. Candidates proposed under a
  /// reading carry its quantities (Candidate::output_quantities).
  std::vector<const AugmentedSimulator*> plant_readings;
  /// The nominal carries the operating point it was identified at (a non-zero
  /// input_offset: an identified model whose means were removed). A constant
  /// force is then indistinguishable from a shift of that operating point
  /// between records, and is not proposed.
  bool identified_operating_point = false;
  std::vector<PhysicsBlock> accepted;             ///< blocks already in the model
  Eigen::MatrixXd u, y;                           ///< rows x m, rows x l
  Eigen::MatrixXd current;                        ///< rows x l
  double Ts = 0.0;
  std::vector<double> mode_frequencies_hz;        ///< where the model-error FRF is significant (peaks of falsified bands)
  std::vector<double> peak_frequencies_hz;        ///< residual peaks not coherent with any input
  double frequency_resolution_hz = 0.0;           ///< bin width of the spectra the frequencies came from
};

/// One candidate per kind and channel (and per frequency for modes and
/// periodic disturbances), sorted by detector_score, highest first.
/// Kinds that do not apply (cross_coupling on a SISO model) are not proposed.
std::vector<Candidate> propose_candidates(const DetectionData& data, const DetectionOptions& options = {});

}  // namespace sysid
