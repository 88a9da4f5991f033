#pragma once
// What the two procedures of `sysid diagnose` share (include/sysid/diagnose/
// diagnose.hpp): the three-part procedure (diagnose) and the confirmation
// procedure (diagnose_confirmed) run the same steps — locate, propose, fit and
// judge the candidates, accept one, prove — and differ in where a candidate's
// gain is scored, where it is tested, how the winner is chosen and where the
// fit is validated. The session holds the record, the linear core with its
// simulators, the accepted blocks and the report; the procedures in diagnose.cpp
// make the choices. Internal to src/diagnose.
#include <Eigen/Dense>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sysid/diagnose/diagnose.hpp"
#include "sysid/diagnose/parameter_uncertainty.hpp"

namespace sysid {

/// How many standard errors a defining parameter must be from its null value
/// for a finding to be named (DESIGN.md "diagnose": "within two standard errors
/// of zero" is not reported).
inline constexpr double kParameterZ = 2.0;

/// A recording in the nominal's deviation coordinates.
struct Recording {
  Eigen::MatrixXd u, y;
};

/// Raw (u, y) less the nominal's offsets.
Recording deviation_recording(const AugmentedModel& model, const Eigen::Ref<const Eigen::MatrixXd>& u,
                              const Eigen::Ref<const Eigen::MatrixXd>& y);

/// (core, blocks) simulated on a recording that starts wherever the machine was
/// (deviation coordinates), from the initial state that best explains its start
/// (see RecordingValidation); the state used goes to `x0` when given.
Eigen::MatrixXd simulate_from_estimated_state(const StateSpace& core, int substeps, const std::vector<OutputQuantity>& quantities,
                                              const std::vector<PhysicsBlock>& blocks, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                              const Eigen::Ref<const Eigen::MatrixXd>& y, Eigen::VectorXd* x0 = nullptr);

/// names[k], or prefix followed by k + 1 when the model has no name for it.
std::string channel_name(const std::vector<std::string>& names, long k, const char* prefix);

/// The record's segment boundaries: [0, fit) fits, [fit, estimation) selects,
/// [estimation, total) validates (confirmation: fit = estimation = total).
struct Segments {
  Eigen::Index fit = 0, estimation = 0, total = 0;
};

/// One round's candidates after fitting and judging.
struct JudgedRound {
  std::vector<JudgedCandidate> judged;
  std::vector<std::optional<LinearCoreRefitResult>> refits;  ///< refit_nominal: each candidate's core
};

class DiagnoseSession {
 public:
  /// Checks the arguments (std::invalid_argument, see diagnose()) and sets up the
  /// simulators; `confirm` (deviation coordinates) or nullptr.
  DiagnoseSession(const AugmentedModel& nominal, const Eigen::Ref<const Eigen::MatrixXd>& u_raw,
                  const Eigen::Ref<const Eigen::MatrixXd>& y_raw, const Recording* confirm, const DiagnoseOptions& options);

  const Segments& segments() const { return m_seg; }
  const DiagnoseOptions& options() const { return m_o; }

  /// Step 1: locate_mismatch of the nominal's residual on [0, estimation).
  void locate();
  /// Step 2: the detectors' candidates on the fit rows, scored on the current
  /// residual, the best candidates_per_round.
  std::vector<Candidate> propose() const;
  /// Step 3: each candidate fitted on the fit rows (in parallel), its gain in fit
  /// points on rows [scored_from, estimation) over the current model (or, with
  /// refit_nominal, the core refitted alone), and its improvement z on `test`
  /// (nullptr: the selection rows [fit, estimation); a recording: simulated
  /// there from an estimated initial state). `threshold` is recorded with each.
  JudgedRound judge(const std::vector<Candidate>& candidates, int round, Eigen::Index scored_from, const Recording* test,
                    double threshold);
  /// Gain less the penalty per free parameter (fit points).
  double penalised_gain(const JudgedCandidate& j) const;
  /// The round's candidates go to the report's `considered`.
  void record(const JudgedRound& round);
  /// Accepts candidate `best`: its reading of the outputs, its core (refit_nominal)
  /// or its block; `refit_blocks`: then refit every accepted block together on
  /// the fit rows (local stage).
  void accept(const JudgedRound& round, int best, bool refit_blocks);
  /// The accepted blocks (and core, with refit_nominal) refitted on [0, estimation).
  void refit_on_estimation_rows();
  /// Step 4: findings in the order accepted, each with the validation fit per
  /// output before and after it by `validation_fit(findings so far, their
  /// simulation of the log)`, and the report finished; `validation` describes it.
  DiagnoseReport finish(const std::function<Eigen::VectorXd(const std::vector<Candidate>&, const Eigen::MatrixXd&)>& validation_fit,
                        const std::string& validation);

  // For the validation functions of the procedures.
  const Recording& log() const { return m_log; }
  const StateSpace& core() const { return m_core; }
  const std::vector<OutputQuantity>& quantities() const { return m_quantities; }
  const std::vector<PhysicsBlock>& base() const { return m_base; }
  const AugmentedSimulator& simulator_for(const std::vector<Candidate>& set, const std::vector<PhysicsBlock>& fixed) const;

 private:
  void build_simulators();
  /// "position, velocity": the readings tried (m_readings), in words.
  std::string readings_words() const;
  LinearCoreRefitResult refit_core(const std::vector<Candidate>& blocks, Eigen::Index rows, int steps,
                                   const std::vector<OutputQuantity>& reading) const;
  Eigen::MatrixXd simulate_refit(const LinearCoreRefitResult& r, int steps, Eigen::Index rows,
                                 const std::vector<OutputQuantity>& reading) const;
  void adopt(const LinearCoreRefitResult& r);
  void fix_reading(const JudgedRound& round, int best);
  /// A fitted candidate's standard errors, its optional terms held where the
  /// data do not show them (beyond the round's `threshold` in standard errors),
  /// and whether its defining parameter is significant.
  void judge_parameters(const AugmentedSimulator& sim, const std::vector<PhysicsBlock>& fixed, JudgedCandidate& j,
                        Eigen::Index rows, double threshold) const;
  /// The accepted candidates' standard errors, fitted together on [0,
  /// estimation); drops (with a warning) those no longer significant.
  std::vector<CandidateUncertainty> final_uncertainty();
  /// Each accepted candidate's optional terms held at their null values when the
  /// findings together fit rows [0, rows) as well without them.
  void hold_unneeded_optional_terms(Eigen::Index rows);
  /// The findings ranked most important first: each next one the finding that,
  /// added to those before it, leaves the least simulation cost on [0,
  /// estimation) (the order found is the order of the search, not of importance:
  /// a later finding may explain more once an earlier one is refitted with it).
  void order_by_importance(std::vector<CandidateUncertainty>& uncertainty);
  /// The best other kind fitted in the round a finding was accepted in, in words.
  std::string best_alternative(const JudgedCandidate& accepted) const;

  const AugmentedModel& m_nominal;
  const DiagnoseOptions& m_o;
  const Recording* m_confirm;
  Segments m_seg;
  DiagnoseReport m_report;
  Recording m_log;
  StateSpace m_core;  ///< the nominal, or with refit_nominal its refit after each acceptance
  Eigen::VectorXd m_core_x0;
  int m_substeps = 1;
  std::vector<OutputQuantity> m_quantities;  ///< how the plant's forces read the outputs
  std::unique_ptr<AugmentedSimulator> m_fast, m_fine;
  std::map<std::vector<OutputQuantity>, std::unique_ptr<AugmentedSimulator>> m_readings;  ///< readings to try
  std::vector<PhysicsBlock> m_base;  ///< blocks already in the nominal
  std::vector<Candidate> m_accepted;
  std::vector<JudgedCandidate> m_acceptance;  ///< how each accepted candidate passed, same order
  CandidateFitOptions m_local_fit;            ///< refits after an acceptance: the local stage only
  Eigen::MatrixXd m_y_nominal;                ///< the nominal's simulation of the log
};

}  // namespace sysid
