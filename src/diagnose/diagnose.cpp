// The two procedures of `sysid diagnose`: locate, name, model, prove — on three
// parts of one record, or confirmed on a second recording. Method in
// include/sysid/diagnose/diagnose.hpp; the steps they share in
// detail/diagnose_session.hpp.
#include "sysid/diagnose/diagnose.hpp"

#include <sstream>
#include <stdexcept>

#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"
#include "diagnose/detail/diagnose_session.hpp"
#include "sysid/core/distributions.hpp"
#include "sysid/diagnose/physics_kind.hpp"
#include "sysid/validate/fit.hpp"

namespace sysid {

std::string finding_summary(const PhysicsBlock& b, const std::vector<std::string>& input_names,
                            const std::vector<std::string>& output_names, double ts) {
  return physics_kind(b.kind).summary(b, {channel_name(input_names, b.input, "u"), channel_name(output_names, b.output, "y"), ts});
}

DiagnoseReport diagnose(const AugmentedModel& nominal, const Eigen::Ref<const Eigen::MatrixXd>& u,
                        const Eigen::Ref<const Eigen::MatrixXd>& y, const DiagnoseOptions& options) {
  DiagnoseSession session(nominal, u, y, nullptr, options);
  const Segments seg = session.segments();
  session.locate();
  for (int round = 1; round <= options.max_findings; ++round) {
    const std::vector<Candidate> candidates = session.propose();
    if (candidates.empty()) break;
    // Each candidate scored and tested on the selection segment; Bonferroni over
    // the candidates of the round.
    const double threshold = normal_quantile(1.0 - options.significance / static_cast<double>(candidates.size()));
    JudgedRound judged = session.judge(candidates, round, seg.fit, nullptr, threshold);
    int best = -1;
    double best_gain = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < judged.judged.size(); ++k) {
      JudgedCandidate& j = judged.judged[k];
      const double gain = session.penalised_gain(j);
      j.significant = j.t_statistic > threshold && gain > options.min_gain_points && j.parameters_significant;
      if (j.significant && gain > best_gain) best_gain = gain, best = static_cast<int>(k);
    }
    session.record(judged);
    if (best < 0) break;
    session.accept(judged, best, /*refit_blocks=*/true);
  }
  // Prove: refit on the whole estimation part, score on the held-out rows.
  session.refit_on_estimation_rows();
  const Eigen::Index V = seg.total - seg.estimation;
  const Recording& log = session.log();
  std::ostringstream v;
  v << "last " << format_number(100.0 * static_cast<double>(V) / static_cast<double>(seg.total), 3) << " % of samples (" << V << " of "
    << seg.total << ")";
  return session.finish([&](const std::vector<Candidate>&, const Eigen::MatrixXd& on_log) -> Eigen::VectorXd {
    return fit_percent(log.y.bottomRows(V), on_log.bottomRows(V));
  }, v.str());
}

DiagnoseReport diagnose_confirmed(const AugmentedModel& nominal, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                  const Eigen::Ref<const Eigen::MatrixXd>& y, const Eigen::Ref<const Eigen::MatrixXd>& u_confirm,
                                  const Eigen::Ref<const Eigen::MatrixXd>& y_confirm, const DiagnoseOptions& options) {
  const Recording confirm = deviation_recording(nominal, u_confirm, y_confirm);
  DiagnoseSession session(nominal, u, y, &confirm, options);
  session.locate();
  // One test per round, at the full level: a fixed-sequence procedure.
  const double threshold = normal_quantile(1.0 - options.significance);
  for (int round = 1; round <= options.max_findings; ++round) {
    const std::vector<Candidate> candidates = session.propose();
    if (candidates.empty()) break;
    // Ranked by the gain on the whole log (in-sample); only the best-ranked one
    // is tested on the recording, and the first that fails ends the search.
    JudgedRound judged = session.judge(candidates, round, 0, &confirm, threshold);
    int best = -1;
    double best_gain = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < judged.judged.size(); ++k) {
      const double gain = session.penalised_gain(judged.judged[k]);
      if (gain > options.min_gain_points && judged.judged[k].parameters_significant && gain > best_gain)
        best_gain = gain, best = static_cast<int>(k);
    }
    for (std::size_t k = 0; k < judged.judged.size(); ++k)
      judged.judged[k].significant = static_cast<int>(k) == best && judged.judged[k].t_statistic > threshold;
    session.record(judged);
    if (best < 0 || !judged.judged[static_cast<std::size_t>(best)].significant) break;
    // The model kept is the one the recording confirmed: no refit after acceptance.
    session.accept(judged, best, /*refit_blocks=*/false);
  }
  // Prove on the recording, with the very models it confirmed.
  std::ostringstream v;
  v << "the independent recording (" << confirm.y.rows() << " samples, initial state estimated), which confirmed each finding";
  return session.finish([&](const std::vector<Candidate>& set, const Eigen::MatrixXd&) -> Eigen::VectorXd {
    const bool plain = set.empty();
    const StateSpace& core = plain ? nominal.nominal : session.core();
    const int steps = session.simulator_for(set, session.base()).substeps();
    return fit_percent(confirm.y, simulate_from_estimated_state(core, steps, session.quantities(),
                                                                combine_blocks(session.base(), set), confirm.u, confirm.y));
  }, v.str());
}

namespace {

/// The model simulated from the initial state that best explains the start of y
/// (see RecordingValidation); returns the fit per output and sets model.x0.
Eigen::VectorXd fit_from_estimated_state(AugmentedModel& model, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                         const Eigen::Ref<const Eigen::MatrixXd>& y) {
  const Recording r = deviation_recording(model, u, y);
  return fit_percent(r.y, simulate_from_estimated_state(model.nominal, model.substeps, model.output_quantities, model.blocks, r.u, r.y, &model.x0));
}

}  // namespace

RecordingValidation validate_on_recording(const AugmentedModel& nominal, const AugmentedModel& augmented,
                                          const Eigen::Ref<const Eigen::MatrixXd>& u, const Eigen::Ref<const Eigen::MatrixXd>& y) {
  if (nominal.nominal.inputs() != augmented.nominal.inputs() || nominal.nominal.outputs() != augmented.nominal.outputs() ||
      nominal.nominal.Ts != augmented.nominal.Ts)
    throw std::invalid_argument("validate_on_recording: the augmented model must have the nominal's channels and sample time");
  if (u.rows() != y.rows() || u.cols() != nominal.nominal.inputs() || y.cols() != nominal.nominal.outputs() || y.rows() < 1)
    throw std::invalid_argument("validate_on_recording: need u N x " + std::to_string(nominal.nominal.inputs()) + " and y N x " +
                                std::to_string(nominal.nominal.outputs()) + ", N >= 1");
  RecordingValidation v;
  AugmentedModel before = nominal, after = augmented;
  v.fit_before = fit_from_estimated_state(before, u, y);
  v.fit_after = fit_from_estimated_state(after, u, y);
  v.x0_before = before.x0;
  v.x0_after = after.x0;
  return v;
}

}  // namespace sysid
