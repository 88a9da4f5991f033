// Tests for include/sysid/diagnose/linear_core_refit.hpp: a nominal holding a
// compromise of a nonlinearity (wrong poles and gain) is brought back to the true
// linear dynamics once the nonlinearity is a block in the loop.
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/diagnose/linear_core_refit.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "../support/diagnose_cases.hpp"

namespace test_unit_diagnose_linear_core_refit {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using sysid::test::physics_block;

/// Two first-order tanks in cascade (poles a1 upper, a2 lower), level of the lower
/// one out: x1+ = a1 x1 + (1 - a1) u, x2+ = a2 x2 + (1 - a2) g x1, y = x2.
sysid::StateSpace cascaded_tanks(double a1, double a2, double gain) {
  return sysid::StateSpace(MatrixXd{{a1, 0.0}, {(1.0 - a2) * gain, a2}}, MatrixXd{{1.0 - a1}, {0.0}}, MatrixXd{{0.0, 1.0}},
                           MatrixXd::Zero(1, 1), 4.0);
}

/// Slow random steps (a multisine-like pump command), deviation coordinates.
MatrixXd pump_command(Eigen::Index n, std::uint64_t seed) {
  const MatrixXd noise = sysid::test::white_noise(n / 40 + 1, 1, seed);
  MatrixXd u(n, 1);
  for (Eigen::Index k = 0; k < n; ++k) u(k, 0) = 1.2 * noise(k / 40, 0);
  return u;
}

double rms(const MatrixXd& e) { return std::sqrt(e.squaredNorm() / static_cast<double>(e.size())); }

sysid::Candidate store_candidate(double limit, double pole, double spill) {
  sysid::Candidate c;
  c.block = physics_block("saturation", {{"limit", limit}, {"storage_pole", pole}, {"spill", spill}});
  c.free = {{"limit", 0.2, 2.0}, {"storage_pole", pole * pole, std::sqrt(pole)}, {"spill", 0.0, 1.0}};
  return c;
}

}  // namespace

TEST(LinearCoreRefit, RecoversTheTanksBehindAnOverflowingUpperTank) {
  const sysid::StateSpace truth = cascaded_tanks(0.97, 0.93, 1.0);
  const sysid::Candidate true_store = store_candidate(0.9, 0.97, 0.4);
  const MatrixXd u = pump_command(3000, 11), u_check = pump_command(3000, 12);
  const sysid::AugmentedSimulator true_sim(truth);
  const MatrixXd y = true_sim.simulate({true_store.block}, u) + sysid::test::white_noise(3000, 1, 13, 0.01);
  const MatrixXd y_check = true_sim.simulate({true_store.block}, u_check);

  // A nominal holding the compromise (both poles faster, gain low) and the block
  // started away from the truth.
  const sysid::StateSpace compromise = cascaded_tanks(0.95, 0.90, 0.85);
  const sysid::Candidate start = store_candidate(1.2, 0.95, 0.1);
  const sysid::LinearCoreRefitResult r = sysid::refit_linear_core(compromise, VectorXd(), {}, {start}, u, y, u.rows(), 1);
  ASSERT_TRUE(r.refitted);
  EXPECT_LT(r.cost, 0.05 * r.start_cost);
  Eigen::VectorXd found = r.poles_after.real();
  std::sort(found.data(), found.data() + found.size());
  EXPECT_NEAR(found[0], 0.93, 3e-3);
  EXPECT_NEAR(found[1], 0.97, 3e-3);
  EXPECT_NEAR(r.blocks.front().block.param("limit"), 0.9, 0.03);
  EXPECT_NEAR(r.blocks.front().block.param("spill"), 0.4, 0.1);
  // On a record it never saw, within a few times the noise of the fitted one.
  const sysid::AugmentedSimulator refitted(r.model, 1);
  EXPECT_LT(rms(y_check - refitted.simulate({r.blocks.front().block}, u_check)), 0.03);
  const sysid::AugmentedSimulator before(compromise, 1);
  EXPECT_GT(rms(y_check - before.simulate({start.block}, u_check)), 0.1);
}

TEST(LinearCoreRefit, MovesTheModesOfAMimoNominalToTheData) {
  // Two inputs, two outputs, a real pole pair and a complex pair (the real
  // modal form's 2x2 block), no physics blocks: the refit is an output-error
  // fit of poles, B, D and x0 with C held.
  const MatrixXd C{{1.0, 0.5, 0.2, 0.0}, {0.0, 1.0, 0.3, 0.6}};
  const MatrixXd B{{0.3, 0.1}, {0.0, 0.2}, {0.25, -0.1}, {0.1, 0.3}};
  auto system = [&](double a1, double a2, double r, double angle) {
    MatrixXd A = MatrixXd::Zero(4, 4);
    A(0, 0) = a1;
    A(1, 1) = a2;
    A.block<2, 2>(2, 2) << r * std::cos(angle), r * std::sin(angle), -r * std::sin(angle), r * std::cos(angle);
    return sysid::StateSpace(A, B, C, MatrixXd::Zero(2, 2), 1.0);
  };
  const sysid::StateSpace truth = system(0.95, 0.85, 0.9, 0.4), off = system(0.93, 0.87, 0.88, 0.44);
  const MatrixXd u = sysid::test::white_noise(3000, 2, 31);
  const MatrixXd y = sysid::simulate(truth, u);
  const sysid::LinearCoreRefitResult r = sysid::refit_linear_core(off, VectorXd(), {}, {}, u, y, u.rows(), 1);
  ASSERT_TRUE(r.refitted);
  EXPECT_LT(r.cost, 1e-3 * r.start_cost);
  const Eigen::VectorXcd expected = sysid::poles(truth);
  for (Eigen::Index k = 0; k < expected.size(); ++k) {
    double nearest = 1.0;
    for (Eigen::Index q = 0; q < r.poles_after.size(); ++q) nearest = std::min(nearest, std::abs(r.poles_after[q] - expected[k]));
    EXPECT_LT(nearest, 2e-3) << expected[k];
  }
}

TEST(LinearCoreRefit, ATrueNominalStaysAndLargeOrDefectiveNominalsAreNotRefitted) {
  const sysid::StateSpace truth = cascaded_tanks(0.97, 0.93, 1.0);
  const MatrixXd u = pump_command(2000, 21);
  const MatrixXd y = sysid::simulate(truth, u);
  const sysid::LinearCoreRefitResult same = sysid::refit_linear_core(truth, VectorXd(), {}, {}, u, y, u.rows(), 1);
  ASSERT_TRUE(same.refitted);
  EXPECT_LE(same.cost, same.start_cost);
  EXPECT_LT(same.start_cost, 1e-20);  // the modal form reproduces the nominal exactly

  sysid::LinearCoreRefitOptions small;
  small.max_order = 1;
  const sysid::LinearCoreRefitResult skipped = sysid::refit_linear_core(truth, VectorXd(), {}, {}, u, y, u.rows(), 1, small);
  EXPECT_FALSE(skipped.refitted);
  ASSERT_FALSE(skipped.warnings.empty());
  EXPECT_TRUE(skipped.model.A.isApprox(truth.A));

  // A Jordan block (defective A): no eigenvector basis, no refit.
  const sysid::StateSpace jordan(MatrixXd{{0.9, 1.0}, {0.0, 0.9}}, MatrixXd{{0.0}, {1.0}}, MatrixXd{{1.0, 0.0}},
                                 MatrixXd::Zero(1, 1), 1.0);
  const sysid::LinearCoreRefitResult defective =
      sysid::refit_linear_core(jordan, VectorXd(), {}, {}, u, sysid::simulate(jordan, u), u.rows(), 1);
  EXPECT_FALSE(defective.refitted);
  EXPECT_THROW(sysid::refit_linear_core(truth, VectorXd(), {}, {}, u, y, 0, 1), std::invalid_argument);
}

}  // namespace test_unit_diagnose_linear_core_refit
