// The cascaded tanks (issue 6, scope 7; ../shared/data/real/cascaded_tanks and
// its README): what sysid's physics vocabulary can model there. The upper tank
// overflows for large pump inputs and part of the spill falls into the lower
// tank. A store `saturation` (physics_block.hpp) on the order-2 linear model
// identified by n4sid, with the linear dynamics refitted around it
// (linear_core_refit.hpp) on the estimation record, must bring the free-run RMSE
// on the test record below 0.5 V from the linear model's ~0.61 V (same initial
// state as the estimation record, as the benchmark's protocol states).
//
// The first test checks the model class and the refit. The second is the
// diagnosis itself (issue 6's acceptance): `diagnose` in confirmation mode
// (diagnose.hpp) fits and ranks on the estimation record, the test record
// confirms each finding, and the overflow must be named first with the test
// RMSE below 0.5 V. Cut in three, the 1 024-sample record cannot prove it: its
// two overflow episodes do not fill both a fit and a selection segment.
#include <sysid/diagnose/diagnose.hpp>
#include <sysid/diagnose/linear_core_refit.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/subspace/n4sid.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>

#include "../support/diagnose_cases.hpp"

namespace test_acceptance_diagnose_cascaded_tanks {

namespace {

const std::string kTanks = std::string(SYSID_SOURCE_DIR) + "/../shared/data/real/cascaded_tanks/";

double rmse(const Eigen::MatrixXd& y, const Eigen::MatrixXd& y_hat) {
  return std::sqrt((y - y_hat).squaredNorm() / static_cast<double>(y.size()));
}

/// The two records and the order-2 linear model n4sid identifies on the first.
struct Tanks {
  sysid::IoData estimation, test;
  sysid::N4sidResult linear;
};

Tanks load_tanks() {
  sysid::LogOptions lo;
  lo.inputs = {"u"};
  lo.outputs = {"y"};
  Tanks t{sysid::read_log(kTanks + "estimation.csv", lo), sysid::read_log(kTanks + "test.csv", lo), {}};
  sysid::N4sidOptions no;
  no.order = 2;
  t.linear = sysid::n4sid(t.estimation, no);
  return t;
}

}  // namespace

TEST(DiagnoseCascadedTanks, OverflowingUpperTankWithRefittedTanksBeatsHalfAVolt) {
  if (!std::filesystem::exists(kTanks + "estimation.csv")) GTEST_SKIP() << "no " << kTanks;
  const Tanks tanks = load_tanks();
  const sysid::IoData &est = tanks.estimation, &test = tanks.test;
  const sysid::N4sidResult& linear = tanks.linear;

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

TEST(DiagnoseCascadedTanks, DiagnoseNamesTheOverflowAndTheTestRecordConfirmsIt) {
  if (!std::filesystem::exists(kTanks + "estimation.csv")) GTEST_SKIP() << "no " << kTanks;
  const Tanks tanks = load_tanks();
  const sysid::AugmentedModel nominal = sysid::test::nominal_from(tanks.linear);

  sysid::DiagnoseOptions o;
  o.refit_nominal = true;  // the nominal was identified on this machine
  const auto& e = tanks.estimation.experiments.front();
  const auto& t = tanks.test.experiments.front();
  const sysid::DiagnoseReport r = sysid::diagnose_confirmed(nominal, e.u, e.y, t.u, t.y, o);
  ASSERT_FALSE(r.findings.empty()) << "no finding";
  const sysid::PhysicsBlock& first = r.findings.front().candidate.block;
  EXPECT_EQ(first.kind, "saturation") << r.findings.front().summary;
  EXPECT_GT(first.param("storage_pole"), 0.0) << "an amplifier, not a store that overflows";  // a tank's overflow
  for (const auto& f : r.findings) {
    std::cout << "  " << f.candidate.block.kind << ": " << f.summary << " (t = " << f.t_statistic << ", test fit "
              << f.fit_before << " -> " << f.fit_after << " %)\n";
    EXPECT_GT(f.fit_after, f.fit_before);
  }
  // The benchmark's figure: free-run RMSE on the test record, from the
  // estimation record's initial state (the same for both records, its README says).
  const double before = rmse(t.y, sysid::simulate_augmented(nominal, t.u));
  const double after = rmse(t.y, sysid::simulate_augmented(r.augmented, t.u));
  std::cout << "cascaded tanks, diagnose confirmed on the test record: test RMSE " << before << " V -> " << after << " V, "
            << r.findings.size() << " finding(s); test fit " << r.fit_before << " -> " << r.fit_after << " %\n";
  EXPECT_GT(before, 0.55);
  EXPECT_LT(after, 0.5);
  EXPECT_GE(r.fit_after - r.fit_before, 1.0);
}

}  // namespace test_acceptance_diagnose_cascaded_tanks
