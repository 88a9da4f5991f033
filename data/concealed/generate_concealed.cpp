// Generates the concealed-physics suite of data/concealed/README.md: for each
// scenario, a log of a "true" machine, the linear nominal model that leaves one
// piece of physics out (or none, for the null scenarios), and the truth. The test
// of `sysid diagnose` is that it finds the hidden piece and that modelling it
// improves the fit on the last 30 % of the samples.
//
//   sysid_generate_concealed OUTDIR
//
// writes OUTDIR/<scenario>/{log.csv, nominal.json, truth.json} and prints a table
// of the nominal and oracle fits. Deterministic: fixed seeds, std::mt19937_64 with
// std::normal_distribution (libstdc++), multisine phases from sysid::multisine.
//
// The true system is simulated in continuous time: classical RK4 with a fixed step
// h = Ts/20, the sampled input held constant over each sample (ZOH), the nonlinear
// forces inside the plant (Coulomb friction, also direction-dependent, cubic
// stiffness, a constant force) evaluated in the RK4 derivative, the actuator
// nonlinearities (play, dead zone, clipping, discrete Bouc-Wen) applied to the
// sampled input, the sensor effects (gain, hum, offset and drift) to the sampled
// output, then Gaussian measurement noise (white; coloured in null_drive_velocity).
// y is the driven mass's position, velocity or acceleration (nominal.json says
// which in "output_quantities"); an acceleration output has direct feedthrough and
// is sampled just after the input switches. One scenario runs in closed loop: a PD
// position controller computes u from the quantised noisy encoder reading, sample
// by sample, and the log records the controller's output.
#include <sysid/core/discretize.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/model_json.hpp>
#include <sysid/signal/excitation.hpp>
#include <sysid/validate/fit.hpp>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using sysid::StateSpace;
using json = nlohmann::ordered_json;  // truth.json keeps the order written

constexpr double kFs = 2000.0;
constexpr double kTs = 1.0 / kFs;
constexpr Eigen::Index kSamples = 20000;
constexpr int kSubsteps = 20;                // RK4 steps per sample: h = Ts / 20
constexpr double kValidationFraction = 0.3;  // fits are reported on the last 30 %
constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// Fixed-capacity vectors and matrices for the RK4 loop: the true systems have at
/// most 3 masses (6 states) + a hidden mode (2) + an actuator lag (1), and the
/// derivative is evaluated 80 times per sample, so heap allocation is avoided.
constexpr int kMaxStates = 12;
using Vec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxStates, 1>;
using RowVec = Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, kMaxStates>;
using Mat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxStates, kMaxStates>;

double rms(const Eigen::VectorXd& x) { return std::sqrt(x.squaredNorm() / static_cast<double>(x.size())); }

// ---------------------------------------------------------------------------
// Plants: grounded mass-spring chains with modal damping
// ---------------------------------------------------------------------------

struct Plant {
  std::string name;             ///< flexible_arm | piezo_isolator | positioning_stage | linear_drive | guided_drive
  std::string y_unit;           ///< unit of y
  std::string output_quantity = "position";  ///< what y measures at the driven mass: position | velocity | acceleration
  std::string velocity_unit;    ///< unit of `velocity` (the friction's v_eps); empty: y_unit/s
  StateSpace continuous;        ///< u (N) -> y, x = [q; dq/dt] in SI (D != 0 only for an acceleration output)
  /// Velocity of the driven mass = velocity * x (position output: dy/dt, output units per second).
  Eigen::RowVectorXd velocity;
  double driven_mass = 0;       ///< kg
  double scale = 1;             ///< output units per metre
  std::vector<double> freq_hz, damping;  ///< modes, ascending
  std::vector<double> residue;  ///< driven-point residues: G(s) = sum_i residue_i / (s^2 + 2 zeta_i w_i s + w_i^2)
  json description;
};

/// Purpose: a chain ground -k0- m0 -k1- m1 -k2- m2 ..., force on mass `driven`,
/// y = scale * (displacement of mass `driven`), with modal damping ratios `zeta`
/// (ascending modes).
/// Method: mass-normalised modes Phi from the symmetric problem
/// M^-1/2 K M^-1/2 v = w^2 v, Phi = M^-1/2 V; damping matrix
/// C = M Phi diag(2 zeta_i w_i) Phi^T M, so that Phi^T C Phi = diag(2 zeta_i w_i)
/// and the poles are exactly -zeta_i w_i +- j w_i sqrt(1 - zeta_i^2).
Plant chain_plant(const std::string& name, const std::vector<double>& masses, const std::vector<double>& springs,
                  const std::vector<double>& zeta, int driven, double scale, const std::string& y_unit) {
  const int n = static_cast<int>(masses.size());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n);
  K(0, 0) += springs[0];
  for (int i = 1; i < n; ++i) {
    K(i - 1, i - 1) += springs[i];
    K(i, i) += springs[i];
    K(i - 1, i) -= springs[i];
    K(i, i - 1) -= springs[i];
  }
  Eigen::VectorXd m(n), m_isqrt(n);
  for (int i = 0; i < n; ++i) m(i) = masses[i], m_isqrt(i) = 1.0 / std::sqrt(masses[i]);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(m_isqrt.asDiagonal() * K * m_isqrt.asDiagonal());
  const Eigen::VectorXd w = eig.eigenvalues().cwiseSqrt();
  const Eigen::MatrixXd phi = m_isqrt.asDiagonal() * eig.eigenvectors();
  Eigen::VectorXd two_zeta_w(n);
  for (int i = 0; i < n; ++i) two_zeta_w(i) = 2.0 * zeta[i] * w(i);
  const Eigen::MatrixXd M = m.asDiagonal();
  const Eigen::MatrixXd C = M * phi * two_zeta_w.asDiagonal() * phi.transpose() * M;

  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  a.topRightCorner(n, n).setIdentity();
  a.bottomLeftCorner(n, n) = -(m.cwiseInverse().asDiagonal() * K);
  a.bottomRightCorner(n, n) = -(m.cwiseInverse().asDiagonal() * C);
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(2 * n, 1);
  b(n + driven, 0) = 1.0 / masses[driven];
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(1, 2 * n);
  c(0, driven) = scale;

  Plant p;
  p.name = name;
  p.y_unit = y_unit;
  p.continuous = StateSpace(a, b, c, Eigen::MatrixXd::Zero(1, 1), 0.0);
  p.continuous.input_names = {"u"};
  p.continuous.output_names = {"y"};
  p.velocity = Eigen::RowVectorXd::Zero(2 * n);
  p.velocity(n + driven) = scale;
  p.driven_mass = masses[driven];
  p.scale = scale;
  json modes = json::array();
  for (int i = 0; i < n; ++i) {
    p.freq_hz.push_back(w(i) / kTwoPi);
    p.damping.push_back(zeta[i]);
    // Mass-normalised modes: the driven-point receptance is sum_i phi_di^2 / (s^2 + ...).
    p.residue.push_back(scale * phi(driven, i) * phi(driven, i));
    modes.push_back({{"freq_hz", w(i) / kTwoPi}, {"damping", zeta[i]}, {"residue", p.residue.back()}});
  }
  p.description = {{"masses_kg", masses}, {"springs_N_per_m", springs}, {"driven_mass_index", driven},
                   {"modes", modes}, {"u_unit", "N"}, {"y_unit", y_unit}};
  return p;
}

double stiffness(double mass, double freq_hz) { return mass * std::pow(kTwoPi * freq_hz, 2); }

/// Hub (1 kg, driven) and tip (0.12 kg): modes 25.0 Hz (dominant at the hub) and 35.6 Hz.
Plant flexible_arm() {
  return chain_plant("flexible_arm", {1.0, 0.12}, {stiffness(1.0, 29.2), stiffness(0.12, 30.4)}, {0.02, 0.015}, 0, 1e3,
                     "mm");
}
/// Base frame (10 kg) on a soft suspension, payload (5 kg, driven) on a piezo stack:
/// suspension mode ~10 Hz, payload mode ~153 Hz.
Plant piezo_isolator() {
  return chain_plant("piezo_isolator", {10.0, 5.0}, {stiffness(15.0, 10.0), stiffness(5.0, 125.0)}, {0.05, 0.01}, 1,
                     1e6, "um");
}
/// Carriage (2 kg, driven) on a flexure guide, tool (0.5 kg) on the carriage:
/// suspension mode ~4 Hz, structural mode ~300 Hz.
Plant positioning_stage() {
  return chain_plant("positioning_stage", {2.0, 0.5}, {stiffness(2.5, 4.0), stiffness(0.5, 270.0)}, {0.05, 0.02}, 0,
                     1e3, "mm");
}

/// A pole pair of a continuous system: natural frequency |s| / 2 pi and damping
/// ratio -Re(s) / |s|, the convention of `missing_mode` and `mode_shift`.
struct PolePair {
  double freq_hz = 0, damping = 0;
};

/// The lightly damped pole pairs (Im s > 0), ascending, and the real poles (rad/s) of A.
std::vector<PolePair> pole_pairs(const Eigen::MatrixXd& a, std::vector<double>* real_poles = nullptr) {
  const Eigen::VectorXcd s = Eigen::EigenSolver<Eigen::MatrixXd>(a, false).eigenvalues();
  std::vector<PolePair> pairs;
  for (const auto& z : s) {
    if (z.imag() > 1e-9 * std::abs(z)) pairs.push_back({std::abs(z) / kTwoPi, -z.real() / std::abs(z)});
    else if (std::abs(z.imag()) <= 1e-9 * std::abs(z) && real_poles) real_poles->push_back(z.real());
  }
  std::sort(pairs.begin(), pairs.end(), [](const PolePair& l, const PolePair& r) { return l.freq_hz < r.freq_hz; });
  if (real_poles) std::sort(real_poles->begin(), real_poles->end());
  return pairs;
}

/// Purpose: a linear-motor drive. A rigid carriage (mass m_c, driven by the motor
/// force u) with viscous friction c0 to the frame, carrying a tool (m_t) on a
/// structural spring k1 with damper c1, and (guide_hz > 0) held by a flexure guide
/// k0 to the frame, so that it returns to rest. k1 = mu w_t^2, c1 = 2 zeta_t w_t mu
/// with mu = m_c m_t / (m_c + m_t) (the tool mode of a free carriage);
/// k0 = (m_c + m_t) (2 pi guide_hz)^2. The exact poles (eigenvalues of A) are
/// listed in the description; c0 and k0 move them slightly from these targets.
/// Output: the carriage's position, velocity or acceleration times `scale`. The
/// acceleration of a force-driven mass has direct feedthrough: y = scale (A_v x +
/// u / m_c), so C = scale A_v (the carriage's row of A) and D = scale / m_c.
/// State: guided [q_c, q_t, v_c, v_t]; free [q_t - q_c, v_c, v_t] (no rigid-body
/// position state: a free drive has no position output here), SI units.
Plant drive_plant(const std::string& name, double m_c, double m_t, double tool_hz, double tool_zeta, double viscous,
                  double guide_hz, const std::string& quantity, double scale, const std::string& y_unit,
                  const std::string& velocity_unit) {
  const bool guided = guide_hz > 0;
  const double mu = m_c * m_t / (m_c + m_t), wt = kTwoPi * tool_hz;
  const double k1 = mu * wt * wt, c1 = 2.0 * tool_zeta * wt * mu;
  const double k0 = guided ? (m_c + m_t) * std::pow(kTwoPi * guide_hz, 2) : 0.0;
  const int n = guided ? 4 : 3, vc = n - 2, vt = n - 1;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n), b = Eigen::MatrixXd::Zero(n, 1);
  if (guided) {
    a(0, vc) = 1.0;
    a(1, vt) = 1.0;
    // m_c v_c' = u - k0 q_c - c0 v_c + k1 (q_t - q_c) + c1 (v_t - v_c); m_t v_t' = -k1 (q_t - q_c) - c1 (v_t - v_c)
    a(vc, 0) = -(k0 + k1) / m_c;
    a(vc, 1) = k1 / m_c;
    a(vt, 0) = k1 / m_t;
    a(vt, 1) = -k1 / m_t;
  } else {
    // d = q_t - q_c: d' = v_t - v_c; m_c v_c' = u - c0 v_c + k1 d + c1 (v_t - v_c); m_t v_t' = -k1 d - c1 (v_t - v_c)
    a(0, vc) = -1.0;
    a(0, vt) = 1.0;
    a(vc, 0) = k1 / m_c;
    a(vt, 0) = -k1 / m_t;
  }
  a(vc, vc) = -(viscous + c1) / m_c;
  a(vc, vt) = c1 / m_c;
  a(vt, vc) = c1 / m_t;
  a(vt, vt) = -c1 / m_t;
  b(vc, 0) = 1.0 / m_c;
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(1, n), d = Eigen::MatrixXd::Zero(1, 1);
  if (quantity == "position") {
    if (!guided) throw std::logic_error(name + ": a free drive has no position output here");
    c(0, 0) = scale;
  } else if (quantity == "velocity") {
    c(0, vc) = scale;
  } else if (quantity == "acceleration") {
    c = scale * a.row(vc);
    d(0, 0) = scale / m_c;
  } else {
    throw std::logic_error(name + ": unknown output quantity " + quantity);
  }

  Plant p;
  p.name = name;
  p.y_unit = y_unit;
  p.output_quantity = quantity;
  p.velocity_unit = velocity_unit;
  p.continuous = StateSpace(a, b, c, d, 0.0);
  p.continuous.input_names = {"u"};
  p.continuous.output_names = {"y"};
  p.velocity = Eigen::RowVectorXd::Zero(n);
  p.velocity(vc) = scale;
  p.driven_mass = m_c;
  p.scale = scale;
  std::vector<double> real_poles;
  json modes = json::array();
  for (const PolePair& m : pole_pairs(a, &real_poles)) {
    p.freq_hz.push_back(m.freq_hz);
    p.damping.push_back(m.damping);
    modes.push_back({{"freq_hz", m.freq_hz}, {"damping", m.damping}});
  }
  p.description = {{"carriage_kg", m_c}, {"tool_kg", m_t}, {"tool_spring_N_per_m", k1}, {"tool_damper_N_s_per_m", c1},
                   {"viscous_friction_N_s_per_m", viscous}, {"guide_spring_N_per_m", k0},
                   {"modes", modes}, {"real_poles_rad_per_s", real_poles}, {"u_unit", "N"},
                   {"output_quantity", quantity}, {"y_unit", y_unit}, {"velocity_unit", velocity_unit}};
  return p;
}

/// Linear drive on a free carriage (2 kg carriage, 0.3 kg tool on a 150 Hz
/// structure, 8 N s/m viscous friction): velocity output in mm/s.
Plant linear_drive() {
  return drive_plant("linear_drive", 2.0, 0.3, 150.0, 0.02, 8.0, 0.0, "velocity", 1e3, "mm/s", "mm/s");
}
/// The same drive held by a flexure guide (suspension GUIDE_HZ), which returns it to
/// rest: acceleration output in m/s^2 (an accelerometer on the carriage) or the
/// position in um (a 1 um encoder).
constexpr double kGuideHz = 8.0;
// Sizes of the drive scenarios' inputs and hidden effects (tuned so that each
// hidden effect costs the nominal a few per cent; see the README).
constexpr double kGuidedMultisineRms = 0.3, kGuidedSineAmplitude = 10.0;  // N
constexpr double kDriveFriction = 0.1, kAccelerationFriction = 0.02, kDriveDeadzone = 0.2;  // N
constexpr double kLoopConstantForce = -0.6, kLoopFriction = 0.4;  // N
constexpr double kLoopKp = 0.06, kLoopKd = 5e-4;  // N/um, N s/um
Plant guided_drive(const std::string& quantity) {
  return quantity == "acceleration"
             ? drive_plant("guided_drive", 2.0, 0.3, 150.0, 0.02, 8.0, kGuideHz, quantity, 1.0, "m/s^2", "m/s")
             : drive_plant("guided_drive", 2.0, 0.3, 150.0, 0.02, 8.0, kGuideHz, quantity, 1e6, "um", "um/s");
}

/// The positioning stage whose flexure (the spring from the frame to the carriage)
/// is `ratio` times stiffer than the nominal's, with the same damping matrix and
/// masses: purely linear, the first mode moves up by about sqrt(ratio) and its
/// damping ratio drops by about as much.
Plant stiffer_flexure(const Plant& stage, double ratio) {
  Plant p = stage;
  const double k0 = stage.description["springs_N_per_m"][0].get<double>();
  const Eigen::Index n = stage.continuous.order() / 2;
  p.continuous.A(n, 0) -= (ratio - 1.0) * k0 / stage.description["masses_kg"][0].get<double>();
  p.freq_hz.clear();
  p.damping.clear();
  json modes = json::array();
  for (const PolePair& m : pole_pairs(p.continuous.A)) {
    p.freq_hz.push_back(m.freq_hz);
    p.damping.push_back(m.damping);
    modes.push_back({{"freq_hz", m.freq_hz}, {"damping", m.damping}});
  }
  p.description["springs_N_per_m"][0] = ratio * k0;
  p.description["modes"] = modes;
  p.description["damping_matrix"] = "the nominal stage's (same dampers)";
  return p;
}

// ---------------------------------------------------------------------------
// Inputs
// ---------------------------------------------------------------------------

struct InputSpec {
  double f_min_hz = 1, f_max_hz = 100;  ///< band of the random-phase multisine
  double multisine_rms = 1;             ///< N
  std::uint64_t seed = 1;               ///< multisine phases
  double sine_hz = 0, sine_amplitude = 0;  ///< slow large sine (velocity reversals), N
  double burst_gain = 1;                   ///< multisine amplitude at the burst peaks
  double burst_period_s = 2, burst_length_s = 0.6, burst_start_s = 0.7;
};

/// u(t) = envelope(t) * multisine(t) + A sin(2 pi f t): the multisine (period = the
/// record) covers the plant's modes; the sine gives slow large strokes; the Hann
/// bursts in the envelope give the largest amplitudes, in the estimation part and
/// in the held-out 30 % alike.
Eigen::VectorXd make_input(const InputSpec& s) {
  sysid::MultisineOptions o;
  o.fs_hz = kFs;
  o.f_min_hz = s.f_min_hz;
  o.f_max_hz = s.f_max_hz;
  o.samples = kSamples;
  o.period = kSamples;
  o.rms = s.multisine_rms;
  o.seed = s.seed;
  const Eigen::VectorXd ms = sysid::multisine(o).col(0);
  Eigen::VectorXd u(kSamples);
  for (Eigen::Index k = 0; k < kSamples; ++k) {
    const double t = static_cast<double>(k) * kTs;
    double envelope = 1.0;
    if (s.burst_gain != 1.0 && t >= s.burst_start_s) {
      const double phase = std::fmod(t - s.burst_start_s, s.burst_period_s);
      if (phase < s.burst_length_s)
        envelope += (s.burst_gain - 1.0) * 0.5 * (1.0 - std::cos(kTwoPi * phase / s.burst_length_s));
    }
    u(k) = envelope * ms(k) + s.sine_amplitude * std::sin(kTwoPi * s.sine_hz * t);
  }
  return u;
}

// ---------------------------------------------------------------------------
// Hidden physics
// ---------------------------------------------------------------------------

struct Effects {
  int delay_samples = 0;                       ///< time_delay
  double lag_corner_hz = 0;                    ///< input_lag (0: none)
  /// A first-order store in the actuator that the nominal HAS (a pneumatic
  /// chamber filled through a valve: its pressure force follows the command at
  /// this corner), capped by a relief valve at store_limit N, which the nominal
  /// lacks: saturation of a store (0: none).
  double store_corner_hz = 0, store_limit = 0;
  double backlash_width = 0;                   ///< full width of the play, N
  double deadzone_width = 0;                   ///< full width, N
  double saturation_limit = 0;                 ///< N (0: none)
  double bw_alpha = 0, bw_beta = 0, bw_gamma = 0;  ///< discrete Bouc-Wen (alpha 0: none)
  double friction_level = 0;                   ///< Coulomb force, N
  /// Direction-dependent Coulomb force (0: symmetric): level_positive while the
  /// driven mass moves in the +u direction, level_negative while it moves in the
  /// -u direction; friction_level is then their mean.
  double friction_positive = 0, friction_negative = 0;
  double constant_force = 0;                   ///< N on the driven mass, + = the direction of +u (gravity)
  double cubic_coefficient = 0;                ///< N per (output unit)^3
  double mode_freq_hz = 0, mode_damping = 0;   ///< missing_mode (freq 0: none)
  double mode_relative_residue = 0;            ///< residue / driven-point residue of the plant's first mode
  double gain_ratio = 1;                       ///< gain_error: measured / true
  // Sensor additions, given relative to the scenario and turned into absolute values:
  double hum_freq_hz = 0, hum_phase_rad = 0;
  double hum_rms_over_noise = 0;    ///< hum RMS = this * noise RMS
  double offset_over_signal = 0;    ///< offset = this * RMS of the plant output
  double drift_over_signal = 0;     ///< slope * duration = this * RMS of the plant output
};

/// Force reaching the plant over each sample from the sampled command u:
/// delay by whole samples, then the actuator nonlinearity (at most one is used
/// per scenario; the order would be play, dead zone, clipping, Bouc-Wen).
Eigen::VectorXd actuator_force(const Eigen::VectorXd& u_in, const Effects& fx) {
  const Eigen::Index n = u_in.size();
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  for (Eigen::Index k = fx.delay_samples; k < n; ++k) u(k) = u_in(k - fx.delay_samples);
  Eigen::VectorXd f = u;
  if (fx.backlash_width > 0) {
    // Play operator: b follows u - w/2 when u pushes up past it, u + w/2 when
    // u pushes down past it, otherwise holds; b0 = clamp(0, u0 - w/2, u0 + w/2).
    const double half = 0.5 * fx.backlash_width;
    double b = 0.0;
    for (Eigen::Index k = 0; k < n; ++k) f(k) = b = std::clamp(b, u(k) - half, u(k) + half);
  }
  if (fx.deadzone_width > 0) {
    const double half = 0.5 * fx.deadzone_width;
    for (Eigen::Index k = 0; k < n; ++k) f(k) = std::abs(f(k)) <= half ? 0.0 : f(k) - std::copysign(half, f(k));
  }
  if (fx.saturation_limit > 0) {
    for (Eigen::Index k = 0; k < n; ++k) f(k) = std::clamp(f(k), -fx.saturation_limit, fx.saturation_limit);
  }
  if (fx.bw_alpha > 0) {
    // Discrete Bouc-Wen on the sampled command (the form the diagnose block uses):
    // h[k+1] = h[k] + alpha du - beta |du| h[k] - gamma du |h[k]|, du = u[k+1] - u[k],
    // force over sample k+1 = u[k+1] - h[k+1], h[0] = 0.
    double h = 0.0;
    for (Eigen::Index k = 1; k < n; ++k) {
      const double du = u(k) - u(k - 1);
      h += fx.bw_alpha * du - fx.bw_beta * std::abs(du) * h - fx.bw_gamma * du * std::abs(h);
      f(k) = u(k) - h;
    }
  }
  return f;
}

/// Continuous true plant: the nominal chain, plus (missing_mode) a mode in parallel
/// from the plant force to y, plus (input_lag) a first-order lag state between the
/// actuator force and the plant force, plus the nonlinear internal forces acting on
/// the driven mass.
struct TruePlant {
  Mat A;
  Vec b;         ///< plant force -> state derivative
  Vec c_y, c_v;  ///< y = c_y . x and dy/dt = c_v . x (output units)
  int lag_index = -1;
  double lag_w = 0;
  double lag_limit = std::numeric_limits<double>::infinity();  ///< relief valve on the lag state (store)
  double friction = 0, v_eps = 1, cubic = 0;
  double friction_positive = 0, friction_negative = 0;  ///< direction-dependent levels (0: symmetric `friction`)
  double constant_force = 0;  ///< N on the driven mass
  double d_y = 0;             ///< y = c_y . x + d_y * (force on the driven mass): an acceleration output
  double mode_residue = 0;  ///< residue of the hidden mode, output units / (N s^2)
};

TruePlant true_plant(const Plant& p, const Effects& fx) {
  const int n = static_cast<int>(p.continuous.order());
  const bool mode = fx.mode_freq_hz > 0, lag = fx.lag_corner_hz > 0 || fx.store_corner_hz > 0;
  const int total = n + (mode ? 2 : 0) + (lag ? 1 : 0);
  if (total > kMaxStates) throw std::logic_error("true plant too large for the RK4 buffers");
  TruePlant t;
  t.A = Mat::Zero(total, total);
  t.b = Vec::Zero(total);
  t.c_y = Vec::Zero(total);
  t.c_v = Vec::Zero(total);
  t.A.topLeftCorner(n, n) = p.continuous.A;
  t.b.head(n) = p.continuous.B.col(0);
  t.c_y.head(n) = p.continuous.C.row(0).transpose();
  t.c_v.head(n) = p.velocity.transpose();
  if (mode) {
    // eta'' + 2 zeta w eta' + w^2 eta = r F and y += eta, i.e.
    // G_true(s) = G_nom(s) + r / (s^2 + 2 zeta w s + w^2): the nominal's poles are
    // untouched and the hidden pair is exactly (freq_hz, damping).
    const double w = kTwoPi * fx.mode_freq_hz;
    t.mode_residue = fx.mode_relative_residue * p.residue.front();
    t.A(n, n + 1) = 1.0;
    t.A(n + 1, n) = -w * w;
    t.A(n + 1, n + 1) = -2.0 * fx.mode_damping * w;
    t.b(n + 1) = t.mode_residue;
    t.c_y(n) = 1.0;
    t.c_v(n + 1) = 1.0;
  }
  if (lag) {
    t.lag_index = total - 1;
    t.lag_w = kTwoPi * (fx.lag_corner_hz > 0 ? fx.lag_corner_hz : fx.store_corner_hz);
    if (fx.store_limit > 0) t.lag_limit = fx.store_limit;
  }
  t.friction = fx.friction_level;
  t.friction_positive = fx.friction_positive;
  t.friction_negative = fx.friction_negative;
  t.constant_force = fx.constant_force;
  t.cubic = fx.cubic_coefficient;
  t.d_y = p.continuous.D(0, 0);
  if (t.d_y != 0 && (mode || lag))
    throw std::logic_error("direct feedthrough with a hidden mode or lag is not modelled");
  return t;
}

/// Purpose: the true plant stepped one sample at a time (a closed loop computes
/// each sample's force from the previous outputs), from rest.
/// Method: classical RK4, kSubsteps steps per sample, the force held over the
/// sample (ZOH); the output at t_k is read before the step that applies f[k]:
/// y[k] = c_y . x(t_k) + d_y * (force on the driven mass at t_k with f[k] applied),
/// as in the discrete model y[k] = C x[k] + D u[k] (D = 0 but for an acceleration
/// output, whose sample is the acceleration just after the input switched to f[k]).
/// Numerical aspects: the largest |lambda| h of the linear parts is < 0.06, so RK4's
/// error is ~1e-8 relative; the smooth Coulomb force adds a real eigenvalue of about
/// -level * (c_v . b) / v_eps, which the caller keeps inside RK4's stability interval.
class TrueSimulator {
 public:
  explicit TrueSimulator(const TruePlant& p)
      : p_(p), x_(Vec::Zero(p.A.rows())), k1_(p.A.rows()), k2_(p.A.rows()), k3_(p.A.rows()), k4_(p.A.rows()),
        s_(p.A.rows()) {}

  /// y at the current sample instant, f the force about to be applied.
  double output(double f) const {
    double y = p_.c_y.dot(x_);
    if (p_.d_y != 0) y += p_.d_y * drive(x_, f);
    return y;
  }
  /// Velocity of the driven mass now (the friction's velocity, c_v . x).
  double velocity() const { return p_.c_v.dot(x_); }

  /// Advances one sample with the force f held.
  void step(double f) {
    const double h = kTs / kSubsteps;
    for (int j = 0; j < kSubsteps; ++j) {
      derivative(x_, f, k1_);
      s_ = x_ + 0.5 * h * k1_;
      derivative(s_, f, k2_);
      s_ = x_ + 0.5 * h * k2_;
      derivative(s_, f, k3_);
      s_ = x_ + h * k3_;
      derivative(s_, f, k4_);
      x_ += (h / 6.0) * (k1_ + 2.0 * k2_ + 2.0 * k3_ + k4_);
      if (p_.lag_index >= 0) x_(p_.lag_index) = std::min(x_(p_.lag_index), p_.lag_limit);
    }
  }

 private:
  /// Force on the driven mass (N): the plant force minus friction and cubic forces,
  /// plus the constant force.
  double drive(const Vec& state, double force) const {
    double d = p_.lag_index >= 0 ? state(p_.lag_index) : force;
    if (p_.friction > 0) {
      const double v = p_.c_v.dot(state);
      const double level =
          p_.friction_positive > 0 ? (v > 0 ? p_.friction_positive : p_.friction_negative) : p_.friction;
      d -= level * std::tanh(v / p_.v_eps);
    }
    if (p_.cubic != 0) {
      const double y = p_.c_y.dot(state);
      d -= p_.cubic * y * y * y;
    }
    if (p_.constant_force != 0) d += p_.constant_force;
    return d;
  }
  void derivative(const Vec& state, double force, Vec& d) const {
    const double f = drive(state, force);
    d.noalias() = p_.A * state;
    d += p_.b * f;
    if (p_.lag_index >= 0) {
      d(p_.lag_index) = p_.lag_w * (force - state(p_.lag_index));
      // The relief valve: the chamber does not fill past its limit.
      if (state(p_.lag_index) >= p_.lag_limit && d(p_.lag_index) > 0) d(p_.lag_index) = 0;
    }
  }

  const TruePlant& p_;
  Vec x_, k1_, k2_, k3_, k4_, s_;
};

/// y(t_k) of the true plant driven by the force sequence f (held over each sample), from rest.
Eigen::VectorXd simulate_true(const TruePlant& p, const Eigen::VectorXd& f) {
  TrueSimulator sim(p);
  Eigen::VectorXd y(f.size());
  for (Eigen::Index k = 0; k < f.size(); ++k) {
    y(k) = sim.output(f(k));
    sim.step(f(k));
  }
  if (!y.allFinite()) throw std::runtime_error("true-system simulation diverged");
  return y;
}

// ---------------------------------------------------------------------------
// Scenarios
// ---------------------------------------------------------------------------

/// A discrete PD position loop at the sample rate around the true plant (zero
/// computational delay: u[k] is applied over sample k, from the reading y[k]):
///   u[k] = kp (r[k] - y[k]) - kd (y[k] - y[k-1]) / Ts,  y[-1] = 0,
/// y[k] = quantum * round((y_true(t_k) + noise) / quantum), the encoder reading the
/// log records; r a minimum-jerk stroke to each target in turn, then a dwell.
struct ClosedLoop {
  bool on = false;
  double kp = 0, kd = 0;  ///< N per output unit, N s per output unit
  double quantum = 0;     ///< output units (one encoder count)
  double noise_sigma = 0; ///< output units, white Gaussian, added before the quantisation
  std::vector<double> targets;  ///< stroke end points, output units, from r = 0
  double start_s = 0.2, move_s = 0.2, dwell_s = 0.3;
};

/// r[k] and dr/dt at t_k: minimum-jerk strokes r = p0 + (p1 - p0) (10 s^3 - 15 s^4 + 6 s^5),
/// s = (t - t_j) / move_s, t_j = start_s + j (move_s + dwell_s), then dwells.
void make_reference(const ClosedLoop& c, Eigen::VectorXd& r, Eigen::VectorXd& dr) {
  r.setZero(kSamples);
  dr.setZero(kSamples);
  for (Eigen::Index k = 0; k < kSamples; ++k) {
    const double t = static_cast<double>(k) * kTs;
    double p0 = 0.0;
    for (std::size_t j = 0; j < c.targets.size(); ++j) {
      const double tj = c.start_s + static_cast<double>(j) * (c.move_s + c.dwell_s);
      if (t < tj) break;
      const double p1 = c.targets[j], s = std::min((t - tj) / c.move_s, 1.0);
      r(k) = p0 + (p1 - p0) * s * s * s * (10.0 + s * (-15.0 + 6.0 * s));
      dr(k) = s < 1.0 ? (p1 - p0) / c.move_s * 30.0 * s * s * (1.0 - s) * (1.0 - s) : 0.0;
      p0 = p1;
    }
  }
}

struct LoopProperties {
  double bandwidth_hz = 0;      ///< first frequency where |T| < |T(0)| / sqrt(2), T: r -> y
  double max_abs_pole = 0;      ///< spectral radius of the discrete closed loop
  std::vector<PolePair> pairs;  ///< closed-loop pole pairs (s = log(z) / Ts)
};

/// The PD loop around the nominal discrete plant (x+ = A x + B u, y = C x, D = 0):
/// state [x; y[k-1]], u = kp r - (kp + kd/Ts) C x + (kd/Ts) y[k-1].
LoopProperties loop_properties(const StateSpace& plant, const ClosedLoop& c) {
  const Eigen::Index n = plant.order();
  const double g = c.kd / kTs;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n + 1, n + 1);
  a.topLeftCorner(n, n) = plant.A - (c.kp + g) * plant.B * plant.C;
  a.topRightCorner(n, 1) = g * plant.B;
  a.bottomLeftCorner(1, n) = plant.C;
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + 1);
  b.head(n) = c.kp * plant.B.col(0);
  Eigen::RowVectorXd cc = Eigen::RowVectorXd::Zero(n + 1);
  cc.head(n) = plant.C.row(0);
  LoopProperties lp;
  const Eigen::VectorXcd z = Eigen::EigenSolver<Eigen::MatrixXd>(a, false).eigenvalues();
  for (const auto& zi : z) {
    lp.max_abs_pole = std::max(lp.max_abs_pole, std::abs(zi));
    const std::complex<double> si = std::log(zi) / kTs;
    if (si.imag() > 1e-9) lp.pairs.push_back({std::abs(si) / kTwoPi, -si.real() / std::abs(si)});
  }
  std::sort(lp.pairs.begin(), lp.pairs.end(),
            [](const PolePair& l, const PolePair& r) { return l.freq_hz < r.freq_hz; });
  const auto t_of = [&](double f) {
    const std::complex<double> zf = std::exp(std::complex<double>(0.0, kTwoPi * f * kTs));
    const Eigen::MatrixXcd m = zf * Eigen::MatrixXcd::Identity(n + 1, n + 1) - a.cast<std::complex<double>>();
    const Eigen::VectorXcd x = m.partialPivLu().solve(b.cast<std::complex<double>>());
    return std::abs((cc.cast<std::complex<double>>() * x).value());
  };
  const double t0 = t_of(0.0);
  for (double f = 0.1; f < 0.5 * kFs; f *= 1.002)
    if (t_of(f) < t0 / std::sqrt(2.0)) {
      lp.bandwidth_hz = f;
      break;
    }
  return lp;
}

struct Scenario {
  std::string name;
  const Plant* plant = nullptr;
  InputSpec input;
  Effects fx;
  double noise_over_signal = 0.01;  ///< noise RMS / RMS of the plant output (after the gain)
  std::uint64_t noise_seed = 1;
  std::string concealment;
  // Added with the drive scenarios (issue 33); the defaults leave the older scenarios as they were.
  bool describe_output = false;       ///< truth.json says output_quantity and noise_colour (the newer scenarios)
  const Plant* true_plant = nullptr;  ///< a linearly different true plant (mode_shift); nullptr: *plant
  double stiffness_ratio = 1;         ///< true / nominal flexure stiffness, for the truth (mode_shift)
  double noise_corner_hz = 0;         ///< coloured noise: AR(1) with pole exp(-2 pi f Ts) (0: white)
  std::vector<std::string> forbidden_kinds;  ///< kinds a diagnosis must not report (truth.json)
  ClosedLoop loop;
};

struct Outcome {
  double fit_nominal = 0, fit_oracle = 0;
  double effect_percent = 0;  ///< ||y_true - y_nominal|| / ||y - mean y|| on the held-out part, %
  double noise_rms = 0;
  double v_eps = 0;
  long velocity_reversals = 0;
  std::string note;  ///< how large the hidden effect is where it acts (for the README)
};

Eigen::Index validation_start() {
  return kSamples - static_cast<Eigen::Index>(std::llround(kValidationFraction * static_cast<double>(kSamples)));
}

double fit_on_validation(const Eigen::VectorXd& y, const Eigen::VectorXd& y_hat) {
  const Eigen::Index s = validation_start(), n = kSamples - s;
  return sysid::fit_percent(y.segment(s, n), y_hat.segment(s, n))(0);
}

json effects_json(const TruePlant& tp, const Effects& fx, const Plant& plant, bool describe_output) {
  json e = json::array();
  const auto add = [&e](const char* kind, json params) { e.push_back({{"kind", kind}, {"params", std::move(params)}}); };
  if (fx.mode_freq_hz > 0)
    add("missing_mode", {{"freq_hz", fx.mode_freq_hz}, {"damping", fx.mode_damping}, {"residue", tp.mode_residue}});
  if (fx.delay_samples > 0)
    add("time_delay", {{"delay_s", fx.delay_samples * kTs}, {"samples", fx.delay_samples}});
  if (fx.lag_corner_hz > 0) add("input_lag", {{"corner_hz", fx.lag_corner_hz}});
  if (fx.gain_ratio != 1.0) add("gain_error", {{"ratio", fx.gain_ratio}});
  if (fx.constant_force != 0) add("constant_force", {{"force", fx.constant_force}});
  if (fx.friction_level > 0 && fx.friction_positive > 0)
    add("coulomb_friction", {{"level", fx.friction_level}, {"level_positive", fx.friction_positive},
                             {"level_negative", fx.friction_negative}, {"v_eps", tp.v_eps},
                             {"v_eps_unit", plant.velocity_unit.empty() ? plant.y_unit + "/s" : plant.velocity_unit}});
  else if (fx.friction_level > 0 && describe_output)
    add("coulomb_friction", {{"level", fx.friction_level}, {"v_eps", tp.v_eps},
                             {"v_eps_unit", plant.velocity_unit.empty() ? plant.y_unit + "/s" : plant.velocity_unit}});
  else if (fx.friction_level > 0) add("coulomb_friction", {{"level", fx.friction_level}, {"v_eps", tp.v_eps}});
  if (fx.cubic_coefficient != 0) add("cubic_stiffness", {{"coefficient", fx.cubic_coefficient}});
  if (fx.backlash_width > 0) add("backlash", {{"width", fx.backlash_width}});
  if (fx.deadzone_width > 0) add("deadzone", {{"width", fx.deadzone_width}});
  if (fx.saturation_limit > 0) add("saturation", {{"limit", fx.saturation_limit}});
  if (fx.store_limit > 0)
    add("saturation", {{"limit", fx.store_limit}, {"storage_pole", std::exp(-kTwoPi * fx.store_corner_hz * kTs)}, {"spill", 0.0}});
  if (fx.bw_alpha > 0) add("hysteresis", {{"alpha", fx.bw_alpha}, {"beta", fx.bw_beta}, {"gamma", fx.bw_gamma}});
  return e;
}

/// The plant behind a first-order store of unit DC gain (corner f): u -> store -> plant.
StateSpace with_store(const StateSpace& plant, double corner_hz) {
  const Eigen::Index n = plant.order();
  const double w = kTwoPi * corner_hz;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n + 1, n + 1), B = Eigen::MatrixXd::Zero(n + 1, 1), C = Eigen::MatrixXd::Zero(1, n + 1);
  A.topLeftCorner(n, n) = plant.A;
  A.topRightCorner(n, 1) = plant.B;
  A(n, n) = -w;
  B(n, 0) = w;
  C.leftCols(n) = plant.C;
  StateSpace s(A, B, C, Eigen::MatrixXd::Zero(1, 1), 0.0);
  s.input_names = plant.input_names;
  s.output_names = plant.output_names;
  return s;
}

/// Simulates one scenario, writes its three files, returns the fits.
Outcome run_scenario(const Scenario& sc, const std::filesystem::path& out) {
  const Plant& plant = *sc.plant;
  const Plant& real = sc.true_plant ? *sc.true_plant : plant;  // the plant that made the log
  const Effects& fx = sc.fx;
  const bool closed = sc.loop.on;
  // Open loop: the command is the recipe's; closed loop: the controller's, filled in below.
  Eigen::VectorXd u = closed ? Eigen::VectorXd::Zero(kSamples) : make_input(sc.input);
  Eigen::VectorXd force = actuator_force(u, fx);

  // Linear nominal responses (exact ZOH): the nominal prediction from u, and the
  // driven mass's velocity under the actual force (for the friction's v_eps).
  // A store the nominal has sits in series before the plant.
  StateSpace nominal = sysid::c2d_zoh(fx.store_corner_hz > 0 ? with_store(plant.continuous, fx.store_corner_hz) : plant.continuous, kTs);
  StateSpace velocity_model = plant.continuous;
  velocity_model.C = plant.velocity;
  velocity_model.D.setZero();
  Eigen::VectorXd reference, reference_rate, v_nominal;
  if (closed) make_reference(sc.loop, reference, reference_rate);
  else v_nominal = sysid::simulate(sysid::c2d_zoh(velocity_model, kTs), force).col(0);

  Outcome r;
  TruePlant tp = true_plant(real, fx);
  if (fx.friction_level > 0) {
    // Smooth sign: tanh(v / v_eps), v_eps = 1e-3 of the velocity RMS (closed loop:
    // of the reference's rate). Its slope at v = 0 is a viscous damper level / v_eps;
    // RK4 is stable for |lambda| h < 2.78.
    tp.v_eps = 1e-3 * rms(closed ? reference_rate : v_nominal);
    const double level = std::max({fx.friction_level, fx.friction_positive, fx.friction_negative});
    const double lambda_h = level * tp.c_v.dot(tp.b) / tp.v_eps * (kTs / kSubsteps);
    if (lambda_h > 2.0)
      throw std::logic_error(sc.name + ": friction too stiff for RK4 at h = Ts/20 (|lambda| h = " +
                             std::to_string(lambda_h) + ")");
  }
  r.v_eps = tp.v_eps;

  std::mt19937_64 rng(sc.noise_seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  Eigen::VectorXd y_plant, y_true, y;
  double hum_amplitude = 0, offset = 0, slope = 0;
  LoopProperties loop;
  if (closed) {
    // The loop runs sample by sample: read the encoder, compute u[k], apply it over
    // the sample. The logged y is the quantised noisy reading the controller saw.
    if (tp.d_y != 0) throw std::logic_error(sc.name + ": the closed loop reads a position (D = 0)");
    loop = loop_properties(nominal, sc.loop);
    r.noise_rms = sc.loop.noise_sigma;
    TrueSimulator sim(tp);
    y_plant.resize(kSamples);
    y.resize(kSamples);
    v_nominal.resize(kSamples);  // here: the true velocity, for the reversal count
    double y_previous = 0.0;
    for (Eigen::Index k = 0; k < kSamples; ++k) {
      y_plant(k) = sim.output(0.0);
      v_nominal(k) = sim.velocity();
      // (+ 0.0: a reading rounded to zero from below is written 0, not -0)
      y(k) = sc.loop.quantum * std::round((y_plant(k) + r.noise_rms * gauss(rng)) / sc.loop.quantum) + 0.0;
      u(k) = sc.loop.kp * (reference(k) - y(k)) - sc.loop.kd * (y(k) - y_previous) / kTs;
      y_previous = y(k);
      sim.step(u(k));
    }
    if (!y_plant.allFinite()) throw std::runtime_error("closed-loop simulation diverged");
    force = u;
    y_true = y_plant;
  } else {
    y_plant = fx.gain_ratio * simulate_true(tp, force);
    const double signal_rms = rms(y_plant);
    r.noise_rms = sc.noise_over_signal * signal_rms;

    // Sensor-side additions, sized relative to the signal or the noise.
    y_true = y_plant;
    if (fx.hum_freq_hz > 0) hum_amplitude = std::sqrt(2.0) * fx.hum_rms_over_noise * r.noise_rms;  // peak of a sine
    if (fx.offset_over_signal != 0 || fx.drift_over_signal != 0) {
      offset = fx.offset_over_signal * signal_rms;
      slope = fx.drift_over_signal * signal_rms / (static_cast<double>(kSamples) * kTs);
    }
    for (Eigen::Index k = 0; k < kSamples; ++k) {
      const double t = static_cast<double>(k) * kTs;
      if (hum_amplitude > 0) y_true(k) += hum_amplitude * std::sin(kTwoPi * fx.hum_freq_hz * t + fx.hum_phase_rad);
      y_true(k) += offset + slope * t;
    }

    y = y_true;
    if (sc.noise_corner_hz > 0) {
      // Coloured: AR(1) e[k] = a e[k-1] + sqrt(1 - a^2) sigma w[k], e[0] = sigma w[0],
      // a = exp(-2 pi f_c Ts) (a first-order low-pass at f_c); stationary RMS sigma.
      const double a = std::exp(-kTwoPi * sc.noise_corner_hz * kTs), gain = std::sqrt(1.0 - a * a);
      double e = 0.0;
      for (Eigen::Index k = 0; k < kSamples; ++k) {
        const double w = r.noise_rms * gauss(rng);
        e = k == 0 ? w : a * e + gain * w;
        y(k) += e;
      }
    } else {
      for (Eigen::Index k = 0; k < kSamples; ++k) y(k) += r.noise_rms * gauss(rng);
    }
  }
  const Eigen::VectorXd y_nominal = sysid::simulate(nominal, u).col(0);
  for (Eigen::Index k = 1; k < kSamples; ++k)
    if ((v_nominal(k) > 0) != (v_nominal(k - 1) > 0)) ++r.velocity_reversals;

  // The affected mode of a linearly different true plant (mode_shift).
  PolePair mode_nominal, mode_true;
  if (sc.true_plant) {
    mode_nominal = {plant.freq_hz.front(), plant.damping.front()};  // exact by construction (chain_plant)
    mode_true = pole_pairs(real.continuous.A).front();
  }

  // How large the effect is where it acts, for the README's concealment column.
  char note[160] = "";
  const double u_range = u.maxCoeff() - u.minCoeff();
  if (fx.cubic_coefficient != 0) {
    // Linear stiffness seen at the driven mass at DC, N per output unit: 1 / G(0).
    const double k_static = 1.0 / (-plant.continuous.C * plant.continuous.A.inverse() * plant.continuous.B)(0, 0);
    const double y_rms = rms(y_plant), y_max = y_plant.cwiseAbs().maxCoeff();
    std::snprintf(note, sizeof note, "c y^2 / k_static: %.2f %% at y_rms, %.1f %% at max|y|",
                  100.0 * fx.cubic_coefficient * y_rms * y_rms / k_static,
                  100.0 * fx.cubic_coefficient * y_max * y_max / k_static);
  } else if (closed) {
    std::snprintf(note, sizeof note, "|force| / rms u: %.1f %%, level / rms u: %.1f %%; loop %.1f Hz, poles |z| < %.4f",
                  100.0 * std::abs(fx.constant_force) / rms(u), 100.0 * fx.friction_level / rms(u), loop.bandwidth_hz,
                  loop.max_abs_pole);
  } else if (sc.true_plant) {
    std::snprintf(note, sizeof note, "mode %.3f Hz (zeta %.4f) -> %.3f Hz (zeta %.4f)", mode_nominal.freq_hz,
                  mode_nominal.damping, mode_true.freq_hz, mode_true.damping);
  } else if (fx.friction_level > 0) {
    std::snprintf(note, sizeof note, "level / max|u|: %.1f %%", 100.0 * fx.friction_level / u.cwiseAbs().maxCoeff());
  } else if (fx.store_limit > 0) {
    const double a = std::exp(-kTwoPi * fx.store_corner_hz * kTs);
    double level = 0.0;
    Eigen::Index capped = 0;
    for (Eigen::Index k = 0; k < kSamples; ++k) {
      level = a * level + (1.0 - a) * u(k);
      if (level > fx.store_limit) ++capped, level = fx.store_limit;
    }
    std::snprintf(note, sizeof note, "capped samples: %.1f %%, limit / peak command %.2f",
                  100.0 * static_cast<double>(capped) / kSamples, fx.store_limit / u.maxCoeff());
  } else if (fx.saturation_limit > 0) {
    const auto clipped = (u.array().abs() > fx.saturation_limit).count();
    std::snprintf(note, sizeof note, "clipped samples: %.2f %%, limit / u_rms %.2f",
                  100.0 * static_cast<double>(clipped) / kSamples, fx.saturation_limit / rms(u));
  } else if (fx.bw_alpha > 0 || fx.backlash_width > 0 || fx.deadzone_width > 0) {
    const Eigen::VectorXd dev = u - force;
    std::snprintf(note, sizeof note, "(u - force): max %.1f %%, rms %.2f %% of the u range", 100.0 * dev.cwiseAbs().maxCoeff() / u_range,
                  100.0 * rms(dev) / u_range);
  }
  r.note = note;

  r.fit_nominal = fit_on_validation(y, y_nominal);
  r.fit_oracle = fit_on_validation(y, y_true);
  {
    const Eigen::Index s = validation_start(), n = kSamples - s;
    const Eigen::VectorXd yv = y.segment(s, n);
    r.effect_percent =
        100.0 * (y_true - y_nominal).segment(s, n).norm() / (yv.array() - yv.mean()).matrix().norm();
  }

  // Files.
  const std::filesystem::path dir = out / sc.name;
  std::filesystem::create_directories(dir);
  Eigen::MatrixXd table(kSamples, 3);
  table.col(0) = Eigen::VectorXd::LinSpaced(kSamples, 0.0, static_cast<double>(kSamples - 1)) * kTs;
  table.col(1) = u;
  table.col(2) = y;
  sysid::write_csv((dir / "log.csv").string(), {"t", "u", "y"}, table);

  sysid::ModelFile model;
  model.model = nominal;
  model.provenance = {{"method", "generator"}, {"scenario", sc.name}};
  model.extra["output_quantities"] = {plant.output_quantity};  // what y measures (DESIGN.md "Model files")
  sysid::write_model_json((dir / "nominal.json").string(), model);

  json effects = effects_json(tp, fx, plant, sc.describe_output);
  if (hum_amplitude > 0)
    effects.push_back({{"kind", "periodic_disturbance"},
                       {"params", {{"freq_hz", fx.hum_freq_hz}, {"amplitude", hum_amplitude}, {"phase_rad", fx.hum_phase_rad}}}});
  if (offset != 0 || slope != 0) effects.push_back({{"kind", "offset_drift"}, {"params", {{"offset", offset}, {"slope", slope}}}});
  if (sc.true_plant)
    effects.push_back({{"kind", "mode_shift"},
                       {"params", {{"freq_hz", mode_true.freq_hz}, {"damping", mode_true.damping},
                                   {"nominal_freq_hz", mode_nominal.freq_hz}, {"nominal_damping", mode_nominal.damping},
                                   {"stiffness_ratio", sc.stiffness_ratio},
                                   {"spring", "flexure (frame to carriage)"}}}});
  json input = {{"multisine_band_hz", {sc.input.f_min_hz, sc.input.f_max_hz}},
                {"multisine_rms", sc.input.multisine_rms},
                {"multisine_seed", sc.input.seed}};
  if (sc.input.sine_amplitude > 0) input["sine"] = {{"freq_hz", sc.input.sine_hz}, {"amplitude", sc.input.sine_amplitude}};
  if (sc.input.burst_gain != 1.0)
    input["bursts"] = {{"gain", sc.input.burst_gain}, {"start_s", sc.input.burst_start_s},
                       {"period_s", sc.input.burst_period_s}, {"length_s", sc.input.burst_length_s}};
  if (closed)
    input = {{"logged_u", "the PD controller's output (see controller)"},
             {"reference", {{"profile", "minimum-jerk strokes r = p0 + (p1 - p0)(10 s^3 - 15 s^4 + 6 s^5), "
                                        "s = (t - t_j) / move_s, t_j = start_s + j (move_s + dwell_s), then a dwell"},
                            {"targets", sc.loop.targets}, {"unit", plant.y_unit}, {"start_s", sc.loop.start_s},
                            {"move_s", sc.loop.move_s}, {"dwell_s", sc.loop.dwell_s}}}};
  json truth;
  truth["scenario"] = sc.name;
  truth["plant"] = plant.name;
  if (sc.describe_output) truth["output_quantity"] = plant.output_quantity;
  truth["effects"] = effects;
  if (!sc.forbidden_kinds.empty()) truth["forbidden_kinds"] = sc.forbidden_kinds;
  if (closed) {
    json pairs = json::array();
    for (const PolePair& pp : loop.pairs) pairs.push_back({{"freq_hz", pp.freq_hz}, {"damping", pp.damping}});
    truth["closed_loop"] = true;
    truth["controller"] = {
        {"law", "u[k] = kp (r[k] - y[k]) - kd (y[k] - y[k-1]) / Ts, y[-1] = 0; y the logged encoder reading; "
                "u[k] held over sample k (no computational delay)"},
        {"kp", sc.loop.kp}, {"kd", sc.loop.kd}, {"kp_unit", "N/" + plant.y_unit}, {"kd_unit", "N s/" + plant.y_unit},
        {"Ts", kTs},
        {"measurement", "y[k] = quantum * round((y_true(t_k) + noise_rms * w[k]) / quantum), w white Gaussian"},
        {"quantum", sc.loop.quantum},
        {"bandwidth_hz", loop.bandwidth_hz},
        {"bandwidth_definition", "first frequency where |T(r -> y)| falls below |T(0)| / sqrt(2), nominal plant"},
        {"closed_loop_pole_pairs", pairs},
        {"max_abs_pole", loop.max_abs_pole}};
  }
  truth["concealment"] = sc.concealment;
  truth["noise_rms"] = r.noise_rms;
  if (sc.describe_output) {
    if (sc.noise_corner_hz > 0)
      truth["noise_colour"] = {{"kind", "first-order low-pass (AR(1))"}, {"corner_hz", sc.noise_corner_hz},
                               {"pole", std::exp(-kTwoPi * sc.noise_corner_hz * kTs)},
                               {"law", "e[k] = a e[k-1] + sqrt(1 - a^2) noise_rms w[k], e[0] = noise_rms w[0], "
                                       "w white Gaussian; noise_rms is the stationary RMS"}};
    else
      truth["noise_colour"] = closed ? "white, before the encoder's quantisation" : "white";
  }
  truth["fit_nominal"] = r.fit_nominal;
  truth["fit_oracle"] = r.fit_oracle;
  truth["validation"] = "last 30% of samples";
  truth["validation_start_index"] = validation_start();
  truth["fs_hz"] = kFs;
  truth["samples"] = kSamples;
  truth["input"] = input;
  truth["plant_parameters"] = plant.description;
  if (sc.true_plant) truth["true_plant_parameters"] = real.description;
  sysid::write_file_atomically((dir / "truth.json").string(), truth.dump(2) + "\n");
  return r;
}

struct Plants {
  Plant arm = flexible_arm(), iso = piezo_isolator(), stage = positioning_stage();
  Plant drive = linear_drive();                         ///< velocity output
  Plant guided_acceleration = guided_drive("acceleration");
  Plant guided_position = guided_drive("position");
  static constexpr double kStiffnessRatio = 1.08;       ///< stage_stiffness_error
  Plant stiff_stage = stiffer_flexure(stage, kStiffnessRatio);
};

std::vector<Scenario> scenarios(const Plants& plants) {
  const Plant &arm = plants.arm, &iso = plants.iso, &stage = plants.stage;
  // Excitations per plant: a multisine over the modes, plus slow strokes where the
  // effect needs velocity reversals or large amplitudes.
  InputSpec arm_in;
  arm_in.f_min_hz = 2.0;
  arm_in.f_max_hz = 100.0;
  arm_in.multisine_rms = 1.0;
  arm_in.seed = 101;

  InputSpec iso_in;
  iso_in.f_min_hz = 1.0;
  iso_in.f_max_hz = 400.0;
  iso_in.multisine_rms = 0.1;
  iso_in.seed = 201;

  InputSpec stage_in;
  stage_in.f_min_hz = 2.0;
  stage_in.f_max_hz = 500.0;
  stage_in.multisine_rms = 0.3;
  stage_in.seed = 301;
  stage_in.sine_hz = 1.0;
  stage_in.sine_amplitude = 3.0;

  std::vector<Scenario> v;
  const auto add = [&v](std::string name, const Plant& p, InputSpec in, Effects fx, double noise, std::uint64_t seed,
                        std::string concealment) {
    Scenario s;
    s.name = std::move(name);
    s.plant = &p;
    s.input = in;
    s.fx = fx;
    s.noise_over_signal = noise;
    s.noise_seed = seed;
    s.concealment = std::move(concealment);
    v.push_back(std::move(s));
  };

  {
    Effects fx;
    fx.mode_freq_hz = 22.0;
    fx.mode_damping = 0.012;
    fx.mode_relative_residue = 0.04;
    add("arm_missing_mode", arm, arm_in, fx, 0.01, 1001,
        "A weak mode at 22 Hz, 12 % below the dominant 25 Hz mode, whose peak is an order of magnitude lower and "
        "sits on the flank of the dominant resonance.");
  }
  {
    Effects fx;
    fx.delay_samples = 1;
    add("arm_time_delay", arm, arm_in, fx, 0.02, 1002,
        "One sample (0.5 ms) of transport delay: the magnitude response is unchanged, the phase lags by 6 deg at "
        "the 35 Hz mode.");
  }
  {
    Effects fx;
    fx.delay_samples = 2;
    add("isolator_time_delay2", iso, iso_in, fx, 0.02, 1003,
        "Two samples (1 ms) of transport delay: the magnitude response is unchanged and the slow suspension "
        "motion, which dominates the output, is barely shifted.");
  }
  {
    Effects fx;
    fx.lag_corner_hz = 300.0;
    add("isolator_input_lag", iso, iso_in, fx, 0.02, 1004,
        "A 300 Hz amplifier corner, above every mode: at the 10 Hz suspension mode, which dominates the output, it "
        "lags by 2 deg; only the weaker 153 Hz payload mode sees 27 deg and an 11 % lower gain.");
  }
  {
    Effects fx;
    fx.gain_ratio = 1.06;
    add("arm_gain_error", arm, arm_in, fx, 0.02, 1005,
        "The displacement sensor reads 6 % high: every mode, damping and phase is right, only the scale is off, "
        "within a typical calibration tolerance.");
  }
  {
    Effects fx;
    fx.friction_level = 0.1;
    add("stage_coulomb_friction", stage, stage_in, fx, 0.01, 1006,
        "Coulomb friction of 0.1 N against a 3 N stroke: it shows as a small step at each velocity reversal of "
        "the slow stroke and as a slight lag between reversals.");
  }
  {
    Effects fx;
    fx.cubic_coefficient = 3.0;
    InputSpec in = arm_in;
    in.burst_gain = 3.5;
    add("arm_cubic_stiffness", arm, in, fx, 0.01, 1007,
        "A hardening spring that adds under 1 % of the linear stiffness at the RMS amplitude and matters only in "
        "the large-amplitude bursts, where it detunes the resonances.");
  }
  {
    Effects fx;
    fx.backlash_width = 0.25;
    InputSpec in = stage_in;
    in.multisine_rms = 0.04;
    add("stage_backlash", stage, in, fx, 0.01, 1008,
        "A play of 0.25 N full width (4 % of the 6 N stroke): the force lags the command by half the play after "
        "each reversal of the command.");
  }
  {
    Effects fx;
    fx.deadzone_width = 0.2;
    add("stage_deadzone", stage, stage_in, fx, 0.01, 1009,
        "An amplifier dead zone of 0.2 N full width (3 % of the 6 N stroke): it removes 0.1 N from every command, "
        "which looks like a small gain and phase error of the slow stroke.");
  }
  {
    Effects fx;
    fx.saturation_limit = 0.24;
    add("isolator_saturation", iso, iso_in, fx, 0.01, 1010,
        "The amplifier clips at 2.4 times the input RMS: only the largest peaks of the multisine (under 2 % of "
        "the samples) are cut.");
  }
  {
    Effects fx;
    fx.bw_alpha = 0.12;
    fx.bw_beta = 1.5;
    fx.bw_gamma = 0.5;
    InputSpec in = iso_in;
    in.multisine_rms = 0.02;
    in.f_max_hz = 250.0;
    in.sine_hz = 2.0;
    in.sine_amplitude = 1.0;
    add("isolator_hysteresis", iso, in, fx, 0.01, 1011,
        "Bouc-Wen hysteresis at the piezo stack whose loop is a few per cent of the stroke; between reversals "
        "it looks like a slightly lower actuator gain.");
  }
  {
    Effects fx;
    fx.hum_freq_hz = 50.0;
    fx.hum_phase_rad = 0.7;
    fx.hum_rms_over_noise = 0.7;
    add("isolator_hum", iso, iso_in, fx, 0.16, 1012,
        "50 Hz mains hum on the sensor with 0.7 times the RMS of the white measurement noise, between the "
        "suspension and the payload modes.");
  }
  {
    Effects fx;
    fx.offset_over_signal = 0.03;
    fx.drift_over_signal = 0.05;
    add("stage_offset_drift", stage, stage_in, fx, 0.01, 1013,
        "A sensor offset of 3 % of the signal RMS and a drift of 5 % over the 10 s record, below the "
        "slow stroke's amplitude.");
  }
  {
    Effects fx;
    fx.friction_level = 0.07;
    fx.hum_freq_hz = 50.0;
    fx.hum_phase_rad = 2.1;
    fx.hum_rms_over_noise = 1.0;
    add("stage_friction_and_hum", stage, stage_in, fx, 0.015, 1014,
        "Two small effects at once: Coulomb friction of 0.07 N (2 % of the peak force) and 50 Hz hum as strong "
        "as the measurement noise.");
  }
  {
    Effects fx;
    fx.store_corner_hz = 20.0;
    fx.store_limit = 2.85;
    add("stage_relief_valve", stage, stage_in, fx, 0.01, 1017,
        "A pneumatic actuator whose chamber (20 Hz fill, in the nominal) has a relief valve at 2.85 N: only the top "
        "of the largest pushes of the 3 N stroke is capped, one-sided, and the fill lag smooths the cap.");
  }
  add("null_arm", arm, arm_in, Effects{}, 0.02, 1015, "Nothing is hidden: the nominal model is the true plant.");
  add("null_isolator", iso, iso_in, Effects{}, 0.02, 1016, "Nothing is hidden: the nominal model is the true plant.");

  // The drive scenarios (issue 33): other output quantities, a closed loop, a
  // direction-dependent friction, a purely linear stiffness error, coloured noise.
  // Their nominal.json and truth.json say what y measures (output_quantit(y|ies)).
  const Plant &drive = plants.drive, &guided_acc = plants.guided_acceleration, &guided_pos = plants.guided_position;
  InputSpec drive_in;  // as the stage's: a multisine over the modes plus a 1 Hz stroke, 20 reversals
  drive_in.f_min_hz = 2.0;
  drive_in.f_max_hz = 500.0;
  drive_in.multisine_rms = 0.3;
  drive_in.seed = 401;
  drive_in.sine_hz = 1.0;
  drive_in.sine_amplitude = 3.0;
  InputSpec guided_in = drive_in;
  guided_in.seed = 501;
  guided_in.multisine_rms = kGuidedMultisineRms;
  guided_in.sine_amplitude = kGuidedSineAmplitude;
  const auto add_new = [&v, &add](std::string name, const Plant& p, InputSpec in, Effects fx, double noise,
                                  std::uint64_t seed, std::string concealment) {
    add(std::move(name), p, in, fx, noise, seed, std::move(concealment));
    v.back().describe_output = true;
  };
  {
    Effects fx;
    fx.friction_level = kDriveFriction;
    add_new("drive_velocity_friction", drive, drive_in, fx, 0.01, 1018,
            "Coulomb friction on a linear drive whose log is the carriage speed: a small step of the speed at each of "
            "the stroke's reversals, otherwise a viscous-looking drag the nominal already has.");
  }
  {
    Effects fx;
    fx.friction_level = kAccelerationFriction;
    add_new("drive_acceleration_friction", guided_acc, guided_in, fx, 0.01, 1019,
            "Coulomb friction seen by an accelerometer on the carriage: a force step at each velocity reversal is an "
            "acceleration pulse, small beside the multisine's broadband accelerations.");
  }
  {
    Effects fx;
    fx.deadzone_width = kDriveDeadzone;
    add_new("drive_velocity_deadzone", drive, drive_in, fx, 0.01, 1020,
            "An amplifier dead zone on a drive whose log is the carriage speed: it removes half its width from every "
            "command, like friction would, but acts on the command, not on the velocity.");
  }
  {
    Effects fx;
    fx.friction_positive = 0.14;
    fx.friction_negative = 0.06;
    fx.friction_level = 0.5 * (fx.friction_positive + fx.friction_negative);
    add_new("stage_asymmetric_friction", stage, stage_in, fx, 0.01, 1021,
            "Coulomb friction that differs by direction, 0.14 N moving in +u and 0.06 N moving in -u: a symmetric "
            "0.1 N friction plus a force of 0.04 N against +u whenever the stage moves, either way (zero at rest).");
  }
  {
    Effects fx;
    fx.constant_force = kLoopConstantForce;
    fx.friction_level = kLoopFriction;
    add_new("drive_closed_loop_constant_force", guided_pos, InputSpec{}, fx, 0.0, 1022,
            "A constant force (gravity on a tilted axis) and Coulomb friction inside a PD position loop: the "
            "controller's output carries the force that holds the load, so the logged u already compensates most "
            "of what the nominal lacks.");
    Scenario& sc = v.back();
    sc.loop.on = true;
    sc.loop.kp = kLoopKp;
    sc.loop.kd = kLoopKd;
    sc.loop.quantum = 1.0;      // 1 um encoder counts
    sc.loop.noise_sigma = 0.3;  // um
    sc.loop.targets = {3000, -2000, 4000, -2500, 1500, -3500, 2500, -1000, 3500, -3000,
                       2000, -4000, 1000, -1500, 3000, -2500, 4000, -2000, 2500, -3000};
  }
  {
    add_new("stage_stiffness_error", stage, stage_in, Effects{}, 0.01, 1023,
            "The flexure is 8 % stiffer than the model's (same masses, same dampers): the 4 Hz suspension mode sits "
            "4 % higher with a 4 % lower damping ratio, and the slow stroke's response is 8 % smaller. "
            "Purely linear: no amplitude dependence.");
    v.back().true_plant = &plants.stiff_stage;
    v.back().stiffness_ratio = Plants::kStiffnessRatio;
    v.back().forbidden_kinds = {"cubic_stiffness"};
  }
  {
    add_new("null_drive_velocity", drive, drive_in, Effects{}, 0.02, 1024,
            "Nothing is hidden: the nominal model is the true plant; the measurement noise is coloured (a 20 Hz "
            "first-order low-pass of white noise), not white.");
    v.back().noise_corner_hz = 20.0;
  }
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: sysid_generate_concealed OUTDIR\n";
    return 1;
  }
  try {
    const auto start = std::chrono::steady_clock::now();
    const std::filesystem::path out = argv[1];
    std::filesystem::create_directories(out);
    const Plants plants;
    for (const Plant* p : {&plants.arm, &plants.iso, &plants.stage, &plants.drive, &plants.guided_position}) {
      std::cout << p->name << ":";
      for (std::size_t i = 0; i < p->freq_hz.size(); ++i)
        std::printf(" %.2f Hz (zeta %.3f)", p->freq_hz[i], p->damping[i]);
      std::cout << "\n";
    }
    std::printf("%-32s %8s %8s %6s %7s %10s %6s  %s\n", "scenario", "fit_nom", "fit_orc", "gap", "effect%",
                "noise_rms", "v_rev", "size of the effect");
    bool ok = true;
    for (const Scenario& sc : scenarios(plants)) {
      const Outcome r = run_scenario(sc, out);
      const double gap = r.fit_oracle - r.fit_nominal;
      const bool null = sc.name.rfind("null_", 0) == 0;
      std::printf("%-32s %8.3f %8.3f %6.3f %7.3f %10.4g %6ld  %s\n", sc.name.c_str(), r.fit_nominal, r.fit_oracle, gap,
                  r.effect_percent, r.noise_rms, r.velocity_reversals, r.note.c_str());
      if (null ? std::abs(gap) > 0.01 : gap < 2.0) {
        std::cerr << sc.name << ": gap " << gap << (null ? " should be ~0" : " is below 2 points") << "\n";
        ok = false;
      }
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("generated in %.2f s into %s\n", seconds, out.string().c_str());
    if (!ok) return 1;
  } catch (const std::exception& ex) {
    std::cerr << "sysid_generate_concealed: " << ex.what() << "\n";
    return 1;
  }
  return 0;
}
