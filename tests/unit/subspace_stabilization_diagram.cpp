// Tests for sysid::stabilization_diagram (include/sysid/subspace/stabilization_diagram.hpp).
#include <sysid/subspace/stabilization_diagram.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include "random_matrices.hpp"

namespace test_unit_subspace_stabilization_diagram {

namespace {

using cd = std::complex<double>;
constexpr double kTs = 1e-3;

/// The discrete pole (Im > 0) of a mode at f Hz with damping ratio zeta.
cd pole(double f, double zeta) {
  const double w = 2.0 * std::numbers::pi * f;
  return std::exp(cd(-zeta * w, w * std::sqrt(1.0 - zeta * zeta)) * kTs);
}

/// Orders lo..hi: every order holds the physical modes (frequency and damping
/// jittered by `jitter`, relative; real shapes times a complex factor, as a
/// classically damped structure's, fixed up to a small perturbation) and one
/// noise pole at a random frequency with a random shape, plus conjugates.
std::vector<sysid::OrderPoles> synthetic_orders(int lo, int hi, const std::vector<std::pair<double, double>>& modes,
                                                double jitter, Eigen::Index outputs, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), frequency(5.0, 450.0);
  std::vector<Eigen::VectorXcd> shapes;
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const cd factor = std::polar(1.0, std::numbers::pi * unit(rng));
    Eigen::VectorXcd s(outputs);
    for (auto& v : s) v = unit(rng) * factor;
    shapes.push_back(s);
  }
  std::vector<sysid::OrderPoles> out;
  for (int n = lo; n <= hi; ++n) {
    std::vector<cd> p;
    std::vector<Eigen::VectorXcd> phi;
    for (std::size_t k = 0; k < modes.size(); ++k) {
      p.push_back(pole(modes[k].first * (1.0 + jitter * unit(rng)), modes[k].second * (1.0 + jitter * unit(rng))));
      Eigen::VectorXcd s = shapes[k];
      for (auto& v : s) v += 1e-3 * cd(unit(rng), unit(rng));
      phi.push_back(s);
    }
    p.push_back(pole(frequency(rng), 0.05));
    Eigen::VectorXcd noise(outputs);
    for (auto& v : noise) v = cd(unit(rng), unit(rng));
    phi.push_back(noise);
    sysid::OrderPoles op;
    op.order = n;
    op.poles.resize(static_cast<Eigen::Index>(2 * p.size()));
    op.shapes.resize(outputs, static_cast<Eigen::Index>(2 * p.size()));
    for (std::size_t k = 0; k < p.size(); ++k) {
      const auto j = static_cast<Eigen::Index>(2 * k);
      op.poles(j) = p[k];
      op.poles(j + 1) = std::conj(p[k]);
      op.shapes.col(j) = phi[k];
      op.shapes.col(j + 1) = phi[k].conjugate();
    }
    out.push_back(std::move(op));
  }
  return out;
}

/// Adds to every order from `from_order` on a pole pair at f Hz with the shape
/// `shape` (up to a small perturbation): a column as stable as a mode's,
/// whatever its shape.
void add_persistent_column(std::vector<sysid::OrderPoles>& orders, int from_order, double f, double zeta,
                           const Eigen::VectorXcd& shape, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (auto& op : orders) {
    if (op.order < from_order) continue;
    const Eigen::Index n = op.poles.size();
    op.poles.conservativeResize(n + 2);
    op.shapes.conservativeResize(shape.size(), n + 2);
    op.poles(n) = pole(f * (1.0 + 1e-4 * unit(rng)), zeta);
    op.poles(n + 1) = std::conj(op.poles(n));
    Eigen::VectorXcd s = shape;
    for (auto& v : s) v += 1e-3 * cd(unit(rng), unit(rng));
    op.shapes.col(n) = s;
    op.shapes.col(n + 1) = s.conjugate();
  }
}

/// A shape of independent circular complex Gaussian entries: a noise mode's.
Eigen::VectorXcd random_shape(Eigen::Index outputs, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  return sysid::test::random_complex_vector(rng, outputs);
}

/// One output, no shapes: levels 100 for the modes at 40 and 123 Hz,
/// `column_level` for the column at 300 Hz, 1 for the wandering poles.
void set_levels(std::vector<sysid::OrderPoles>& orders, double column_level) {
  for (auto& op : orders) {
    op.shapes.resize(0, 0);
    op.levels.resize(op.poles.size());
    for (Eigen::Index k = 0; k < op.poles.size(); ++k) {
      const double f = std::abs(std::log(op.poles(k))) / (2.0 * std::numbers::pi * kTs);
      const bool mode = std::abs(f - 40.0) < 1.0 || std::abs(f - 123.0) < 1.0;
      op.levels(k) = std::abs(f - 300.0) < 1.0 ? column_level : mode ? 100.0 : 1.0;
    }
  }
}

}  // namespace

TEST(StabilizationDiagram, PersistentModesAreColumnsAndWanderingPolesAreNot) {
  const std::vector<std::pair<double, double>> modes = {{40.0, 0.01}, {123.0, 0.02}};
  const auto orders = synthetic_orders(4, 30, modes, 1e-4, 6, 7);
  const sysid::StabilizationDiagram d = sysid::stabilization_diagram(orders, kTs);
  EXPECT_EQ(d.order_lo, 4);
  EXPECT_EQ(d.order_hi, 30);
  EXPECT_TRUE(d.with_shapes);
  ASSERT_EQ(d.modes.size(), 2u) << d.modes_table();
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_NEAR(d.modes[k].freq_hz, modes[k].first, 1e-3 * modes[k].first);
    EXPECT_NEAR(d.modes[k].damping, modes[k].second, 1e-3 * modes[k].second);
    EXPECT_EQ(d.modes[k].first_order, 5);  // stable against the order below from the second order on
    EXPECT_EQ(d.modes[k].stable_poles, 26);
  }
  // Both modes are in every order, so the lowest order holds them.
  EXPECT_EQ(d.chosen_order, 4) << d.rule;
  int stable_noise = 0;
  for (const auto& p : d.poles) {
    const bool physical = std::abs(p.freq_hz - 40.0) < 1.0 || std::abs(p.freq_hz - 123.0) < 1.0;
    if (physical && p.order > 4) EXPECT_EQ(p.mark(true), 's') << p.order << " " << p.freq_hz;
    if (!physical) stable_noise += p.mark(true) == 's';
    if (!physical) EXPECT_EQ(p.mode, -1);
  }
  EXPECT_EQ(stable_noise, 0);
  EXPECT_NE(d.criteria().find("MAC >= 0.98"), std::string::npos) << d.criteria();
}

TEST(StabilizationDiagram, ShapesDecideBetweenPolesOfEqualFrequency) {
  // With shapes that change completely from order to order, a pole is stable in
  // frequency and damping but not in shape: 'd', and no column forms.
  auto orders = synthetic_orders(4, 20, {{60.0, 0.02}}, 1e-4, 4, 11);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (auto& op : orders)
    for (auto& v : op.shapes.reshaped()) v = cd(unit(rng), unit(rng));
  const sysid::StabilizationDiagram d = sysid::stabilization_diagram(orders, kTs);
  EXPECT_TRUE(d.modes.empty()) << d.modes_table();
  EXPECT_EQ(d.chosen_order, 0);
  int marked_d = 0;
  for (const auto& p : d.poles) marked_d += p.mark(true) == 'd';
  EXPECT_GE(marked_d, 14);
  EXPECT_NE(d.rule.find("no column of stable poles"), std::string::npos) << d.rule;
}

TEST(StabilizationDiagram, AColumnWithANoiseShapeIsNotAMode) {
  // 24 outputs: two modes and, from order 10, a column as stable as theirs whose
  // shape is a random complex vector (what a long horizon's high orders fit to
  // sensor noise). The shape test refuses it and names it; the modes stay.
  constexpr Eigen::Index kOutputs = 24;
  const std::vector<std::pair<double, double>> modes = {{40.0, 0.01}, {123.0, 0.02}};
  auto orders = synthetic_orders(4, 30, modes, 1e-4, kOutputs, 21);
  add_persistent_column(orders, 10, 300.0, 0.03, random_shape(kOutputs, 5), 8);
  const sysid::StabilizationDiagram d = sysid::stabilization_diagram(orders, kTs);
  ASSERT_EQ(d.modes.size(), 2u) << d.modes_table();
  for (const auto& m : d.modes) {
    EXPECT_GT(m.shape_collinearity, 0.99);
    EXPECT_EQ(m.random_like_poles, 0);
  }
  ASSERT_EQ(d.noise_columns.size(), 1u) << d.noise_columns_table();
  const sysid::PhysicalMode& noise = d.noise_columns[0];
  EXPECT_NEAR(noise.freq_hz, 300.0, 0.1);
  EXPECT_LT(noise.shape_collinearity, 0.3);
  EXPECT_EQ(noise.random_like_poles, noise.stable_poles);
  EXPECT_NE(d.rule.find("1 column(s) of noise not counted (300 Hz)"), std::string::npos) << d.rule;
  EXPECT_NE(noise.noise_reason.find("shapes no more collinear than noise's"), std::string::npos) << noise.noise_reason;
  EXPECT_NE(d.criteria().find("more collinear than noise's at the 1 % level"), std::string::npos) << d.criteria();
  const std::string table = d.noise_columns_table();
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 2) << table;  // header and the column
  EXPECT_NE(table.find("MPC"), std::string::npos) << table;
  for (const auto& p : d.poles)
    if (std::abs(p.freq_hz - 300.0) < 1.0) EXPECT_EQ(p.mode, -1);

  // With the test off, the noise column counts as a third mode.
  sysid::StabilizationOptions off;
  off.random_shape_level = 0.0;
  const sysid::StabilizationDiagram all = sysid::stabilization_diagram(orders, kTs, off);
  EXPECT_EQ(all.modes.size(), 3u) << all.modes_table();
  EXPECT_TRUE(all.noise_columns.empty());
  EXPECT_EQ(all.criteria().find("collinear"), std::string::npos) << all.criteria();
}

TEST(StabilizationDiagram, AColumnAtTheNoiseLevelIsNotAMode) {
  // One output (no shapes): two modes at level 100, from order 10 a column as
  // stable as theirs at level 1.5, and the wandering noise poles at level 1.
  const std::vector<std::pair<double, double>> modes = {{40.0, 0.01}, {123.0, 0.02}};
  auto orders = synthetic_orders(4, 30, modes, 1e-4, 1, 51);
  add_persistent_column(orders, 10, 300.0, 0.03, Eigen::VectorXcd::Ones(1), 12);
  set_levels(orders, 1.5);
  const sysid::StabilizationDiagram d = sysid::stabilization_diagram(orders, kTs);
  ASSERT_EQ(d.modes.size(), 2u) << d.modes_table() << d.noise_columns_table();
  for (const auto& m : d.modes) EXPECT_NEAR(m.level_ratio, 100.0, 1e-9);
  ASSERT_EQ(d.noise_columns.size(), 1u) << d.noise_columns_table();
  EXPECT_NEAR(d.noise_columns[0].freq_hz, 300.0, 0.1);
  EXPECT_NEAR(d.noise_columns[0].level_ratio, 1.5, 1e-9);
  EXPECT_NE(d.noise_columns[0].noise_reason.find("level 1.5 x the wandering poles' (< 3) from order 11, after every clearer column stands (order 5)"),
            std::string::npos)
      << d.noise_columns[0].noise_reason;
  EXPECT_NE(d.noise_columns_table().find("why not a mode"), std::string::npos) << d.noise_columns_table();
  EXPECT_NE(d.rule.find("1 column(s) of noise not counted (300 Hz)"), std::string::npos) << d.rule;
  EXPECT_NE(d.criteria().find("level >= 3 x the wandering poles'"), std::string::npos) << d.criteria();

  // With the test off the column counts; a column at 3.5 x passes.
  sysid::StabilizationOptions off;
  off.min_level_ratio = 0.0;
  EXPECT_EQ(sysid::stabilization_diagram(orders, kTs, off).modes.size(), 3u);
  set_levels(orders, 3.5);
  EXPECT_EQ(sysid::stabilization_diagram(orders, kTs).modes.size(), 3u);

  // A weak column among the clear columns' orders (stable from order 5, as they
  // are) is not noise that the high orders fit: it stays a mode.
  auto early = synthetic_orders(4, 30, modes, 1e-4, 1, 52);
  add_persistent_column(early, 4, 300.0, 0.03, Eigen::VectorXcd::Ones(1), 13);
  set_levels(early, 1.5);
  const sysid::StabilizationDiagram kept = sysid::stabilization_diagram(early, kTs);
  EXPECT_EQ(kept.modes.size(), 3u) << kept.modes_table() << kept.noise_columns_table();
  EXPECT_TRUE(kept.noise_columns.empty());

  // Levels must match the poles.
  orders[2].levels.resize(1);
  EXPECT_THROW(sysid::stabilization_diagram(orders, kTs), std::invalid_argument);
}

TEST(StabilizationDiagram, AModeSeenByVelocityAndAccelerationSensorsIsKept) {
  // Half the sensors see the mode in quadrature (velocity against acceleration):
  // MPC about 0 but the phase-doubled collinearity 1, so the column stays a mode.
  constexpr Eigen::Index kOutputs = 24;
  auto orders = synthetic_orders(4, 24, {{40.0, 0.01}}, 1e-4, kOutputs, 31);
  Eigen::VectorXcd mixed(kOutputs);
  for (Eigen::Index j = 0; j < kOutputs; ++j) mixed(j) = (j % 2 == 0 ? cd(1.0, 0.0) : cd(0.0, 1.0)) * (1.0 + 0.1 * j);
  add_persistent_column(orders, 4, 200.0, 0.01, mixed, 4);
  const sysid::StabilizationDiagram d = sysid::stabilization_diagram(orders, kTs);
  ASSERT_EQ(d.modes.size(), 2u) << d.modes_table() << d.noise_columns_table();
  EXPECT_NEAR(d.modes[1].freq_hz, 200.0, 0.1);
  EXPECT_GT(d.modes[1].shape_collinearity, 0.99);
  EXPECT_TRUE(d.noise_columns.empty());
}

TEST(StabilizationDiagram, FewOutputsCannotTellANoiseShape) {
  // Six outputs: a random shape is too often as collinear as a mode's for the
  // test to tell (the 1 % quantile exceeds 0.5), so no column is refused for it.
  auto orders = synthetic_orders(4, 24, {{40.0, 0.01}}, 1e-4, 6, 41);
  add_persistent_column(orders, 4, 300.0, 0.03, random_shape(6, 9), 10);
  const sysid::StabilizationDiagram d = sysid::stabilization_diagram(orders, kTs);
  EXPECT_EQ(d.modes.size(), 2u) << d.modes_table();
  EXPECT_TRUE(d.noise_columns.empty());
}

TEST(StabilizationDiagram, OneOutputComparesFrequencyAndDampingOnly) {
  auto orders = synthetic_orders(2, 16, {{25.0, 0.005}}, 1e-4, 1, 13);
  for (auto& op : orders) op.shapes.resize(0, 0);
  const sysid::StabilizationDiagram d = sysid::stabilization_diagram(orders, kTs);
  EXPECT_FALSE(d.with_shapes);
  ASSERT_EQ(d.modes.size(), 1u) << d.modes_table();
  EXPECT_NEAR(d.modes[0].freq_hz, 25.0, 0.01);
  EXPECT_EQ(d.criteria().find("MAC"), std::string::npos) << d.criteria();
  // A damping that jumps by more than 5 % between orders is not stable in damping.
  auto jumping = synthetic_orders(2, 16, {{25.0, 0.005}}, 0.0, 1, 13);
  for (auto& op : jumping) {
    op.shapes.resize(0, 0);
    op.poles(0) = pole(25.0, op.order % 2 == 0 ? 0.005 : 0.01);
    op.poles(1) = std::conj(op.poles(0));
  }
  const sysid::StabilizationDiagram j = sysid::stabilization_diagram(jumping, kTs);
  EXPECT_TRUE(j.modes.empty()) << j.modes_table();
}

TEST(StabilizationDiagram, RealUnstableAndHeavilyDampedPolesAreNotCandidates) {
  sysid::OrderPoles op;
  op.order = 3;
  op.poles.resize(4);
  op.poles << cd(0.9, 0.0), pole(50.0, 0.5), 1.01 * pole(80.0, 0.01), pole(120.0, 0.01);
  const sysid::StabilizationDiagram d = sysid::stabilization_diagram({op}, kTs);
  ASSERT_EQ(d.poles.size(), 1u);
  EXPECT_NEAR(d.poles[0].freq_hz, 120.0, 1e-9);
  EXPECT_EQ(d.poles[0].mark(false), 'o');
}

TEST(StabilizationDiagram, BadArgumentsAreRefused) {
  sysid::OrderPoles a, b;
  a.order = 3;
  b.order = 5;
  EXPECT_THROW(sysid::stabilization_diagram({a, b}, kTs), std::invalid_argument);
  EXPECT_THROW(sysid::stabilization_diagram({a}, 0.0), std::invalid_argument);
  EXPECT_THROW(sysid::stabilization_diagram({}, kTs), std::invalid_argument);
  a.poles = Eigen::VectorXcd::Constant(2, pole(10.0, 0.01));
  a.shapes = Eigen::MatrixXcd::Ones(3, 1);
  EXPECT_THROW(sysid::stabilization_diagram({a}, kTs), std::invalid_argument);
  a.shapes.resize(0, 0);
  sysid::StabilizationOptions o;
  o.random_shape_level = 1.0;
  EXPECT_THROW(sysid::stabilization_diagram({a}, kTs, o), std::invalid_argument);
  o.random_shape_level = 0.01;
  o.min_level_ratio = -1.0;
  EXPECT_THROW(sysid::stabilization_diagram({a}, kTs, o), std::invalid_argument);
}

}  // namespace test_unit_subspace_stabilization_diagram
