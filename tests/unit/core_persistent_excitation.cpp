// Tests for sysid::excitation_order and insufficient_excitation_warnings
// (include/sysid/core/persistent_excitation.hpp), including its Gram-based
// singular values against a direct SVD of the Hankel matrix.
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

/// Relative singular values of the mean-removed Hankel matrix with n columns, by a
/// direct SVD of the explicit matrix (the reference for the Gram-based ones).
VectorXd hankel_singular_values_by_svd(const VectorXd& u, Eigen::Index n) {
  const Eigen::Index rows = u.size() - n + 1;
  const double mean = u.mean();
  Eigen::MatrixXd h(rows, n);
  for (Eigen::Index j = 0; j < n; ++j) h.col(j) = u.segment(j, rows).array() - mean;
  VectorXd sv = Eigen::BDCSVD<Eigen::MatrixXd>(h).singularValues();
  return sv / sv(0);
}

TEST(PersistentExcitation, GramSingularValuesMatchADirectSvd) {
  // The Gram route squares the condition number; the decision only needs the
  // relative singular values well above 1e-5. Checked on a smooth low-pass
  // signal (singular values decaying over many decades), sines in weak noise
  // (a cliff) and white noise.
  const Eigen::Index n = 40, samples = 6000;
  VectorXd smooth = white(samples, 7);
  for (int pass = 0; pass < 4; ++pass)
    for (Eigen::Index t = 1; t < samples; ++t) smooth(t) = 0.9 * smooth(t - 1) + 0.1 * smooth(t);
  VectorXd sines_in_noise = sines(samples, {0.03, 0.08, 0.21}) + 1e-4 * white(samples, 8);
  sysid::ExcitationOrderOptions o;
  o.max_order = n;
  for (const VectorXd& u : {smooth, sines_in_noise, white(samples, 9)}) {
    const sysid::ExcitationOrder pe = sysid::excitation_order(log_of({u}), 0, o);
    const VectorXd reference = hankel_singular_values_by_svd(u, n);
    ASSERT_EQ(pe.singular_values.size(), n);
    for (Eigen::Index k = 0; k < n; ++k)
      EXPECT_NEAR(pe.singular_values(k), reference(k), 1e-6 + 1e-6 * reference(k)) << "singular value " << k;
  }
  EXPECT_EQ(sysid::excitation_order(log_of({sines_in_noise}), 0, o).order, 6);
  EXPECT_EQ(sysid::excitation_order(log_of({smooth}), 0, o).order, n);  // a smooth decay excites every order
}

TEST(PersistentExcitation, FewerRowsThanColumnsGiveThatManySingularValues) {
  sysid::ExcitationOrderOptions o;
  o.max_order = 10;
  o.max_samples = 4;  // a 4 x 10 Hankel matrix: rank 4 at most
  const sysid::ExcitationOrder pe = sysid::excitation_order(log_of({white(100, 4)}), 0, o);
  EXPECT_EQ(pe.singular_values.size(), 4);
  EXPECT_EQ(pe.order, 4);
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
