// Tests of subspace/pole_refinement.hpp: poles moved off the truth come back to
// it on the simulation error (frequencies and damping of a lightly damped
// two-mode plant), the fit rises to the noise ceiling; raced starts keep the one
// that reaches the lower error; a near-defective A is returned unrefined with the
// reason; bad starts are refused.
#include <sysid/core/modal_table.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/subspace/pole_refinement.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

#include "random_systems.hpp"

namespace test_unit_subspace_pole_refinement {

using namespace sysid;

namespace {

constexpr double kTs = 1e-3;

/// The modal block matrix (test::modal_block_matrix) of modes (f Hz, zeta) at kTs.
Eigen::MatrixXd modal_a(const std::vector<std::pair<double, double>>& modes) {
  std::vector<double> f, zeta;
  for (const auto& [fk, zk] : modes) {
    f.push_back(fk);
    zeta.push_back(zk);
  }
  return test::modal_block_matrix(f, zeta, kTs);
}

const std::vector<std::pair<double, double>> kTrueModes{{20.0, 0.02}, {70.0, 0.05}};

/// White input through the true plant, with 1 % output noise (of the output's RMS).
IoData plant_record(Eigen::Index samples, unsigned seed) {
  const Eigen::MatrixXd a = modal_a(kTrueModes);
  Eigen::MatrixXd b(4, 1), c(1, 4);
  b << 1.0, 0.5, -0.8, 0.3;
  c << 1.0, 0.0, 1.0, 0.0;
  const StateSpace plant(a, b, c, Eigen::MatrixXd::Zero(1, 1), kTs);
  const Eigen::MatrixXd u = test::white_noise(samples, 1, seed);
  Eigen::MatrixXd y = simulate(plant, u);
  const double rms = std::sqrt(y.squaredNorm() / static_cast<double>(samples));
  y += 0.01 * rms * test::white_noise(samples, 1, seed + 1);
  return IoData(u, y, kTs);
}

Eigen::MatrixXd c_modal() {
  Eigen::MatrixXd c(1, 4);
  c << 1.0, 0.0, 1.0, 0.0;
  return c;
}

void expect_true_modes(const Eigen::MatrixXd& a, const std::string& what) {
  const auto modes = modal_table(StateSpace(a, Eigen::MatrixXd::Zero(a.rows(), 1), Eigen::MatrixXd::Zero(1, a.rows()),
                                            Eigen::MatrixXd::Zero(1, 1), kTs));
  ASSERT_EQ(modes.size(), 2u) << what;
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_NEAR(modes[k].freq_hz / kTrueModes[k].first, 1.0, 2e-3) << what << " mode " << k;
    EXPECT_NEAR(modes[k].damping / kTrueModes[k].second, 1.0, 0.1) << what << " mode " << k;
  }
}

}  // namespace

TEST(PoleRefinement, PolesMovedOffTheTruthComeBack) {
  const IoData data = plant_record(20000, 3);
  // 3 % off in frequency, damping 1.6 times the truth.
  const Eigen::MatrixXd start = modal_a({{20.6, 0.032}, {67.9, 0.08}});
  const PoleRefinementResult r = refine_poles({{start, c_modal()}}, data);
  ASSERT_TRUE(r.refined) << r.termination;
  EXPECT_EQ(r.start, 0u);
  EXPECT_GT(r.final_fit, r.initial_fit + 5.0) << r.initial_fit << " -> " << r.final_fit;
  EXPECT_GT(r.final_fit, 98.5);  // the noise ceiling: 1 - 1 % = 99 %
  EXPECT_TRUE(r.C.isApprox(c_modal()));
  expect_true_modes(r.A, "refined");
}

TEST(PoleRefinement, TheRefinedAKeepsItsStartsCoordinates) {
  // A start in other coordinates (x = S x'): A' = S^-1 A S, C' = C S. The refined
  // A comes back in those coordinates, with C' unchanged.
  const IoData data = plant_record(20000, 4);
  Eigen::Matrix4d s;
  s << 1.0, 0.3, 0.0, 0.1, 0.0, 1.0, 0.2, 0.0, 0.5, 0.0, 1.0, 0.0, 0.0, 0.1, 0.0, 1.0;
  const Eigen::MatrixXd a = s.inverse() * modal_a({{20.4, 0.025}, {71.0, 0.06}}) * s;
  const Eigen::MatrixXd c = c_modal() * s;
  const PoleRefinementResult r = refine_poles({{a, c}}, data);
  ASSERT_TRUE(r.refined) << r.termination;
  EXPECT_TRUE(r.C.isApprox(c));
  expect_true_modes(r.A, "refined in other coordinates");
}

TEST(PoleRefinement, RacedStartsKeepTheOneThatReachesTheLowerError) {
  const IoData data = plant_record(20000, 5);
  // A start far off (a mode at 150 Hz that the data do not show) and one near the truth.
  const Eigen::MatrixXd far = modal_a({{20.0, 0.3}, {150.0, 0.2}});
  const Eigen::MatrixXd near = modal_a({{20.3, 0.025}, {69.0, 0.06}});
  const PoleRefinementResult r = refine_poles({{far, c_modal()}, {near, c_modal()}}, data);
  EXPECT_EQ(r.start, 1u);
  EXPECT_GT(r.final_fit, 98.5);
  expect_true_modes(r.A, "raced");
}

TEST(PoleRefinement, NearDefectiveAIsReturnedUnrefinedAndBadStartsAreRefused) {
  const IoData data = plant_record(4000, 6);
  Eigen::MatrixXd jordan = Eigen::MatrixXd::Zero(4, 4);
  jordan.diagonal().setConstant(0.9);
  jordan(0, 1) = jordan(1, 2) = jordan(2, 3) = 1.0;  // one eigenvalue of multiplicity 4: no real modal form
  const PoleRefinementResult r = refine_poles({{jordan, c_modal()}}, data);
  EXPECT_FALSE(r.refined);
  EXPECT_TRUE(r.A.isApprox(jordan));
  EXPECT_NE(r.termination.find("modal form"), std::string::npos) << r.termination;
  EXPECT_THROW(refine_poles({}, data), std::invalid_argument);
  EXPECT_THROW(refine_poles({{modal_a({{20.0, -0.01}, {70.0, 0.05}}), c_modal()}}, data), std::invalid_argument);  // unstable
  EXPECT_THROW(refine_poles({{modal_a(kTrueModes), Eigen::MatrixXd::Ones(2, 4)}}, data), std::invalid_argument);  // C rows
}

}  // namespace test_unit_subspace_pole_refinement
