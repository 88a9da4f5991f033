// Tests for sysid::era (include/sysid/realization/era.hpp), including the
// paper's workflow: one actuator excited at a time, SIMO FIR by multi-step NLMS,
// Markov parameters, ERA on the assembled set.
#include <sysid/adaptive/multistep_nlms.hpp>
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/modal_table.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/realization/era.hpp>
#include <sysid/realization/markov_parameters.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <string>
#include <vector>
#include "checks.hpp"
#include "random_systems.hpp"

namespace test_unit_realization_era {

namespace {

using Eigen::MatrixXd;
using sysid::test::has_warning;
using sysid::test::rotated_modal_system;

/// Largest distance from a true pole to its nearest estimated pole (and back).
double pole_distance(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  auto one_way = [](const Eigen::VectorXcd& x, const Eigen::VectorXcd& y) {
    double worst = 0.0;
    for (Eigen::Index i = 0; i < x.size(); ++i) worst = std::max(worst, (y.array() - x[i]).abs().minCoeff());
    return worst;
  };
  return std::max(one_way(a, b), one_way(b, a));
}

/// Max relative frequency-response error over a grid, relative to the peak gain of `ref`.
double frf_error(const sysid::StateSpace& est, const sysid::StateSpace& ref) {
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(400, 0.0, 0.5 / ref.Ts);
  const auto Ge = sysid::frequency_response(est, f), Gr = sysid::frequency_response(ref, f);
  double err = 0.0, peak = 0.0;
  for (std::size_t i = 0; i < Ge.size(); ++i) {
    err = std::max(err, (Ge[i] - Gr[i]).cwiseAbs().maxCoeff());
    peak = std::max(peak, Gr[i].cwiseAbs().maxCoeff());
  }
  return err / peak;
}

TEST(RealizationEra, ExactMarkovParametersGivePolesToRoundingLevel) {
  // 6th-order, lightly damped (zeta 0.5-2 %), 3 outputs x 2 inputs. Exact
  // Markov parameters give a rank-6 H(0); ERA is then exact up to rounding in
  // the SVD and the eigenvalues: ~ eps cond(eigenvector matrix) ||A||, far below 1e-8.
  const sysid::StateSpace sys = rotated_modal_system({0.04, 0.11, 0.27}, {0.005, 0.01, 0.02}, 2, 3, 1);
  const sysid::MarkovParameters mp = sysid::markov_parameters(sys, 60);
  struct Case {
    sysid::EraOptions o;
    const char* name;
  };
  std::vector<Case> cases(5);
  cases[0].o.order = 6;
  cases[0].name = "fixed order, default alpha/beta";
  cases[1].name = "gap rule";
  cases[2].o.rule = sysid::EraOrderRule::threshold;
  cases[2].o.threshold = 1e-8;
  cases[2].name = "threshold rule";
  cases[3].o.order = 6;
  cases[3].o.row_blocks = 3;  // alpha l = 9 >= 6
  cases[3].o.column_blocks = 4;  // beta m = 8 >= 6
  cases[3].name = "small Hankel";
  cases[4].o.row_blocks = 10;
  cases[4].o.max_order = 12;
  cases[4].name = "alpha given, gap rule capped";
  for (const Case& c : cases) {
    const sysid::EraResult r = sysid::era(mp, c.o);
    EXPECT_EQ(r.order, 6) << c.name;
    EXPECT_LT(pole_distance(sysid::poles(r.model), sysid::poles(sys)), 1e-8) << c.name;
    EXPECT_LT(frf_error(r.model, sys), 1e-8) << c.name;
    const auto me = sysid::modal_table(r.model), mt = sysid::modal_table(sys);
    ASSERT_EQ(me.size(), mt.size()) << c.name;
    for (std::size_t i = 0; i < mt.size(); ++i) {
      EXPECT_NEAR(me[i].freq_hz / mt[i].freq_hz, 1.0, 1e-8) << c.name;
      EXPECT_NEAR(me[i].damping / mt[i].damping, 1.0, 1e-6) << c.name;  // damping = -Re s / |s|: relative to a small number
    }
    EXPECT_TRUE(r.warnings.empty()) << c.name << ": " << r.warnings.front();
    EXPECT_EQ(r.model.Ts, 1.0);
  }
  // Default alpha/beta: all 60 Markov parameters, alpha l ~ beta m.
  const sysid::EraResult r = sysid::era(mp);
  EXPECT_EQ(r.row_blocks + r.column_blocks, 60);
  EXPECT_EQ(r.row_blocks, 24);  // round(60 * 2 / 5)
  // Exact data: a gap of at least 8 decades after sigma_6.
  EXPECT_GT(r.singular_values[5] / r.singular_values[6], 1e8);
}

TEST(RealizationEra, StackedSingleInputExperimentsEqualTheMimoRealisation) {
  // Two SIMO "experiments" (one input each) stacked column-wise must realise
  // the 2-input system: same frequency response, inputs in experiment order.
  const sysid::StateSpace sys = rotated_modal_system({0.06, 0.19, 0.33}, {0.01, 0.02, 0.015}, 2, 3, 2);
  std::vector<sysid::MarkovParameters> parts;
  for (int j = 0; j < 2; ++j) {
    sysid::StateSpace sj(sys.A, sys.B.col(j), sys.C, sys.D.col(j), 1.0);
    sj.input_names = {j == 0 ? "act1" : "act2"};
    parts.push_back(sysid::markov_parameters(sj, 40));
  }
  sysid::EraOptions o;
  o.order = 6;
  const sysid::EraResult r = sysid::era(parts, o);
  ASSERT_EQ(r.model.inputs(), 2);
  EXPECT_LT(frf_error(r.model, sys), 1e-8);
  EXPECT_EQ(r.model.input_names, (std::vector<std::string>{"act1", "act2"}));
  // Different lengths: the common part is used, with a warning.
  parts[1].h.resize(30);
  const sysid::EraResult r2 = sysid::era(parts, o);
  EXPECT_LT(frf_error(r2.model, sys), 1e-8);
  EXPECT_TRUE(has_warning(r2.warnings, "different numbers of Markov parameters"));
}

TEST(RealizationEra, PolesFromMultiStepNlmsEstimatesWithinOnePercent) {
  // The isolator workflow. Chosen to be well identifiable by a 256-tap FIR:
  // modes at 0.08, 0.17, 0.31 cycles/sample with zeta 5, 4, 3 %, so the slowest
  // decays as exp(-2 pi 0.08 0.05 k) to 0.16 % of its start within 256 samples
  // (truncation bias negligible), modes separated by a factor ~2 in frequency,
  // white excitation of one actuator at a time, 30 dB SNR on every output.
  // The LMS misalignment is then ~-35 dB, i.e. ~2 % RMS error on the Markov
  // parameters, and ERA's frequency error is far below 1 % (measured ~1e-4).
  const sysid::StateSpace sys = rotated_modal_system({0.08, 0.17, 0.31}, {0.05, 0.04, 0.03}, 2, 3, 7);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<sysid::MarkovParameters> parts;
  const Eigen::Index N = 30000;
  for (int j = 0; j < 2; ++j) {
    MatrixXd u = MatrixXd::Zero(N, 2);
    for (Eigen::Index k = 0; k < N; ++k) u(k, j) = g(rng);
    MatrixXd y = sysid::simulate(sys, u);
    for (Eigen::Index c = 0; c < y.cols(); ++c) {
      const double sigma = 0.0316 * std::sqrt(y.col(c).squaredNorm() / static_cast<double>(N));  // 30 dB
      for (Eigen::Index k = 0; k < N; ++k) y(k, c) += sigma * g(rng);
    }
    sysid::MultiStepNlmsOptions o;
    o.taps = 256;
    o.gamma = {0.5, 0.3, 0.2};
    o.mu = 0.5;
    const sysid::MultiStepNlmsResult lms = sysid::multistep_nlms(u.col(j), y, o);
    parts.push_back(sysid::markov_from_fir(lms.fir, 1.0));
  }
  for (int order : {6, 0}) {  // fixed and automatic (gap)
    sysid::EraOptions eo;
    eo.order = order;
    const sysid::EraResult r = sysid::era(parts, eo);
    ASSERT_EQ(r.order, 6) << r.order_rule;
    const auto me = sysid::modal_table(r.model), mt = sysid::modal_table(sys);
    ASSERT_EQ(me.size(), mt.size());
    for (std::size_t i = 0; i < mt.size(); ++i) {
      EXPECT_NEAR(me[i].freq_hz / mt[i].freq_hz, 1.0, 0.01) << "mode " << i;
      EXPECT_NEAR(me[i].damping / mt[i].damping, 1.0, 0.1) << "mode " << i;
      EXPECT_TRUE(me[i].stable);
    }
    // The assembled 3x2 model also reproduces the frequency response: a
    // Markov-parameter error of ~2 % RMS bounds the FRF error at a few % of the peak.
    EXPECT_LT(frf_error(r.model, sys), 0.05);
  }
}

TEST(RealizationEra, WarnsAboutUnstablePolesAndWeakOrderDecision) {
  // Exact Markov parameters of a slightly unstable system: ERA realises it
  // faithfully and says so.
  sysid::StateSpace sys = rotated_modal_system({0.1, 0.2}, {0.01, 0.02}, 1, 2, 5);
  sys.A *= 1.02 / sysid::poles(sys).cwiseAbs().maxCoeff();
  sysid::EraOptions o;
  o.order = 4;
  const sysid::EraResult r = sysid::era(sysid::markov_parameters(sys, 30), o);
  EXPECT_LT(pole_distance(sysid::poles(r.model), sysid::poles(sys)), 1e-8);
  EXPECT_TRUE(has_warning(r.warnings, "unstable pole"));
  // Fixed order far above the true one, Markov parameters with a noise floor:
  // sigma_8 and sigma_9 both belong to the noise, a weak order decision.
  sysid::MarkovParameters noisy = sysid::markov_parameters(rotated_modal_system({0.1, 0.2}, {0.05, 0.05}, 1, 2, 6), 30);
  std::mt19937_64 rng(4);
  std::normal_distribution<double> g(0.0, 1e-3);
  for (MatrixXd& h : noisy.h)
    for (Eigen::Index i = 0; i < h.size(); ++i) h.data()[i] += g(rng);
  o.order = 8;
  const sysid::EraResult r8 = sysid::era(noisy, o);
  EXPECT_TRUE(has_warning(r8.warnings, "weak order decision"));
}

TEST(RealizationEra, BadOptionsThrow) {
  const sysid::StateSpace sys = rotated_modal_system({0.1, 0.2}, {0.05, 0.05}, 2, 2, 8);
  const sysid::MarkovParameters mp = sysid::markov_parameters(sys, 10);
  auto expect_throw = [&](const sysid::EraOptions& o, const std::string& text) {
    try {
      sysid::era(mp, o);
      ADD_FAILURE() << "no exception for " << text;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  sysid::EraOptions o;
  o.order = 9;
  o.row_blocks = 2;  // alpha l = 4 < 9
  expect_throw(o, "order <= min(alpha l, beta m)");
  o = {};
  o.row_blocks = 6;
  o.column_blocks = 6;
  expect_throw(o, "alpha + beta <= M");
  o = {};
  o.rule = sysid::EraOrderRule::threshold;
  o.threshold = 0.0;
  expect_throw(o, "0 < threshold < 1");
  o = {};
  o.order = -1;
  expect_throw(o, "order >= 0");

  sysid::MarkovParameters short_mp = mp;
  short_mp.h.resize(2);
  EXPECT_THROW(sysid::era(short_mp), std::invalid_argument);
  sysid::MarkovParameters other = sysid::markov_parameters(rotated_modal_system({0.1}, {0.05}, 1, 3, 9), 10);
  EXPECT_THROW(sysid::era(std::vector<sysid::MarkovParameters>{mp, other}), std::invalid_argument);  // 2 vs 3 outputs
  sysid::MarkovParameters slow = mp;
  slow.Ts = 2.0;
  EXPECT_THROW(sysid::era(std::vector<sysid::MarkovParameters>{mp, slow}), std::invalid_argument);
  EXPECT_THROW(sysid::era(std::vector<sysid::MarkovParameters>{}), std::invalid_argument);
  sysid::MarkovParameters zero = mp;
  for (MatrixXd& h : zero.h) h.setZero();
  EXPECT_THROW(sysid::era(zero), std::invalid_argument);  // a property of the data, not a numerical failure
}

}  // namespace

}  // namespace test_unit_realization_era
