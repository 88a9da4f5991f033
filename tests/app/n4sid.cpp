// End-to-end: sysid n4sid on logs made with sysid excite + sysid simulate from a
// known 4th-order plant (modes 50 Hz / zeta 0.02 and 120 Hz / zeta 0.05, 1 kHz),
// with 1 % output noise added here.
#include <sysid/core/modal_table.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/model_json.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <regex>

#include "run_cli.hpp"

namespace test_app_n4sid {

using namespace sysid;
using namespace sysid::test;

namespace {

/// Input made by `sysid excite` (broadband multisine), output by `sysid simulate`,
/// then white noise of `noise` times the output RMS added to y; written as t,u,y.
void make_log(const TempDir& dir, const std::string& stem, int seed, double noise, int samples = 4000) {
  const std::string u_csv = dir / (stem + "_u.csv"), y_csv = dir / (stem + "_y.csv");
  CliResult r = run_cli({"excite", "--signal", "multisine", "--fs", "1000", "--band", "0:499", "--samples",
                         std::to_string(samples), "--seed", std::to_string(seed), "--out", u_csv});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  r = run_cli({"simulate", dir / "plant.json", u_csv, "--out", y_csv});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const Eigen::VectorXd t = csv_column(u_csv, "t"), u = csv_column(u_csv, "u");
  Eigen::VectorXd y = csv_column(y_csv, "y");
  const double rms = std::sqrt(y.squaredNorm() / static_cast<double>(y.size()));
  y += white_noise(y.size(), 1, static_cast<std::uint64_t>(1000 + seed), noise * rms).col(0);
  Eigen::MatrixXd table(t.size(), 3);
  table << t, u, y;
  write_csv(dir / (stem + ".csv"), {"t", "u", "y"}, table);
}

int printed_order(const std::string& out) {
  std::smatch m;
  static const std::regex re(R"((?:^|\n)order: (\d+) \()");
  return std::regex_search(out, m, re) ? std::stoi(m[1]) : -1;
}

}  // namespace

/// A fixture has the linkage of the TEST_F classes derived from it: it stays out of
/// the anonymous namespace (-Wsubobject-linkage in a unity translation unit).
class N4sidApp : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    s_dir = std::make_unique<TempDir>();
    write_model(*s_dir / "plant.json", four_mode_plant());
    make_log(*s_dir, "log", 1, 0.01);
    make_log(*s_dir, "fresh", 2, 0.01);
  }
  static void TearDownTestSuite() { s_dir.reset(); }
  static std::string path(const std::string& f) { return *s_dir / f; }

  /// Simulation fit of a model file on the fresh log, via sysid compare.
  static double fresh_fit(const std::string& model) {
    const CliResult r = run_cli({"compare", model, path("fresh.csv"), "--inputs", "u", "--outputs", "y"});
    EXPECT_EQ(r.exit_code, 0) << describe(r);
    return fit_after(r.out, "fit [%]", "y");
  }

  static inline std::unique_ptr<TempDir> s_dir;
};

TEST_F(N4sidApp, AutoOrderPicksFourAndFitsFreshData) {
  // The singular values drop by ~1000x after the 4th (1 % noise): the gap rule
  // must see it. (The default rule is the library's; see DefaultRuleFindsTheModes.)
  const std::string model = path("auto.json");
  const CliResult r = run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--order", "auto",
                               "--order-rule", "gap", "--out", model});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(printed_order(r.out), 4) << r.out;
  // The rule that chose it is named: "order: 4 (<rule>)".
  EXPECT_NE(r.out.find("\norder: 4 (largest singular-value gap"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("leading singular values (10 of"), std::string::npos) << r.out;  // 2 * order + 2
  EXPECT_NE(r.out.find("excited band:"), std::string::npos);
  EXPECT_NE(r.out.find("freq [Hz]"), std::string::npos);  // modal table
  EXPECT_GT(fit_after(r.out, "fit on estimation data", "y"), 95.0) << r.out;
  ASSERT_TRUE(std::filesystem::exists(model));

  // The model is good on data it never saw (1 % noise: the best possible fit is ~99).
  EXPECT_GT(fresh_fit(model), 95.0);

  // Basis-invariant check of the identified physics: the two modes.
  const ModelFile f = read_model_json(model);
  const std::vector<Mode> modes = modal_table(f.model);
  ASSERT_EQ(modes.size(), 2u);
  EXPECT_NEAR(modes[0].freq_hz, 50.0, 0.5);
  EXPECT_NEAR(modes[0].damping, 0.02, 0.004);
  EXPECT_NEAR(modes[1].freq_hz, 120.0, 1.0);
  EXPECT_NEAR(modes[1].damping, 0.05, 0.01);

  // Model file contents: innovation model with offsets, names and provenance.
  EXPECT_EQ(f.K.rows(), 4);
  EXPECT_EQ(f.noise_covariance.rows(), 1);
  EXPECT_EQ(f.x0.size(), 4);
  EXPECT_EQ(f.input_offset.size(), 1);
  EXPECT_EQ(f.output_offset.size(), 1);
  EXPECT_EQ(f.model.input_names, std::vector<std::string>{"u"});
  EXPECT_EQ(f.model.output_names, std::vector<std::string>{"y"});
  const nlohmann::json& p = f.provenance;
  EXPECT_EQ(p.at("method"), "n4sid");
  EXPECT_EQ(p.at("order"), 4);
  EXPECT_TRUE(p.at("order_rule").is_string());
  EXPECT_GE(p.at("horizon").get<int>(), 2);
  EXPECT_EQ(p.at("data"), path("log.csv"));
  ASSERT_TRUE(p.at("fit_percent").is_array());
  EXPECT_GT(p.at("fit_percent")[0].get<double>(), 95.0);
  EXPECT_GT(p.at("singular_values").size(), 8u);
  ASSERT_EQ(p.at("excited_band_hz").size(), 2u);
  EXPECT_GT(p.at("excited_band_hz")[1].get<double>(), 400.0);
  EXPECT_TRUE(p.at("hankel_route").is_string());
  EXPECT_TRUE(p.at("sysid_version").is_string());
  EXPECT_FALSE(p.contains("validation"));  // no validation data given
}

TEST_F(N4sidApp, EveryHankelRouteGivesTheModelAndIsRecorded) {
  // --hankel forces one compression route (hankel/block_hankel.hpp); on this
  // broadband log all three are accurate, and the model file says which ran.
  for (const std::string route : {"qr", "cholesky", "cholesky_double_double"}) {
    const std::string model = path("route_" + route + ".json");
    const CliResult r = run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--order", "4",
                                 "--hankel", route, "--out", model});
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    EXPECT_EQ(read_model_json(model).provenance.at("hankel_route"), route);
    EXPECT_GT(fresh_fit(model), 95.0) << route;
  }
}

TEST_F(N4sidApp, DefaultRuleFindsTheModes) {
  // Whatever the library's default order rule, the automatic order must contain
  // the two true modes and predict fresh data.
  const std::string model = path("default.json");
  const CliResult r = run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--out", model});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const int order = printed_order(r.out);
  EXPECT_GE(order, 4) << r.out;
  EXPECT_LE(order, 6) << r.out;
  const std::vector<Mode> modes = modal_table(read_model_json(model).model);
  auto has_mode = [&](double f, double zeta) {
    for (const Mode& m : modes)
      if (std::abs(m.freq_hz - f) < 0.01 * f && std::abs(m.damping - zeta) < 0.2 * zeta) return true;
    return false;
  };
  EXPECT_TRUE(has_mode(50.0, 0.02)) << r.out;
  EXPECT_TRUE(has_mode(120.0, 0.05)) << r.out;
  EXPECT_GT(fresh_fit(model), 95.0);
}

TEST_F(N4sidApp, CorrelationTestRuleIsSelectableAndNamed) {
  // --order-rule test: the canonical correlations above the noise level; the
  // report names the rule and the correlations on either side of the order.
  const std::string model = path("test_rule.json");
  const CliResult r = run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--order-rule", "test",
                               "--max-order", "0", "--out", model});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(printed_order(r.out), 4) << r.out;
  EXPECT_NE(r.out.find("(canonical-correlation test (largest root, level 0.001): r_4 = "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("r_5 = "), std::string::npos) << r.out;
  const CliResult bad = run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--order-rule", "aic"});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--order-rule"), std::string::npos) << describe(bad);
}

TEST_F(N4sidApp, SplitValidatesOnTheHeldOutSamples) {
  const std::string model = path("split.json");
  const CliResult r = run_cli(
      {"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--split", "0.7", "--order-rule", "gap", "--out", model});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(printed_order(r.out), 4) << r.out;
  const double val = fit_after(r.out, "fit on validation data", "y");
  EXPECT_GT(val, 95.0) << r.out;
  EXPECT_NE(r.out.find("last 30% of samples"), std::string::npos) << r.out;
  const ModelFile f = read_model_json(model);
  EXPECT_EQ(f.provenance.at("validation"), "last 30% of samples");
  EXPECT_NEAR(f.provenance.at("validation_fit_percent")[0].get<double>(), val, 0.006);  // printed with 2 decimals
  EXPECT_GT(fresh_fit(model), 95.0);
}

TEST_F(N4sidApp, ValidateFileReportsTheFitOnThatFile) {
  const std::string model = path("validate.json");
  const CliResult r = run_cli(
      {"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--validate", path("fresh.csv"), "--out", model});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const double val = fit_after(r.out, "fit on validation data", "y");
  EXPECT_GT(val, 95.0) << r.out;
  const ModelFile f = read_model_json(model);
  EXPECT_EQ(f.provenance.at("validation"), path("fresh.csv"));
  // The validation fit is what sysid compare reports on the same file.
  EXPECT_NEAR(val, fresh_fit(model), 0.011);
}

TEST_F(N4sidApp, OrderRangePrintsTheTableAndWritesTheBest) {
  const std::string model = path("sweep.json");
  const CliResult r = run_cli(
      {"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--order", "2:6", "--split", "0.7", "--out", model});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  // Rows "order  est y  val y".
  std::map<int, std::pair<double, double>> rows;
  static const std::regex row_re(R"(\n\s+(\d+)\s+(-?[\d.]+)\s+(-?[\d.]+)(?=\n))");
  for (auto it = std::sregex_iterator(r.out.begin(), r.out.end(), row_re); it != std::sregex_iterator(); ++it)
    rows[std::stoi((*it)[1])] = {std::stod((*it)[2]), std::stod((*it)[3])};
  ASSERT_EQ(rows.size(), 5u) << r.out;
  for (int n = 2; n <= 6; ++n) EXPECT_TRUE(rows.count(n)) << n;
  // Order 2 misses a mode; 4 is right; more states than 4 buy nothing but noise.
  EXPECT_GT(rows[4].second, rows[2].second + 10.0) << r.out;
  EXPECT_NEAR(rows[6].second, rows[4].second, 1.5) << r.out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex(R"(best mean validation fit: order (\d+))"))) << r.out;
  const int best = std::stoi(m[1]);
  EXPECT_GE(best, 4);
  for (const auto& [n, fits] : rows) EXPECT_LE(fits.second, rows[best].second) << n;
  const ModelFile f = read_model_json(model);
  EXPECT_EQ(f.model.order(), best);
  EXPECT_EQ(f.provenance.at("order"), best);
  EXPECT_EQ(f.provenance.at("order_sweep").size(), 5u);
  EXPECT_GT(fresh_fit(model), 95.0);
}

TEST_F(N4sidApp, MoespAndCvaWeightingsWork) {
  for (const std::string method : {"moesp", "cva"}) {
    const std::string model = path(method + ".json");
    const CliResult r =
        run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--method", method, "--order", "4", "--out", model});
    ASSERT_EQ(r.exit_code, 0) << describe(r);
    EXPECT_NE(r.out.find(method + ": order 4"), std::string::npos) << r.out;  // brief report names the weighting
    EXPECT_EQ(read_model_json(model).provenance.at("method"), method);
    EXPECT_GT(fresh_fit(model), 95.0) << method;
  }
}

TEST_F(N4sidApp, HelpHasAnExample) {
  const CliResult r = run_cli({"n4sid", "--help"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.out.find("Example"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("sysid n4sid log.csv --inputs"), std::string::npos) << r.out;
  for (const char* option : {"--inputs", "--outputs", "--ts", "--nan-policy", "--method", "--order", "--max-order",
                             "--order-rule", "--horizon", "--enforce-stability", "--hankel", "--validate", "--split", "--band-limit",
                             "--stabilization", "--noise-shape-level", "--min-level-ratio", "--out"})
    EXPECT_NE(r.out.find(option), std::string::npos) << option;
}

TEST_F(N4sidApp, StabilizationDiagramChoosesTheOrderAndWritesItsPoles) {
  // The two modes (50 and 120 Hz) stand as columns over orders 2..24; the lowest
  // order that holds both is 4, and the CSV lists every plotted pole with its marks.
  const std::string model = path("stab.json"), table = path("stab.csv");
  const CliResult r = run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--order", "2:24",
                               "--stabilization", table, "--out", model});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.out.find("stabilization diagram, orders 2..24"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("physical modes (columns of stable poles)"), std::string::npos) << r.out;
  EXPECT_EQ(printed_order(r.out), 4) << r.out;
  const ModelFile f = read_model_json(model);
  const std::vector<Mode> modes = modal_table(f.model);
  ASSERT_EQ(modes.size(), 2u);
  EXPECT_NEAR(modes[0].freq_hz, 50.0, 0.5);
  EXPECT_NEAR(modes[1].freq_hz, 120.0, 1.0);
  const CsvTable t = read_csv(table);
  for (const char* c : {"order", "freq_hz", "damping", "stable_frequency", "stable_damping", "stable_shape", "mode", "level"})
    EXPECT_NO_THROW(t.column(c)) << c;
  int in_modes = 0;
  double weakest_mode_level = std::numeric_limits<double>::infinity(), strongest_other_level = 0;
  for (Eigen::Index k = 0; k < t.values.rows(); ++k) {
    EXPECT_GE(t.values(k, t.column("order")), 2);
    EXPECT_LE(t.values(k, t.column("order")), 24);
    const bool in_mode = t.values(k, t.column("mode")) > 0;
    in_modes += in_mode;
    // Each pole's level (the compression's singular values weighted by its
    // eigenvector): the two modes' poles stand above the noise poles that wander.
    const double level = t.values(k, t.column("level"));
    ASSERT_TRUE(std::isfinite(level) && level > 0) << "row " << k;
    if (t.values(k, t.column("order")) < 8) continue;  // above the true order 4 with room to spare
    if (in_mode) weakest_mode_level = std::min(weakest_mode_level, level);
    else strongest_other_level = std::max(strongest_other_level, level);
  }
  EXPECT_GE(in_modes, 2 * 10);  // both columns stable over most orders
  EXPECT_GT(weakest_mode_level, strongest_other_level);

  // The diagram shows a range of orders: a single order is a usage error, nothing written.
  const std::string bad = path("stab_bad.csv");
  const CliResult single = run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--order", "4",
                                    "--stabilization", bad});
  EXPECT_EQ(single.exit_code, 1) << describe(single);
  EXPECT_NE(single.err.find("--order LO:HI"), std::string::npos) << single.err;
  EXPECT_FALSE(std::filesystem::exists(bad));

  // The shape test's level belongs to the diagram: alone it is a usage error;
  // outside 0..0.5 it is refused.
  const CliResult alone = run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--noise-shape-level", "0"});
  EXPECT_EQ(alone.exit_code, 1) << describe(alone);
  EXPECT_NE(alone.err.find("--noise-shape-level requires --stabilization"), std::string::npos) << alone.err;
  const CliResult wild = run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--order", "2:24",
                                  "--stabilization", bad, "--noise-shape-level", "2"});
  EXPECT_EQ(wild.exit_code, 1) << describe(wild);
  EXPECT_FALSE(std::filesystem::exists(bad));
  const CliResult level_alone = run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--min-level-ratio", "0"});
  EXPECT_EQ(level_alone.exit_code, 1) << describe(level_alone);
  EXPECT_NE(level_alone.err.find("--min-level-ratio requires --stabilization"), std::string::npos) << level_alone.err;
  const CliResult negative = run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--order", "2:24",
                                      "--stabilization", bad, "--min-level-ratio", "-1"});
  EXPECT_EQ(negative.exit_code, 1) << describe(negative);
  EXPECT_FALSE(std::filesystem::exists(bad));
}

TEST_F(N4sidApp, StabilizationDiagramNamesTheNoiseColumnOfThe8x8Log) {
  // data/avi8x8.csv over orders 2..40: a column at 444 Hz from order 27 stands at
  // the wandering poles' level; the report names it and the model keeps order 16
  // (tests/acceptance/subspace_avi8x8.cpp has the numbers).
  const std::string log = std::string(SYSID_TEST_DATA_DIR) + "/avi8x8.csv", table = path("avi_stab.csv");
  const CliResult r = run_cli({"n4sid", log, "--inputs", "u1,u2,u3,u4,u5,u6,u7,u8", "--outputs", "y1,y2,y3,y4,y5,y6,y7,y8",
                               "--order", "2:40", "--stabilization", table});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.out.find("not modes: columns of noise"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("x the wandering poles' (< 3)"), std::string::npos) << r.out;
  EXPECT_EQ(printed_order(r.out), 16) << r.out;
  const CsvTable t = read_csv(table);
  double modes = 0.0;
  for (Eigen::Index k = 0; k < t.values.rows(); ++k) modes = std::max(modes, t.values(k, t.column("mode")));
  EXPECT_EQ(modes, 8.0);  // the noise column's poles carry no mode number

  // With the level test off, the column counts as a ninth mode and the order follows it.
  const CliResult all = run_cli({"n4sid", log, "--inputs", "u1,u2,u3,u4,u5,u6,u7,u8", "--outputs", "y1,y2,y3,y4,y5,y6,y7,y8",
                                 "--order", "2:40", "--stabilization", path("avi_stab_all.csv"), "--min-level-ratio", "0"});
  ASSERT_EQ(all.exit_code, 0) << describe(all);
  EXPECT_EQ(all.out.find("not modes"), std::string::npos) << all.out;
  EXPECT_GT(printed_order(all.out), 16) << all.out;
}

TEST_F(N4sidApp, SplitAndValidateTogetherAreAUsageError) {
  const std::string model = path("both.json");
  const CliResult r = run_cli({"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--split", "0.5", "--validate",
                               path("fresh.csv"), "--out", model});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_FALSE(std::filesystem::exists(model));
}

TEST_F(N4sidApp, BandLimitIsPassedToTheLibraryAndRecorded) {
  const std::string model = path("band.json");
  const CliResult r = run_cli(
      {"n4sid", path("log.csv"), "--inputs", "u", "--outputs", "y", "--order", "4", "--band-limit", "400", "--out", model});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.out.find("band limit: 400 Hz"), std::string::npos) << r.out;
  const ModelFile f = read_model_json(model);
  EXPECT_EQ(f.provenance.at("band_limit_hz").get<double>(), 400.0);
  EXPECT_GT(f.model.order(), 4);  // the low-pass is in series with the identified 4th-order model
}

}  // namespace test_app_n4sid
