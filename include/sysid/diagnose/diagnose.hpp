#pragma once
/// @file
/// Purpose: `sysid diagnose` as a library call — locate where a nominal
/// simulation model and a recording disagree, name the physics the simulation
/// left out, fit it, and prove the fit improves on samples held out from every
/// fit (issue 6; report contract in DESIGN.md "diagnose: the report contract").
///
/// Method. The record is cut in three, in time order:
///   [0, fit)          detection and parameter fitting (first 50 % by default),
///   [fit, estimation) selection: ranks and accepts candidates (next 20 %),
///   [estimation, N)   validation: fit_before / fit_after only (last 30 %).
///  1. Locate: the nominal's simulation residual on the estimation part goes
///     through locate_mismatch (model-error FRF bands, incoherent residual peaks,
///     windows, amplitude / reversal / position dependence).
///  2. Name: propose_candidates scores every kind of physics on the residual.
///  3. Model: the best-scoring candidates are fitted (fit_candidates: DIRECT-L then
///     BOBYQA) on [0, fit); each is judged on the selection segment by a paired
///     test on the squared simulation errors before and after it: the reduction
///     of the sum of squares, standardised by its spread under "the change only
///     fits noise" (computed from the noise autocovariance, so coloured residuals
///     are accounted for; see improvement_z in diagnose.cpp), must exceed the
///     Bonferroni-corrected normal quantile for the number of candidates tried
///     (in the spirit of Diebold and Mariano, J. Bus. Econ. Stat. 13 (1995)). Among the significant
///     ones the largest selection gain, penalised per parameter, is accepted; all
///     accepted blocks are refitted together and the next round starts from the
///     augmented model's residual, until no candidate passes.
///  4. Prove: the accepted blocks are refitted (locally) on [0, estimation) and
///     fit_before / fit_after are measured on the validation segment, per finding
///     in the order found.
/// A correct nominal model yields no findings unless a test fires by chance
/// (probability about `significance` per round).
///
/// Confirmation mode (diagnose_confirmed, `sysid diagnose --validate FILE
/// --confirm`), for a short record whose effect shows in few episodes (the
/// cascaded tanks overflow twice in 1 024 samples: cut in three, no segment
/// holds enough of it). A second, independent recording takes the place of the
/// selection and validation segments:
///  - every candidate is fitted on the whole log and ranked there by its
///    in-sample gain, penalised per parameter;
///  - only the best-ranked one is tested, once, on the independent recording
///    (the same paired test, each model simulated from the initial state that
///    best explains the recording's start), at the full `significance`;
///  - the first candidate that fails ends the search. Because the order comes
///    from the log alone, the rounds are a fixed-sequence procedure: the chance
///    of any false finding stays below `significance` with no Bonferroni
///    division (Westfall and Krishen, J. Stat. Plan. Inference 99 (2001)).
/// The recording is never fitted: fit_before / fit_after are measured on it,
/// with the very models it confirmed (no refit after acceptance). The only
/// numbers taken from it are each model's initial state (n per model, by
/// estimate_initial_state), since it starts wherever the machine was.
/// Calibration: the test's noise autocovariance is Bartlett-tapered (see
/// improvement_z), which underestimates the long-run variance of very
/// persistent noise; with noise correlated over 1/15 of the recording, 2 % of
/// null runs gave a finding at the 1 % level, as in the three-part mode (README).
#include <Eigen/Dense>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sysid/diagnose/augmented_model.hpp"
#include "sysid/diagnose/candidate_fit.hpp"
#include "sysid/diagnose/feedback_check.hpp"
#include "sysid/diagnose/hypotheses.hpp"
#include "sysid/diagnose/linear_core_refit.hpp"
#include "sysid/diagnose/mismatch_location.hpp"

namespace sysid {

struct DiagnoseOptions {
  double fit_fraction = 0.5;         ///< first part: detection and fitting
  double selection_fraction = 0.2;   ///< next part: ranking and acceptance; the rest validates
  int max_findings = 4;              ///< rounds of add-the-best
  int candidates_per_round = 16;     ///< fit this many best-scoring candidates per round (16: every SISO kind)
  double significance = 0.01;        ///< per round, shared by the candidates tried (Bonferroni)
  Eigen::Index max_correlation_lag = 500;  ///< lags of the noise autocovariance in the acceptance test
  double min_gain_points = 0.05;     ///< minimum penalised gain on the selection segment, fit points
  double penalty_points_per_parameter = 0.02;  ///< penalty per free parameter, fit points
  /// Fewest samples in each of the three segments. 200 keeps the acceptance test
  /// and the held-out fit meaningful for most records; a short record whose
  /// effect shows in few episodes (the cascaded tanks overflow twice in 1 024
  /// samples) may need smaller segments to have an episode in fit and selection.
  Eigen::Index min_segment_samples = 200;
  /// Refit the nominal's linear dynamics together with the blocks
  /// (linear_core_refit.hpp) — for a nominal identified from the same machine,
  /// whose poles and gains hold a compromise of the nonlinearity the blocks
  /// model. Every candidate is then fitted with the core and judged against the
  /// core refitted alone on the same fit segment; an accepted one brings its
  /// core along. Off by default: a simulation model from first principles is
  /// what the diagnosis tests, not something to tune.
  bool refit_nominal = false;
  LinearCoreRefitOptions refit;
  DetectionOptions detection;
  CandidateFitOptions fit;
  MismatchLocationOptions location;
};

/// What refit_nominal did.
struct NominalRefit {
  bool attempted = false;  ///< refit_nominal was on
  bool applied = false;    ///< an accepted finding brought a refitted core (then in `augmented`)
  Eigen::VectorXcd poles_before, poles_after;  ///< discrete poles of the nominal and of the final core
};

/// A candidate after fitting, with its judgement on the selection segment.
struct JudgedCandidate {
  Candidate candidate;         ///< fitted parameters
  /// Fit points gained on the selection segment (mean over outputs); in
  /// confirmation mode, on the whole log (in-sample: the ranking).
  double selection_gain = 0;
  /// Standardised held-out SSE reduction (z): on the selection segment, or in
  /// confirmation mode on the independent recording (only the best-ranked
  /// candidate of a round is tested there; the others' values are for reading).
  double t_statistic = 0;
  double t_threshold = 0;      ///< what it had to exceed
  /// Standard errors of its free parameters on the rows it was fitted on
  /// (parameter_uncertainty.hpp), and whether a defining parameter differs from
  /// its null value by more than two of them (DESIGN.md: otherwise the finding
  /// may not be reported under its kind's name); `parameter_evidence` in words.
  std::map<std::string, double> standard_errors;
  bool parameters_significant = true;
  std::string parameter_evidence;
  bool significant = false;
  int round = 0;
};

struct Finding {
  Candidate candidate;  ///< the block with its final parameters, the detector's evidence
  double fit_before = 0, fit_after = 0;  ///< validation fit (mean over outputs, %) without / with it
  double selection_gain = 0, t_statistic = 0;
  std::optional<std::pair<double, double>> band_hz;          ///< where in frequency, when it has a place there
  std::vector<std::pair<double, double>> time_windows_s;     ///< flagged residual windows it explains, if any
  std::string summary;  ///< one sentence in plain engineering words
  /// Standard error of each reported parameter (DESIGN.md "uncertainty"), from
  /// the final fit; `parameter_evidence` says how far its defining parameter is
  /// from its null value in standard errors.
  std::map<std::string, double> uncertainty;
  std::string parameter_evidence;
  /// Why this kind and not another: the best other kind of its round and its
  /// selection gain, and, for kinds another can mimic (friction, a dead zone),
  /// where in time the residual it explains lives.
  std::string alternative, where;
};

struct DiagnoseReport {
  double fit_before = 0, fit_after = 0;           ///< validation fit, mean over outputs (%)
  Eigen::VectorXd fit_before_per_output, fit_after_per_output;
  std::string validation;                          ///< e.g. "last 30 % of samples (6000 of 20000)"
  Eigen::Index fit_rows = 0, estimation_rows = 0;  ///< the segment boundaries used
  std::vector<Finding> findings;                   ///< ranked, most important first; empty = no significant mismatch
  std::vector<JudgedCandidate> considered;         ///< every candidate fitted, all rounds
  MismatchLocation location;                       ///< the nominal's mismatch on the estimation part
  /// Whether the inputs react to the outputs' noise on the estimation part (a
  /// closed loop: the logged input is a controller's output). The nominal is
  /// still simulated open-loop from the logged input, which stays valid; the
  /// report says so (a warning), because the noise fed back into the input
  /// correlates with it and can bias the fitted parameters of small effects.
  OutputFeedbackCheck closed_loop;
  NominalRefit nominal_refit;                      ///< refit_nominal's outcome (not attempted by default)
  AugmentedModel augmented;                        ///< the nominal (refitted, if nominal_refit.applied) with the findings' blocks
  Eigen::MatrixXd simulated_before, simulated_after;  ///< whole record, raw coordinates (for plots)
  /// How the plant's forces read each output: the nominal's quantities, or where
  /// it had none, the reading an accepted force was found under (unknown when
  /// none was); the augmented model carries them.
  std::vector<OutputQuantity> output_quantities;
  std::string reading_note;  ///< which reading was used and why, when a quantity was not given
  std::vector<std::string> warnings;
};

/// Runs the whole loop. `nominal` carries the nominal state-space model (its
/// blocks, if any, are kept as accepted), u and y are the raw log (N x m, N x l),
/// in the nominal's channel order.
/// Preconditions (std::invalid_argument): sizes agree with the nominal, values
/// finite, fractions in (0, 1) with fit + selection < 1, at least
/// min_segment_samples (>= 50) samples in every segment.
DiagnoseReport diagnose(const AugmentedModel& nominal, const Eigen::Ref<const Eigen::MatrixXd>& u,
                        const Eigen::Ref<const Eigen::MatrixXd>& y, const DiagnoseOptions& options = {});

/// Confirmation mode (see the file comment): fits on the whole log (u, y), tests
/// each round's best-ranked candidate once on the independent recording
/// (u_confirm, y_confirm: raw, the same channels and sample time), and reports
/// fit_before / fit_after on that recording. fit_fraction and
/// selection_fraction are not used.
/// Preconditions (std::invalid_argument): as diagnose(), with at least
/// min_segment_samples samples in the log and in the recording, finite values.
DiagnoseReport diagnose_confirmed(const AugmentedModel& nominal, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                  const Eigen::Ref<const Eigen::MatrixXd>& y, const Eigen::Ref<const Eigen::MatrixXd>& u_confirm,
                                  const Eigen::Ref<const Eigen::MatrixXd>& y_confirm, const DiagnoseOptions& options = {});

/// The nominal's and the augmented model's fit on an independent recording (the
/// `--validate` file): per output, %, each model simulated from its own initial
/// state. The recording starts wherever the machine was, so a zero initial state
/// would charge both models a start-up transient that lasts the nominal's settling
/// time (seconds for a lightly damped structure). x0 comes from linear least
/// squares on the nominal's free response C A^t x0 fitted to the model's
/// zero-state residual (estimate_initial_state, validate/compare.hpp): exact for
/// the linear model and for blocks at the input or the sensor, a best linear
/// estimate when a block feeds a force back inside the plant.
struct RecordingValidation {
  Eigen::VectorXd fit_before, fit_after;  ///< per output (%)
  Eigen::VectorXd x0_before, x0_after;    ///< the initial states used
};

/// Preconditions (std::invalid_argument): `augmented` has the nominal's channels and
/// sample time (its linear core may be refitted); u N x m and y N x l match it, N >= 1.
RecordingValidation validate_on_recording(const AugmentedModel& nominal, const AugmentedModel& augmented,
                                          const Eigen::Ref<const Eigen::MatrixXd>& u, const Eigen::Ref<const Eigen::MatrixXd>& y);

/// A sentence describing a fitted block, e.g. "The recordings contain a lightly
/// damped mode at 31.6 Hz (damping 0.012) that the simulation lacks." `ts` is
/// the nominal's sample time (a store's pole is told as a time constant).
std::string finding_summary(const PhysicsBlock& block, const std::vector<std::string>& input_names,
                            const std::vector<std::string>& output_names, double ts);

}  // namespace sysid
