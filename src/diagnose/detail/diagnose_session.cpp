// The steps both diagnose procedures share; see detail/diagnose_session.hpp and
// include/sysid/diagnose/diagnose.hpp for the method.
#include "diagnose/detail/diagnose_session.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "diagnose/detail/detection_context.hpp"
#include "sysid/core/format_number.hpp"
#include "diagnose/detail/residual_events.hpp"
#include "sysid/core/identification_warnings.hpp"
#include "sysid/core/parallel_for.hpp"
#include "sysid/core/poles_zeros.hpp"
#include "sysid/diagnose/feedback_check.hpp"
#include "sysid/diagnose/parameter_uncertainty.hpp"
#include "sysid/diagnose/physics_kind.hpp"
#include "sysid/validate/compare.hpp"
#include "sysid/validate/fit.hpp"

namespace sysid {

Eigen::MatrixXd simulate_from_estimated_state(const StateSpace& core, int substeps, const std::vector<OutputQuantity>& quantities,
                                              const std::vector<PhysicsBlock>& blocks, const Eigen::Ref<const Eigen::MatrixXd>& u,
                                              const Eigen::Ref<const Eigen::MatrixXd>& y, Eigen::VectorXd* x0) {
  const Eigen::MatrixXd residual = y - AugmentedSimulator(core, substeps, Eigen::VectorXd(), quantities).simulate(blocks, u);
  const Eigen::VectorXd start = estimate_initial_state(core, Eigen::MatrixXd::Zero(u.rows(), core.inputs()), residual);
  if (x0) *x0 = start;
  return AugmentedSimulator(core, substeps, start, quantities).simulate(blocks, u);
}

Recording deviation_recording(const AugmentedModel& model, const Eigen::Ref<const Eigen::MatrixXd>& u,
                              const Eigen::Ref<const Eigen::MatrixXd>& y) {
  Recording r{u, y};
  if (model.input_offset.size()) r.u.rowwise() -= model.input_offset.transpose();
  if (model.output_offset.size()) r.y.rowwise() -= model.output_offset.transpose();
  return r;
}

std::string channel_name(const std::vector<std::string>& names, long k, const char* prefix) {
  return k < static_cast<long>(names.size()) ? names[k] : prefix + std::to_string(k + 1);
}

namespace {

double mean_fit(const Eigen::Ref<const Eigen::MatrixXd>& y, const Eigen::Ref<const Eigen::MatrixXd>& y_hat) {
  return fit_percent(y, y_hat).mean();
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

/// The relative degree of output i's collocated path (input i, or the only
/// input) as the nominal's continuous equivalent shows it at the Nyquist
/// frequency w = pi / Ts, or -1 when it does not say: a force moves a mass's acceleration
/// at once (a direct feedthrough: degree 0), its velocity one integration later
/// (degree 1) and its position two. At w the path is about D + CB/(jw) +
/// CAB/(jw)^2; the degree counts only when one term dominates the others 20-fold.
/// An identified model, whose feedthrough and first Markov parameter carry noise,
/// usually does not say.
int relative_degree(const StateSpace& continuous, Eigen::Index i, double Ts) {
  const StateSpace& c = continuous;
  const Eigen::Index j = i < c.inputs() ? i : 0;
  const double w = std::numbers::pi / Ts;
  const double h0 = std::abs(c.D(i, j)), h1 = std::abs(c.C.row(i).dot(c.B.col(j))) / w,
               h2 = std::abs(c.C.row(i).dot(c.A * c.B.col(j))) / (w * w);
  constexpr double dominates = 20.0;
  if (h0 > dominates * std::max(h1, h2)) return 0;
  if (h1 > dominates * std::max(h0, h2)) return 1;
  if (h2 > dominates * std::max(h0, h1)) return 2;
  return -1;
}

/// The readings of the outputs to try for the plant's forces when some output's
/// quantity is unknown: each unknown one read as a position, as a velocity or as
/// an acceleration — those the relative degree of every unknown output allows
/// (degree 0: an acceleration, 1: a velocity, 2: a position — the plant's forces
/// are collocated with their output, and a velocity behind a spring is not a
/// collocated reading; any reading when the degree is not decisive or there is no
/// continuous equivalent; all three when no reading fits every output). Empty
/// when every quantity is known.
std::vector<std::vector<OutputQuantity>> readings_to_try(const std::vector<OutputQuantity>& quantities,
                                                         const std::optional<StateSpace>& continuous, double Ts) {
  std::vector<std::vector<OutputQuantity>> out;
  if (std::none_of(quantities.begin(), quantities.end(), [](OutputQuantity q) { return q == OutputQuantity::unknown; }))
    return out;
  const std::vector<OutputQuantity> all = {OutputQuantity::position, OutputQuantity::velocity, OutputQuantity::acceleration};
  std::vector<bool> plausible(all.size(), true);
  for (std::size_t i = 0; i < quantities.size(); ++i) {
    if (quantities[i] != OutputQuantity::unknown || !continuous) continue;
    const int degree = relative_degree(*continuous, static_cast<Eigen::Index>(i), Ts);
    if (degree < 0) continue;
    for (std::size_t r = 0; r < all.size(); ++r) plausible[r] = plausible[r] && static_cast<int>(r) == 2 - degree;
  }
  std::vector<OutputQuantity> tried;
  for (std::size_t r = 0; r < all.size(); ++r)
    if (plausible[r]) tried.push_back(all[r]);
  if (tried.empty()) tried = all;
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
  s << " was not given (--output-quantity); forces inside the plant were tried under each reading the nominal's "
       "relative degree allows, and "
    << won.candidate.block.kind << " under this one gained " << format_number(won.selection_gain, 3)
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
      << format_number(j->selection_gain, 3);
  }
  if (best_other.empty()) s << " (the only reading it allows)";
  return s.str();
}

}  // namespace

DiagnoseSession::DiagnoseSession(const AugmentedModel& nominal, const Eigen::Ref<const Eigen::MatrixXd>& u_raw,
                                 const Eigen::Ref<const Eigen::MatrixXd>& y_raw, const Recording* confirm,
                                 const DiagnoseOptions& options)
    : m_nominal(nominal), m_o(options), m_confirm(confirm) {
  check_arguments(nominal, u_raw, y_raw, confirm, options, m_seg);
  const StateSpace& model = nominal.nominal;
  m_report.warnings = record_warnings(model, u_raw, y_raw);
  m_report.fit_rows = m_seg.fit;
  m_report.estimation_rows = m_seg.estimation;
  m_log = deviation_recording(nominal, u_raw, y_raw);
  m_core = model;
  m_core_x0 = nominal.x0;
  m_substeps = options.detection.feedback_substeps > 0 ? options.detection.feedback_substeps
                                                       : (model.D.cwiseAbs().maxCoeff() > 0.0 ? 1 : 4);
  // How the outputs are read by the plant's forces: as the nominal says, and
  // where it does not, each reading in turn (readings_to_try) until a force
  // accepted under one fixes it.
  m_quantities = nominal.output_quantities;
  if (m_quantities.empty()) m_quantities.assign(static_cast<std::size_t>(model.outputs()), OutputQuantity::unknown);
  build_simulators();
  for (const auto& w : m_fine->warnings()) m_report.warnings.push_back(w);
  m_base = nominal.blocks;  // blocks already in the model stay
  m_report.nominal_refit.attempted = options.refit_nominal;
  m_report.nominal_refit.poles_before = poles(model);
  m_report.nominal_refit.poles_after = m_report.nominal_refit.poles_before;
  m_local_fit = options.fit;
  m_local_fit.global_evaluations_per_parameter = 0;
  m_y_nominal = m_fine->simulate(m_base, m_log.u);
}

std::string DiagnoseSession::readings_words() const {
  std::string words;
  const auto unknown =
      static_cast<std::size_t>(std::find(m_quantities.begin(), m_quantities.end(), OutputQuantity::unknown) - m_quantities.begin());
  for (const auto& [reading, simulator] : m_readings)
    words += (words.empty() ? "" : ", ") + std::string(quantity_name(reading[unknown]));
  return words;
}

void DiagnoseSession::build_simulators() {
  m_fast = std::make_unique<AugmentedSimulator>(m_core, 1, m_core_x0, m_quantities);
  m_fine = std::make_unique<AugmentedSimulator>(m_core, m_substeps, m_core_x0, m_quantities);
  m_readings.clear();
  for (auto& r : readings_to_try(m_quantities, m_fine->continuous_equivalent(), m_core.Ts))
    m_readings[r] = std::make_unique<AugmentedSimulator>(m_core, m_substeps, m_core_x0, r);
}

const AugmentedSimulator& DiagnoseSession::simulator_for(const std::vector<Candidate>& set,
                                                         const std::vector<PhysicsBlock>& fixed) const {
  for (const auto& c : set)
    if (!c.output_quantities.empty() && c.output_quantities != m_quantities) return *m_readings.at(c.output_quantities);
  bool feedback = std::any_of(fixed.begin(), fixed.end(),
                              [](const PhysicsBlock& b) { return b.info().stage == BlockStage::plant_feedback; });
  for (const auto& c : set) feedback = feedback || c.substeps > 1;
  return feedback ? *m_fine : *m_fast;
}

// The core and every block refitted together (refit_nominal), on rows [0, rows),
// under a reading of the outputs (the model's, or a candidate's).
LinearCoreRefitResult DiagnoseSession::refit_core(const std::vector<Candidate>& blocks, Eigen::Index rows, int steps,
                                                  const std::vector<OutputQuantity>& reading) const {
  return refit_linear_core(m_core, m_core_x0, m_base, blocks, m_log.u.topRows(rows), m_log.y.topRows(rows), rows, steps, m_o.refit,
                           reading);
}

Eigen::MatrixXd DiagnoseSession::simulate_refit(const LinearCoreRefitResult& r, int steps, Eigen::Index rows,
                                                const std::vector<OutputQuantity>& reading) const {
  return AugmentedSimulator(r.model, steps, r.x0, reading).simulate(combine_blocks(m_base, r.blocks), m_log.u, rows);
}

// A refit's core and blocks become the model's.
void DiagnoseSession::adopt(const LinearCoreRefitResult& r) {
  m_core = r.model;
  m_core_x0 = r.x0;
  m_accepted = r.blocks;
  build_simulators();
}

void DiagnoseSession::locate() {
  const Eigen::Index E = m_seg.estimation;
  const auto& u = m_log.u;
  const auto& y = m_log.y;
  m_report.location = locate_mismatch(u.topRows(E), y.topRows(E), (y - m_y_nominal).topRows(E), m_y_nominal.topRows(E),
                                      m_core.Ts, m_o.location);
  try {
    m_report.closed_loop = check_output_feedback(u.topRows(E), y.topRows(E), m_y_nominal.topRows(E), m_core.Ts);
  } catch (const std::invalid_argument&) {
    // Too short a record for the test's regression: not tested (closed_loop.tested false).
  }
  if (m_report.closed_loop.feedback_detected)
    m_report.warnings.push_back(
        "diagnose: " + m_report.closed_loop.evidence +
        "; the measurement noise fed back through the controller also correlates with the logged input, so small "
        "effects' fitted parameters may be biased: confirm them on an open-loop record or with --validate");
}

std::vector<Candidate> DiagnoseSession::propose() const {
  const std::vector<PhysicsBlock> fixed = combine_blocks(m_base, m_accepted);
  const Eigen::Index fit_rows = m_seg.fit;
  DetectionData data;
  data.simulator = m_fine.get();
  for (const auto& [reading, simulator] : m_readings) data.plant_readings.push_back(simulator.get());
  data.accepted = fixed;
  data.identified_operating_point = m_nominal.input_offset.size() > 0 && m_nominal.input_offset.cwiseAbs().maxCoeff() > 0.0;
  data.u = m_log.u.topRows(fit_rows);
  data.y = m_log.y.topRows(fit_rows);
  data.current = simulator_for({}, fixed).simulate(fixed, m_log.u, fit_rows);
  data.Ts = m_core.Ts;
  // Candidate frequencies come from the location of the nominal's residual
  // (bands, peaks), computed once.
  for (const auto& ch : m_report.location.outputs) {
    for (const auto& band : ch.bands) data.mode_frequencies_hz.push_back(band.peak_hz);
    for (const auto& peak : ch.peaks) data.peak_frequencies_hz.push_back(peak.freq_hz);
    if (ch.freq_hz.size() > 1) data.frequency_resolution_hz = ch.freq_hz[1] - ch.freq_hz[0];
  }
  std::vector<Candidate> candidates = propose_candidates(data, m_o.detection);
  if (static_cast<int>(candidates.size()) > m_o.candidates_per_round) candidates.resize(static_cast<std::size_t>(m_o.candidates_per_round));
  return candidates;
}

JudgedRound DiagnoseSession::judge(const std::vector<Candidate>& candidates, int round, Eigen::Index scored_from,
                                   const Recording* test, double threshold) {
  const auto& u = m_log.u;
  const auto& y = m_log.y;
  const Eigen::Index fit_rows = m_seg.fit, scored = m_seg.estimation - scored_from;
  const auto u_fit = u.topRows(fit_rows);
  const auto y_fit = y.topRows(fit_rows);
  const std::vector<PhysicsBlock> fixed = combine_blocks(m_base, m_accepted);
  const AugmentedSimulator& current_sim = simulator_for({}, fixed);
  // With refit_nominal every candidate is fitted together with the linear core,
  // and judged against the core refitted alone on the same rows: both have seen
  // the same data, so the test asks whether the physics helps beyond a better
  // linear fit (the nominal itself may have been identified on the selection
  // segment, which would favour it).
  Eigen::MatrixXd reference = current_sim.simulate(fixed, u, m_seg.estimation), reference_test;
  if (test) reference_test = simulate_from_estimated_state(m_core, current_sim.substeps(), m_quantities, fixed, test->u, test->y);
  if (m_o.refit_nominal) {
    const LinearCoreRefitResult alone = refit_core(m_accepted, fit_rows, current_sim.substeps(), m_quantities);
    if (alone.refitted) {
      reference = simulate_refit(alone, current_sim.substeps(), m_seg.estimation, m_quantities);
      if (test)
        reference_test = simulate_from_estimated_state(alone.model, current_sim.substeps(), m_quantities,
                                                       combine_blocks(m_base, alone.blocks), test->u, test->y);
    } else if (round == 1) {  // e.g. too large a nominal: the candidates are judged on the nominal as given
      for (const auto& w : alone.warnings) m_report.warnings.push_back("diagnose: " + w);
    }
  }
  const double before_fit = mean_fit(y.middleRows(scored_from, scored), reference.middleRows(scored_from, scored));
  JudgedRound out;
  out.judged.resize(candidates.size());
  out.refits.resize(candidates.size());
  // Candidates are independent: fit them on all cores (each thread its own NLopt
  // instance; the simulators are read-only).
  parallel_for(candidates.size(), [&](std::size_t index) {
    const Candidate& cand = candidates[index];
    const AugmentedSimulator& sim = simulator_for({cand}, fixed);
    CandidateFitResult fitted = fit_candidates(sim, fixed, {cand}, u_fit, y_fit, fit_rows, m_o.fit);
    JudgedCandidate& j = out.judged[index];
    j.candidate = fitted.fitted.front();
    j.round = round;
    // Honest parameters: terms the data do not show are held at their null value
    // (and the rest refitted), and a candidate whose defining parameter is within
    // two standard errors of its null value may not win the round.
    judge_parameters(sim, fixed, j, fit_rows, threshold);
    fitted.fitted = {j.candidate};
    Eigen::MatrixXd after;
    const StateSpace* candidate_core = &m_core;
    std::vector<PhysicsBlock> blocks;
    if (m_o.refit_nominal) {
      std::vector<Candidate> all = m_accepted;
      all.push_back(j.candidate);
      LinearCoreRefitResult r = refit_core(all, fit_rows, sim.substeps(), sim.output_quantities());
      if (r.refitted) {
        after = simulate_refit(r, sim.substeps(), m_seg.estimation, sim.output_quantities());
        j.candidate = r.blocks.back();
        blocks = combine_blocks(m_base, r.blocks);
        out.refits[index] = std::move(r);
        candidate_core = &out.refits[index]->model;
      }
    }
    if (after.size() == 0) {
      blocks = combine_blocks(fixed, fitted.fitted);
      after = sim.simulate(blocks, u, m_seg.estimation);
    }
    j.selection_gain = mean_fit(y.middleRows(scored_from, scored), after.middleRows(scored_from, scored)) - before_fit;
    if (test) {
      const Eigen::MatrixXd after_test =
          simulate_from_estimated_state(*candidate_core, sim.substeps(), sim.output_quantities(), blocks, test->u, test->y);
      j.t_statistic = improvement_z(test->y, reference_test, after_test, 0, test->y.rows(), m_o.max_correlation_lag);
    } else {
      j.t_statistic = improvement_z(y, reference, after, m_seg.fit, m_seg.estimation, m_o.max_correlation_lag);
    }
    j.t_threshold = threshold;
  });
  return out;
}

void DiagnoseSession::judge_parameters(const AugmentedSimulator& sim, const std::vector<PhysicsBlock>& fixed, JudgedCandidate& j,
                                       Eigen::Index rows, double threshold) const {
  const auto u = m_log.u.topRows(rows);
  const auto y = m_log.y.topRows(rows);
  auto uncertainty = [&] { return candidate_uncertainty(parameter_uncertainty(sim, fixed, {j.candidate}, u, y, rows), {j.candidate}, 0); };
  try {
    CandidateUncertainty cu = uncertainty();
    // An optional term is one more hypothesis of the round: it must pass the
    // round's threshold (a Wald test), not just two standard errors.
    const auto held = insignificant_optional_terms(j.candidate, cu.standard_errors, std::max(threshold, kParameterZ));
    if (!held.empty()) {
      hold_at_null(j.candidate, held);
      j.candidate = fit_candidates(sim, fixed, {j.candidate}, u, y, rows, m_local_fit).fitted.front();
      cu = uncertainty();
    }
    j.standard_errors = cu.standard_errors;
    j.parameters_significant = defining_parameter_differs(j.candidate, cu.standard_errors, kParameterZ, &j.parameter_evidence);
  } catch (const std::invalid_argument& e) {
    // Cannot happen for a fit's own result; kept honest if it does.
    j.parameters_significant = false;
    j.parameter_evidence = std::string("no standard errors: ") + e.what();
  }
}

double DiagnoseSession::penalised_gain(const JudgedCandidate& j) const {
  return j.selection_gain - m_o.penalty_points_per_parameter * static_cast<double>(j.candidate.free.size());
}

void DiagnoseSession::record(const JudgedRound& round) {
  for (const auto& j : round.judged) m_report.considered.push_back(j);
}

// A force accepted under one reading of the outputs fixes their quantities.
void DiagnoseSession::fix_reading(const JudgedRound& round, int best) {
  const auto& r = round.judged[static_cast<std::size_t>(best)].candidate.output_quantities;
  if (r.empty() || r == m_quantities) return;
  m_report.reading_note = reading_note(m_quantities, r, round.judged, best, m_core.output_names);
  m_quantities = r;
  build_simulators();
}

void DiagnoseSession::accept(const JudgedRound& round, int best, bool refit_blocks) {
  const auto index = static_cast<std::size_t>(best);
  m_acceptance.push_back(round.judged[index]);
  fix_reading(round, best);
  if (round.refits[index]) {
    // The core moves with the blocks (fitted together on the fit segment).
    adopt(*round.refits[index]);
    m_report.nominal_refit.applied = true;
    return;
  }
  m_accepted.push_back(round.judged[index].candidate);
  if (refit_blocks) {
    const Eigen::Index rows = m_seg.fit;
    m_accepted = fit_candidates(simulator_for(m_accepted, m_base), m_base, m_accepted, m_log.u.topRows(rows),
                                m_log.y.topRows(rows), rows, m_local_fit)
                     .fitted;
  }
}

void DiagnoseSession::refit_on_estimation_rows() {
  if (m_accepted.empty()) return;
  const Eigen::Index rows = m_seg.estimation;
  if (m_report.nominal_refit.applied) {
    adopt(refit_core(m_accepted, rows, simulator_for(m_accepted, m_base).substeps(), m_quantities));
    m_report.nominal_refit.poles_after = poles(m_core);
    return;
  }
  m_accepted = fit_candidates(simulator_for(m_accepted, m_base), m_base, m_accepted, m_log.u.topRows(rows), m_log.y.topRows(rows),
                              rows, m_local_fit)
                   .fitted;
}

void DiagnoseSession::hold_unneeded_optional_terms(Eigen::Index rows) {
  if (m_report.nominal_refit.applied || m_accepted.size() < 2) return;
  const auto u = m_log.u.topRows(rows);
  const auto y = m_log.y.topRows(rows);
  for (std::size_t k = 0; k < m_accepted.size(); ++k) {
    const auto& terms = m_accepted[k].block.info().optional_terms;
    std::vector<DefiningParameter> free_terms;
    for (const auto& d : terms)
      if (std::any_of(m_accepted[k].free.begin(), m_accepted[k].free.end(), [&](const FreeParameter& f) { return f.name == d.name; }))
        free_terms.push_back(d);
    if (free_terms.empty()) continue;
    std::vector<Candidate> reduced = m_accepted;
    hold_at_null(reduced[k], free_terms);
    // The accepted findings are fitted on these rows already (refitted there, or
    // the very models the recording confirmed): only the reduced set is fitted.
    const double full = simulation_cost(simulator_for(m_accepted, m_base), combine_blocks(m_base, m_accepted), u, y, rows);
    const CandidateFitResult without = fit_candidates(simulator_for(reduced, m_base), m_base, reduced, u, y, rows, m_local_fit);
    // A term accepted with its kind in an early round may be what a later
    // finding explains better (a one-sided friction standing in for a constant
    // force): the simpler model is kept when it fits the same rows as well, to
    // within a few times what one parameter fitting noise gains (1 / rows).
    if (without.cost <= full * (1.0 + 5.0 / static_cast<double>(rows))) {
      m_accepted = without.fitted;
      m_report.warnings.push_back("diagnose: " + m_accepted[k].block.kind + ": " + std::string(free_terms.front().name) +
                                  " held at " + format_number(free_terms.front().null_value, 3) +
                                  ": with the later findings it no longer improves the fit");
    }
  }
}

std::string DiagnoseSession::best_alternative(const JudgedCandidate& accepted) const {
  const JudgedCandidate* best = nullptr;
  for (const auto& j : m_report.considered)
    if (j.round == accepted.round && j.candidate.block.kind != accepted.candidate.block.kind &&
        (!best || j.selection_gain > best->selection_gain))
      best = &j;
  if (!best) return "no other kind was fitted in its round";
  return "in its round (" + std::to_string(accepted.round) + ") it gained " + format_number(accepted.selection_gain, 3) +
         " points on the selection data; the best other kind, " + best->candidate.block.kind + ", " +
         format_number(best->selection_gain, 3) + (best->significant ? "" : " (not accepted: " + std::string(
                                                                        !best->parameters_significant ? "its parameters are not significant"
                                                                        : best->t_statistic <= best->t_threshold ? "not significant"
                                                                                                                 : "a smaller gain") + ")");
}

void DiagnoseSession::order_by_importance(std::vector<CandidateUncertainty>& uncertainty) {
  if (m_accepted.size() < 2) return;
  const Eigen::Index rows = m_seg.estimation;
  const auto u = m_log.u.topRows(rows);
  const auto y = m_log.y.topRows(rows);
  std::vector<std::size_t> remaining(m_accepted.size()), order;
  for (std::size_t k = 0; k < remaining.size(); ++k) remaining[k] = k;
  std::vector<Candidate> chosen;
  while (!remaining.empty()) {
    std::size_t best = 0;
    double best_cost = std::numeric_limits<double>::infinity();
    for (std::size_t r = 0; r < remaining.size(); ++r) {
      std::vector<Candidate> trial = chosen;
      trial.push_back(m_accepted[remaining[r]]);
      const double cost = simulation_cost(simulator_for(trial, m_base), combine_blocks(m_base, trial), u, y, rows);
      if (cost < best_cost) best_cost = cost, best = r;
    }
    order.push_back(remaining[best]);
    chosen.push_back(m_accepted[remaining[best]]);
    remaining.erase(remaining.begin() + static_cast<std::ptrdiff_t>(best));
  }
  std::vector<JudgedCandidate> acceptance;
  std::vector<CandidateUncertainty> ordered_uncertainty;
  for (std::size_t k : order) {
    acceptance.push_back(m_acceptance[k]);
    ordered_uncertainty.push_back(uncertainty[k]);
  }
  m_accepted = chosen;
  m_acceptance = acceptance;
  uncertainty = ordered_uncertainty;
}

std::vector<CandidateUncertainty> DiagnoseSession::final_uncertainty() {
  const Eigen::Index rows = m_seg.estimation;
  const auto u = m_log.u.topRows(rows);
  const auto y = m_log.y.topRows(rows);
  std::vector<CandidateUncertainty> out;
  hold_unneeded_optional_terms(rows);
  // A finding accepted in an early round may lose its significance when later
  // ones are fitted with it: each pass drops those whose defining parameter is
  // within two standard errors of its null value, refits the rest, and checks again.
  for (bool dropped = true; dropped && !m_accepted.empty();) {
    dropped = false;
    out.clear();
    const AugmentedSimulator& sim = simulator_for(m_accepted, m_base);
    const ParameterUncertainty joint = parameter_uncertainty(sim, m_base, m_accepted, u, y, rows);
    for (std::size_t k = 0; k < m_accepted.size(); ++k) out.push_back(candidate_uncertainty(joint, m_accepted, k));
    for (std::size_t k = m_accepted.size(); k-- > 0;) {
      std::string why;
      if (defining_parameter_differs(m_accepted[k], out[k].standard_errors, kParameterZ, &why)) continue;
      m_report.warnings.push_back("diagnose: " + m_accepted[k].block.kind + " was accepted in round " +
                                  std::to_string(m_acceptance[k].round) + " but is not reported: fitted with the other findings, " +
                                  why + " (needs more than " + format_number(kParameterZ, 2) + ")");
      m_accepted.erase(m_accepted.begin() + static_cast<std::ptrdiff_t>(k));
      m_acceptance.erase(m_acceptance.begin() + static_cast<std::ptrdiff_t>(k));
      dropped = true;
    }
    if (dropped && !m_accepted.empty() && !m_report.nominal_refit.applied)
      m_accepted = fit_candidates(simulator_for(m_accepted, m_base), m_base, m_accepted, u, y, rows, m_local_fit).fitted;
    if (!dropped)
      for (const auto& w : joint.warnings) m_report.warnings.push_back("diagnose: standard errors: " + w);
  }
  return out;
}

DiagnoseReport DiagnoseSession::finish(
    const std::function<Eigen::VectorXd(const std::vector<Candidate>&, const Eigen::MatrixXd&)>& validation_fit,
    const std::string& validation) {
  DiagnoseReport& report = m_report;
  const StateSpace& model = m_nominal.nominal;
  const double Ts = model.Ts;
  if (report.nominal_refit.applied) report.nominal_refit.poles_after = poles(m_core);
  std::vector<CandidateUncertainty> uncertainty = final_uncertainty();
  order_by_importance(uncertainty);
  std::vector<Candidate> so_far;
  Eigen::MatrixXd previous = m_y_nominal;
  report.fit_before_per_output = validation_fit(so_far, m_y_nominal);
  report.fit_before = report.fit_before_per_output.mean();
  Eigen::VectorXd previous_fit = report.fit_before_per_output;
  for (std::size_t k = 0; k < m_accepted.size(); ++k) {
    const Candidate& c = m_accepted[k];
    so_far.push_back(c);
    const Eigen::MatrixXd next = simulator_for(so_far, m_base).simulate(combine_blocks(m_base, so_far), m_log.u);
    const Eigen::VectorXd next_fit = validation_fit(so_far, next);
    Finding f;
    f.candidate = c;
    f.fit_before = previous_fit.mean();
    f.fit_after = next_fit.mean();
    f.selection_gain = m_acceptance[k].selection_gain;
    f.t_statistic = m_acceptance[k].t_statistic;
    f.band_hz = band_of(c.block, report.location);
    f.time_windows_s = explained_windows(report.location, m_log.y, m_y_nominal, previous, next, m_seg.estimation, Ts);
    f.summary = finding_summary(c.block, model.input_names, model.output_names, Ts);
    f.uncertainty = physics_kind(c.block.kind).reported_uncertainty(c, uncertainty[k]);
    f.alternative = best_alternative(m_acceptance[k]);
    {
      const Eigen::Index E = m_seg.estimation;
      const Eigen::VectorXd residual = (m_log.y.col(c.block.output) - previous.col(c.block.output)).head(E);
      const Eigen::VectorXd velocity =
          reading_velocity(previous.col(c.block.output).head(E), m_quantities[static_cast<std::size_t>(c.block.output)], Ts);
      const Eigen::VectorXd command = m_log.u.col(c.block.input).head(E);
      f.where = physics_kind(c.block.kind).where_evidence(c.block, {residual, velocity, command, Ts});
    }
    (void)defining_parameter_differs(c, uncertainty[k].standard_errors, kParameterZ, &f.parameter_evidence);
    report.findings.push_back(f);
    previous = next;
    previous_fit = next_fit;
  }
  if (report.findings.empty() && report.location.any_mismatch) {
    std::string fired;
    for (const auto& f : report.location.fired) fired += (fired.empty() ? "" : ", ") + f;
    report.warnings.push_back("diagnose: the recording disagrees with the simulation (mismatch tests fired: " + fired +
                              "; validation fit " + format_number(report.fit_before, 4) +
                              " %) but no kind of physics in the library explains it significantly: an empty list of "
                              "findings here does not mean the simulation is right");
  }
  report.fit_after_per_output = previous_fit;
  report.fit_after = report.fit_after_per_output.mean();
  report.simulated_before = m_y_nominal;
  report.simulated_after = previous;
  if (m_nominal.output_offset.size()) {
    report.simulated_before.rowwise() += m_nominal.output_offset.transpose();
    report.simulated_after.rowwise() += m_nominal.output_offset.transpose();
  }
  report.validation = validation;
  report.augmented = m_nominal;
  report.augmented.blocks = combine_blocks(m_base, m_accepted);
  report.augmented.output_quantities = m_quantities;
  report.output_quantities = m_quantities;
  if (report.reading_note.empty() &&
      std::any_of(m_quantities.begin(), m_quantities.end(), [](OutputQuantity q) { return q == OutputQuantity::unknown; }))
    report.reading_note = "the quantity of some outputs was not given (--output-quantity): forces inside the plant were tried "
                          "under each reading the nominal's relative degree allows (" + readings_words() +
                          ") and none was accepted, so the quantities stay unknown";
  report.augmented.substeps = simulator_for(m_accepted, m_base).substeps();
  if (report.nominal_refit.applied) {
    report.augmented.nominal = m_core;
    report.augmented.x0 = m_core_x0;
    report.warnings.push_back(
        "diagnose: the nominal's linear dynamics were refitted with the findings (refit_nominal); the augmented model "
        "carries the refitted core, and every finding's fit_after is measured with it");
  }
  return std::move(m_report);
}

}  // namespace sysid
