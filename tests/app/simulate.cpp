// End-to-end: sysid simulate against the library's simulate() on the same model.
#include <sysid/core/simulate.hpp>
#include <sysid/io/model_json.hpp>

#include <gtest/gtest.h>

#include "random_systems.hpp"
#include "run_cli.hpp"

namespace test_app_simulate {

using namespace sysid;
using namespace sysid::test;

namespace {

/// t (1 kHz) and the given columns.
void write_log(const std::string& path, const std::vector<std::string>& names, const Eigen::MatrixXd& cols, bool with_time = true) {
  Eigen::MatrixXd table(cols.rows(), cols.cols() + (with_time ? 1 : 0));
  std::vector<std::string> all;
  if (with_time) {
    table.col(0) = Eigen::VectorXd::LinSpaced(cols.rows(), 0.0, static_cast<double>(cols.rows() - 1)) * 0.001 + Eigen::VectorXd::Constant(cols.rows(), 2.0);
    all.push_back("t");
  }
  table.rightCols(cols.cols()) = cols;
  all.insert(all.end(), names.begin(), names.end());
  write_csv(path, all, table);
}

/// Relative max-abs difference.
double rel_diff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1e-300, b.cwiseAbs().maxCoeff());
}

}  // namespace

TEST(SimulateApp, MatchesTheLibraryWithOffsetsAndKeepsTheTimeColumn) {
  TempDir dir;
  const StateSpace plant = four_mode_plant();
  const Eigen::VectorXd in_off = Eigen::VectorXd::Constant(1, 0.75), out_off = Eigen::VectorXd::Constant(1, -4.0);
  write_model(dir / "m.json", plant, {}, in_off, out_off);
  const Eigen::MatrixXd u = white_noise(1500, 1, 1, 1.0);
  write_log(dir / "log.csv", {"u"}, u);
  const CliResult r = run_cli({"simulate", dir / "m.json", dir / "log.csv", "--out", dir / "sim.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const CsvTable out = read_csv(dir / "sim.csv");
  ASSERT_EQ(out.names, (std::vector<std::string>{"t", "y"}));
  ASSERT_EQ(out.values.rows(), 1500);
  // The time column is copied verbatim (shortest round-trip text both ways).
  EXPECT_EQ(out.values.col(0), csv_column(dir / "log.csv", "t"));
  // y = simulate(u - input_offset) + output_offset: same arithmetic, same doubles
  // up to the order of the operations (1e-12 relative).
  const Eigen::MatrixXd expected = (simulate(plant, (u.array() - 0.75).matrix()).array() - 4.0).matrix();
  EXPECT_LT(rel_diff(out.values.rightCols(1), expected), 1e-12);
}

TEST(SimulateApp, MimoColumnsAreNamedAsTheModelOutputsAndInputsMapByName) {
  TempDir dir;
  StateSpace sys = random_modal_system(2, 2, 3, 17);
  sys.Ts = 0.001;
  sys.input_names = {"force", "torque"};
  sys.output_names = {"acc1", "acc2", "acc3"};
  write_model(dir / "m.json", sys);
  const Eigen::MatrixXd u = white_noise(800, 2, 3, 1.0);
  // The log has the columns in another order and under other names.
  Eigen::MatrixXd cols(800, 3);
  cols << u.col(1), Eigen::VectorXd::Zero(800), u.col(0);
  write_log(dir / "log.csv", {"b", "junk", "a"}, cols, /*with_time=*/false);
  CliResult r = run_cli({"simulate", dir / "m.json", dir / "log.csv", "--inputs", "a,b", "--ts", "0.001", "--out", dir / "sim.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const CsvTable out = read_csv(dir / "sim.csv");
  ASSERT_EQ(out.names, (std::vector<std::string>{"acc1", "acc2", "acc3"}));  // no time column in, none out
  EXPECT_LT(rel_diff(out.values, simulate(sys, u)), 1e-12);

  // Default inputs are the model's names: this log has none of them.
  r = run_cli({"simulate", dir / "m.json", dir / "log.csv", "--ts", "0.001", "--out", dir / "sim2.csv"});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_NE(r.err.find("no column 'force'"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "sim2.csv"));
}

TEST(SimulateApp, InitialStateZeroModelAndEstimate) {
  TempDir dir;
  const StateSpace plant = four_mode_plant();
  Eigen::VectorXd x0(4);
  x0 << 3.0, -1.0, 2.0, 0.5;
  write_model(dir / "m.json", plant, {}, {}, {}, x0);
  const Eigen::MatrixXd u = white_noise(1000, 1, 8, 1.0);
  const Eigen::MatrixXd y = simulate(plant, u, x0);
  Eigen::MatrixXd cols(1000, 2);
  cols << u, y;
  write_log(dir / "log.csv", {"u", "y"}, cols);

  auto run = [&](const std::vector<std::string>& extra) {
    // --force: each call replaces the previous run's output.
    std::vector<std::string> args{"simulate", dir / "m.json", dir / "log.csv", "--out", dir / "sim.csv", "--force"};
    args.insert(args.end(), extra.begin(), extra.end());
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 0) << describe(r);
    return Eigen::MatrixXd(csv_column(dir / "sim.csv", "y"));
  };
  // Default zero: misses the free response of x0.
  EXPECT_GT(rel_diff(run({}), y), 0.1);
  // x0 from the model file: exact.
  EXPECT_LT(rel_diff(run({"--x0", "model"}), y), 1e-12);
  // x0 estimated from the log's outputs: exact up to the least-squares rounding.
  EXPECT_LT(rel_diff(run({"--x0", "estimate", "--outputs", "y"}), y), 1e-8);
}

TEST(SimulateApp, PolynomialModelFilesRunThroughTheirStateSpace) {
  TempDir dir;
  // y[t] = 0.5 y[t-1] + u[t-1]: ARX with A = 1 - 0.5 q^-1, B = q^-1.
  StateSpace ss(Eigen::MatrixXd::Constant(1, 1, 0.5), Eigen::MatrixXd::Ones(1, 1), Eigen::MatrixXd::Ones(1, 1),
                Eigen::MatrixXd::Zero(1, 1), 0.001);
  ss.input_names = {"u"};
  ss.output_names = {"y"};
  ModelFile f;
  f.type = "polynomial";
  f.model = ss;
  f.extra = {{"A", {1.0, -0.5}}, {"B", {0.0, 1.0}}, {"nk", 1}};
  write_model_json(dir / "arx.json", f);
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(6, 1);
  u(0, 0) = 1.0;  // impulse
  write_log(dir / "log.csv", {"u"}, u);
  const CliResult r = run_cli({"simulate", dir / "arx.json", dir / "log.csv", "--out", dir / "sim.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  Eigen::VectorXd expected(6);
  expected << 0, 1, 0.5, 0.25, 0.125, 0.0625;  // impulse response 0.5^(t-1)
  EXPECT_EQ(csv_column(dir / "sim.csv", "y"), expected);
}

TEST(SimulateApp, SampleTimeMismatchIsAnError) {
  TempDir dir;
  write_model(dir / "m.json", four_mode_plant());  // Ts = 0.001
  write_log(dir / "log.csv", {"u"}, white_noise(100, 1, 1, 1.0), /*with_time=*/false);
  const CliResult r = run_cli({"simulate", dir / "m.json", dir / "log.csv", "--ts", "0.002", "--out", dir / "sim.csv"});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_NE(r.err.find("sample time"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "sim.csv"));
}

TEST(SimulateApp, ContinuousModelsAreDiscretisedAtTheLogRate) {
  TempDir dir;
  // dx/dt = -10 x + 10 u, y = x: step response 1 - exp(-10 t) at the samples (exact ZOH).
  StateSpace c(Eigen::MatrixXd::Constant(1, 1, -10.0), Eigen::MatrixXd::Constant(1, 1, 10.0), Eigen::MatrixXd::Ones(1, 1),
               Eigen::MatrixXd::Zero(1, 1), 0.0);
  c.input_names = {"u"};
  c.output_names = {"y"};
  write_model(dir / "c.json", c);
  write_log(dir / "log.csv", {"u"}, Eigen::MatrixXd::Ones(200, 1));
  const CliResult r = run_cli({"simulate", dir / "c.json", dir / "log.csv", "--out", dir / "sim.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const Eigen::VectorXd y = csv_column(dir / "sim.csv", "y");
  for (Eigen::Index k = 0; k < y.size(); ++k) EXPECT_NEAR(y(k), 1.0 - std::exp(-10.0 * 0.001 * static_cast<double>(k)), 1e-12);
}

TEST(SimulateApp, HelpHasAnExample) {
  const CliResult r = run_cli({"simulate", "--help"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.out.find("Example"), std::string::npos);
  EXPECT_NE(r.out.find("sysid simulate model.json log.csv"), std::string::npos) << r.out;
}

}  // namespace test_app_simulate
