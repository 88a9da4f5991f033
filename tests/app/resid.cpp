// End-to-end: sysid resid (residual whiteness and independence, Ljung-Box, CSV of correlations).
#include <sysid/core/simulate.hpp>
#include <sysid/validate/residual_analysis.hpp>

#include <gtest/gtest.h>

#include <filesystem>

#include "innovation_log.hpp"
#include "run_cli.hpp"

namespace test_app_resid {

using namespace sysid;
using namespace sysid::test;

namespace {

/// The text after "<label>" up to the end of its line.
std::string line_after(const std::string& text, const std::string& label) {
  const auto p = text.find(label);
  if (p == std::string::npos) return "";
  const auto start = p + label.size();
  return text.substr(start, text.find('\n', start) - start);
}

/// A log and the true model's file in a temporary directory.
struct LogAndTrueModel {
  TempDir dir;
  StateSpace plant = four_mode_plant();
  InnovationLog d;
  LogAndTrueModel() : d(innovation_log(plant, 4000, 0.05, 2.0, 3)) {
    write_model(dir / "true.json", plant, d.K);
    write_siso_log(dir / "log.csv", d.u, d.y);
  }
};

}  // namespace

TEST(ResidApp, TrueModelLeavesWhiteResidualsIndependentOfTheInput) {
  LogAndTrueModel s;
  const CliResult r = run_cli({"resid", s.dir / "true.json", s.dir / "log.csv", "--out", s.dir / "resid.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.out.find("one-step prediction errors"), std::string::npos) << r.out;
  EXPECT_EQ(line_after(r.out, "y:\n  whiteness: ").rfind("white", 0), 0u) << r.out;
  EXPECT_EQ(line_after(r.out, "  input u: ").rfind("independent of input u", 0), 0u) << r.out;
  const double p = number_after(r.out, "), p = ");
  EXPECT_GT(p, 0.01) << r.out;

  // The CSV: one row per lag -25..25, the documented columns, the library's numbers.
  const CsvTable t = read_csv(s.dir / "resid.csv");
  ASSERT_EQ(t.names, (std::vector<std::string>{"lag", "acf_y", "bound", "xcf_y_u", "bound_y_u"}));
  ASSERT_EQ(t.values.rows(), 51);
  EXPECT_EQ(t.values(0, 0), -25.0);
  EXPECT_EQ(t.values(50, 0), 25.0);
  EXPECT_EQ(t.values(25, 1), 1.0);                   // acf at lag 0
  EXPECT_EQ(t.values(24, 1), t.values(26, 1));       // even
  EXPECT_NEAR(t.values(0, 2), 2.5758293035489 / std::sqrt(4000.0), 1e-12);
  const Experiment e{s.d.u, s.d.y, "log"};
  const ResidualAnalysisResult lib = analyze_residuals(model_residuals(s.plant, s.d.K, e), s.d.u);
  for (Eigen::Index k = 0; k < 51; ++k) EXPECT_NEAR(t.values(k, 3), lib.input_correlation(k, 0), 1e-12) << k;
  EXPECT_NEAR(t.values(0, 4), lib.input_correlation_bound(0), 1e-15);
  EXPECT_NEAR(p, lib.ljung_box_p(0), 0.001 + 0.01 * p);  // printed with 3 digits
}

TEST(ResidApp, WrongPolesAreNotWhiteAndCorrelateWithTheInput) {
  LogAndTrueModel s;
  // The same structure with the first mode at 55 Hz instead of 50 Hz: the
  // residual carries (G0 - G) u, a lightly damped response to the white input,
  // so it is both coloured and correlated with u at positive lags.
  const StateSpace wrong = modal_siso({{55.0, 0.02, 1.0}, {120.0, 0.05, 3.0}}, 0.001);
  write_model(s.dir / "wrong.json", wrong, s.d.K);
  const CliResult r = run_cli({"resid", s.dir / "wrong.json", s.dir / "log.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(line_after(r.out, "y:\n  whiteness: ").rfind("not white: autocorrelation outside the 99 % bound at lag", 0),
            0u)
      << r.out;
  EXPECT_LT(number_after(r.out, "), p = "), 1e-6) << r.out;
  EXPECT_EQ(line_after(r.out, "  input u: ").rfind("correlated with input u at lag", 0), 0u) << r.out;
  EXPECT_NE(r.out.find("input dynamics the model misses"), std::string::npos) << r.out;
}

TEST(ResidApp, PolynomialModelsSubtractTheirNoiseParametersFromTheLjungBoxDof) {
  LogAndTrueModel s;
  // ARMAX(4, 4, 2): the noise model C / A has na + nc = 6 estimated parameters.
  const std::string model = s.dir / "armax.json";
  const CliResult fit = run_cli({"armax", s.dir / "log.csv", "--inputs", "u", "--outputs", "y", "--na", "4", "--nb", "4",
                                 "--nc", "2", "--nk", "0", "--out", model});
  ASSERT_EQ(fit.exit_code, 0) << describe(fit);
  const CliResult r = run_cli({"resid", model, s.dir / "log.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.out.find("(25 lags, 19 dof)"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("25 lags - 6 noise-model parameters"), std::string::npos) << r.err;
  // --noise-params overrides the file; a state-space file subtracts nothing.
  const CliResult given = run_cli({"resid", model, s.dir / "log.csv", "--noise-params", "2"});
  EXPECT_NE(given.out.find("(25 lags, 23 dof)"), std::string::npos) << given.out;
  const CliResult state_space = run_cli({"resid", s.dir / "true.json", s.dir / "log.csv"});
  EXPECT_NE(state_space.out.find("(25 lags, 25 dof)"), std::string::npos) << state_space.out;
  // More noise parameters than lags: exit 1 (usage) naming both.
  const CliResult few = run_cli({"resid", model, s.dir / "log.csv", "--max-lag", "5"});
  EXPECT_EQ(few.exit_code, 1) << describe(few);
  EXPECT_NE(few.err.find("6 parameters"), std::string::npos) << few.err;
}

TEST(ResidApp, ModelWithoutKalmanGainUsesTheSimulationErrorAndSaysSo) {
  LogAndTrueModel s;
  write_model(s.dir / "nok.json", s.plant);
  const CliResult r = run_cli({"resid", s.dir / "nok.json", s.dir / "log.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.err.find("no Kalman gain K"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("simulation errors"), std::string::npos) << r.out;
  // The simulation error is K e filtered by the plant plus e: coloured, but still
  // independent of the (white) input, since the plant model itself is right.
  EXPECT_EQ(line_after(r.out, "y:\n  whiteness: ").rfind("not white", 0), 0u) << r.out;
  EXPECT_EQ(line_after(r.out, "  input u: ").rfind("independent of input u", 0), 0u) << r.out;
}

TEST(ResidApp, BadInputsExitTwoAndWriteNothing) {
  LogAndTrueModel s;
  const std::string out = s.dir / "resid.csv";
  write_text_file(s.dir / "garbage.json", "{ \"type\": \"state-space\", \"Ts\": 0.001, ");
  const auto cases = std::vector<std::pair<std::vector<std::string>, std::string>>{
      {{"resid", s.dir / "true.json", s.dir / "log.csv", "--inputs", "w", "--out", out}, "w"},      // missing column
      {{"resid", s.dir / "true.json", s.dir / "log.csv", "--inputs", "u,y", "--out", out}, "1 input(s)"},
      {{"resid", s.dir / "garbage.json", s.dir / "log.csv", "--out", out}, "garbage.json"},
      {{"resid", s.dir / "missing.json", s.dir / "log.csv", "--out", out}, "missing.json"},
      {{"resid", s.dir / "true.json", s.dir / "nolog.csv", "--out", out}, "nolog.csv"},
      {{"resid", s.dir / "true.json", s.dir / "log.csv", "--max-lag", "4000", "--out", out}, "too few samples"},
  };
  for (const auto& [args, expect] : cases) {
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << describe(r);
    EXPECT_NE(r.err.find(expect), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
  // A model with two inputs against a log that has one named like it.
  const StateSpace p = s.plant;
  Eigen::MatrixXd B2(p.order(), 2), D2(1, 2);
  B2 << p.B, p.B;
  D2 << p.D, p.D;
  StateSpace two(p.A, B2, p.C, D2, p.Ts);
  two.input_names = {"u", "u2"};
  two.output_names = {"y"};
  write_model(s.dir / "two.json", two, s.d.K);
  const CliResult r2 = run_cli({"resid", s.dir / "two.json", s.dir / "log.csv", "--out", out});
  EXPECT_EQ(r2.exit_code, 2) << describe(r2);
  EXPECT_NE(r2.err.find("u2"), std::string::npos) << r2.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  // Contradicting options are a usage error (exit 1).
  const CliResult r1 = run_cli({"resid", s.dir / "true.json", s.dir / "log.csv", "--noise-params", "25", "--out", out});
  EXPECT_EQ(r1.exit_code, 1) << describe(r1);
  EXPECT_NE(r1.err.find("--noise-params"), std::string::npos) << r1.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(ResidApp, HelpDocumentsTheColumnsAndHasAnExample) {
  const CliResult r = run_cli({"resid", "--help"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  for (const std::string word : {"Example", "sysid resid model.json", "--max-lag", "acf_<y>", "xcf_<y>_<u>",
                                 "bound_<y>_<u>", "feedback"})
    EXPECT_NE(r.out.find(word), std::string::npos) << word << "\n" << r.out;
  const CliResult top = run_cli({"--help"});
  EXPECT_NE(top.out.find("resid"), std::string::npos) << top.out;
}

}  // namespace test_app_resid
