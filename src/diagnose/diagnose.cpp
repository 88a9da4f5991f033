// The diagnose loop: locate, name, model, prove. Method in
// include/sysid/diagnose/diagnose.hpp.
#include "sysid/diagnose/diagnose.hpp"

#include <algorithm>
#include <map>
#include <memory>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/identification_warnings.hpp"
#include "sysid/core/parallel_for.hpp"
#include "sysid/core/poles_zeros.hpp"
#include "sysid/core/distributions.hpp"
#include "sysid/validate/compare.hpp"
#include "sysid/diagnose/physics_kind.hpp"
#include "sysid/validate/fit.hpp"

namespace sysid {

namespace {

double mean_fit(const Eigen::Ref<const Eigen::MatrixXd>& y, const Eigen::Ref<const Eigen::MatrixXd>& y_hat) {
  return fit_percent(y, y_hat).mean();
}

/// (core, blocks) simulated on a recording that starts wherever the machine was
/// (deviation coordinates), from the initial state that best explains its start
/// (see RecordingValidation); the state used goes to `x0` when given.
Eigen::MatrixXd simulate_from_estimated_state(const StateSpace& core, int substeps, const std::vector<OutputQuantity>& quantities,
                                              const std::vector<PhysicsBlock>& blocks, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                              const Eigen::Ref<const Eigen::MatrixXd>& y, Eigen::VectorXd* x0 = nullptr) {
  const Eigen::MatrixXd residual = y - AugmentedSimulator(core, substeps, Eigen::VectorXd(), quantities).simulate(blocks, u);
  const Eigen::VectorXd start = estimate_initial_state(core, Eigen::MatrixXd::Zero(u.rows(), core.inputs()), residual);
  if (x0) *x0 = start;
  return AugmentedSimulator(core, substeps, start, quantities).simulate(blocks, u);
}

/// Paired test of "the candidate does not improve the simulation" on rows
/// [from, to): the SSE reduction D = sum_t (e_before^2 - e_after^2) against its
/// spread under the null. With delta = y_after - y_before (fitted on other
/// samples, so independent of the noise here) and the null e_before = n,
/// D = 2 sum delta n - sum delta^2, whose standard deviation is
/// 2 sqrt(sum_{t,s} delta_t delta_s R_n(t - s)) — the exact variance of a linear
/// functional of a stationary Gaussian noise. R_n is estimated from e_after
/// (Bartlett-tapered up to `max_lag`, so the estimate stays non-negative
/// definite). Outputs are weighted by 1 / var(y_i) and taken as independent.
/// Returns D / sd: about N(-||delta|| / (2 sigma), 1) or below under the null.
double improvement_z(const Eigen::MatrixXd& y, const Eigen::MatrixXd& before, const Eigen::MatrixXd& after, Eigen::Index from,
                     Eigen::Index to, Eigen::Index max_lag) {
  const Eigen::Index n = to - from;
  const Eigen::Index L = std::min(max_lag, n / 4);
  double gain = 0.0, variance = 0.0;
  for (Eigen::Index i = 0; i < y.cols(); ++i) {
    const auto yi = y.col(i).segment(from, n);
    const double w = 1.0 / std::max((yi.array() - yi.mean()).square().mean(), std::numeric_limits<double>::min());
    const Eigen::VectorXd e_before = yi - before.col(i).segment(from, n), e_after = yi - after.col(i).segment(from, n);
    const Eigen::VectorXd delta = e_before - e_after;
    const Eigen::VectorXd noise = e_after.array() - e_after.mean();
    gain += w * (e_before.squaredNorm() - e_after.squaredNorm());
    double v = 0.0;
    for (Eigen::Index k = 0; k <= L; ++k) {
      const double r = noise.head(n - k).dot(noise.tail(n - k)) / static_cast<double>(n);
      const double c = delta.head(n - k).dot(delta.tail(n - k));
      const double taper = 1.0 - static_cast<double>(k) / static_cast<double>(L + 1);
      v += (k == 0 ? 1.0 : 2.0) * taper * r * c;
    }
    variance += w * w * 4.0 * std::max(v, 0.0);
  }
  if (!(variance > 0)) return gain > 0 ? std::numeric_limits<double>::infinity() : 0.0;
  return gain / std::sqrt(variance);
}

std::string channel_name(const std::vector<std::string>& names, long k, const char* prefix) {
  return k < static_cast<long>(names.size()) ? names[k] : prefix + std::to_string(k + 1);
}

struct Segments {
  Eigen::Index fit = 0, estimation = 0, total = 0;
};

/// An independent recording in the nominal's deviation coordinates (confirmation mode).
struct Recording {
  Eigen::MatrixXd u, y;
};

Recording deviation_recording(const AugmentedModel& model, const Eigen::Ref<const Eigen::MatrixXd>& u,
                              const Eigen::Ref<const Eigen::MatrixXd>& y) {
  Recording r{u, y};
  if (model.input_offset.size()) r.u.rowwise() -= model.input_offset.transpose();
  if (model.output_offset.size()) r.y.rowwise() -= model.output_offset.transpose();
  return r;
}

void check_arguments(const AugmentedModel& nominal, const Eigen::Ref<const Eigen::MatrixXd>& u,
                     const Eigen::Ref<const Eigen::MatrixXd>& y, const Recording* confirm, const DiagnoseOptions& o,
                     Segments& s) {
  nominal.nominal.validate();
  if (!nominal.nominal.is_discrete()) throw std::invalid_argument("diagnose: need a discrete nominal model");
  if (u.rows() != y.rows()) throw std::invalid_argument("diagnose: need u.rows() == y.rows()");
  if (u.cols() != nominal.nominal.inputs() || y.cols() != nominal.nominal.outputs())
    throw std::invalid_argument("diagnose: the log's channels must match the nominal model's inputs and outputs");
  if (!u.allFinite() || !y.allFinite()) throw std::invalid_argument("diagnose: u and y must be finite");
  const auto& names = nominal.nominal.output_names;
  for (Eigen::Index i = 0; i < y.cols(); ++i)
    if (!(y.col(i).maxCoeff() > y.col(i).minCoeff()))
      throw std::invalid_argument("diagnose: output '" +
                                  (i < static_cast<Eigen::Index>(names.size()) ? names[i] : "y" + std::to_string(i + 1)) +
                                  "' is constant (a stuck or disconnected sensor?): there is nothing to compare the simulation with");
  if (o.max_correlation_lag < 1) throw std::invalid_argument("diagnose: need max_correlation_lag >= 1");
  if (o.min_segment_samples < 50) throw std::invalid_argument("diagnose: need min_segment_samples >= 50");
  s.total = y.rows();
  if (confirm) {
    // The whole log fits and ranks; the recording confirms and validates.
    if (confirm->u.rows() != confirm->y.rows() || confirm->u.cols() != u.cols() || confirm->y.cols() != y.cols())
      throw std::invalid_argument("diagnose: the confirming recording must have the log's input and output channels");
    if (!confirm->u.allFinite() || !confirm->y.allFinite())
      throw std::invalid_argument("diagnose: the confirming recording's values must be finite");
    const Eigen::Index shortest = std::min(s.total, confirm->y.rows());
    if (shortest < o.min_segment_samples)
      throw std::invalid_argument("diagnose: need at least " + std::to_string(o.min_segment_samples) +
                                  " samples in the log and in the confirming recording (have " + std::to_string(s.total) +
                                  " and " + std::to_string(confirm->y.rows()) + ")");
    s.fit = s.estimation = s.total;
    return;
  }
  if (!(o.fit_fraction > 0 && o.selection_fraction > 0 && o.fit_fraction + o.selection_fraction < 1))
    throw std::invalid_argument("diagnose: need fit_fraction, selection_fraction > 0 and their sum < 1");
  s.fit = static_cast<Eigen::Index>(std::floor(o.fit_fraction * static_cast<double>(s.total)));
  s.estimation = static_cast<Eigen::Index>(std::floor((o.fit_fraction + o.selection_fraction) * static_cast<double>(s.total)));
  const Eigen::Index shortest = std::min({s.fit, s.estimation - s.fit, s.total - s.estimation});
  if (shortest < o.min_segment_samples)
    throw std::invalid_argument("diagnose: need at least " + std::to_string(o.min_segment_samples) +
                                " samples in each of the fit, selection and validation segments (have " +
                                std::to_string(shortest) + " in the shortest; record has " + std::to_string(s.total) + ")");
}

/// What the record cannot tell (issue 8, hostile data): a constant input does not
/// test the simulation's response to it; an input exciting fewer frequencies than
/// the model has modes tests it only there; plus the glitches and collinear inputs
/// every identification warns about (core/identification_warnings.hpp).
std::vector<std::string> record_warnings(const StateSpace& model, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                         const Eigen::Ref<const Eigen::MatrixXd>& y) {
  const IoData data(u, y, model.Ts, model.input_names, model.output_names);
  std::vector<std::string> out;
  for (Eigen::Index j = 0; j < u.cols(); ++j)
    if (!(u.col(j).maxCoeff() > u.col(j).minCoeff()))
      out.push_back("diagnose: input '" + data.input_name(j) +
                    "' is constant: the record does not test the simulation's response to it; only effects that do "
                    "not depend on it (offset, drift, periodic disturbance) can be found");
  const Eigen::Index order = model.A.rows();
  for (auto& w : identification_data_warnings(data, 2 * order, "a test of the order-" + std::to_string(order) + " simulation model",
                                              "diagnose"))
    out.push_back(std::move(w));
  return out;
}

/// The falsified band or residual peak a block explains, for the report's location.
std::optional<std::pair<double, double>> band_of(const PhysicsBlock& b, const MismatchLocation& loc) {
  // Kinds with a frequency (modes, periodic disturbances) have a place in frequency.
  const auto& names = b.info().parameters;
  const auto has = [&](const char* name) {
    return std::any_of(names.begin(), names.end(), [&](const char* p) { return std::string(p) == name; });
  };
  if (!has("freq_hz")) return std::nullopt;
  const double f = b.param("freq_hz");
  if (b.output < static_cast<long>(loc.outputs.size()))
    for (const auto& band : loc.outputs[b.output].bands)
      if (band.lo_hz <= f * 1.02 && f <= band.hi_hz * 1.02) return std::make_pair(band.lo_hz, band.hi_hz);
  const double halfwidth = has("damping") ? std::max(3.0 * b.param("damping") * f, 0.5) : 0.5;
  return std::make_pair(f - halfwidth, f + halfwidth);
}

/// The flagged residual windows (location step, estimation part) that a finding
/// explains: on any output, the window's residual mean square falls, from the
/// simulation before the finding to the one after it, by at least half of its
/// excess over the window floor (floor = the nominal residual's mean square there
/// over its energy ratio, the location step's own figures). Windows another
/// finding explains, or that no block reduces, are not listed.
std::vector<std::pair<double, double>> explained_windows(const MismatchLocation& loc, const Eigen::MatrixXd& y,
                                                         const Eigen::MatrixXd& nominal, const Eigen::MatrixXd& before,
                                                         const Eigen::MatrixXd& after, Eigen::Index estimation, double Ts) {
  // The residual of a simulation on output i, centred over the estimation part as
  // locate_mismatch centres it; each is formed once per output.
  const auto centred = [&](const Eigen::MatrixXd& sim, Eigen::Index i) {
    Eigen::VectorXd r = (y.col(i) - sim.col(i)).head(estimation);
    r.array() -= r.mean();
    return r;
  };
  const auto window_ms = [](const Eigen::VectorXd& r, Eigen::Index s0, Eigen::Index s1) {
    return r.segment(s0, s1 - s0).squaredNorm() / static_cast<double>(s1 - s0);
  };
  std::vector<std::pair<double, double>> out;
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(loc.outputs.size()) && i < y.cols(); ++i) {
    const auto& windows = loc.outputs[static_cast<std::size_t>(i)].windows;
    if (std::none_of(windows.begin(), windows.end(), [](const ResidualWindow& w) { return w.flagged; })) continue;
    const Eigen::VectorXd r_nominal = centred(nominal, i), r_before = centred(before, i), r_after = centred(after, i);
    for (const auto& w : windows) {
      if (!w.flagged || !(w.energy_ratio > 0.0)) continue;
      const Eigen::Index s0 = std::clamp<Eigen::Index>(std::llround(w.t0_s / Ts), 0, estimation);
      const Eigen::Index s1 = std::clamp<Eigen::Index>(std::llround(w.t1_s / Ts), s0, estimation);
      if (s1 - s0 < 2) continue;
      const double floor = window_ms(r_nominal, s0, s1) / w.energy_ratio;
      const double ms_before = window_ms(r_before, s0, s1), ms_after = window_ms(r_after, s0, s1);
      if (ms_before > floor && ms_before - ms_after >= 0.5 * (ms_before - floor)) {
        const std::pair<double, double> t{w.t0_s, w.t1_s};
        if (std::find(out.begin(), out.end(), t) == out.end()) out.push_back(t);
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

std::string finding_summary(const PhysicsBlock& b, const std::vector<std::string>& input_names,
                            const std::vector<std::string>& output_names, double ts) {
  return physics_kind(b.kind).summary(b, {channel_name(input_names, b.input, "u"), channel_name(output_names, b.output, "y"), ts});
}

namespace {

/// The readings of the outputs to try for the plant's forces when some output's
/// quantity is unknown: each unknown one read as a position, as a velocity, and
/// — when the nominal has a direct feedthrough, as a force-to-acceleration path
/// has — as an acceleration. Empty when every quantity is known.
std::vector<std::vector<OutputQuantity>> readings_to_try(const std::vector<OutputQuantity>& quantities, const StateSpace& core) {
  std::vector<std::vector<OutputQuantity>> out;
  if (std::none_of(quantities.begin(), quantities.end(), [](OutputQuantity q) { return q == OutputQuantity::unknown; }))
    return out;
  std::vector<OutputQuantity> tried = {OutputQuantity::position, OutputQuantity::velocity};
  if (core.D.cwiseAbs().maxCoeff() > 0.0) tried.push_back(OutputQuantity::acceleration);
  for (OutputQuantity reading : tried) {
    std::vector<OutputQuantity> r = quantities;
    for (auto& q : r)
      if (q == OutputQuantity::unknown) q = reading;
    out.push_back(r);
  }
  return out;
}

/// Why the outputs were read as `chosen`: the accepted force's selection gain
/// under that reading against the best force under each other reading.
std::string reading_note(const std::vector<OutputQuantity>& before, const std::vector<OutputQuantity>& chosen,
                         const std::vector<JudgedCandidate>& judged, int best, const std::vector<std::string>& output_names) {
  std::ostringstream s;
  s << "the quantity of output";
  bool first = true;
  for (std::size_t i = 0; i < before.size(); ++i)
    if (before[i] == OutputQuantity::unknown) {
      s << (first ? " " : ", ") << channel_name(output_names, static_cast<long>(i), "y") << " (read as " << quantity_name(chosen[i]) << ")";
      first = false;
    }
  const JudgedCandidate& won = judged[static_cast<std::size_t>(best)];
  s << " was not given (--output-quantity); forces inside the plant were tried under each reading, and "
    << won.candidate.block.kind << " under this one gained " << fixed(won.selection_gain, 3)
    << " points on the selection segment";
  std::map<std::vector<OutputQuantity>, const JudgedCandidate*> best_other;
  for (const auto& j : judged) {
    const auto& r = j.candidate.output_quantities;
    if (r.empty() || r == chosen) continue;
    auto& slot = best_other[r];
    if (!slot || j.selection_gain > slot->selection_gain) slot = &j;
  }
  for (const auto& [reading, j] : best_other) {
    std::string name = "?";
    for (std::size_t i = 0; i < before.size(); ++i)
      if (before[i] == OutputQuantity::unknown) name = quantity_name(reading[i]);
    s << "; the best under the " << name << " reading (" << j->candidate.block.kind << ") "
      << fixed(j->selection_gain, 3);
  }
  return s.str();
}

/// diagnose() and, with `confirm` (deviation coordinates), diagnose_confirmed().
DiagnoseReport run_diagnose(const AugmentedModel& nominal, const Eigen::Ref<const Eigen::MatrixXd>& u_raw,
                            const Eigen::Ref<const Eigen::MatrixXd>& y_raw, const Recording* confirm,
                            const DiagnoseOptions& o) {
  Segments seg;
  check_arguments(nominal, u_raw, y_raw, confirm, o, seg);
  DiagnoseReport report;
  report.warnings = record_warnings(nominal.nominal, u_raw, y_raw);
  report.fit_rows = seg.fit;
  report.estimation_rows = seg.estimation;
  const StateSpace& model = nominal.nominal;
  const double Ts = model.Ts;

  // Deviation coordinates of the nominal.
  const Recording log = deviation_recording(nominal, u_raw, y_raw);
  const Eigen::MatrixXd &u = log.u, &y = log.y;

  // The linear core the blocks act on: the nominal, or with refit_nominal its
  // refit after each acceptance (simulators rebuilt then).
  StateSpace core = model;
  Eigen::VectorXd core_x0 = nominal.x0;
  const int substeps = o.detection.feedback_substeps > 0 ? o.detection.feedback_substeps
                                                          : (model.D.cwiseAbs().maxCoeff() > 0.0 ? 1 : 4);
  // How the outputs are read by the plant's forces: as the nominal says, and
  // where it does not, each reading in turn (readings_to_try) until a force
  // accepted under one fixes it.
  std::vector<OutputQuantity> quantities = nominal.output_quantities;
  if (quantities.empty()) quantities.assign(static_cast<std::size_t>(model.outputs()), OutputQuantity::unknown);
  std::unique_ptr<AugmentedSimulator> fast, fine;
  std::map<std::vector<OutputQuantity>, std::unique_ptr<AugmentedSimulator>> readings;
  auto build_simulators = [&] {
    fast = std::make_unique<AugmentedSimulator>(core, 1, core_x0, quantities);
    fine = std::make_unique<AugmentedSimulator>(core, substeps, core_x0, quantities);
    readings.clear();
    for (auto& r : readings_to_try(quantities, core)) readings[r] = std::make_unique<AugmentedSimulator>(core, substeps, core_x0, r);
  };
  build_simulators();
  for (const auto& w : fine->warnings()) report.warnings.push_back(w);
  auto simulator_for = [&](const std::vector<Candidate>& set, const std::vector<PhysicsBlock>& fixed) -> const AugmentedSimulator& {
    for (const auto& c : set)
      if (!c.output_quantities.empty() && c.output_quantities != quantities) return *readings.at(c.output_quantities);
    bool feedback = std::any_of(fixed.begin(), fixed.end(),
                                [](const PhysicsBlock& b) { return b.info().stage == BlockStage::plant_feedback; });
    for (const auto& c : set) feedback = feedback || c.substeps > 1;
    return feedback ? *fine : *fast;
  };
  std::vector<PhysicsBlock> base = nominal.blocks;  // blocks already in the model stay
  std::vector<Candidate> accepted;
  // The core and every block refitted together (refit_nominal), on rows [0, rows).
  // Both under a reading of the outputs (the model's, or a candidate's).
  auto refit_core = [&](const std::vector<Candidate>& blocks, Eigen::Index rows, int steps, const std::vector<OutputQuantity>& reading) {
    return refit_linear_core(core, core_x0, base, blocks, u.topRows(rows), y.topRows(rows), rows, steps, o.refit, reading);
  };
  auto simulate_refit = [&](const LinearCoreRefitResult& r, int steps, Eigen::Index rows, const std::vector<OutputQuantity>& reading) {
    return AugmentedSimulator(r.model, steps, r.x0, reading).simulate(combine_blocks(base, r.blocks), u, rows);
  };
  // A refit's core and blocks become the model's.
  auto adopt = [&](const LinearCoreRefitResult& r) {
    core = r.model;
    core_x0 = r.x0;
    accepted = r.blocks;
    build_simulators();
  };
  report.nominal_refit.attempted = o.refit_nominal;
  report.nominal_refit.poles_before = poles(model);
  report.nominal_refit.poles_after = report.nominal_refit.poles_before;

  std::vector<JudgedCandidate> acceptance;  ///< how each accepted candidate passed, same order
  // Refits after an acceptance start from good values: the local stage only.
  CandidateFitOptions local_fit = o.fit;
  local_fit.global_evaluations_per_parameter = 0;
  const Eigen::MatrixXd y_nominal = fine->simulate(base, u);

  // 1. Locate, on the estimation part only.
  {
    const Eigen::Index E = seg.estimation;
    report.location = locate_mismatch(u.topRows(E), y.topRows(E), (y - y_nominal).topRows(E), y_nominal.topRows(E), Ts, o.location);
  }
  const Eigen::Index fit_rows = seg.fit;
  const auto u_fit = u.topRows(fit_rows);
  const auto y_fit = y.topRows(fit_rows);

  for (int round = 1; round <= o.max_findings; ++round) {
    const std::vector<PhysicsBlock> fixed = combine_blocks(base, accepted);
    const AugmentedSimulator& current_sim = simulator_for({}, fixed);
    const Eigen::MatrixXd current = current_sim.simulate(fixed, u, seg.estimation);

    // 2. Name: detectors on the fit segment, scored on the current residual.
    // Candidate frequencies come from the location of the nominal's residual
    // (bands, peaks), computed once.
    DetectionData data;
    data.simulator = fine.get();
    for (const auto& [reading, simulator] : readings) data.plant_readings.push_back(simulator.get());
    data.accepted = fixed;
    data.u = u_fit;
    data.y = y_fit;
    data.current = current.topRows(fit_rows);
    data.Ts = Ts;
    for (const auto& ch : report.location.outputs) {
      for (const auto& band : ch.bands) data.mode_frequencies_hz.push_back(band.peak_hz);
      for (const auto& peak : ch.peaks) data.peak_frequencies_hz.push_back(peak.freq_hz);
      if (ch.freq_hz.size() > 1) data.frequency_resolution_hz = ch.freq_hz[1] - ch.freq_hz[0];
    }
    std::vector<Candidate> candidates = propose_candidates(data, o.detection);
    if (static_cast<int>(candidates.size()) > o.candidates_per_round) candidates.resize(o.candidates_per_round);

    // 3. Model and judge each on the selection segment (confirmation mode: rank
    // on the whole log, test the best on the independent recording).
    const int tried = static_cast<int>(candidates.size());
    if (tried == 0) break;
    // Bonferroni over the candidates of the round; one test per round when confirming.
    const double level = confirm ? o.significance : o.significance / tried;
    const double t_threshold = normal_quantile(1.0 - level);
    // With refit_nominal every candidate is fitted together with the linear core,
    // and judged against the core refitted alone on the same rows: both have seen
    // the same data, so the test asks whether the physics helps beyond a better
    // linear fit (the nominal itself may have been identified on the selection
    // segment, which would favour it).
    Eigen::MatrixXd reference = current, reference_confirm;
    if (confirm) reference_confirm = simulate_from_estimated_state(core, current_sim.substeps(), quantities, fixed, confirm->u, confirm->y);
    if (o.refit_nominal) {
      const LinearCoreRefitResult alone = refit_core(accepted, fit_rows, current_sim.substeps(), quantities);
      if (alone.refitted) {
        reference = simulate_refit(alone, current_sim.substeps(), seg.estimation, quantities);
        if (confirm)
          reference_confirm = simulate_from_estimated_state(alone.model, current_sim.substeps(), quantities,
                                                            combine_blocks(base, alone.blocks), confirm->u, confirm->y);
      } else if (round == 1) {  // e.g. too large a nominal: the candidates are judged on the nominal as given
        for (const auto& w : alone.warnings) report.warnings.push_back("diagnose: " + w);
      }
    }
    // Gains are measured on the selection segment, or in confirmation mode on the whole log.
    const Eigen::Index scored_from = confirm ? 0 : seg.fit, scored = seg.estimation - scored_from;
    const double before_fit = mean_fit(y.middleRows(scored_from, scored), reference.middleRows(scored_from, scored));
    int best = -1;
    double best_score = -std::numeric_limits<double>::infinity();
    // Candidates are independent: fit them on all cores (each thread its own NLopt
    // instance; the simulators are read-only).
    std::vector<JudgedCandidate> judged(candidates.size());
    std::vector<std::optional<LinearCoreRefitResult>> refits(candidates.size());
    parallel_for(candidates.size(), [&](std::size_t index) {
      const Candidate& cand = candidates[index];
      const AugmentedSimulator& sim = simulator_for({cand}, fixed);
      CandidateFitResult fitted = fit_candidates(sim, fixed, {cand}, u_fit, y_fit, fit_rows, o.fit);
      JudgedCandidate& j = judged[index];
      j.candidate = fitted.fitted.front();
      j.round = round;
      Eigen::MatrixXd after;
      const StateSpace* candidate_core = &core;
      std::vector<PhysicsBlock> blocks;
      if (o.refit_nominal) {
        std::vector<Candidate> all = accepted;
        all.push_back(j.candidate);
        LinearCoreRefitResult r = refit_core(all, fit_rows, sim.substeps(), sim.output_quantities());
        if (r.refitted) {
          after = simulate_refit(r, sim.substeps(), seg.estimation, sim.output_quantities());
          j.candidate = r.blocks.back();
          blocks = combine_blocks(base, r.blocks);
          refits[index] = std::move(r);
          candidate_core = &refits[index]->model;
        }
      }
      if (after.size() == 0) {
        blocks = combine_blocks(fixed, fitted.fitted);
        after = sim.simulate(blocks, u, seg.estimation);
      }
      j.selection_gain = mean_fit(y.middleRows(scored_from, scored), after.middleRows(scored_from, scored)) - before_fit;
      if (confirm) {
        const Eigen::MatrixXd after_confirm = simulate_from_estimated_state(*candidate_core, sim.substeps(), sim.output_quantities(), blocks, confirm->u, confirm->y);
        j.t_statistic = improvement_z(confirm->y, reference_confirm, after_confirm, 0, confirm->y.rows(), o.max_correlation_lag);
      } else {
        j.t_statistic = improvement_z(y, reference, after, seg.fit, seg.estimation, o.max_correlation_lag);
      }
      j.t_threshold = t_threshold;
    });
    auto penalised_gain = [&](const JudgedCandidate& j) {
      return j.selection_gain - o.penalty_points_per_parameter * static_cast<double>(j.candidate.free.size());
    };
    for (std::size_t index = 0; index < judged.size(); ++index) {
      JudgedCandidate& j = judged[index];
      const double penalised = penalised_gain(j);
      // Confirming, every candidate is eligible here; only the best-ranked one is then tested.
      j.significant = (confirm || j.t_statistic > t_threshold) && penalised > o.min_gain_points;
      if (j.significant && penalised > best_score) {
        best_score = penalised;
        best = static_cast<int>(index);
      }
    }
    if (confirm) {
      for (std::size_t index = 0; index < judged.size(); ++index)
        judged[index].significant = static_cast<int>(index) == best && judged[index].t_statistic > t_threshold;
      if (best >= 0 && !judged[best].significant) best = -1;  // the fixed sequence ends at its first failure
    }
    for (const auto& j : judged) report.considered.push_back(j);
    if (best < 0) break;
    acceptance.push_back(judged[best]);
    // A force accepted under one reading of the outputs fixes their quantities.
    auto fix_reading = [&](const JudgedCandidate& j) {
      const auto& r = j.candidate.output_quantities;
      if (r.empty() || r == quantities) return;
      report.reading_note = reading_note(quantities, r, judged, best, model.output_names);
      quantities = r;
      build_simulators();
    };
    if (refits[best]) {
      fix_reading(judged[best]);
      // The core moves with the blocks (fitted together on the fit segment).
      adopt(*refits[best]);
      report.nominal_refit.applied = true;
    } else {
      fix_reading(judged[best]);
      accepted.push_back(judged[best].candidate);
      // Confirming, the model kept is the one the recording confirmed.
      if (!confirm)
        accepted = fit_candidates(simulator_for(accepted, base), base, accepted, u_fit, y_fit, fit_rows, local_fit).fitted;
    }
  }

  // 4. Prove: refit on the whole estimation part (confirming, it was fitted on
  // the whole log already, and the recording confirmed those very models), then
  // score on validation.
  if (confirm) {
    if (report.nominal_refit.applied) report.nominal_refit.poles_after = poles(core);
  } else if (!accepted.empty() && report.nominal_refit.applied) {
    adopt(refit_core(accepted, seg.estimation, simulator_for(accepted, base).substeps(), quantities));
    report.nominal_refit.poles_after = poles(core);
  } else if (!accepted.empty()) {
    accepted = fit_candidates(simulator_for(accepted, base), base, accepted, u.topRows(seg.estimation),
                              y.topRows(seg.estimation), seg.estimation, local_fit)
                   .fitted;
  }
  const Eigen::Index V = seg.total - seg.estimation;
  // The validation fit per output of the findings so far, whose simulation of the log is `on_log`.
  auto validation_fit = [&](const std::vector<Candidate>& set, const Eigen::MatrixXd& on_log) -> Eigen::VectorXd {
    if (!confirm) return fit_percent(y.bottomRows(V), on_log.bottomRows(V));
    if (set.empty())
      return fit_percent(confirm->y, simulate_from_estimated_state(model, fine->substeps(), quantities, base, confirm->u, confirm->y));
    return fit_percent(confirm->y, simulate_from_estimated_state(core, simulator_for(set, base).substeps(), quantities,
                                                                 combine_blocks(base, set), confirm->u, confirm->y));
  };
  std::vector<Candidate> so_far;
  Eigen::MatrixXd previous = y_nominal;
  report.fit_before_per_output = validation_fit(so_far, y_nominal);
  report.fit_before = report.fit_before_per_output.mean();
  Eigen::VectorXd previous_fit = report.fit_before_per_output;
  for (std::size_t k = 0; k < accepted.size(); ++k) {
    const Candidate& c = accepted[k];
    so_far.push_back(c);
    const Eigen::MatrixXd next = simulator_for(so_far, base).simulate(combine_blocks(base, so_far), u);
    const Eigen::VectorXd next_fit = validation_fit(so_far, next);
    Finding f;
    f.candidate = c;
    f.fit_before = previous_fit.mean();
    f.fit_after = next_fit.mean();
    f.selection_gain = acceptance[k].selection_gain;
    f.t_statistic = acceptance[k].t_statistic;
    f.band_hz = band_of(c.block, report.location);
    f.time_windows_s = explained_windows(report.location, y, y_nominal, previous, next, seg.estimation, Ts);
    f.summary = finding_summary(c.block, model.input_names, model.output_names, Ts);
    report.findings.push_back(f);
    previous = next;
    previous_fit = next_fit;
  }
  report.fit_after_per_output = previous_fit;
  report.fit_after = report.fit_after_per_output.mean();
  report.simulated_before = y_nominal;
  report.simulated_after = previous;
  if (nominal.output_offset.size()) {
    report.simulated_before.rowwise() += nominal.output_offset.transpose();
    report.simulated_after.rowwise() += nominal.output_offset.transpose();
  }
  std::ostringstream v;
  if (confirm)
    v << "the independent recording (" << confirm->y.rows() << " samples, initial state estimated), which confirmed each finding";
  else
    v << "last " << fixed(100.0 * static_cast<double>(V) / static_cast<double>(seg.total), 3) << " % of samples (" << V
      << " of " << seg.total << ")";
  report.validation = v.str();

  report.augmented = nominal;
  report.augmented.blocks = combine_blocks(base, accepted);
  report.augmented.output_quantities = quantities;
  report.output_quantities = quantities;
  if (report.reading_note.empty() && !readings_to_try(nominal.output_quantities.empty()
                                                          ? std::vector<OutputQuantity>(static_cast<std::size_t>(model.outputs()))
                                                          : nominal.output_quantities,
                                                      model)
                                          .empty())
    report.reading_note =
        "the quantity of some outputs was not given (--output-quantity): forces inside the plant were tried under each "
        "reading (position, velocity" + std::string(model.D.cwiseAbs().maxCoeff() > 0.0 ? ", acceleration" : "") +
        ") and none was accepted, so the quantities stay unknown";
  report.augmented.substeps = simulator_for(accepted, base).substeps();
  if (report.nominal_refit.applied) {
    report.augmented.nominal = core;
    report.augmented.x0 = core_x0;
    report.warnings.push_back(
        "diagnose: the nominal's linear dynamics were refitted with the findings (refit_nominal); the augmented model "
        "carries the refitted core, and every finding's fit_after is measured with it");
  }
  return report;
}

}  // namespace

DiagnoseReport diagnose(const AugmentedModel& nominal, const Eigen::Ref<const Eigen::MatrixXd>& u,
                        const Eigen::Ref<const Eigen::MatrixXd>& y, const DiagnoseOptions& options) {
  return run_diagnose(nominal, u, y, nullptr, options);
}

DiagnoseReport diagnose_confirmed(const AugmentedModel& nominal, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                  const Eigen::Ref<const Eigen::MatrixXd>& y, const Eigen::Ref<const Eigen::MatrixXd>& u_confirm,
                                  const Eigen::Ref<const Eigen::MatrixXd>& y_confirm, const DiagnoseOptions& options) {
  const Recording confirm = deviation_recording(nominal, u_confirm, y_confirm);
  return run_diagnose(nominal, u, y, &confirm, options);
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
