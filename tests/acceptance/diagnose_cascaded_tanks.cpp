// The cascaded tanks (issue 6, scope 7; ../shared/data/real/cascaded_tanks and
// its README): what sysid's physics vocabulary can model there. The upper tank
// overflows for large pump inputs and part of the spill falls into the lower
// tank. A store `saturation` (physics_block.hpp) on the order-2 linear model
// identified by n4sid, with the linear dynamics refitted around it
// (linear_core_refit.hpp) on the estimation record, must bring the free-run RMSE
// on the test record below 0.5 V from the linear model's ~0.61 V (same initial
// state as the estimation record, as the benchmark's protocol states).
//
// This checks the model class and the refit, not the diagnosis: `diagnose`
// does not yet accept the overflow on this 1 024-sample record (README, issue 6).
#include <sysid/diagnose/linear_core_refit.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/subspace/n4sid.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>

namespace test_acceptance_diagnose_cascaded_tanks {

namespace {

const std::string kTanks = std::string(SYSID_SOURCE_DIR) + "/../shared/data/real/cascaded_tanks/";

double rmse(const Eigen::MatrixXd& y, const Eigen::MatrixXd& y_hat) {
  return std::sqrt((y - y_hat).squaredNorm() / static_cast<double>(y.size()));
}

}  // namespace

TEST(DiagnoseCascadedTanks, OverflowingUpperTankWithRefittedTanksBeatsHalfAVolt) {
  if (!std::filesystem::exists(kTanks + "estimation.csv")) GTEST_SKIP() << "no " << kTanks;
  sysid::LogOptions lo;
  lo.inputs = {"u"};
  lo.outputs = {"y"};
  const sysid::IoData est = sysid::read_log(kTanks + "estimation.csv", lo);
  const sysid::IoData test = sysid::read_log(kTanks + "test.csv", lo);
  sysid::N4sidOptions no;
  no.order = 2;
  const sysid::N4sidResult linear = sysid::n4sid(est, no);

  auto deviation = [](Eigen::MatrixXd m, double offset) {
    m.array() -= offset;
    return m;
  };
  const Eigen::MatrixXd u = deviation(est.experiments.front().u, linear.input_offset(0));
  const Eigen::MatrixXd y = deviation(est.experiments.front().y, linear.output_offset(0));
  const Eigen::MatrixXd u_test = deviation(test.experiments.front().u, linear.input_offset(0));
  const Eigen::MatrixXd y_test = deviation(test.experiments.front().y, linear.output_offset(0));

  // The store starts at the slow tank's pole, overflowing near the top of its
  // range; spill, limit and the linear dynamics are fitted.
  sysid::Candidate overflow;
  overflow.block.kind = "saturation";
  overflow.block.params = {{"limit", 1.0}, {"storage_pole", 0.97}, {"spill", 0.5}};
  overflow.free = {{"limit", 0.2, 3.0}, {"storage_pole", 0.9, 0.99}, {"spill", 0.0, 1.0}};
  const sysid::LinearCoreRefitResult r = sysid::refit_linear_core(linear.model, linear.x0, {}, {overflow}, u, y, u.rows(), 1);
  ASSERT_TRUE(r.refitted);

  const double before = rmse(y_test, sysid::AugmentedSimulator(linear.model, 1, linear.x0).simulate({}, u_test));
  const double after = rmse(y_test, sysid::AugmentedSimulator(r.model, 1, r.x0).simulate({r.blocks.front().block}, u_test));
  const sysid::PhysicsBlock& b = r.blocks.front().block;
  std::cout << "cascaded tanks test RMSE: linear " << before << " V, overflow + refitted tanks " << after << " V (limit "
            << b.param("limit") << ", spill " << b.param("spill") << ", store pole " << b.param("storage_pole") << ")\n";
  EXPECT_GT(before, 0.55);  // the linear model of the issue (~0.6 V)
  EXPECT_LT(after, 0.5);
  // The spill into the lower tank carries part of it: without it the same fit is worse.
  sysid::Candidate lost = overflow;
  lost.block.params["spill"] = 0.0;
  lost.free = {{"limit", 0.2, 3.0}, {"storage_pole", 0.9, 0.99}};
  const sysid::LinearCoreRefitResult no_spill = sysid::refit_linear_core(linear.model, linear.x0, {}, {lost}, u, y, u.rows(), 1);
  const double after_no_spill =
      rmse(y_test, sysid::AugmentedSimulator(no_spill.model, 1, no_spill.x0).simulate({no_spill.blocks.front().block}, u_test));
  std::cout << "  without spill: " << after_no_spill << " V\n";
  EXPECT_GT(after_no_spill, after);
}

}  // namespace test_acceptance_diagnose_cascaded_tanks
