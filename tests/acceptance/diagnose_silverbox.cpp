// Acceptance of `diagnose` on a real recording (issue 6, scope 7): the Silverbox
// (an electronic Duffing oscillator; ../shared/data/real/silverbox, protocol in
// its README). Nominal = a second-order linear model identified by n4sid on the
// estimation multisine (rows 40650..105711 of SNLS80mV). diagnose on that record
// must name cubic_stiffness first, and the augmented model must bring the
// free-run RMSE on the full arrow test (rows 100..40574, first 50 samples
// excluded) from the linear model's ~14 mV to below 1.4 mV — below every
// published black-box baseline (LSTM 2.68, GRU 2.80, deep state-space encoder
// 1.41 mV).
//
// Under the sanitizers (tests/support/sanitizers.hpp) diagnose sees the first
// 15 000 samples of the estimation multisine instead of 65 062: the same code
// paths and the same assertions, at a quarter of the cost (measured with the
// optimised build: 12 000 samples still name cubic_stiffness first and reach
// 0.50 mV on the arrow, against 0.45 mV with the whole record).
#include <sysid/core/simulate.hpp>
#include <sysid/diagnose/diagnose.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/subspace/n4sid.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>

#include "../support/diagnose_cases.hpp"
#include "../support/sanitizers.hpp"

namespace test_acceptance_diagnose_silverbox {

namespace {

const std::string kSilverbox = std::string(SYSID_SOURCE_DIR) + "/../shared/data/real/silverbox/SNLS80mV.csv";

double rmse_mv(const Eigen::VectorXd& y, const Eigen::VectorXd& y_hat, Eigen::Index skip) {
  const Eigen::Index n = y.size() - skip;
  return 1e3 * std::sqrt((y.tail(n) - y_hat.tail(n)).squaredNorm() / static_cast<double>(n));
}

TEST(DiagnoseSilverbox, NamesCubicStiffnessAndBeatsThePublishedBaselines) {
  if (!std::filesystem::exists(kSilverbox)) GTEST_SKIP() << "no " << kSilverbox;
  sysid::LogOptions lo;
  lo.inputs = {"u"};
  lo.outputs = {"y"};
  const sysid::IoData all = sysid::read_log(kSilverbox, lo);
  const auto& e = all.experiments.front();
  const Eigen::Index estimation_samples = sysid::test::kSanitized ? 15000 : 65062;
  const Eigen::MatrixXd u_est = e.u.middleRows(40650, estimation_samples), y_est = e.y.middleRows(40650, estimation_samples);
  const Eigen::MatrixXd u_test = e.u.middleRows(100, 40475), y_test = e.y.middleRows(100, 40475);

  sysid::N4sidOptions no;
  no.order = 2;
  sysid::IoData est;
  est.Ts = all.Ts;
  est.input_names = {"u"};
  est.output_names = {"y"};
  est.add_experiment({u_est, y_est, "silverbox estimation"});
  const sysid::N4sidResult linear = sysid::n4sid(est, no);
  const sysid::AugmentedModel nominal = sysid::test::nominal_from(linear);

  const sysid::DiagnoseReport report = sysid::diagnose(nominal, u_est, y_est);
  ASSERT_FALSE(report.findings.empty());
  EXPECT_EQ(report.findings[0].candidate.block.kind, "cubic_stiffness") << report.findings[0].summary;

  sysid::AugmentedModel linear_only = nominal, augmented = report.augmented;
  linear_only.x0 = augmented.x0 = Eigen::VectorXd();  // free run from rest; 50 samples skipped
  const double before = rmse_mv(y_test.col(0), sysid::simulate_augmented(linear_only, u_test).col(0), 50);
  const double after = rmse_mv(y_test.col(0), sysid::simulate_augmented(augmented, u_test).col(0), 50);
  std::cout << "Silverbox arrow (full) test RMSE: linear " << before << " mV, augmented " << after << " mV; "
            << report.findings[0].summary << "\n";
  EXPECT_GT(before, 10.0);  // the linear model's ~14 mV: the nominal is what the issue describes
  EXPECT_LT(after, 1.4);
}

}  // namespace

}  // namespace test_acceptance_diagnose_silverbox
