// Tests for the detectors (include/sysid/diagnose/hypotheses.hpp,
// propose_candidates): each kind's detector on data made with that kind's block
// at a known value, the readings of an output whose quantity is unknown, and
// the channel each stage is proposed on.
#include <sysid/core/discretize.hpp>
#include <sysid/core/math_constants.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/diagnose/augmented_model.hpp>
#include <sysid/diagnose/hypotheses.hpp>
#include <sysid/diagnose/physics_kind.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../support/diagnose_cases.hpp"
#include "../support/random_matrices.hpp"

namespace test_unit_diagnose_hypotheses {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using sysid::Candidate;
using sysid::kTwoPi;
using sysid::OutputQuantity;
using sysid::PhysicsBlock;
using sysid::StateSpace;
using sysid::test::physics_block;

constexpr double kTs = 0.5e-3;
constexpr Eigen::Index kRows = 4000;  // 2 s

/// Continuous mass-spring-damper (unit mass), force in; outputs the rows of C.
StateSpace oscillator(double f_hz, double zeta, MatrixXd C = MatrixXd{{1.0, 0.0}}) {
  const double w = kTwoPi * f_hz;
  const Eigen::Index l = C.rows();
  return StateSpace(MatrixXd{{0.0, 1.0}, {-w * w, -2.0 * zeta * w}}, MatrixXd{{0.0}, {1.0}}, std::move(C),
                    MatrixXd::Zero(l, 1), 0.0);
}

/// The positioning stage: 20 Hz, damping 0.05, position out, sampled at 2 kHz.
constexpr double kStageHz = 20.0, kStageDamping = 0.05;
StateSpace stage() { return sysid::c2d_zoh(oscillator(kStageHz, kStageDamping), kTs); }

std::string listing(const std::vector<Candidate>& candidates) {
  std::ostringstream s;
  for (const Candidate& c : candidates) {
    s << "  " << c.block.kind << " (" << c.block.input << " -> " << c.block.output << ") score " << c.detector_score;
    for (const auto& [name, value] : c.block.params) s << " " << name << "=" << value;
    s << "\n";
  }
  return s.str();
}

/// The nominal's simulation and the measurement made with `truth` (1 % noise),
/// ready for propose_candidates.
struct Case {
  sysid::AugmentedSimulator simulator;
  sysid::DetectionData data;

  Case(const StateSpace& nominal, const std::vector<PhysicsBlock>& truth, const MatrixXd& u, int substeps = 4,
       const MatrixXd* y_given = nullptr)
      : simulator(nominal, substeps) {
    data.simulator = &simulator;
    data.u = u;
    data.current = simulator.simulate({}, u);
    const MatrixXd y = y_given ? *y_given : simulator.simulate(truth, u);
    data.y = y + noise(y, 1000 + static_cast<std::uint64_t>(u.rows()));
    data.Ts = nominal.Ts;
  }

  static MatrixXd noise(const MatrixXd& y, std::uint64_t seed) {
    MatrixXd e = sysid::test::white_noise(y.rows(), y.cols(), seed);
    for (Eigen::Index i = 0; i < y.cols(); ++i) {
      const double sd = std::sqrt((y.col(i).array() - y.col(i).mean()).square().mean());
      e.col(i) *= 0.01 * sd;
    }
    return e;
  }
};

/// The best candidate of `kind` among the first three, or nullptr.
const Candidate* in_top_three(const std::vector<Candidate>& candidates, const std::string& kind) {
  for (std::size_t k = 0; k < std::min<std::size_t>(3, candidates.size()); ++k)
    if (candidates[k].block.kind == kind) return &candidates[k];
  return nullptr;
}

/// Within a factor `factor` of the truth (same sign).
void expect_within_factor(double start, double truth, double factor, const std::string& what) {
  EXPECT_GT(start / truth, 1.0 / factor) << what << ": start " << start << ", truth " << truth;
  EXPECT_LT(start / truth, factor) << what << ": start " << start << ", truth " << truth;
}

/// The stage's input: filtered noise and a slow sine stroke (velocity reversals).
MatrixXd stage_input() { return sysid::test::reversing_excitation(kRows, kTs, 21); }

struct Truth {
  PhysicsBlock block;
  std::string parameter;   ///< the defining parameter checked
  double tolerance;        ///< relative (0.1) or a factor (2.0)
  bool factor = true;
  double null_value = 0.0; ///< the start's and the truth's distance from it is compared
};

/// Proposes on `c` and checks that `t`'s kind is among the first three with its
/// start near the truth; `found` gets that candidate (kind empty when absent).
void expect_detected(const Case& c, const Truth& t, Candidate& found_out) {
  found_out = Candidate{};
  const std::vector<Candidate> candidates = sysid::propose_candidates(c.data);
  ASSERT_FALSE(candidates.empty());
  EXPECT_TRUE(std::is_sorted(candidates.begin(), candidates.end(),
                             [](const Candidate& a, const Candidate& b) { return a.detector_score > b.detector_score; }));
  const Candidate* found = in_top_three(candidates, t.block.kind);
  ASSERT_NE(found, nullptr) << t.block.kind << " not in the top three:\n" << listing(candidates);
  found_out = *found;
  const double start = found->block.param(t.parameter) - t.null_value, truth = t.block.param(t.parameter) - t.null_value;
  if (t.factor) {
    expect_within_factor(start, truth, t.tolerance, t.block.kind + " " + t.parameter);
  } else {
    EXPECT_NEAR(start, truth, t.tolerance * std::abs(truth)) << t.block.kind << " " << t.parameter;
  }
  EXPECT_GT(found->detector_score, 0.3) << t.block.kind << "\n" << listing(candidates);
  EXPECT_FALSE(found->free.empty()) << t.block.kind;
  for (const sysid::FreeParameter& p : found->free) {
    const double v = found->block.param(p.name);
    EXPECT_LE(p.lower, v) << t.block.kind << " " << p.name;
    EXPECT_GE(p.upper, v) << t.block.kind << " " << p.name;
  }
}

// ---------------------------------------------------------------- detectors, one kind at a time

TEST(ProposeCandidatesDetectors, ActuatorKinds) {
  const StateSpace d = stage();
  const MatrixXd u = stage_input();
  const double u_rms = std::sqrt(u.squaredNorm() / static_cast<double>(u.rows())), u_max = u.cwiseAbs().maxCoeff();
  const double u_range = u.maxCoeff() - u.minCoeff();
  const std::vector<Truth> truths = {
      {physics_block("time_delay", {{"delay_s", 0.6 * kTs}}), "delay_s", 0.1, false},  // linear up to one sample
      {physics_block("input_lag", {{"corner_hz", 150.0}}), "corner_hz", 2.0},
      {physics_block("deadzone", {{"width", 0.3 * u_rms}}), "width", 2.0},
      {physics_block("backlash", {{"width", 0.2 * u_rms}}), "width", 2.0},
      {physics_block("saturation", {{"limit", 0.6 * u_max}}), "limit", 2.0},
      {physics_block("hysteresis", {{"alpha", 0.1}, {"beta", 4.0 / u_range}, {"gamma", 4.0 / u_range}}), "alpha", 2.0},
  };
  for (const Truth& t : truths) {
    SCOPED_TRACE(t.block.kind);
    Candidate found;
    expect_detected(Case(d, {t.block}, u, 1), t, found);
  }
}

TEST(ProposeCandidatesDetectors, PlantForces) {
  const StateSpace d = stage();
  const MatrixXd u = stage_input();
  const double u_rms = std::sqrt(u.squaredNorm() / static_cast<double>(u.rows()));
  const MatrixXd y_lin = sysid::simulate(d, u);
  const double p_max = y_lin.cwiseAbs().maxCoeff(), w = kTwoPi * kStageHz;
  const double p_var = y_lin.squaredNorm() / static_cast<double>(kRows), cubic = 0.3 * w * w / (p_max * p_max);
  const VectorXd v = (y_lin.col(0).tail(kRows - 1) - y_lin.col(0).head(kRows - 1)) / kTs;
  const double v_rms = std::sqrt(v.squaredNorm() / static_cast<double>(v.size()));
  const std::vector<Truth> truths = {
      {physics_block("coulomb_friction", {{"level", 0.1 * u_rms}, {"velocity_scale", 0.01 * v_rms}, {"asymmetry", 0.0}}), "level", 2.0},
      // The nominal is the best linear approximation of the stiffening plant: it
      // holds the cubic term's average stiffness 3 c E[p^2], which the truth's
      // linear coefficient takes back out (physics_block.hpp). Otherwise the
      // data show mostly a stiffer linear spring, which mode_shift explains.
      {physics_block("cubic_stiffness", {{"coefficient", cubic}, {"linear_coefficient", -3.0 * cubic * p_var}}), "coefficient", 2.0},
      {physics_block("constant_force", {{"force", 0.2 * u_rms}}), "force", 0.1, false},  // linear in the force
  };
  for (const Truth& t : truths) {
    SCOPED_TRACE(t.block.kind);
    Candidate found;
    expect_detected(Case(d, {t.block}, u, 4), t, found);
  }
}

TEST(ProposeCandidatesDetectors, ModalKinds) {
  const StateSpace d = stage();
  const MatrixXd u = stage_input();
  {
    // A 45 Hz mode the nominal lacks, 20 % of the nominal's static gain.
    const double gain = 0.2 / std::pow(kTwoPi * kStageHz, 2);
    const Truth t{physics_block("missing_mode", {{"freq_hz", 45.0}, {"damping", 0.02}, {"static_gain", gain}, {"velocity_gain", 0.0}}),
                  "static_gain", 2.0};
    Case c(d, {t.block}, u, 1);
    c.data.mode_frequencies_hz = {45.0};
    Candidate found;
    expect_detected(c, t, found);
    if (found.block.kind == t.block.kind) EXPECT_NEAR(found.block.param("freq_hz"), 45.0, 0.03 * 45.0);
  }
  {
    // The nominal's mode 1.2 % higher (measured on the moved oscillator itself).
    const StateSpace moved = sysid::c2d_zoh(oscillator(1.012 * kStageHz, kStageDamping), kTs);
    const MatrixXd y = sysid::simulate(moved, u);
    const Truth t{physics_block("mode_shift", {{"freq_hz", 1.012 * kStageHz}}), "freq_hz", 2.0, true, kStageHz};
    Candidate found;
    expect_detected(Case(d, {}, u, 1, &y), t, found);
    if (found.block.kind == t.block.kind) {
      EXPECT_NEAR(found.block.param("nominal_freq_hz"), kStageHz, 1e-6 * kStageHz);
      EXPECT_NEAR(found.block.param("nominal_damping"), kStageDamping, 1e-6);
    }
  }
}

TEST(ProposeCandidatesDetectors, SensorKinds) {
  const StateSpace d = stage();
  const MatrixXd u = stage_input();
  const MatrixXd y_lin = sysid::simulate(d, u);
  const double y_sd = std::sqrt((y_lin.array() - y_lin.mean()).square().mean()), T = kRows * kTs;
  {
    const Truth t{physics_block("gain_error", {{"ratio", 1.08}}), "ratio", 0.1, false, 1.0};
    Candidate found;
    expect_detected(Case(d, {t.block}, u, 1), t, found);
  }
  for (const char* parameter : {"offset", "slope"}) {
    const Truth t{physics_block("offset_drift", {{"offset", 0.2 * y_sd}, {"slope", -0.3 * y_sd / T}}), parameter, 0.1, false};
    Candidate found;
    expect_detected(Case(d, {t.block}, u, 1), t, found);
  }
  {
    const Truth t{physics_block("periodic_disturbance", {{"freq_hz", 50.2}, {"amplitude", 0.3 * y_sd}, {"phase_rad", 0.7}}),
                  "amplitude", 0.1, false};
    Case c(d, {t.block}, u, 1);
    c.data.peak_frequencies_hz = {50.0};
    c.data.frequency_resolution_hz = 0.5;
    Candidate found;
    expect_detected(c, t, found);
    if (found.block.kind == t.block.kind) EXPECT_NEAR(found.block.param("freq_hz"), 50.2, 0.05 / T);
  }
}

/// Two decoupled stages (20 Hz and 31 Hz), input j to output j.
StateSpace two_stages() {
  const StateSpace a = oscillator(20, 0.05), b = oscillator(31, 0.04);
  MatrixXd A = MatrixXd::Zero(4, 4), B = MatrixXd::Zero(4, 2), C = MatrixXd::Zero(2, 4);
  A.topLeftCorner(2, 2) = a.A;
  A.bottomRightCorner(2, 2) = b.A;
  B.block(0, 0, 2, 1) = a.B;
  B.block(2, 1, 2, 1) = b.B;
  C.block(0, 0, 1, 2) = a.C;
  C.block(1, 2, 1, 2) = b.C;
  return sysid::c2d_zoh(StateSpace(A, B, C, MatrixXd::Zero(2, 2), 0.0), kTs);
}

MatrixXd two_inputs(Eigen::Index rows) {
  MatrixXd u(rows, 2);
  u.col(0) = sysid::test::reversing_excitation(rows, kTs, 22).col(0);
  u.col(1) = sysid::test::reversing_excitation(rows, kTs, 23).col(0);
  return u;
}

TEST(ProposeCandidatesDetectors, CrossCoupling) {
  const StateSpace d = two_stages();
  const MatrixXd u = two_inputs(kRows);
  // Input 0's motion seen at output 1, at 30 % of output 1's own size.
  const MatrixXd y = sysid::simulate(d, u);
  const double gain = 0.3 * std::sqrt(y.col(1).squaredNorm() / y.col(0).squaredNorm());
  const Truth t{physics_block("cross_coupling", {{"gain", gain}}, 0, 1), "gain", 0.1, false};
  Candidate found;
  expect_detected(Case(d, {t.block}, u, 1), t, found);
  EXPECT_EQ(found.block.input, 0);
  EXPECT_EQ(found.block.output, 1);
}

// ---------------------------------------------------------------- readings of an unknown quantity

TEST(ProposeCandidatesReadings, FrictionOncePerReadingAndTheTrueReadingScoresHigher) {
  // The stage measured by its velocity; the truth is friction read from it.
  const StateSpace d = sysid::c2d_zoh(oscillator(kStageHz, kStageDamping, MatrixXd{{0.0, 1.0}}), kTs);
  const MatrixXd u = stage_input();
  const sysid::AugmentedSimulator as_position(d, 4, {}, {OutputQuantity::position});
  const sysid::AugmentedSimulator as_velocity(d, 4, {}, {OutputQuantity::velocity});
  const MatrixXd y_lin = sysid::simulate(d, u);
  const double u_rms = std::sqrt(u.squaredNorm() / static_cast<double>(u.rows()));
  const double v_rms = std::sqrt(y_lin.squaredNorm() / static_cast<double>(y_lin.rows()));
  const PhysicsBlock truth = physics_block("coulomb_friction", {{"level", 0.1 * u_rms}, {"velocity_scale", 0.01 * v_rms}, {"asymmetry", 0.0}});
  const MatrixXd y = as_velocity.simulate({truth}, u);
  Case c(d, {}, u, 4, &y);  // the model's own reading: unknown
  c.data.plant_readings = {&as_position, &as_velocity};
  const std::vector<Candidate> candidates = sysid::propose_candidates(c.data);
  std::map<std::string, std::vector<const Candidate*>> by_kind;
  for (const Candidate& k : candidates) by_kind[k.block.kind].push_back(&k);
  for (const char* kind : {"coulomb_friction", "cubic_stiffness"}) {
    ASSERT_EQ(by_kind[kind].size(), 2u) << kind << "\n" << listing(candidates);
    std::set<std::vector<OutputQuantity>> readings;
    for (const Candidate* k : by_kind[kind]) readings.insert(k->output_quantities);
    ASSERT_EQ(readings, (std::set<std::vector<OutputQuantity>>{{OutputQuantity::position}, {OutputQuantity::velocity}})) << kind;
  }
  // A constant force reads no motion: once, under the model's reading.
  ASSERT_EQ(by_kind["constant_force"].size(), 1u);
  EXPECT_TRUE(by_kind["constant_force"].front()->output_quantities.empty());
  const auto& friction = by_kind["coulomb_friction"];
  const Candidate* velocity = friction[0]->output_quantities.front() == OutputQuantity::velocity ? friction[0] : friction[1];
  const Candidate* position = velocity == friction[0] ? friction[1] : friction[0];
  EXPECT_GT(velocity->detector_score, position->detector_score + 0.1) << listing(candidates);
  EXPECT_EQ(candidates.front().block.kind, "coulomb_friction") << listing(candidates);
  EXPECT_EQ(candidates.front().output_quantities, std::vector<OutputQuantity>{OutputQuantity::velocity});
  expect_within_factor(velocity->block.param("level"), truth.param("level"), 2.0, "level under the velocity reading");
}

// ---------------------------------------------------------------- channels

using Paths = std::multiset<std::pair<long, long>>;

/// (input, output) of each kind's candidates; at(kind) is empty for a kind not proposed.
struct Channels {
  std::map<std::string, Paths> of;
  Paths at(const std::string& kind) const {
    const auto it = of.find(kind);
    return it == of.end() ? Paths{} : it->second;
  }
  std::size_t size() const { return of.size(); }
};

Channels channels(const std::vector<Candidate>& candidates) {
  Channels out;
  for (const Candidate& c : candidates) out.of[c.block.kind].insert({c.block.input, c.block.output});
  return out;
}

TEST(ProposeCandidatesChannels, TwoByTwo) {
  const StateSpace d = two_stages();
  const MatrixXd u = two_inputs(1000);
  Case c(d, {}, u, 4);
  c.data.mode_frequencies_hz = {45.0};
  c.data.peak_frequencies_hz = {50.0};
  const auto found = channels(sysid::propose_candidates(c.data));
  const Paths collocated = {{0, 0}, {1, 1}}, per_output = {{0, 0}, {0, 1}};
  for (const char* kind : {"time_delay", "input_lag", "deadzone", "backlash", "saturation", "hysteresis"})
    EXPECT_EQ(found.at(kind), collocated) << kind << ": once per input, seen at its own output";
  for (const char* kind : {"gain_error", "offset_drift", "periodic_disturbance"}) EXPECT_EQ(found.at(kind), per_output) << kind;
  for (const char* kind : {"coulomb_friction", "cubic_stiffness", "constant_force", "missing_mode"})
    EXPECT_EQ(found.at(kind), collocated) << kind << ": collocated only";
  EXPECT_EQ(found.at("cross_coupling"), (Paths{{0, 1}, {1, 0}}));
  // Each stage's one lightly damped mode, on its own path (the other path's
  // residue is zero but the path is collocated all the same).
  ASSERT_FALSE(found.at("mode_shift").empty());
  for (const auto& [j, i] : found.at("mode_shift")) EXPECT_EQ(i, j);
  EXPECT_EQ(found.size(), sysid::physics_kinds().size());
}

TEST(ProposeCandidatesChannels, OneInputTwoOutputsAndTwoInputsOneOutput) {
  const StateSpace two = two_stages();
  const MatrixXd u = two_inputs(1000);
  {
    // Input 0 only, both outputs: actuator and plant forces at output 0; modes on every path.
    const StateSpace d(two.A, two.B.col(0), two.C, two.D.col(0), kTs);
    Case c(d, {}, u.col(0), 4);
    c.data.mode_frequencies_hz = {45.0};
    const auto found = channels(sysid::propose_candidates(c.data));
    EXPECT_EQ(found.at("deadzone"), (Paths{{0, 0}}));
    EXPECT_EQ(found.at("coulomb_friction"), (Paths{{0, 0}}));
    EXPECT_EQ(found.at("missing_mode"), (Paths{{0, 0}, {0, 1}}));
    EXPECT_EQ(found.at("gain_error"), (Paths{{0, 0}, {0, 1}}));
    EXPECT_EQ(found.at("cross_coupling"), (Paths{{0, 1}}));
  }
  {
    // Both inputs, output 0 only: actuators seen at the only output; the plant's
    // forces from every input onto it; no coupling.
    const StateSpace d(two.A, two.B, two.C.row(0), two.D.row(0), kTs);
    Case c(d, {}, u, 4);
    c.data.mode_frequencies_hz = {45.0};
    const auto found = channels(sysid::propose_candidates(c.data));
    EXPECT_EQ(found.at("deadzone"), (Paths{{0, 0}, {1, 0}}));
    EXPECT_EQ(found.at("coulomb_friction"), (Paths{{0, 0}, {1, 0}}));
    EXPECT_EQ(found.at("missing_mode"), (Paths{{0, 0}, {1, 0}}));
    EXPECT_EQ(found.at("gain_error"), (Paths{{0, 0}}));
    EXPECT_TRUE(found.at("cross_coupling").empty());
  }
}

TEST(ProposeCandidatesChannels, ConstantInputProposesNoActuatorOrPlantForce) {
  // Input 1 held: no evidence about its actuator or the forces it meets.
  const StateSpace d = two_stages();
  MatrixXd u = two_inputs(1000);
  u.col(1).setConstant(2.0);
  const Case c(d, {}, u, 4);
  const auto found = channels(sysid::propose_candidates(c.data));
  for (const char* kind : {"time_delay", "deadzone", "saturation", "coulomb_friction", "constant_force"})
    EXPECT_EQ(found.at(kind), (Paths{{0, 0}})) << kind;
}

TEST(ProposeCandidatesChannels, InvalidArgumentsThrow) {
  const StateSpace d = stage();
  const MatrixXd u = stage_input().topRows(500);
  const Case c(d, {}, u, 4);
  ASSERT_NO_THROW(sysid::propose_candidates(c.data));
  auto expect_throw = [&](auto change, const char* what) {
    sysid::DetectionData data = c.data;
    change(data);
    EXPECT_THROW(sysid::propose_candidates(data), std::invalid_argument) << what;
  };
  expect_throw([](sysid::DetectionData& x) { x.simulator = nullptr; }, "no simulator");
  expect_throw([](sysid::DetectionData& x) { x.u = x.u.topRows(400).eval(); }, "u rows");
  expect_throw([](sysid::DetectionData& x) { x.current = x.current.topRows(400).eval(); }, "current rows");
  expect_throw([](sysid::DetectionData& x) { x.current = MatrixXd::Zero(x.y.rows(), 2); }, "current columns");
  expect_throw([](sysid::DetectionData& x) { x.Ts = 0.0; }, "Ts = 0");
  expect_throw([](sysid::DetectionData& x) { x.Ts = -kTs; }, "Ts < 0");
  expect_throw([](sysid::DetectionData& x) { x.Ts = NAN; }, "Ts NaN");
  expect_throw([](sysid::DetectionData& x) { x.plant_readings = {nullptr}; }, "missing reading");
  const StateSpace two_outputs = sysid::c2d_zoh(oscillator(kStageHz, kStageDamping, MatrixXd{{1.0, 0.0}, {0.0, 1.0}}), kTs);
  const sysid::AugmentedSimulator other(two_outputs, 4);
  expect_throw([&](sysid::DetectionData& x) { x.plant_readings = {&other}; }, "reading with other outputs");
}

}  // namespace

}  // namespace test_unit_diagnose_hypotheses
