// Tests for the physics kinds (include/sysid/diagnose/physics_kind.hpp), each on
// its own: the registry, and every kind's part in the simulation against an
// independent implementation of its equation written here from the headers'
// comments (actuator laws, sensor formulas, the plant's force laws, an RK4
// reference of the continuous plant with the force, exactly discretised
// parallel modes), and the output quantities the plant's forces read.
#include <sysid/core/discretize.hpp>
#include <sysid/core/math_constants.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/diagnose/augmented_model.hpp>
#include <sysid/diagnose/physics_kind.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <tuple>
#include <string>
#include <vector>

#include "../support/diagnose_cases.hpp"
#include "../support/random_matrices.hpp"

namespace test_unit_diagnose_physics_kind {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using sysid::kTwoPi;
using sysid::OutputQuantity;
using sysid::PhysicsBlock;
using sysid::StateSpace;
using sysid::test::physics_block;

constexpr double kTs = 0.5e-3;

/// Continuous mass-spring-damper (unit mass), force in, x1 = position, x2 =
/// velocity; the outputs are the rows of C (default: the position).
StateSpace oscillator(double f_hz, double zeta, MatrixXd C = MatrixXd{{1.0, 0.0}}) {
  const double w = kTwoPi * f_hz;
  const Eigen::Index l = C.rows();
  return StateSpace(MatrixXd{{0.0, 1.0}, {-w * w, -2.0 * zeta * w}}, MatrixXd{{0.0}, {1.0}}, std::move(C),
                    MatrixXd::Zero(l, 1), 0.0);
}

double relative_error(const MatrixXd& a, const MatrixXd& b) { return (a - b).norm() / b.norm(); }

std::vector<std::string> names(const std::vector<const char*>& list) { return {list.begin(), list.end()}; }

bool contains(const std::vector<const char*>& list, const char* name) {
  return std::any_of(list.begin(), list.end(), [&](const char* p) { return std::string(p) == name; });
}

// ---------------------------------------------------------------- registry

TEST(PhysicsKindRegistry, NamesAreUniqueAndFound) {
  const auto& kinds = sysid::physics_kinds();
  std::set<std::string> seen;
  for (const sysid::PhysicsKind* k : kinds) {
    ASSERT_NE(k, nullptr);
    const std::string name = k->info().kind;
    EXPECT_TRUE(seen.insert(name).second) << "duplicate kind " << name;
    EXPECT_EQ(&sysid::physics_kind(name), k) << name;
    EXPECT_EQ(&sysid::block_kind_info(name), &k->info()) << name;
  }
  // The 13 DESIGN.md kinds and the two added since, none lost.
  const std::set<std::string> expected = {"missing_mode", "time_delay", "gain_error", "input_lag", "coulomb_friction",
                                          "backlash", "deadzone", "saturation", "cubic_stiffness", "hysteresis",
                                          "periodic_disturbance", "offset_drift", "cross_coupling", "mode_shift",
                                          "constant_force"};
  EXPECT_EQ(seen, expected);
  for (const std::string unknown : {"no_such_kind", "", "Deadzone", "deadzone "}) {
    EXPECT_THROW(sysid::physics_kind(unknown), std::invalid_argument) << "'" << unknown << "'";
    EXPECT_THROW(sysid::block_kind_info(unknown), std::invalid_argument) << "'" << unknown << "'";
  }
}

TEST(PhysicsKindRegistry, ReportedDefiningAndOptionalTermsNameParameters) {
  for (const sysid::PhysicsKind* k : sysid::physics_kinds()) {
    const sysid::BlockKindInfo& info = k->info();
    const std::string kind = info.kind;
    EXPECT_FALSE(info.parameters.empty()) << kind;
    const std::vector<std::string> parameters = names(info.parameters);
    EXPECT_EQ(std::set<std::string>(parameters.begin(), parameters.end()).size(), parameters.size()) << kind << ": a parameter twice";
    for (const char* r : info.reported) EXPECT_TRUE(contains(info.parameters, r)) << kind << " reports " << r;
    for (const auto* list : {&info.defining, &info.optional_terms})
      for (const sysid::DefiningParameter& d : *list) {
        EXPECT_TRUE(contains(info.parameters, d.name)) << kind << ": " << d.name;
        if (d.null_parameter != nullptr) EXPECT_TRUE(contains(info.parameters, d.null_parameter)) << kind << ": " << d.null_parameter;
      }
    // A parameter a file may omit is one of the kind's; others have no default.
    double value = 0.0;
    for (const char* p : info.parameters) {
      if (k->optional_default(p, value)) EXPECT_TRUE(std::isfinite(value)) << kind << ": " << p;
    }
    EXPECT_FALSE(k->optional_default("no_such_parameter", value)) << kind;
    // The default reports are the reported parameters (friction adds its two directions).
    PhysicsBlock b = physics_block(kind, {});
    for (const char* p : info.parameters) b.params[p] = 0.5;
    const auto reported = k->reported(b);
    for (const char* r : info.reported) EXPECT_EQ(reported.count(r), 1u) << kind << ": " << r;
    EXPECT_FALSE(k->summary(b, {"u", "y", kTs}).empty()) << kind;
    // Only the plant's forces have a force law.
    sysid::PlantForce force;
    EXPECT_EQ(k->plant_force(b, force), info.stage == sysid::BlockStage::plant_feedback) << kind;
  }
}

TEST(PhysicsKindRegistry, BlockKindsMatchThePhysicsKinds) {
  const auto& kinds = sysid::physics_kinds();
  const auto& infos = sysid::block_kinds();
  ASSERT_EQ(infos.size(), kinds.size());
  for (std::size_t k = 0; k < kinds.size(); ++k) {
    const sysid::BlockKindInfo& a = infos[k];
    const sysid::BlockKindInfo& b = kinds[k]->info();
    EXPECT_EQ(std::string(a.kind), std::string(b.kind));
    EXPECT_EQ(a.stage, b.stage) << a.kind;
    EXPECT_EQ(names(a.parameters), names(b.parameters)) << a.kind;
    EXPECT_EQ(names(a.reported), names(b.reported)) << a.kind;
    EXPECT_EQ(a.defining.size(), b.defining.size()) << a.kind;
    EXPECT_EQ(a.chain_order, b.chain_order) << a.kind;
  }
  // The actuator chain's documented order: saturation, delay, dead zone, play,
  // hysteresis; the sensor stage's: gain, coupling, offset, periodic.
  auto order = [](const char* kind) { return sysid::block_kind_info(kind).chain_order; };
  EXPECT_LT(order("saturation"), order("time_delay"));
  EXPECT_LT(order("time_delay"), order("deadzone"));
  EXPECT_LT(order("deadzone"), order("backlash"));
  EXPECT_LT(order("backlash"), order("hysteresis"));
  EXPECT_LT(order("gain_error"), order("cross_coupling"));
  EXPECT_LT(order("cross_coupling"), order("offset_drift"));
  EXPECT_LT(order("offset_drift"), order("periodic_disturbance"));
}

// ---------------------------------------------------------------- actuator kinds
// Each law written from the kind's header comment, in a form of its own.

VectorXd deadzone_law(const VectorXd& u, double width) {
  VectorXd w(u.size());
  for (Eigen::Index k = 0; k < u.size(); ++k) w[k] = std::copysign(std::max(std::abs(u[k]) - 0.5 * width, 0.0), u[k]);
  return w;
}

/// Play operator from rest at 0: the output moves only when the input pulls it
/// by more than half the play.
VectorXd play_law(const VectorXd& u, double width) {
  VectorXd w(u.size());
  double out = 0.0;
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    if (u[k] - out > 0.5 * width) out = u[k] - 0.5 * width;
    if (out - u[k] > 0.5 * width) out = u[k] + 0.5 * width;
    w[k] = out;
  }
  return w;
}

/// The sampled command, interpolated linearly in time, at t - delay (0 before the record).
VectorXd delay_law(const VectorXd& u, double delay_s, double Ts) {
  VectorXd w(u.size());
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    const double t = static_cast<double>(k) * Ts - delay_s;
    const double position = t / Ts;
    const auto before = static_cast<Eigen::Index>(std::floor(position));
    const double weight = position - static_cast<double>(before);
    auto at = [&](Eigen::Index i) { return i >= 0 && i < u.size() ? u[i] : 0.0; };
    w[k] = at(before) + weight * (at(before + 1) - at(before));
  }
  return w;
}

/// Discrete Bouc-Wen (n = 1): force = u - h, h from 0 at the first sample.
VectorXd bouc_wen_law(const VectorXd& u, double alpha, double beta, double gamma) {
  VectorXd w = u;
  double h = 0.0;
  for (Eigen::Index k = 1; k < u.size(); ++k) {
    const double du = u[k] - u[k - 1];
    h = h + alpha * du - beta * std::abs(du) * h - gamma * du * std::abs(h);
    w[k] = u[k] - h;
  }
  return w;
}

/// A command with slow reversals, small and large amplitudes.
VectorXd actuator_command(Eigen::Index n) {
  const MatrixXd noise = sysid::test::white_noise(n, 1, 11);
  VectorXd u(n);
  for (Eigen::Index k = 0; k < n; ++k) u[k] = 2.0 * std::sin(kTwoPi * static_cast<double>(k) / 400.0) + 0.3 * noise(k, 0);
  return u;
}

VectorXd actuate(const PhysicsBlock& b, const VectorXd& u, double Ts = kTs) {
  return sysid::actuator_output({b}, u, Ts, u.size()).col(0);
}

TEST(PhysicsKindActuator, DeadzoneBacklashAndAmplifierSaturation) {
  const VectorXd u = actuator_command(2000);
  const double width = 0.8;
  VectorXd w = actuate(physics_block("deadzone", {{"width", width}}), u);
  EXPECT_LT((w - deadzone_law(u, width)).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_GT((w - u).cwiseAbs().maxCoeff(), 0.3);  // the case is not trivial
  w = actuate(physics_block("backlash", {{"width", width}}), u);
  EXPECT_LT((w - play_law(u, width)).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_GT((w - u).cwiseAbs().maxCoeff(), 0.3);
  w = actuate(physics_block("saturation", {{"limit", 1.2}}), u);
  EXPECT_LT((w - u.cwiseMax(-1.2).cwiseMin(1.2)).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_DOUBLE_EQ(w.maxCoeff(), 1.2);
  EXPECT_DOUBLE_EQ(w.minCoeff(), -1.2);
  // Null values: no width, a limit beyond the command.
  EXPECT_EQ(actuate(physics_block("deadzone", {{"width", 0.0}}), u), u);
  EXPECT_EQ(actuate(physics_block("backlash", {{"width", 0.0}}), u), u);
  EXPECT_EQ(actuate(physics_block("saturation", {{"limit", 10.0}}), u), u);
}

TEST(PhysicsKindActuator, StoreOverflowOnAHandWorkedCommand) {
  // Pole a = 0.5, limit 1, command 0, 3, 3, 3, 0 from a store at 0. Level v and
  // seen level z (physics_block.hpp): filled = a v + (1 - a) u, v+ = min(filled, 1),
  // z+ = v+ + spill (filled - v+) / (1 - a), out = (z+ - a z) / (1 - a).
  // spill 0:    filled 0, 1.5, 2, 2, 0.5 -> z+ 0, 1, 1, 1, 0.5 -> out 0, 2, 1, 1, 0.
  // spill 0.25: z+ 0, 1.25, 1.5, 1.5, 0.5 -> out 0, 2.5, 1.75, 1.5, -0.5.
  const VectorXd u = (VectorXd(5) << 0, 3, 3, 3, 0).finished();
  const auto store = [](double spill) {
    return physics_block("saturation", {{"limit", 1.0}, {"storage_pole", 0.5}, {"spill", spill}});
  };
  EXPECT_LT((actuate(store(0.0), u, 1.0) - (VectorXd(5) << 0, 2, 1, 1, 0).finished()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((actuate(store(0.25), u, 1.0) - (VectorXd(5) << 0, 2.5, 1.75, 1.5, -0.5).finished()).cwiseAbs().maxCoeff(), 1e-15);
  // Below the limit the store passes the command on unchanged.
  const VectorXd small = 0.4 * actuator_command(500) / 2.3;
  ASSERT_LT(small.maxCoeff(), 1.0);
  EXPECT_LT((actuate(store(0.25), small, 1.0) - small).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(PhysicsKindActuator, FractionalDelayInterpolatesTheCommand) {
  const VectorXd u = actuator_command(800);
  for (double samples : {0.0, 0.3, 1.0, 2.75, 7.5}) {
    const VectorXd w = actuate(physics_block("time_delay", {{"delay_s", samples * kTs}}), u);
    EXPECT_LT((w - delay_law(u, samples * kTs, kTs)).cwiseAbs().maxCoeff(), 1e-12) << samples;  // |u| < 4
  }
}

TEST(PhysicsKindActuator, HysteresisIsTheDiscreteBoucWenLoop) {
  const VectorXd u = actuator_command(2000);
  const double range = u.maxCoeff() - u.minCoeff();
  for (const auto& [alpha, beta, gamma] : {std::tuple{0.2, 4.0 / range, 4.0 / range}, std::tuple{0.1, 1.0 / range, -0.5 / range},
                                           std::tuple{0.0, 1.0, 1.0}}) {
    const VectorXd w = actuate(physics_block("hysteresis", {{"alpha", alpha}, {"beta", beta}, {"gamma", gamma}}), u);
    EXPECT_LT((w - bouc_wen_law(u, alpha, beta, gamma)).cwiseAbs().maxCoeff(), 1e-13) << alpha;
    if (alpha > 0) EXPECT_GT((w - u).cwiseAbs().maxCoeff(), 0.05) << alpha;
  }
}

TEST(PhysicsKindActuator, ChainOrderNotFileOrder) {
  // Listed backwards, the actuator blocks still act as saturation, delay, dead
  // zone, play, hysteresis.
  const VectorXd u = actuator_command(1500);
  const std::vector<PhysicsBlock> blocks = {physics_block("hysteresis", {{"alpha", 0.1}, {"beta", 0.5}, {"gamma", 0.5}}),
                                            physics_block("backlash", {{"width", 0.3}}), physics_block("deadzone", {{"width", 0.4}}),
                                            physics_block("time_delay", {{"delay_s", 2.5 * kTs}}), physics_block("saturation", {{"limit", 1.5}})};
  const VectorXd expected =
      bouc_wen_law(play_law(deadzone_law(delay_law(u.cwiseMax(-1.5).cwiseMin(1.5), 2.5 * kTs, kTs), 0.4), 0.3), 0.1, 0.5, 0.5);
  EXPECT_LT((sysid::actuator_output(blocks, u, kTs, u.size()).col(0) - expected).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(PhysicsKindActuator, InputLagConvergesAtSecondOrderToTheExactCascade) {
  // The plant driven through 1 / (1 + s / wc), exactly discretised as one system.
  const StateSpace plant = oscillator(30, 0.02);
  const double corner = 150.0, wc = kTwoPi * corner;
  MatrixXd A = MatrixXd::Zero(3, 3), B = MatrixXd::Zero(3, 1), C = MatrixXd::Zero(1, 3);
  A.topLeftCorner(2, 2) = plant.A;
  A.block(0, 2, 2, 1) = plant.B;
  A(2, 2) = -wc;
  B(2, 0) = wc;
  C(0, 0) = 1.0;
  const StateSpace cascade = sysid::c2d_zoh(StateSpace(A, B, C, MatrixXd::Zero(1, 1), 0.0), kTs);
  const MatrixXd u = sysid::test::white_noise(3000, 1, 12);
  const MatrixXd exact = sysid::simulate(cascade, u);
  const StateSpace d = sysid::c2d_zoh(plant, kTs);
  const PhysicsBlock lag = physics_block("input_lag", {{"corner_hz", corner}});
  const double e4 = relative_error(sysid::AugmentedSimulator(d, 4).simulate({lag}, u), exact);
  const double e8 = relative_error(sysid::AugmentedSimulator(d, 8).simulate({lag}, u), exact);
  const double lag_effect = relative_error(sysid::simulate(d, u), exact);
  EXPECT_GT(lag_effect, 0.1);
  EXPECT_LT(e8, 2e-3 * lag_effect);
  EXPECT_GT(e4 / e8, 3.0);  // second order in wc h: halving h quarters the error
  EXPECT_LT(e4 / e8, 5.0);
}

// ---------------------------------------------------------------- sensor kinds

/// Two decoupled oscillators (20 Hz, 31 Hz), input j to output j.
StateSpace two_by_two() {
  const StateSpace a = oscillator(20, 0.03), b = oscillator(31, 0.02);
  MatrixXd A = MatrixXd::Zero(4, 4), B = MatrixXd::Zero(4, 2), C = MatrixXd::Zero(2, 4);
  A.topLeftCorner(2, 2) = a.A;
  A.bottomRightCorner(2, 2) = b.A;
  B.block(0, 0, 2, 1) = a.B;
  B.block(2, 1, 2, 1) = b.B;
  C.block(0, 0, 1, 2) = a.C;
  C.block(1, 2, 1, 2) = b.C;
  return sysid::c2d_zoh(StateSpace(A, B, C, MatrixXd::Zero(2, 2), 0.0), kTs);
}

TEST(PhysicsKindSensor, EachSensorKindIsItsFormulaOnTheNominalOutput) {
  const StateSpace d = two_by_two();
  const MatrixXd u = sysid::test::white_noise(3000, 2, 13);
  const sysid::AugmentedSimulator sim(d);
  const MatrixXd y0 = sysid::simulate(d, u);
  const VectorXd t = VectorXd::LinSpaced(u.rows(), 0.0, static_cast<double>(u.rows() - 1) * kTs);
  const double scale = y0.col(1).cwiseAbs().maxCoeff();
  auto check = [&](const PhysicsBlock& b, const VectorXd& expected_1) {
    const MatrixXd y = sim.simulate({b}, u);
    EXPECT_LT((y.col(0) - y0.col(0)).cwiseAbs().maxCoeff(), 1e-14 * scale) << b.kind << ": output 0 untouched";
    EXPECT_LT((y.col(1) - expected_1).cwiseAbs().maxCoeff(), 1e-12 * scale) << b.kind;
    EXPECT_GT((y.col(1) - y0.col(1)).cwiseAbs().maxCoeff(), 0.01 * scale) << b.kind << ": not trivial";
  };
  check(physics_block("gain_error", {{"ratio", 0.93}}, 0, 1), 0.93 * y0.col(1));
  check(physics_block("offset_drift", {{"offset", 0.1 * scale}, {"slope", -0.3 * scale}}, 0, 1),
        y0.col(1).array() + 0.1 * scale - 0.3 * scale * t.array());
  check(physics_block("periodic_disturbance", {{"freq_hz", 47.0}, {"amplitude", 0.05 * scale}, {"phase_rad", -1.1}}, 0, 1),
        y0.col(1).array() + 0.05 * scale * (kTwoPi * 47.0 * t.array() - 1.1).sin());
  // cross_coupling: input 0's own response (at output 0), scaled, added at output 1.
  MatrixXd only_0 = u;
  only_0.col(1).setZero();
  const VectorXd direct_0 = sysid::simulate(d, only_0).col(0);
  check(physics_block("cross_coupling", {{"gain", 0.4}}, 0, 1), y0.col(1) + 0.4 * direct_0);
  // Together, in the chain order: the gain scales the simulated output only,
  // then coupling, offset and sine add.
  const MatrixXd y = sim.simulate({physics_block("offset_drift", {{"offset", 0.2}, {"slope", 0.0}}, 0, 1),
                                   physics_block("cross_coupling", {{"gain", 0.4}}, 0, 1),
                                   physics_block("gain_error", {{"ratio", 0.93}}, 0, 1)},
                                  u);
  const VectorXd expected = (0.93 * y0.col(1) + 0.4 * direct_0).array() + 0.2;
  EXPECT_LT((y.col(1) - expected).cwiseAbs().maxCoeff(), 1e-12 * scale);
}

// ---------------------------------------------------------------- the plant's forces

sysid::PlantForce force_of(const PhysicsBlock& b) {
  sysid::PlantForce f;
  EXPECT_TRUE(sysid::physics_kind(b.kind).plant_force(b, f)) << b.kind;
  return f;
}

TEST(PhysicsKindPlantForce, LawsAreTheDocumentedForces) {
  const double level = 2.0, asymmetry = -0.5, s = 0.3, c = 7.0, lin = -1.5, constant = 0.8;
  const sysid::PlantForce friction =
      force_of(physics_block("coulomb_friction", {{"level", level}, {"velocity_scale", s}, {"asymmetry", asymmetry}}, 1, 2));
  const sysid::PlantForce symmetric = force_of(physics_block("coulomb_friction", {{"level", level}, {"velocity_scale", s}}));
  const sysid::PlantForce cubic = force_of(physics_block("cubic_stiffness", {{"coefficient", c}, {"linear_coefficient", lin}}));
  const sysid::PlantForce push = force_of(physics_block("constant_force", {{"force", constant}}));
  EXPECT_EQ(friction.input, 1);
  EXPECT_EQ(friction.output, 2);
  for (double p : {-2.0, -0.1, 0.0, 0.7, 3.0})
    for (double v : {-5.0, -0.2, -1e-3, 0.0, 1e-3, 0.25, 4.0}) {
      const double t = std::tanh(v / s);
      EXPECT_NEAR(friction(p, v), -level * (t + asymmetry * std::abs(t)), 1e-14) << p << " " << v;
      EXPECT_NEAR(symmetric(p, v), -level * t, 1e-14);
      EXPECT_NEAR(cubic(p, v), -(c * p * p + lin) * p, 1e-12);
      EXPECT_EQ(push(p, v), constant);
    }
  // Far from rest friction is level (1 + asymmetry) moving positive, level (1 - asymmetry) moving negative.
  EXPECT_NEAR(friction(0.0, 100.0), -level * (1.0 + asymmetry), 1e-12);
  EXPECT_NEAR(friction(0.0, -100.0), level * (1.0 - asymmetry), 1e-12);
  // Reported: DESIGN.md's two directions, when they differ.
  const auto reported = sysid::physics_kind("coulomb_friction")
                            .reported(physics_block("coulomb_friction", {{"level", level}, {"velocity_scale", s}, {"asymmetry", asymmetry}}));
  EXPECT_EQ(reported.at("level_positive"), level * (1.0 + asymmetry));
  EXPECT_EQ(reported.at("level_negative"), level * (1.0 - asymmetry));
}

/// RK4 at Ts/200 of p'' = u + force(p, p') - 2 zeta w p' - w^2 p, u held over each sample.
VectorXd rk4_reference(const MatrixXd& u, double w, double zeta, const std::function<double(double, double)>& force) {
  const int sub = 200;
  const double h = kTs / sub;
  VectorXd y(u.rows());
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  for (Eigen::Index k = 0; k < u.rows(); ++k) {
    y[k] = x[0];
    auto f = [&](const Eigen::Vector2d& s) {
      return Eigen::Vector2d(s[1], u(k, 0) + force(s[0], s[1]) - 2 * zeta * w * s[1] - w * w * s[0]);
    };
    for (int i = 0; i < sub; ++i) {
      const Eigen::Vector2d a = f(x), b = f(x + 0.5 * h * a), c = f(x + 0.5 * h * b), d = f(x + h * c);
      x += h / 6 * (a + 2 * b + 2 * c + d);
    }
  }
  return y;
}

TEST(PhysicsKindPlantForce, SimulationConvergesToTheContinuousPlantWithTheForce) {
  const double f = 20.0, zeta = 0.03, w = kTwoPi * f;
  const StateSpace d = sysid::c2d_zoh(oscillator(f, zeta), kTs);
  const MatrixXd u = sysid::test::reversing_excitation(4000, kTs, 14);
  const VectorXd y_lin = sysid::simulate(d, u).col(0);
  const double p_max = y_lin.cwiseAbs().maxCoeff();
  const double v_rms = std::sqrt(((y_lin.tail(3999) - y_lin.head(3999)) / kTs).squaredNorm() / 3999);
  const double u_rms = std::sqrt(u.squaredNorm() / static_cast<double>(u.rows()));
  const double level = 0.1 * u_rms, asymmetry = 0.3, s = 0.05 * v_rms;
  const double c = 0.2 * w * w / (p_max * p_max), lin = -0.05 * w * w, push = 0.2 * u_rms;
  struct Case {
    PhysicsBlock block;
    std::function<double(double, double)> force;
    double tolerance;  // at 8 substeps, relative to the output
  };
  const std::vector<Case> cases = {
      {physics_block("coulomb_friction", {{"level", level}, {"velocity_scale", s}, {"asymmetry", asymmetry}}),
       [&](double, double v) { return -level * (std::tanh(v / s) + asymmetry * std::abs(std::tanh(v / s))); }, 1.5e-3},
      {physics_block("cubic_stiffness", {{"coefficient", c}, {"linear_coefficient", lin}}),
       [&](double p, double) { return -(c * p * p + lin) * p; }, 1.5e-3},
      // A constant force held over each step is exact: round-off and RK4's error only.
      {physics_block("constant_force", {{"force", push}}), [&](double, double) { return push; }, 1e-9}};
  for (const Case& k : cases) {
    const VectorXd exact = rk4_reference(u, w, zeta, k.force);
    const double effect = (exact - y_lin).norm() / exact.norm();
    EXPECT_GT(effect, 0.02) << k.block.kind << ": the force matters";
    const double e4 = relative_error(sysid::AugmentedSimulator(d, 4).simulate({k.block}, u), exact);
    const double e8 = relative_error(sysid::AugmentedSimulator(d, 8).simulate({k.block}, u), exact);
    EXPECT_LT(e8, k.tolerance) << k.block.kind << " (effect " << effect << ")";
    // The force is held from each step's start: first order in the step, the
    // error halves with it (unless it is round-off, as for the constant force).
    if (k.tolerance > 1e-6) {
      EXPECT_GT(e4 / e8, 1.8) << k.block.kind;
      EXPECT_LT(e4 / e8, 2.2) << k.block.kind;
    } else {
      EXPECT_LT(e4, k.tolerance) << k.block.kind;
    }
  }
}

// ---------------------------------------------------------------- parallel modes

TEST(PhysicsKindParallel, MissingModeIsTheExactParallelConnection) {
  const StateSpace nominal_c = oscillator(25, 0.02);
  const double f = 41.0, zeta = 0.015, w = kTwoPi * f, gs = 0.3, gv = -0.2;
  const StateSpace mode_c = oscillator(f, zeta);
  // Output: nominal + gs w^2 q + gv w q' of the mode q'' + 2 zeta w q' + w^2 q = force.
  MatrixXd A = MatrixXd::Zero(4, 4), B(4, 1), C(1, 4);
  A.topLeftCorner(2, 2) = nominal_c.A;
  A.bottomRightCorner(2, 2) = mode_c.A;
  B << nominal_c.B, mode_c.B;
  C << nominal_c.C, gs * w * w, gv * w;
  const StateSpace parallel = sysid::c2d_zoh(StateSpace(A, B, C, MatrixXd::Zero(1, 1), 0.0), kTs);
  const MatrixXd u = sysid::test::white_noise(3000, 1, 15);
  const PhysicsBlock mode = physics_block("missing_mode", {{"freq_hz", f}, {"damping", zeta}, {"static_gain", gs}, {"velocity_gain", gv}});
  const MatrixXd exact = sysid::simulate(parallel, u);
  const StateSpace d = sysid::c2d_zoh(nominal_c, kTs);
  EXPECT_GT(relative_error(sysid::simulate(d, u), exact), 0.1);
  for (int substeps : {1, 3}) EXPECT_LT(relative_error(sysid::AugmentedSimulator(d, substeps).simulate({mode}, u), exact), 1e-9) << substeps;
}

TEST(PhysicsKindParallel, ModeShiftMovesTheNominalModeAndAtItsOwnValuesChangesNothing) {
  // Nominal: one mode with numerator b1 s + b0 (C picks b0 position + b1 velocity).
  const double b0 = 1.0, b1 = 0.004;
  const MatrixXd C{{b0, b1}};
  const StateSpace d = sysid::c2d_zoh(oscillator(30, 0.02, C), kTs);
  const MatrixXd u = sysid::test::white_noise(3000, 1, 16);
  const auto shift = [&](double f, double zeta) {
    return physics_block("mode_shift", {{"freq_hz", f}, {"damping", zeta}, {"nominal_freq_hz", 30.0}, {"nominal_damping", 0.02},
                                        {"numerator_b0", b0}, {"numerator_b1", b1}});
  };
  const sysid::AugmentedSimulator sim(d, 2);
  const MatrixXd y0 = sysid::simulate(d, u);
  // The nominal mode taken out and put back: round-off of the two modal terms only.
  EXPECT_LT(relative_error(sim.simulate({shift(30.0, 0.02)}, u), y0), 5e-11);
  const MatrixXd moved = sysid::simulate(sysid::c2d_zoh(oscillator(30.9, 0.035, C), kTs), u);
  EXPECT_GT(relative_error(y0, moved), 0.1);
  EXPECT_LT(relative_error(sim.simulate({shift(30.9, 0.035)}, u), moved), 1e-9);
}

// ---------------------------------------------------------------- output quantities

/// x = (position, velocity) of a unit mass on a 20 Hz spring, outputs: rows of C
/// (position, velocity and, with `acceleration`, a = force - c v - k p, D = 1).
StateSpace measured_oscillator(bool acceleration) {
  const double w = kTwoPi * 20.0, zeta = 0.03;
  MatrixXd C{{1.0, 0.0}, {0.0, 1.0}};
  MatrixXd D = MatrixXd::Zero(2, 1);
  if (acceleration) {
    C.conservativeResize(3, 2);
    C.row(2) << -w * w, -2 * zeta * w;
    D = MatrixXd{{0.0}, {0.0}, {1.0}};
  }
  StateSpace c = oscillator(20.0, zeta, C);
  c.D = D;
  return sysid::c2d_zoh(c, kTs);
}

PhysicsBlock friction_at(long output, double level, double s) {
  return physics_block("coulomb_friction", {{"level", level}, {"velocity_scale", s}, {"asymmetry", 0.3}}, 0, output);
}

PhysicsBlock cubic_at(long output, double c) {
  return physics_block("cubic_stiffness", {{"coefficient", c}, {"linear_coefficient", 0.0}}, 0, output);
}

/// The scales of the case: the force's size, its velocity scale, a 20 % stiffening at the peak.
struct ForceScales {
  double level, s, c;
};
ForceScales force_scales(const StateSpace& d, const MatrixXd& u) {
  const MatrixXd y = sysid::simulate(d, u);
  const double p_max = y.col(0).cwiseAbs().maxCoeff(), v_rms = std::sqrt(y.col(1).squaredNorm() / static_cast<double>(y.rows()));
  const double w = kTwoPi * 20.0;
  return {0.1 * std::sqrt(u.squaredNorm() / static_cast<double>(u.rows())), 0.05 * v_rms, 0.2 * w * w / (p_max * p_max)};
}

TEST(PhysicsKindOutputQuantity, VelocityOutputGivesTheSameMotionAsThePositionOutput) {
  // Output 0 read as a position gives the velocity as C (A_c x + B_c f) = x2 (C B
  // is zero for a position); output 1 read as a velocity gives x2 itself and the
  // position as an integrator state of the same continuous equivalent,
  // discretised with it: p = x1 exactly. The two simulations differ by round-off
  // in the matrix logarithm and exponential only (about 1e-13 here; a running
  // sum or a difference instead of the exact states would be off by ~1e-3).
  const StateSpace d = measured_oscillator(false);
  const MatrixXd u = sysid::test::reversing_excitation(3000, kTs, 17);
  const ForceScales k = force_scales(d, u);
  const sysid::AugmentedSimulator sim(d, 4, {}, {OutputQuantity::position, OutputQuantity::velocity});
  const MatrixXd y0 = sim.simulate({}, u);
  for (const auto& [from_position, from_velocity] :
       {std::pair{friction_at(0, k.level, k.s), friction_at(1, k.level, k.s)}, std::pair{cubic_at(0, k.c), cubic_at(1, k.c)}}) {
    const MatrixXd a = sim.simulate({from_position}, u), b = sim.simulate({from_velocity}, u);
    EXPECT_GT(relative_error(a, y0), 0.02) << from_position.kind << ": the force matters";
    EXPECT_LT(relative_error(b, a), 1e-10) << from_position.kind;
  }
}

TEST(PhysicsKindOutputQuantity, AccelerationOutputGivesTheSameMotionAsThePositionOutput) {
  // a = C_2 x + D_2 f with f held over the step: the velocity and position
  // integrator states are the exact (ZOH) integrals, so x2 and x1 again up to
  // round-off. The feedthrough D_2 makes the model's D nonzero: one step per
  // sample, and the position reading's fixed point (D_0 = 0) settles at once.
  const StateSpace d = measured_oscillator(true);
  const MatrixXd u = sysid::test::reversing_excitation(3000, kTs, 18);
  const ForceScales k = force_scales(d, u);
  const sysid::AugmentedSimulator sim(
      d, 1, {}, {OutputQuantity::position, OutputQuantity::velocity, OutputQuantity::acceleration});
  const MatrixXd y0 = sim.simulate({}, u);
  for (const auto& [from_position, from_acceleration] :
       {std::pair{friction_at(0, k.level, k.s), friction_at(2, k.level, k.s)}, std::pair{cubic_at(0, k.c), cubic_at(2, k.c)}}) {
    const MatrixXd a = sim.simulate({from_position}, u), b = sim.simulate({from_acceleration}, u);
    EXPECT_GT(relative_error(a, y0), 0.02) << from_position.kind << ": the force matters";
    EXPECT_LT(relative_error(b, a), 1e-10) << from_position.kind;
    PhysicsBlock from_velocity = from_position;
    from_velocity.output = 1;
    EXPECT_LT(relative_error(sim.simulate({from_velocity}, u), a), 1e-10) << from_position.kind;
  }
}

TEST(PhysicsKindOutputQuantity, WithoutAContinuousEquivalentTheIntegralsAreRunningSums) {
  // A discrete pole at -0.4: no matrix logarithm, so one step per sample and the
  // velocity output's position is the running sum Ts * sum_{j<k} y_j. The
  // simulation must be that recursion, written out here.
  const double Ts = 1e-3;
  const StateSpace d(MatrixXd{{0.98, 0.05}, {0.0, -0.4}}, MatrixXd{{0.02}, {0.3}}, MatrixXd{{1.0, 0.5}}, MatrixXd::Zero(1, 1), Ts);
  const sysid::AugmentedSimulator sim(d, 4, {}, {OutputQuantity::velocity});
  EXPECT_FALSE(sim.has_continuous_equivalent());
  EXPECT_EQ(sim.substeps(), 1);
  EXPECT_FALSE(sim.warnings().empty());
  const MatrixXd u = sysid::test::reversing_excitation(3000, Ts, 19) / 3000.0;
  const MatrixXd y_lin = sysid::simulate(d, u);
  const double v_rms = std::sqrt(y_lin.squaredNorm() / static_cast<double>(y_lin.rows()));
  const double level = 0.2, s = 0.05 * v_rms, c = 3.0;
  const std::vector<PhysicsBlock> blocks = {
      physics_block("coulomb_friction", {{"level", level}, {"velocity_scale", s}, {"asymmetry", 0.0}}),
      physics_block("cubic_stiffness", {{"coefficient", c}, {"linear_coefficient", 0.0}})};
  const MatrixXd y = sim.simulate(blocks, u);
  ASSERT_TRUE(y.allFinite());
  VectorXd expected(u.rows());
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  double position = 0.0;
  for (Eigen::Index k = 0; k < u.rows(); ++k) {
    const double v = (d.C * x)(0);
    const double f = u(k, 0) - level * std::tanh(v / s) - c * position * position * position;
    expected[k] = v;
    position += Ts * v;
    x = d.A * x + d.B * f;
  }
  EXPECT_GT(relative_error(y_lin, expected), 0.02);  // the forces matter
  EXPECT_LT(relative_error(y, expected), 1e-12);
}

}  // namespace

}  // namespace test_unit_diagnose_physics_kind
