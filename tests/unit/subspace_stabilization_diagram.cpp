// Tests for sysid::stabilization_diagram (include/sysid/subspace/stabilization_diagram.hpp).
#include <sysid/subspace/stabilization_diagram.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

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
/// jittered by `jitter`, relative; shapes fixed up to a small perturbation) and
/// one noise pole at a random frequency with a random shape, plus conjugates.
std::vector<sysid::OrderPoles> synthetic_orders(int lo, int hi, const std::vector<std::pair<double, double>>& modes,
                                                double jitter, Eigen::Index outputs, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), frequency(5.0, 450.0);
  std::vector<Eigen::VectorXcd> shapes;
  for (std::size_t k = 0; k < modes.size(); ++k) {
    Eigen::VectorXcd s(outputs);
    for (auto& v : s) v = cd(unit(rng), unit(rng));
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

}  // namespace

TEST(StabilizationDiagram, ModalAssuranceCriterion) {
  Eigen::VectorXcd a(3), b(3);
  a << cd(1, 0), cd(0, 2), cd(-1, 1);
  EXPECT_NEAR(sysid::modal_assurance_criterion(a, a), 1.0, 1e-15);
  EXPECT_NEAR(sysid::modal_assurance_criterion(a, cd(0.0, -3.0) * a), 1.0, 1e-15);  // complex scaling: the same shape
  b << cd(0, 2), cd(1, 0), cd(0, 0);
  b -= (a.dot(b) / a.squaredNorm()) * a;  // orthogonal to a
  EXPECT_NEAR(sysid::modal_assurance_criterion(a, b), 0.0, 1e-15);
  EXPECT_EQ(sysid::modal_assurance_criterion(a, Eigen::VectorXcd::Zero(3)), 0.0);
}

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
}

}  // namespace test_unit_subspace_stabilization_diagram
