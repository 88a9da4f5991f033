// Tests for sysid::excitation_order and insufficient_excitation_warnings
// (include/sysid/core/persistent_excitation.hpp).
#include <sysid/core/persistent_excitation.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace test_unit_core_persistent_excitation {

namespace {

using Eigen::VectorXd;

VectorXd white(Eigen::Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  VectorXd x(n);
  for (auto& v : x) v = g(rng);
  return x;
}

/// Sum of sines at the given frequencies (fractions of the sample rate), plus an offset.
VectorXd sines(Eigen::Index n, const std::vector<double>& frequencies, double offset = 0.0) {
  VectorXd x = VectorXd::Constant(n, offset);
  for (Eigen::Index t = 0; t < n; ++t)
    for (std::size_t k = 0; k < frequencies.size(); ++k)
      x(t) += std::sin(2.0 * std::numbers::pi * frequencies[k] * static_cast<double>(t) + 0.7 * static_cast<double>(k));
  return x;
}

sysid::IoData log_of(const std::vector<VectorXd>& experiments_u) {
  sysid::IoData d;
  d.Ts = 1e-3;
  d.input_names = {"u"};
  d.output_names = {"y"};
  for (const auto& u : experiments_u) {
    sysid::Experiment e;
    e.u = u;
    e.y = VectorXd::Zero(u.size());
    d.experiments.push_back(std::move(e));
  }
  return d;
}

TEST(PersistentExcitation, OrderOfSinesWhiteNoiseAndAConstant) {
  sysid::ExcitationOrderOptions o;
  o.max_order = 20;
  EXPECT_EQ(sysid::excitation_order(log_of({sines(4000, {0.05}, 3.0)}), 0, o).order, 2);
  EXPECT_EQ(sysid::excitation_order(log_of({sines(4000, {0.05, 0.11, 0.23})}), 0, o).order, 6);
  EXPECT_EQ(sysid::excitation_order(log_of({white(4000, 1)}), 0, o).order, 20);
  const sysid::ExcitationOrder constant = sysid::excitation_order(log_of({VectorXd::Constant(4000, 2.5)}), 0, o);
  EXPECT_EQ(constant.order, 0);
  EXPECT_EQ(constant.singular_values.size(), 0);
}

TEST(PersistentExcitation, ExperimentsAtDifferentFrequenciesAddUp) {
  // Two single-sine experiments at different frequencies excite order 4 together,
  // which neither does alone: the Hankel rows of both are stacked.
  sysid::ExcitationOrderOptions o;
  o.max_order = 10;
  EXPECT_EQ(sysid::excitation_order(log_of({sines(3000, {0.05}), sines(3000, {0.17})}), 0, o).order, 4);
}

TEST(PersistentExcitation, WarningNamesTheInputTheModelAndTheOrders) {
  const auto warnings = sysid::insufficient_excitation_warnings(log_of({sines(4000, {0.05})}), 8, "ARX(4, 4)", "arx");
  ASSERT_EQ(warnings.size(), 1u);
  const std::string& w = warnings.front();
  EXPECT_EQ(w.rfind("arx: input u is persistently exciting of order 2 only", 0), 0u) << w;
  EXPECT_NE(w.find("ARX(4, 4) needs order 8"), std::string::npos) << w;
  EXPECT_TRUE(sysid::insufficient_excitation_warnings(log_of({white(4000, 2)}), 8, "ARX(4, 4)", "arx").empty());
  // Just enough: three sines for order 6.
  EXPECT_TRUE(sysid::insufficient_excitation_warnings(log_of({sines(4000, {0.05, 0.11, 0.23})}), 6, "m", "").empty());
}

TEST(PersistentExcitation, ScaleDoesNotChangeTheOrder) {
  sysid::ExcitationOrderOptions o;
  o.max_order = 12;
  for (double scale : {1e-9, 1.0, 1e9}) {
    const VectorXd u = scale * sines(4000, {0.05, 0.2});
    EXPECT_EQ(sysid::excitation_order(log_of({u}), 0, o).order, 4) << "scale " << scale;
  }
}

TEST(PersistentExcitation, PreconditionsAreChecked) {
  EXPECT_THROW(sysid::excitation_order(log_of({white(100, 3)}), 1), std::invalid_argument);
  sysid::ExcitationOrderOptions o;
  o.max_order = 0;
  EXPECT_THROW(sysid::excitation_order(log_of({white(100, 3)}), 0, o), std::invalid_argument);
  o.max_order = 200;
  EXPECT_THROW(sysid::excitation_order(log_of({white(100, 3)}), 0, o), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_core_persistent_excitation
