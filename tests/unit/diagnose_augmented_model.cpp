// Tests for the augmented-model simulation (include/sysid/diagnose/augmented_model.hpp):
// each block against an independent construction (exact discretisation of the
// linear cascade, an RK4 reference for plant forces, hand-worked actuator cases).
#include <sysid/core/discretize.hpp>
#include <sysid/core/math_constants.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/diagnose/augmented_model.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <random>

#include "../support/diagnose_cases.hpp"

namespace test_unit_diagnose_augmented_model {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using sysid::PhysicsBlock;
using sysid::StateSpace;

constexpr double kTs = 0.5e-3;
using sysid::kTwoPi;

/// Continuous mass-spring-damper, force in, position out (x1 = position, x2 = velocity).
StateSpace oscillator(double f_hz, double zeta) {
  const double w = kTwoPi * f_hz;
  return StateSpace(MatrixXd{{0.0, 1.0}, {-w * w, -2.0 * zeta * w}}, MatrixXd{{0.0}, {1.0}}, MatrixXd{{1.0, 0.0}},
                    MatrixXd::Zero(1, 1), 0.0);
}

using sysid::test::physics_block;

MatrixXd test_input(Eigen::Index n, std::uint64_t seed) { return sysid::test::white_noise(n, 1, seed); }

double relative_error(const MatrixXd& a, const MatrixXd& b) { return (a - b).norm() / b.norm(); }

TEST(AugmentedModel, NoBlocksIsTheNominal) {
  const StateSpace d = sysid::c2d_zoh(oscillator(30, 0.02), kTs);
  const MatrixXd u = test_input(3000, 1);
  const sysid::AugmentedSimulator sim(d, 4);
  EXPECT_LT(relative_error(sim.simulate({}, u), sysid::simulate(d, u)), 1e-13);
}

TEST(AugmentedModel, SensorBlocksAddExactly) {
  const StateSpace d = sysid::c2d_zoh(oscillator(30, 0.02), kTs);
  const MatrixXd u = test_input(2000, 2);
  const sysid::AugmentedSimulator sim(d);
  const MatrixXd y0 = sysid::simulate(d, u);
  const MatrixXd y = sim.simulate({physics_block("gain_error", {{"ratio", 1.05}}), physics_block("offset_drift", {{"offset", 0.3}, {"slope", -0.2}}),
                                   physics_block("periodic_disturbance", {{"freq_hz", 50.0}, {"amplitude", 0.01}, {"phase_rad", 0.4}})},
                                  u);
  for (Eigen::Index k = 0; k < y.rows(); k += 97) {
    const double t = k * kTs;
    EXPECT_NEAR(y(k, 0), 1.05 * y0(k, 0) + 0.3 - 0.2 * t + 0.01 * std::sin(kTwoPi * 50 * t + 0.4), 1e-12);
  }
}

TEST(AugmentedModel, MissingModeEqualsTheParallelConnectionDiscretisedExactly) {
  const StateSpace nominal_c = oscillator(25, 0.02);
  const StateSpace mode_c = oscillator(31, 0.01);
  const double static_gain = 0.2, w = kTwoPi * 31;
  // Parallel connection in continuous time: output = nominal + static_gain w^2 q.
  MatrixXd A = MatrixXd::Zero(4, 4), B(4, 1), C(1, 4);
  A.topLeftCorner(2, 2) = nominal_c.A;
  A.bottomRightCorner(2, 2) = mode_c.A;
  B << nominal_c.B, mode_c.B;
  C << nominal_c.C, static_gain * w * w * mode_c.C;
  const StateSpace parallel = sysid::c2d_zoh(StateSpace(A, B, C, MatrixXd::Zero(1, 1), 0.0), kTs);
  const MatrixXd u = test_input(4000, 3);
  const sysid::AugmentedSimulator sim(sysid::c2d_zoh(nominal_c, kTs));
  const MatrixXd y = sim.simulate(
      {physics_block("missing_mode", {{"freq_hz", 31.0}, {"damping", 0.01}, {"static_gain", static_gain}, {"velocity_gain", 0.0}})}, u);
  EXPECT_LT(relative_error(y, sysid::simulate(parallel, u)), 1e-9);
}

TEST(AugmentedModel, ModeShiftMovesTheNominalModeExactly) {
  // Nominal: two modes in parallel, 25 Hz and 60 Hz, each 1 / (s^2 + 2 zeta w s + w^2)
  // from force to position (numerator b0 = 1, b1 = 0). mode_shift moves the 60 Hz
  // mode to 61.2 Hz with damping 0.03: the result must equal the nominal built with
  // the moved mode, to round-off.
  auto two_modes = [](double f2, double zeta2) {
    const StateSpace a = oscillator(25, 0.02), b = oscillator(f2, zeta2);
    MatrixXd A = MatrixXd::Zero(4, 4), B(4, 1), C(1, 4);
    A.topLeftCorner(2, 2) = a.A;
    A.bottomRightCorner(2, 2) = b.A;
    B << a.B, b.B;
    C << a.C, b.C;
    return sysid::c2d_zoh(StateSpace(A, B, C, MatrixXd::Zero(1, 1), 0.0), kTs);
  };
  const MatrixXd u = test_input(4000, 5);
  const sysid::AugmentedSimulator sim(two_modes(60.0, 0.02));
  const auto shift = [](double f, double zeta) {
    return physics_block("mode_shift", {{"freq_hz", f}, {"damping", zeta}, {"nominal_freq_hz", 60.0}, {"nominal_damping", 0.02},
                                        {"numerator_b0", 1.0}, {"numerator_b1", 0.0}});
  };
  EXPECT_LT(relative_error(sim.simulate({shift(61.2, 0.03)}, u), sysid::simulate(two_modes(61.2, 0.03), u)), 1e-9);
  // Not moved: the nominal itself (the removed and the added mode cancel).
  EXPECT_LT(relative_error(sim.simulate({shift(60.0, 0.02)}, u), sysid::simulate(two_modes(60.0, 0.02), u)), 1e-12);
}

TEST(AugmentedModel, WholeSampleDelayShiftsAndFractionalDelayInterpolates) {
  const StateSpace d = sysid::c2d_zoh(oscillator(30, 0.05), kTs);
  const MatrixXd u = test_input(1000, 4);
  const sysid::AugmentedSimulator sim(d);
  MatrixXd shifted = MatrixXd::Zero(1000, 1);
  shifted.bottomRows(998) = u.topRows(998);
  EXPECT_LT(relative_error(sim.simulate({physics_block("time_delay", {{"delay_s", 2 * kTs}})}, u), sysid::simulate(d, shifted)), 1e-13);
  const MatrixXd y0 = sim.simulate({}, u), y1 = sim.simulate({physics_block("time_delay", {{"delay_s", kTs}})}, u);
  const MatrixXd half = sim.simulate({physics_block("time_delay", {{"delay_s", 0.25 * kTs}})}, u);
  EXPECT_LT(relative_error(half, 0.75 * y0 + 0.25 * y1), 1e-12);  // linear in the fraction
}

TEST(AugmentedModel, DelayLongerThanTheRecordLeavesNothing) {
  // Found by fuzzing the augmented-model reader: delay_s 1e300 made the delay in
  // samples overflow the index type (undefined behaviour). Any delay past the record
  // delays everything out of it; the same for an advance.
  const StateSpace d = sysid::c2d_zoh(oscillator(30, 0.05), kTs);
  const MatrixXd u = test_input(200, 5);
  const sysid::AugmentedSimulator sim(d);
  for (double delay : {1e300, 1e6 * kTs, 300 * kTs})
    EXPECT_EQ(sim.simulate({physics_block("time_delay", {{"delay_s", delay}})}, u).cwiseAbs().maxCoeff(), 0.0) << delay;
}

TEST(AugmentedModel, InputLagConvergesToTheExactCascade) {
  const StateSpace plant = oscillator(30, 0.02);
  const double corner = 150.0, wc = kTwoPi * corner;
  MatrixXd A = MatrixXd::Zero(3, 3), B = MatrixXd::Zero(3, 1), C = MatrixXd::Zero(1, 3);
  A.topLeftCorner(2, 2) = plant.A;
  A.block(0, 2, 2, 1) = plant.B;  // the lag output drives the plant
  A(2, 2) = -wc;
  B(2, 0) = wc;
  C(0, 0) = 1.0;
  const StateSpace cascade = sysid::c2d_zoh(StateSpace(A, B, C, MatrixXd::Zero(1, 1), 0.0), kTs);
  const MatrixXd u = test_input(4000, 5);
  const MatrixXd exact = sysid::simulate(cascade, u);
  const StateSpace d = sysid::c2d_zoh(plant, kTs);
  const auto lag = physics_block("input_lag", {{"corner_hz", corner}});
  const double e1 = relative_error(sysid::AugmentedSimulator(d, 1).simulate({lag}, u), exact);
  const double e8 = relative_error(sysid::AugmentedSimulator(d, 8).simulate({lag}, u), exact);
  EXPECT_LT(e1, 2e-2);  // the lag's mean over the step is held: second order in wc Ts
  EXPECT_LT(e8, e1 / 10);
}

/// RK4 reference for m x'' + c x' + k x + k3 x^3 + F tanh(x'/vs) = u (ZOH u), fine step.
VectorXd rk4_reference(const MatrixXd& u, double w, double zeta, double k3, double friction, double vs) {
  const int sub = 200;
  const double h = kTs / sub;
  VectorXd y(u.rows());
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  for (Eigen::Index k = 0; k < u.rows(); ++k) {
    y[k] = x[0];
    auto f = [&](const Eigen::Vector2d& s) {
      const double force = u(k, 0) - k3 * s[0] * s[0] * s[0] - friction * std::tanh(s[1] / vs);
      return Eigen::Vector2d(s[1], force - 2 * zeta * w * s[1] - w * w * s[0]);
    };
    for (int i = 0; i < sub; ++i) {
      const Eigen::Vector2d a = f(x), b = f(x + 0.5 * h * a), c = f(x + 0.5 * h * b), d = f(x + h * c);
      x += h / 6 * (a + 2 * b + 2 * c + d);
    }
  }
  return y;
}

TEST(AugmentedModel, PlantForcesConvergeToTheContinuousTimeSystem) {
  const double f = 20.0, zeta = 0.03, w = kTwoPi * f;
  const StateSpace d = sysid::c2d_zoh(oscillator(f, zeta), kTs);
  const MatrixXd u = 3000.0 * test_input(4000, 6);  // static deflection ~ u / w^2 ~ 0.2
  const VectorXd y_lin = sysid::simulate(d, u).col(0);
  const double ymax = y_lin.cwiseAbs().maxCoeff();
  const double k3 = 0.2 * w * w / (ymax * ymax);  // 20 % stiffening at the peak
  const double vrms = std::sqrt(((y_lin.tail(3999) - y_lin.head(3999)) / kTs).squaredNorm() / 3999);
  const double friction = 30.0, vs = 0.01 * vrms;
  const VectorXd exact = rk4_reference(u, w, zeta, k3, friction, vs);
  const std::vector<PhysicsBlock> blocks = {physics_block("cubic_stiffness", {{"coefficient", k3}, {"linear_coefficient", 0.0}}),
                                            physics_block("coulomb_friction", {{"level", friction}, {"velocity_scale", vs}})};
  const double effect = (exact - y_lin).norm() / exact.norm();
  const double e1 = relative_error(sysid::AugmentedSimulator(d, 1).simulate(blocks, u), exact);
  const double e8 = relative_error(sysid::AugmentedSimulator(d, 8).simulate(blocks, u), exact);
  EXPECT_GT(effect, 0.02);        // the forces matter
  EXPECT_LT(e8, 0.05 * effect);   // and the augmented model reproduces them
  EXPECT_LT(e8, e1);
}

TEST(AugmentedModel, ActuatorNonlinearitiesOnHandWorkedSignals) {
  MatrixXd ramp(7, 1);
  ramp << -3, -2, -1, 0, 1, 2, 3;
  const MatrixXd dz = sysid::actuator_output({physics_block("deadzone", {{"width", 2.0}})}, ramp, kTs, 7);
  EXPECT_TRUE(dz.col(0).isApprox((VectorXd(7) << -2, -1, 0, 0, 0, 1, 2).finished()));
  const MatrixXd sat = sysid::actuator_output({physics_block("saturation", {{"limit", 1.5}})}, ramp, kTs, 7);
  EXPECT_TRUE(sat.col(0).isApprox((VectorXd(7) << -1.5, -1.5, -1, 0, 1, 1.5, 1.5).finished()));
  MatrixXd triangle(9, 1);
  triangle << 0, 1, 2, 3, 2, 1, 0, 1, 2;
  const MatrixXd bl = sysid::actuator_output({physics_block("backlash", {{"width", 2.0}})}, triangle, kTs, 9);
  // Up: follows u - 1; at the reversal it holds until u has come down by the width.
  EXPECT_TRUE(bl.col(0).isApprox((VectorXd(9) << 0, 0, 1, 2, 2, 2, 1, 1, 1).finished()));
  const MatrixXd none = sysid::actuator_output({physics_block("hysteresis", {{"alpha", 0.0}, {"beta", 1.0}, {"gamma", 1.0}})}, triangle, kTs, 9);
  EXPECT_TRUE(none.isApprox(triangle));
  // Bouc-Wen loop: going up and coming down through the same input gives different forces.
  const MatrixXd hy = sysid::actuator_output({physics_block("hysteresis", {{"alpha", 0.2}, {"beta", 0.5}, {"gamma", 0.1}})}, triangle, kTs, 9);
  EXPECT_GT(std::abs(hy(1, 0) - hy(5, 0)), 0.05);
}

/// The store's own recursion (physics_block.hpp): level v clipped at the limit,
/// the next stage sees z = v + spill * overflow / (1 - a).
VectorXd clipped_store_seen_level(const VectorXd& u, double a, double limit, double spill) {
  VectorXd z(u.size());
  double v = std::min(u[0], limit), seen = v;
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    z[k] = seen;
    const double filled = a * v + (1.0 - a) * u[k];
    v = std::min(filled, limit);
    seen = v + spill * (filled - v) / (1.0 - a);
  }
  return z;
}

TEST(AugmentedModel, StoreOverflowMakesTheNominalStoreReproduceTheClippedLevel) {
  // The nominal is the store itself (pole a, unit DC gain, level out): fed the
  // block's output it must give the clipped store's level exactly, with and
  // without spill; below the limit the block is the identity.
  const double a = 0.97, limit = 0.8;
  const StateSpace store(MatrixXd{{a}}, MatrixXd{{1.0 - a}}, MatrixXd{{1.0}}, MatrixXd::Zero(1, 1), 4.0);
  MatrixXd u(600, 1);
  for (Eigen::Index k = 0; k < u.rows(); ++k) u(k, 0) = 1.5 * std::sin(kTwoPi * static_cast<double>(k) / 300.0);
  for (double spill : {0.0, 0.4, 1.0}) {
    const PhysicsBlock b = physics_block("saturation", {{"limit", limit}, {"storage_pole", a}, {"spill", spill}});
    const MatrixXd w = sysid::actuator_output({b}, u, store.Ts, u.rows());
    VectorXd x0(1);
    x0 << std::min(u(0, 0), limit);
    const MatrixXd level = sysid::simulate(store, w, x0);
    const VectorXd expected = clipped_store_seen_level(u.col(0), a, limit, spill);
    EXPECT_LT((level.col(0) - expected).cwiseAbs().maxCoeff(), 1e-12) << "spill " << spill;
    EXPECT_GT(expected.maxCoeff(), limit - 1e-12);  // the store did overflow
    if (spill == 0.0) {
      EXPECT_LE(level.maxCoeff(), limit + 1e-12);
    }
  }
  const PhysicsBlock high = physics_block("saturation", {{"limit", 2.0}, {"storage_pole", a}, {"spill", 0.5}});
  EXPECT_LT((sysid::actuator_output({high}, u, store.Ts, u.rows()) - u).cwiseAbs().maxCoeff(), 1e-12);
  // A block from before storage_pole and spill existed is an amplifier (defaults 0).
  EXPECT_EQ(physics_block("saturation", {{"limit", 1.0}}).param("storage_pole"), 0.0);
  EXPECT_EQ(physics_block("saturation", {{"limit", 1.0}}).param("spill"), 0.0);
}

TEST(AugmentedModel, RejectsBadBlocks) {
  const StateSpace d = sysid::c2d_zoh(oscillator(30, 0.02), kTs);
  const sysid::AugmentedSimulator sim(d);
  const MatrixXd u = test_input(100, 7);
  EXPECT_THROW(sim.simulate({physics_block("magic", {})}, u), std::invalid_argument);
  EXPECT_THROW(sim.simulate({physics_block("deadzone", {})}, u), std::invalid_argument);
  EXPECT_THROW(sim.simulate({physics_block("deadzone", {{"width", -1.0}})}, u), std::invalid_argument);
  EXPECT_THROW(sim.simulate({physics_block("saturation", {{"limit", 1.0}, {"storage_pole", 1.0}})}, u), std::invalid_argument);
  EXPECT_THROW(sim.simulate({physics_block("saturation", {{"limit", 1.0}, {"storage_pole", 0.5}, {"spill", 1.5}})}, u),
               std::invalid_argument);
  EXPECT_THROW(sim.simulate({physics_block("saturation", {{"limit", -1.0}})}, u), std::invalid_argument);
  EXPECT_THROW(sim.simulate({physics_block("deadzone", {{"width", 1.0}}, 1)}, u), std::invalid_argument);
  EXPECT_THROW(sim.simulate({physics_block("missing_mode", {{"freq_hz", 5000.0}, {"damping", 0.01}, {"static_gain", 1.0}, {"velocity_gain", 0.0}})}, u),
               std::invalid_argument);  // above Nyquist
  EXPECT_THROW(sim.simulate({physics_block("time_delay", {{"delay_s", NAN}})}, u), std::invalid_argument);
  EXPECT_THROW(sim.simulate({}, MatrixXd::Zero(10, 2)), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_diagnose_augmented_model
