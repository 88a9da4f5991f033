// End-to-end: sysid compare (simulation and k-step prediction fit).
#include <sysid/core/simulate.hpp>
#include <sysid/validate/compare.hpp>

#include <gtest/gtest.h>

#include "innovation_log.hpp"
#include "run_cli.hpp"

namespace test_app_compare {

using namespace sysid;
using namespace sysid::test;

TEST(CompareApp, OneStepPredictionBeatsSimulationOnNoisyInnovationData) {
  TempDir dir;
  const StateSpace plant = four_mode_plant();
  const InnovationLog d = innovation_log(plant, 4000, 0.05, 2.0, 3);
  write_model(dir / "m.json", plant, d.K);
  write_siso_log(dir / "log.csv", d.u, d.y);

  const CliResult sim = run_cli({"compare", dir / "m.json", dir / "log.csv"});
  ASSERT_EQ(sim.exit_code, 0) << describe(sim);
  const CliResult pred = run_cli({"compare", dir / "m.json", dir / "log.csv", "--predict", "1"});
  ASSERT_EQ(pred.exit_code, 0) << describe(pred);
  EXPECT_NE(sim.out.find("simulation"), std::string::npos) << sim.out;
  EXPECT_NE(pred.out.find("1-step-ahead prediction"), std::string::npos) << pred.out;
  const double fit_sim = fit_after(sim.out, "fit [%]", "y"), fit_pred = fit_after(pred.out, "fit [%]", "y");
  // The 1-step error is the innovation alone, the simulation error carries the
  // plant-filtered noise K e too.
  EXPECT_GT(fit_pred, fit_sim + 5.0) << sim.out << pred.out;

  // The numbers are the library's (printed with 2 decimals).
  const Experiment e{d.u, d.y, "log"};
  CompareOptions o;
  EXPECT_NEAR(fit_sim, compare(plant, d.K, e, o).fit_percent(0), 0.006);
  o.predict_steps = 1;
  EXPECT_NEAR(fit_pred, compare(plant, d.K, e, o).fit_percent(0), 0.006);
  // Longer horizons lie in between.
  const CliResult p10 = run_cli({"compare", dir / "m.json", dir / "log.csv", "--predict", "10"});
  ASSERT_EQ(p10.exit_code, 0) << describe(p10);
  const double fit10 = fit_after(p10.out, "fit [%]", "y");
  EXPECT_LT(fit10, fit_pred);
  EXPECT_GT(fit10, fit_sim);
}

TEST(CompareApp, PredictWithoutKalmanGainIsAnError) {
  TempDir dir;
  const StateSpace plant = four_mode_plant();
  write_model(dir / "m.json", plant);  // no K
  const Eigen::MatrixXd u = white_noise(500, 1, 1, 1.0);
  write_siso_log(dir / "log.csv", u, simulate(plant, u));
  const CliResult r = run_cli({"compare", dir / "m.json", dir / "log.csv", "--predict", "1"});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_NE(r.err.find("Kalman gain"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(dir / "m.json"), std::string::npos) << r.err;
}

TEST(CompareApp, ExactDataWithOffsetsAndInitialState) {
  TempDir dir;
  const StateSpace plant = four_mode_plant();
  Eigen::VectorXd x0(4);
  x0 << 2.0, 1.0, -1.0, 0.5;
  const Eigen::VectorXd in_off = Eigen::VectorXd::Constant(1, 1.25), out_off = Eigen::VectorXd::Constant(1, 7.0);
  write_model(dir / "m.json", plant, {}, in_off, out_off, x0);
  const Eigen::MatrixXd u = white_noise(2000, 1, 4, 1.0);
  const Eigen::MatrixXd y = (simulate(plant, u, x0).array() + 7.0).matrix();
  write_siso_log(dir / "log.csv", (u.array() + 1.25).matrix(), y);

  for (const std::string x0_mode : {"estimate", "model"}) {
    const CliResult r = run_cli({"compare", dir / "m.json", dir / "log.csv", "--x0", x0_mode});
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    EXPECT_NEAR(fit_after(r.out, "fit [%]", "y"), 100.0, 0.005) << x0_mode << ": " << r.out;
  }
  const CliResult zero = run_cli({"compare", dir / "m.json", dir / "log.csv", "--x0", "zero"});
  ASSERT_EQ(zero.exit_code, 0) << describe(zero);
  EXPECT_LT(fit_after(zero.out, "fit [%]", "y"), 99.0) << zero.out;
}

TEST(CompareApp, ChannelCountMustMatchTheModel) {
  TempDir dir;
  const StateSpace plant = four_mode_plant();
  write_model(dir / "m.json", plant);
  const Eigen::MatrixXd u = white_noise(300, 1, 1, 1.0);
  write_siso_log(dir / "log.csv", u, simulate(plant, u));
  const CliResult r = run_cli({"compare", dir / "m.json", dir / "log.csv", "--outputs", "y,u"});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_NE(r.err.find("1 output(s)"), std::string::npos) << r.err;
}

TEST(CompareApp, HelpHasAnExample) {
  const CliResult r = run_cli({"compare", "--help"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.out.find("Example"), std::string::npos);
  EXPECT_NE(r.out.find("sysid compare model.json"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--predict"), std::string::npos);
}

}  // namespace test_app_compare
