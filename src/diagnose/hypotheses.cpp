// Detectors of the physics hypotheses; the method is documented in
// include/sysid/diagnose/hypotheses.hpp.
#include "sysid/diagnose/hypotheses.hpp"
#include "sysid/core/format_number.hpp"
#include "sysid/core/math_constants.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

namespace sysid {

namespace {

constexpr double kTiny = std::numeric_limits<double>::min();

/// The eigen-decomposition of the nominal's continuous equivalent A = V diag(p) V^-1,
/// with C V and V^-1 B: every path's modal residues r = (C V)_ik (V^-1 B)_kj.
/// Empty (no poles) when there is no continuous equivalent or V is (nearly)
/// defective — no reliable residues then.
struct ModalBasis {
  Eigen::VectorXcd poles;
  Eigen::MatrixXcd output_shapes;  ///< C V, l x n
  Eigen::MatrixXcd input_shapes;   ///< V^-1 B, n x m
};

ModalBasis modal_basis(const DetectionData& d) {
  ModalBasis basis;
  const auto& continuous = d.simulator->continuous_equivalent();
  if (!continuous) return basis;
  Eigen::EigenSolver<Eigen::MatrixXd> eig(continuous->A);
  if (eig.info() != Eigen::Success) return basis;
  const Eigen::MatrixXcd V = eig.eigenvectors();
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXcd>(V).singularValues();
  if (!(sv(sv.size() - 1) > 1e-10 * sv(0))) return basis;
  basis.poles = eig.eigenvalues();
  basis.output_shapes = continuous->C.cast<std::complex<double>>() * V;
  basis.input_shapes = V.partialPivLu().solve(continuous->B.cast<std::complex<double>>());
  return basis;
}

/// Shared quantities of the detection data.
struct Context {
  const DetectionData& d;
  const DetectionOptions& o;
  Eigen::Index rows = 0, m = 0, l = 0;
  Eigen::VectorXd output_weight;  ///< 1 / std(y_i)
  Eigen::MatrixXd residual;       ///< y - current
  double residual_energy = 0.0;   ///< weighted
  ModalBasis nominal_basis;       ///< of the nominal, once for every path

  Context(const DetectionData& data, const DetectionOptions& options)
      : d(data), o(options), nominal_basis(modal_basis(data)) {
    rows = d.y.rows();
    m = d.u.cols();
    l = d.y.cols();
    output_weight.resize(l);
    for (Eigen::Index i = 0; i < l; ++i) {
      const double sd = std::sqrt((d.y.col(i).array() - d.y.col(i).mean()).square().mean());
      output_weight[i] = 1.0 / std::max(sd, kTiny);
    }
    residual = d.y - d.current;
    residual_energy = weighted(residual).squaredNorm();
  }

  Eigen::VectorXd weighted(const Eigen::MatrixXd& signal) const {
    Eigen::MatrixXd w = signal * output_weight.asDiagonal();
    return Eigen::Map<const Eigen::VectorXd>(w.data(), w.size());
  }
  /// Weighted change of the output when `block` is added to the accepted ones.
  Eigen::VectorXd effect(const PhysicsBlock& block) const {
    std::vector<PhysicsBlock> blocks = d.accepted;
    blocks.push_back(block);
    return weighted(d.simulator->simulate(blocks, d.u, rows) - d.current);
  }
  /// Fraction of the residual energy explained by adding `effect` as it is.
  double explained_as_is(const Eigen::VectorXd& change) const {
    const Eigen::VectorXd r = weighted(residual);
    return residual_energy > 0 ? 1.0 - (r - change).squaredNorm() / residual_energy : 0.0;
  }
  /// Least squares of the residual on the columns of G: coefficients and the
  /// fraction of the residual energy they explain (QR, no normal equations).
  std::pair<Eigen::VectorXd, double> regress(const Eigen::MatrixXd& G) const {
    const Eigen::VectorXd r = weighted(residual);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(G);
    if (qr.rank() < G.cols() || residual_energy <= 0) return {Eigen::VectorXd::Zero(G.cols()), 0.0};
    const Eigen::VectorXd c = qr.solve(r);
    return {c, 1.0 - (r - G * c).squaredNorm() / residual_energy};
  }
  double rms(const Eigen::VectorXd& x) const { return std::sqrt(x.squaredNorm() / std::max<double>(1, x.size())); }
  double duration() const { return static_cast<double>(rows) * d.Ts; }
};

/// Columns: the weighted output change per unit of each probed parameter, each
/// probe taken alone from `block` (whose effect must vanish as it is) by its step.
Eigen::MatrixXd sensitivities(const Context& c, const PhysicsBlock& block,
                              const std::vector<std::pair<std::string, double>>& probes) {
  Eigen::MatrixXd G(c.rows * c.l, static_cast<Eigen::Index>(probes.size()));
  for (std::size_t k = 0; k < probes.size(); ++k) {
    PhysicsBlock probed = block;
    probed.params[probes[k].first] += probes[k].second;
    G.col(static_cast<Eigen::Index>(k)) = c.effect(probed) / probes[k].second;
  }
  return G;
}

PhysicsBlock make_block(const std::string& kind, long input, long output) {
  PhysicsBlock b;
  b.kind = kind;
  b.input = input;
  b.output = output;
  for (const char* name : b.info().parameters) b.params[name] = 0.0;
  return b;
}

std::string percent(double fraction) {
  std::ostringstream s;
  s.precision(3);
  s << 100.0 * fraction << " %";
  return s.str();
}

/// A single-parameter effect vanishing at p0: the sensitivity regression.
Candidate linearised(const Context& c, PhysicsBlock block, const std::string& name, double p0, double delta,
                     FreeParameter bound, int substeps, const std::string& what) {
  block.params[name] = p0;
  const auto [coefficient, explained] = c.regress(sensitivities(c, block, {{name, delta}}));
  Candidate cand;
  const double start = std::clamp(p0 + coefficient[0], bound.lower, bound.upper);
  block.params[name] = bound.log_scale ? std::max(start, bound.lower) : start;
  cand.block = block;
  cand.free = {bound};
  cand.substeps = substeps;
  cand.detector_score = std::max(0.0, explained);
  cand.evidence = what + " explains " + percent(cand.detector_score) + " of the residual energy (linearised)";
  return cand;
}

void add_sensor_candidates(const Context& c, std::vector<Candidate>& out) {
  for (Eigen::Index i = 0; i < c.l; ++i) {
    const double y_rms = c.rms(c.d.y.col(i).array() - c.d.y.col(i).mean());
    out.push_back(linearised(c, make_block("gain_error", 0, i), "ratio", 1.0, 0.01, {"ratio", 0.5, 2.0, false}, 1,
                             "a scaled copy of the simulated output"));
    {  // offset and drift are linear: two regressors, exact least squares.
      PhysicsBlock b = make_block("offset_drift", 0, i);
      const auto [coef, explained] = c.regress(sensitivities(c, b, {{"offset", 1.0}, {"slope", 1.0}}));
      const double T = c.duration();
      b.params["offset"] = std::clamp(coef[0], -3 * y_rms, 3 * y_rms);
      b.params["slope"] = std::clamp(coef[1], -3 * y_rms / T, 3 * y_rms / T);
      Candidate cand{b, {{"offset", -3 * y_rms, 3 * y_rms}, {"slope", -3 * y_rms / T, 3 * y_rms / T}}, 1,
                     std::max(0.0, explained), "a constant and a ramp explain " + percent(std::max(0.0, explained)) +
                                                   " of the residual energy"};
      out.push_back(cand);
    }
    for (double f0 : c.d.peak_frequencies_hz) {
      // Zoom around the spectral peak: the cost of a sine in frequency is as
      // narrow as 1/T, far finer than the spectral bins, so scan at 0.05/T.
      const double T = c.duration(), df = std::max(c.d.frequency_resolution_hz, 1.0 / T);
      const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(c.rows, 0.0, (c.rows - 1) * c.d.Ts);
      const Eigen::VectorXd r = c.residual.col(i);
      double best_f = f0, best_power = -1, best_a = 0, best_b = 0;
      for (double f = std::max(f0 - 1.5 * df, 0.5 / T); f <= f0 + 1.5 * df; f += 0.05 / T) {
        Eigen::MatrixXd G(c.rows, 2);
        G.col(0) = (kTwoPi * f * t.array()).sin();
        G.col(1) = (kTwoPi * f * t.array()).cos();
        const Eigen::Vector2d ab = (G.transpose() * G).ldlt().solve(G.transpose() * r);  // 2x2, well conditioned
        const double power = (G * ab).squaredNorm();
        if (power > best_power) best_power = power, best_f = f, best_a = ab[0], best_b = ab[1];
      }
      PhysicsBlock b = make_block("periodic_disturbance", 0, i);
      const double amplitude = std::hypot(best_a, best_b), phase = std::atan2(best_b, best_a);
      b.params["freq_hz"] = best_f;
      b.params["amplitude"] = amplitude;
      b.params["phase_rad"] = phase;
      const double explained = c.explained_as_is(c.effect(b));
      out.push_back({b,
                     {{"freq_hz", best_f - 0.5 / T, best_f + 0.5 / T},
                      {"amplitude", 0.0, 3.0 * amplitude + kTiny},
                      {"phase_rad", phase - std::numbers::pi, phase + std::numbers::pi}},
                     1, std::max(0.0, explained),
                     "a residual peak not coherent with the input; a sine explains " + percent(std::max(0.0, explained))});
    }
  }
}

void add_mode_candidates(const Context& c, long j, long i, std::vector<Candidate>& out) {
  for (double f0 : c.d.mode_frequencies_hz) {
    // Grid in frequency and damping; at each point the two residue gains enter
    // linearly and are solved by least squares.
    Candidate best;
    best.detector_score = -1;
    const double f_max = 0.49 / c.d.Ts;  // a mode must stay below Nyquist
    for (double scale : {0.97, 0.985, 1.0, 1.015, 1.03}) {
      if (f0 * scale >= f_max) continue;
      for (double zeta : {0.005, 0.02, 0.06}) {
        PhysicsBlock b = make_block("missing_mode", j, i);
        b.params["freq_hz"] = f0 * scale;
        b.params["damping"] = zeta;
        const auto [coef, explained] = c.regress(sensitivities(c, b, {{"static_gain", 1.0}, {"velocity_gain", 1.0}}));
        if (explained > best.detector_score) {
          b.params["static_gain"] = coef[0];
          b.params["velocity_gain"] = coef[1];
          best.block = b;
          best.detector_score = explained;
        }
      }
    }
    if (best.detector_score < 0) continue;  // every grid point beyond Nyquist
    const double f = best.block.param("freq_hz");
    const double gs = best.block.param("static_gain"), gv = best.block.param("velocity_gain");
    const double reach = 4.0 * std::max(std::abs(gs), std::abs(gv)) + kTiny;
    best.free = {{"freq_hz", 0.85 * f, std::min(1.15 * f, f_max), true},
                 {"damping", 0.001, 0.2, true},
                 {"static_gain", -reach, reach},
                 {"velocity_gain", -reach, reach}};
    best.detector_score = std::max(0.0, best.detector_score);
    best.evidence = "the model-error FRF is significant near " + std::to_string(f0) + " Hz; a mode there explains " +
                    percent(best.detector_score);
    out.push_back(best);
  }
}

/// The grid point whose effect, taken as is, explains most of the residual.
/// Starts below every score: an effect larger than the residual explains a
/// negative fraction (below -1 when the nominal is right), and the least bad grid
/// point must still be returned as the optimiser's start.
Candidate best_as_is(const Context& c, const std::vector<PhysicsBlock>& grid) {
  Candidate best;
  best.block = grid.front();
  best.detector_score = -std::numeric_limits<double>::infinity();
  for (const auto& b : grid) {
    const double explained = c.explained_as_is(c.effect(b));
    if (explained > best.detector_score) best.block = b, best.detector_score = explained;
  }
  return best;
}

/// The nominal's real discrete poles in (0, 1), slowest first: the first-order
/// stores (tanks, thermal masses) an input could fill.
std::vector<double> store_poles(const Context& c) {
  std::vector<double> poles;
  Eigen::EigenSolver<Eigen::MatrixXd> eig(c.d.simulator->nominal().A, false);
  if (eig.info() != Eigen::Success) return poles;
  for (Eigen::Index k = 0; k < eig.eigenvalues().size(); ++k) {
    const std::complex<double> p = eig.eigenvalues()(k);
    if (std::abs(p.imag()) <= 1e-12 * std::abs(p) && p.real() > 0.0 && p.real() < 1.0) poles.push_back(p.real());
  }
  std::sort(poles.begin(), poles.end(), std::greater<>());
  return poles;
}

/// Lowest and highest level of a first-order store (pole a, unit DC gain) filled
/// by u from equilibrium with its first sample, without overflow.
std::pair<double, double> store_level_range(const Eigen::VectorXd& u, double a) {
  double level = u[0], low = level, high = level;
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    level = a * level + (1.0 - a) * u[k];
    low = std::min(low, level);
    high = std::max(high, level);
  }
  return {low, high};
}

/// saturation of a store (physics_block.hpp): the input fills a first-order store
/// with one of the nominal's real poles, which overflows above a level. Grid over
/// the pole (the four slowest), the level (fractions of the store's range) and
/// the spill.
void add_store_overflow_candidate(const Context& c, long j, long out_channel, std::vector<Candidate>& out) {
  std::vector<double> poles = store_poles(c);
  if (poles.empty()) return;
  if (poles.size() > 4) poles.resize(4);
  const Eigen::VectorXd uj = c.d.u.col(j);
  std::vector<PhysicsBlock> grid;
  for (double a : poles) {
    const auto [low, high] = store_level_range(uj, a);
    for (double q : {0.95, 0.85, 0.75, 0.6, 0.45})
      for (double spill : {0.0, 0.5}) {
        PhysicsBlock b = make_block("saturation", j, out_channel);
        b.params["limit"] = low + q * (high - low);
        b.params["storage_pole"] = a;
        b.params["spill"] = spill;
        grid.push_back(b);
      }
  }
  Candidate best = best_as_is(c, grid);
  const double a = best.block.param("storage_pole");
  const auto [low, high] = store_level_range(uj, a);
  // The pole may move by a factor of two in time constant: a nominal fitted to
  // the saturating store holds a compromise of its dynamics.
  best.free = {{"limit", low + 0.3 * (high - low), high}, {"storage_pole", a * a, std::sqrt(a)}, {"spill", 0.0, 1.0}};
  best.detector_score = std::max(0.0, best.detector_score);
  best.evidence = "a store filled by the input (pole " + std::to_string(a) + ") overflowing above " +
                  std::to_string(best.block.param("limit")) + " explains " + percent(best.detector_score);
  out.push_back(best);
}

void add_actuator_candidates(const Context& c, long j, std::vector<Candidate>& out) {
  const long out_channel = j < c.l ? j : 0;
  const Eigen::VectorXd uj = c.d.u.col(j);
  const double u_rms = c.rms(uj), u_max = uj.cwiseAbs().maxCoeff(), u_range = uj.maxCoeff() - uj.minCoeff();
  const double Ts = c.d.Ts;
  // A constant input (zero or not) carries no evidence about the actuator: every
  // effect below would be a constant too (and the Bouc-Wen scale 1/range infinite).
  if (!(u_rms > 0) || !(u_range > 0)) return;
  out.push_back(linearised(c, make_block("time_delay", j, out_channel), "delay_s", 0.0, Ts,
                           {"delay_s", 0.0, c.o.max_delay_samples * Ts}, 1, "a delayed copy of the input"));
  {
    // A lag of time constant tau acts like -tau du/dt at low frequency; the
    // sensitivity is taken in tau and the start converted to a corner.
    PhysicsBlock b = make_block("input_lag", j, out_channel);
    const double tau_probe = 0.25 * Ts;
    b.params["corner_hz"] = 1.0 / (kTwoPi * tau_probe);
    const Eigen::VectorXd g = c.effect(b) / tau_probe;
    const auto [coef, explained] = c.regress(g);
    const double lo = 0.002 / Ts, hi = 1.0 / Ts;
    const double tau = std::max(coef[0], 1.0 / (kTwoPi * hi));
    b.params["corner_hz"] = std::clamp(1.0 / (kTwoPi * tau), lo, hi);
    out.push_back({b, {{"corner_hz", lo, hi, true}}, 1, std::max(0.0, explained),
                   "a low-passed input explains " + percent(std::max(0.0, explained)) + " (linearised)"});
  }
  out.push_back(linearised(c, make_block("deadzone", j, out_channel), "width", 0.0, 0.01 * u_rms,
                           {"width", 0.0, u_max}, 1, "a dead band around zero input"));
  out.push_back(linearised(c, make_block("backlash", j, out_channel), "width", 0.0, 0.01 * u_rms,
                           {"width", 0.0, u_max}, 1, "play at input reversals"));
  {
    // Saturation is not smooth where it vanishes (limit = max |u|): grid of limits.
    std::vector<PhysicsBlock> grid;
    for (double q : {0.995, 0.98, 0.95, 0.9, 0.85, 0.8, 0.7}) {
      PhysicsBlock b = make_block("saturation", j, out_channel);
      b.params["limit"] = q * u_max;
      grid.push_back(b);
    }
    Candidate best = best_as_is(c, grid);
    best.free = {{"limit", 0.3 * u_max, u_max}};
    best.detector_score = std::max(0.0, best.detector_score);
    best.evidence = "clipping the largest inputs explains " + percent(best.detector_score);
    out.push_back(best);
  }
  add_store_overflow_candidate(c, j, out_channel, out);
  {
    // Bouc-Wen: loop width about alpha / (beta + gamma) in input units; grid over
    // the amplitude alpha and the loop's saturation scale.
    std::vector<PhysicsBlock> grid;
    for (double alpha : {0.01, 0.03, 0.1, 0.3})
      for (double shape : {1.0, 4.0, 16.0}) {
        PhysicsBlock b = make_block("hysteresis", j, out_channel);
        b.params["alpha"] = alpha;
        b.params["beta"] = shape / u_range;
        b.params["gamma"] = shape / u_range;
        grid.push_back(b);
      }
    Candidate best = best_as_is(c, grid);
    best.free = {{"alpha", 0.0, 0.6}, {"beta", 0.05 / u_range, 200.0 / u_range, true}, {"gamma", -50.0 / u_range, 200.0 / u_range}};
    best.detector_score = std::max(0.0, best.detector_score);
    best.evidence = "a hysteresis loop (Bouc-Wen) in the actuator explains " + percent(best.detector_score);
    out.push_back(best);
  }
}

void add_plant_candidates(const Context& c, long j, long i, std::vector<Candidate>& out) {
  const Eigen::VectorXd uj = c.d.u.col(j);
  const double u_rms = c.rms(uj), u_max = uj.cwiseAbs().maxCoeff();
  if (!(u_rms > 0) || !(uj.maxCoeff() > uj.minCoeff())) return;  // a constant input excites no motion
  const Eigen::VectorXd position = c.d.current.col(i);
  const double y_peak = std::max(position.cwiseAbs().maxCoeff(), kTiny);
  const int substeps = c.d.simulator->substeps();
  {
    PhysicsBlock b = make_block("coulomb_friction", j, i);
    const Eigen::VectorXd v = (position.tail(c.rows - 1) - position.head(c.rows - 1)) / c.d.Ts;
    b.params["velocity_scale"] = std::max(c.o.friction_velocity_fraction * c.rms(v), kTiny);
    out.push_back(linearised(c, b, "level", 0.0, 0.01 * u_rms, {"level", 0.0, u_max}, substeps,
                             "a force opposing the velocity's sign"));
  }
  {
    // Two sensitivities, the cubic and the linear stiffness (see physics_block.hpp:
    // a best-linear-approximation nominal already holds part of the cubic's
    // stiffness); both enter the force linearly, so least squares gives the start.
    const double reach = u_max / (y_peak * y_peak * y_peak), linear_reach = u_max / y_peak;
    PhysicsBlock b = make_block("cubic_stiffness", j, i);
    const Eigen::MatrixXd G =
        sensitivities(c, b, {{"coefficient", 0.01 * reach}, {"linear_coefficient", 0.01 * linear_reach}});
    const auto [coef, explained] = c.regress(G);
    // Scored by what the cubic adds: the linear term alone is a stiffness error, not this physics.
    const auto [linear_only, linear_explained] = c.regress(G.col(1));
    (void)linear_only;
    b.params["coefficient"] = std::clamp(coef[0], -reach, reach);
    b.params["linear_coefficient"] = std::clamp(coef[1], -linear_reach, linear_reach);
    const double score = std::max(0.0, explained - std::max(0.0, linear_explained));
    out.push_back({b, {{"coefficient", -reach, reach}, {"linear_coefficient", -linear_reach, linear_reach}}, substeps, score,
                   "a force growing with the cube of the position explains " + percent(score) +
                       " beyond a linear stiffness change (linearised)"});
  }
  add_mode_candidates(c, j, i, out);
}

/// One lightly damped mode of the nominal in the path input j -> output i, in the
/// form of a mode_shift block: b1 s + b0 over s^2 + 2 zeta w s + w^2.
struct NominalMode {
  double freq_hz = 0.0, damping = 0.0, b0 = 0.0, b1 = 0.0;
};

/// The nominal's lightly damped modes (damping < 0.3, below 0.45 fs) with their
/// numerators in the path j -> i, from the eigen-decomposition of its continuous
/// equivalent: a pole pair p, conj(p) with residue r = (C v)_i (w^T B)_j contributes
/// (2 Re(r) s - 2 Re(r conj(p))) / (s^2 - 2 Re(p) s + |p|^2).
std::vector<NominalMode> nominal_modes(const Context& c, long j, long i) {
  std::vector<NominalMode> modes;
  const ModalBasis& basis = c.nominal_basis;
  for (Eigen::Index k = 0; k < basis.poles.size(); ++k) {
    const std::complex<double> p = basis.poles(k);
    if (!(p.imag() > 0.0)) continue;
    const double w = std::abs(p), zeta = -p.real() / w, f = w / kTwoPi;
    if (!(zeta > 0.0 && zeta < 0.3) || f >= 0.45 / c.d.Ts) continue;
    const std::complex<double> r = basis.output_shapes(i, k) * basis.input_shapes(k, j);
    modes.push_back({f, zeta, -2.0 * (r * std::conj(p)).real(), 2.0 * r.real()});
  }
  return modes;
}

/// mode_shift: each nominal mode moved in frequency on a small grid (damping kept),
/// then in damping at the best frequency; scored by the residual energy the moved
/// mode explains as it is (a shift is not linear in the frequency beyond a
/// fraction of the half-power bandwidth, so no linearised score).
void add_mode_shift_candidates(const Context& c, long j, long i, std::vector<Candidate>& out) {
  const double f_max = 0.49 / c.d.Ts;
  for (const NominalMode& mode : nominal_modes(c, j, i)) {
    PhysicsBlock b = make_block("mode_shift", j, i);
    b.params["nominal_freq_hz"] = mode.freq_hz;
    b.params["nominal_damping"] = mode.damping;
    b.params["numerator_b0"] = mode.b0;
    b.params["numerator_b1"] = mode.b1;
    b.params["damping"] = mode.damping;
    double best_score = -1.0, best_f = mode.freq_hz, best_zeta = mode.damping;
    for (double scale : {0.97, 0.985, 0.993, 0.997, 1.003, 1.007, 1.015, 1.03}) {
      if (mode.freq_hz * scale >= f_max) continue;
      b.params["freq_hz"] = mode.freq_hz * scale;
      const double score = c.explained_as_is(c.effect(b));
      if (score > best_score) best_score = score, best_f = mode.freq_hz * scale;
    }
    if (best_score < 0.0) continue;
    b.params["freq_hz"] = best_f;
    for (double factor : {0.6, 1.6}) {
      b.params["damping"] = mode.damping * factor;
      const double score = c.explained_as_is(c.effect(b));
      if (score > best_score) best_score = score, best_zeta = mode.damping * factor;
    }
    b.params["damping"] = best_zeta;
    Candidate candidate;
    candidate.block = b;
    candidate.free = {{"freq_hz", 0.9 * mode.freq_hz, std::min(1.1 * mode.freq_hz, f_max), true},
                      {"damping", 0.2 * mode.damping, std::min(5.0 * mode.damping, 0.6), true}};
    candidate.detector_score = std::max(0.0, best_score);
    candidate.evidence = "the simulation's mode at " + format_number(mode.freq_hz) + " Hz moved to " +
                         format_number(best_f) + " Hz explains " + percent(candidate.detector_score);
    out.push_back(candidate);
  }
}

void add_coupling_candidates(const Context& c, std::vector<Candidate>& out) {
  if (c.l < 2) return;
  for (long j = 0; j < std::min(c.m, c.l); ++j)
    for (long i = 0; i < c.l; ++i) {
      if (i == j) continue;
      out.push_back(linearised(c, make_block("cross_coupling", j, i), "gain", 0.0, 0.01, {"gain", -2.0, 2.0}, 1,
                               "input " + std::to_string(j + 1) + "'s motion seen at output " + std::to_string(i + 1)));
    }
}

}  // namespace

std::vector<Candidate> propose_candidates(const DetectionData& data, const DetectionOptions& options) {
  if (data.simulator == nullptr) throw std::invalid_argument("propose_candidates: need a simulator");
  if (data.u.rows() != data.y.rows() || data.current.rows() != data.y.rows() || data.current.cols() != data.y.cols())
    throw std::invalid_argument("propose_candidates: need u, y and current with the same rows (and y, current the same columns)");
  if (!(data.Ts > 0)) throw std::invalid_argument("propose_candidates: need Ts > 0");
  const Context c(data, options);
  std::vector<Candidate> out;
  add_sensor_candidates(c, out);
  for (long j = 0; j < c.m; ++j) {
    add_actuator_candidates(c, j, out);
    // Forces inside the plant are collocated: input j acts where output j is
    // measured (square MIMO) or on the only output (SISO/SIMO).
    for (long i = 0; i < c.l; ++i)
      if (c.l == 1 || i == j) add_plant_candidates(c, j, i, out);
    // Modes, missing or moved, are not collocated: with a single input (SISO,
    // SIMO) every output is a path of it. Square MIMO keeps the collocated paths
    // (add_plant_candidates) to bound the number of candidates.
    for (long i = 0; i < c.l; ++i) {
      if (c.m == 1 && c.l > 1 && i != j) add_mode_candidates(c, j, i, out);
      if (c.m == 1 || i == j) add_mode_shift_candidates(c, j, i, out);
    }
  }
  add_coupling_candidates(c, out);
  std::stable_sort(out.begin(), out.end(),
                   [](const Candidate& a, const Candidate& b) { return a.detector_score > b.detector_score; });
  return out;
}

}  // namespace sysid
