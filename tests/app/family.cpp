// End-to-end: sysid family on five small logs written here (a two-mode plant whose
// modes move with a payload, white-noise input, tiny output noise) with their
// manifest (a numeric 'payload_kg' and a label 'side' column, rows not sorted):
// the family file's contract (DESIGN.md "Model families over operating
// conditions"), another method, the export to MATLAB, and the usage and data errors.
#include <sysid/core/simulate.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/mat_file.hpp>
#include <sysid/io/model_json.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "run_cli.hpp"

namespace test_app_family {

using namespace sysid;
using namespace sysid::test;

namespace {

constexpr double kTs = 1e-3;

/// The members in manifest order: payload (kg) and side.
struct Row {
  double payload;
  const char* side;
};
const std::vector<Row> kRows = {{1.0, "left"}, {0.0, "right"}, {2.0, "left"}, {0.5, "right"}, {1.5, "left"}};

double f1(double p) { return 40.0 / std::sqrt(1.0 + 0.3 * p); }
double f2(double p) { return 110.0 / std::sqrt(1.0 + 0.1 * p); }

StateSpace plant(double p) { return modal_siso({{f1(p), 0.02, 1.0}, {f2(p), 0.04, 3.0}}, kTs); }

std::string log_name(std::size_t k) { return "runs/member" + std::to_string(k) + ".csv"; }

/// t,u,y: white-noise input, the plant's output plus white noise of 1e-4 of its RMS.
void write_log(const std::string& path, const StateSpace& sys, std::uint64_t seed, Eigen::Index samples = 3000) {
  const Eigen::MatrixXd u = white_noise(samples, 1, seed);
  Eigen::MatrixXd y = simulate(sys, u);
  const double rms = std::sqrt(y.squaredNorm() / static_cast<double>(samples));
  y += white_noise(samples, 1, seed + 1000, 1e-4 * rms);
  Eigen::MatrixXd table(samples, 3);
  table.col(0) = Eigen::VectorXd::LinSpaced(samples, 0.0, kTs * static_cast<double>(samples - 1));
  table.col(1) = u;
  table.col(2) = y;
  write_csv(path, {"t", "u", "y"}, table);
}

}  // namespace

/// A fixture has the linkage of the TEST_F classes derived from it: it stays out of
/// the anonymous namespace (-Wsubobject-linkage in a unity translation unit).
class FamilyApp : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    s_dir = std::make_unique<TempDir>();
    std::filesystem::create_directories(s_dir->path() / "runs");
    std::string manifest = "# the arm at five payloads\npayload_kg,side,log\n";
    for (std::size_t k = 0; k < kRows.size(); ++k) {
      write_log(*s_dir / log_name(k), plant(kRows[k].payload), 10 + k);
      manifest += format_payload(kRows[k].payload) + "," + kRows[k].side + "," + log_name(k) + "\n";
    }
    write_text_file(*s_dir / "manifest.csv", manifest);
    s_run = std::make_unique<CliResult>(run_cli({"family", *s_dir / "manifest.csv", "--inputs", "u", "--outputs", "y",
                                                 "--method", "n4sid", "--order", "4", "--out", *s_dir / "family.json"}));
  }
  static void TearDownTestSuite() {
    s_run.reset();
    s_dir.reset();
  }
  static std::string path(const std::string& f) { return *s_dir / f; }
  static std::string format_payload(double p) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f", p);
    return buf;
  }

  static inline std::unique_ptr<TempDir> s_dir;
  static inline std::unique_ptr<CliResult> s_run;
};

TEST_F(FamilyApp, WritesTheFamilyFileOfTheContract) {
  ASSERT_EQ(s_run->exit_code, 0) << describe(*s_run);
  EXPECT_TRUE(contains(s_run->out, "nominal: member")) << s_run->out;
  const nlohmann::json j = read_json(path("family.json"));
  EXPECT_EQ(j["type"], "family");
  EXPECT_EQ(j["Ts"].get<double>(), kTs);
  EXPECT_EQ(j["inputs"], nlohmann::json({"u"}));
  EXPECT_EQ(j["outputs"], nlohmann::json({"y"}));
  EXPECT_EQ(j["conditions"], nlohmann::json({"payload_kg", "side"}));

  // Members in the manifest's order, numbers as numbers and labels as strings.
  ASSERT_TRUE(j["members"].is_array());
  ASSERT_EQ(j["members"].size(), kRows.size());
  for (std::size_t k = 0; k < kRows.size(); ++k) {
    const nlohmann::json& m = j["members"][k];
    ASSERT_TRUE(m["conditions"]["payload_kg"].is_number()) << m["conditions"];
    EXPECT_EQ(m["conditions"]["payload_kg"].get<double>(), kRows[k].payload) << k;
    ASSERT_TRUE(m["conditions"]["side"].is_string()) << m["conditions"];
    EXPECT_EQ(m["conditions"]["side"], kRows[k].side) << k;
    EXPECT_EQ(m["log"], log_name(k)) << "the log as the manifest names it";
    EXPECT_EQ(m["model"]["type"], "state-space");
    EXPECT_EQ(m["model"]["Ts"].get<double>(), kTs);
    ASSERT_EQ(m["fit_percent"].size(), 1u);
    EXPECT_GT(m["fit_percent"][0].get<double>(), 99.0) << k;
    // The member's model is a model file's object.
    const ModelFile file = model_from_json_value(m["model"], "member");
    EXPECT_EQ(file.model.order(), 4);
  }

  // Two modes, each followed through every member at its true frequency.
  ASSERT_EQ(j["modes"].size(), 2u) << j["modes"];
  for (std::size_t k = 0; k < kRows.size(); ++k) {
    EXPECT_NEAR(j["modes"][0]["freq_hz"][k].get<double>(), f1(kRows[k].payload), 0.01 * f1(kRows[k].payload)) << k;
    EXPECT_NEAR(j["modes"][1]["freq_hz"][k].get<double>(), f2(kRows[k].payload), 0.01 * f2(kRows[k].payload)) << k;
    EXPECT_NEAR(j["modes"][0]["damping"][k].get<double>(), 0.02, 0.005) << k;
  }

  // The nominal is a member, its model that member's exactly.
  const nlohmann::json& nominal = j["nominal"];
  ASSERT_TRUE(nominal["member"].is_number_integer()) << nominal["member"];
  const int member = nominal["member"].get<int>();
  ASSERT_GE(member, 0);
  ASSERT_LT(member, static_cast<int>(kRows.size()));
  EXPECT_TRUE(nominal["criterion"].is_string());
  EXPECT_FALSE(nominal["criterion"].get<std::string>().empty());
  EXPECT_EQ(nominal["model"], j["members"][static_cast<std::size_t>(member)]["model"]);

  // The uncertainty: the default form, the band, >= 200 frequencies and a weight.
  const nlohmann::json& u = j["uncertainty"];
  EXPECT_EQ(u["form"], "multiplicative-output");
  ASSERT_EQ(u["band_hz"].size(), 2u);
  EXPECT_LT(u["band_hz"][0].get<double>(), 5.0) << "white input: the band starts near 0";
  EXPECT_GT(u["band_hz"][1].get<double>(), 400.0) << "and ends near Nyquist";
  ASSERT_GE(u["frequency_hz"].size(), 200u);
  ASSERT_EQ(u["bound"].size(), u["frequency_hz"].size());
  double previous = 0.0;
  for (std::size_t k = 0; k < u["frequency_hz"].size(); ++k) {
    const double f = u["frequency_hz"][k].get<double>();
    EXPECT_GT(f, previous) << k;
    EXPECT_GE(f, u["band_hz"][0].get<double>());
    EXPECT_LE(f, u["band_hz"][1].get<double>());
    EXPECT_GE(u["bound"][k].get<double>(), 0.0) << k;
    previous = f;
  }
  ASSERT_TRUE(u["weight"].is_object());
  EXPECT_EQ(u["weight"]["type"], "state-space");
  EXPECT_EQ(u["weight"]["Ts"].get<double>(), kTs);
  const ModelFile weight = model_from_json_value(u["weight"], "weight");
  EXPECT_EQ(weight.model.inputs(), 1);
  EXPECT_EQ(weight.model.outputs(), 1);
  EXPECT_EQ(weight.model.order(), 4) << "the default --weight-order";
}

TEST_F(FamilyApp, ExportWritesTheMembersAsAModelArray) {
  ASSERT_EQ(s_run->exit_code, 0) << describe(*s_run);
  const CliResult r = run_cli({"export", path("family.json"), "--mat", path("family.mat")});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::vector<MatVariable> v = read_mat_file(path("family.mat"));
  auto find = [&v](const std::string& name) -> const MatVariable* {
    for (const MatVariable& m : v)
      if (m.name == name) return &m;
    return nullptr;
  };
  const MatVariable* a = find("A_members");
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a->dims, (std::vector<std::size_t>{4, 4, kRows.size()}));
  ASSERT_NE(find("D_members"), nullptr);
  EXPECT_EQ(find("D_members")->dims, (std::vector<std::size_t>{1, 1, kRows.size()}));
  ASSERT_NE(find("A_weight"), nullptr);
  ASSERT_NE(find("bound"), nullptr);
  EXPECT_GE(find("bound")->values.rows(), 200);
  ASSERT_NE(find("conditions"), nullptr);
  EXPECT_EQ(find("conditions")->cell_rows, kRows.size());
  EXPECT_EQ(find("conditions")->cell_cols, 2u);
  // The nominal's A is the member's page.
  const nlohmann::json j = read_json(path("family.json"));
  const int member = j["nominal"]["member"].get<int>();
  const Eigen::MatrixXd page = a->values.middleCols(4 * member, 4);
  EXPECT_EQ(find("A")->values, page);
}

TEST_F(FamilyApp, ArxIsAMethodToo) {
  const CliResult r = run_cli({"family", path("manifest.csv"), "--inputs", "u", "--outputs", "y", "--method", "arx", "--na",
                               "4", "--nb", "4", "--weight-order", "2", "--uncertainty", "additive", "--band", "10:200",
                               "--out", path("arx_family.json")});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const nlohmann::json j = read_json(path("arx_family.json"));
  ASSERT_EQ(j["members"].size(), kRows.size());
  EXPECT_EQ(j["members"][0]["model"]["type"], "polynomial");
  EXPECT_EQ(j["uncertainty"]["form"], "additive");
  EXPECT_EQ(j["uncertainty"]["band_hz"], nlohmann::json({10.0, 200.0}));
  EXPECT_EQ(j["uncertainty"]["frequency_hz"][0].get<double>(), 10.0);
  EXPECT_EQ(j["uncertainty"]["frequency_hz"].back().get<double>(), 200.0);
  ASSERT_EQ(j["modes"].size(), 2u) << j["modes"];
  for (std::size_t k = 0; k < kRows.size(); ++k)
    EXPECT_NEAR(j["modes"][1]["freq_hz"][k].get<double>(), f2(kRows[k].payload), 0.02 * f2(kRows[k].payload)) << k;
  EXPECT_EQ(model_from_json_value(j["uncertainty"]["weight"], "weight").model.order(), 2);
}

TEST_F(FamilyApp, AValidateColumnGivesTheFitOnTheValidationLog) {
  // Fresh logs of the same plants as validation, except member 1 whose
  // 'validation' log is another member's plant: its fit must show it.
  std::string manifest = "payload_kg,log,validate\n";
  for (std::size_t k = 0; k < 3; ++k) {
    const std::string fresh = "runs/fresh" + std::to_string(k) + ".csv";
    write_log(path(fresh), plant(kRows[k == 1 ? 2 : k].payload), 50 + k);
    manifest += format_payload(kRows[k].payload) + "," + log_name(k) + "," + fresh + "\n";
  }
  write_text_file(path("validated.csv"), manifest);
  const CliResult r = run_cli({"family", path("validated.csv"), "--inputs", "u", "--outputs", "y", "--method", "n4sid",
                               "--order", "4", "--out", path("validated.json")});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.out, "on each validate log")) << r.out;
  const nlohmann::json j = read_json(path("validated.json"));
  ASSERT_EQ(j["members"].size(), 3u);
  EXPECT_EQ(j["members"][0]["validate"], "runs/fresh0.csv");
  EXPECT_GT(j["members"][0]["fit_percent"][0].get<double>(), 99.0);
  EXPECT_GT(j["members"][2]["fit_percent"][0].get<double>(), 99.0);
  EXPECT_LT(j["members"][1]["fit_percent"][0].get<double>(), 90.0) << "fit on another plant's log";
}

TEST_F(FamilyApp, UsageErrorsExitOne) {
  const std::vector<std::string> base = {"family", path("manifest.csv"), "--inputs", "u", "--outputs", "y"};
  auto run = [&base](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return run_cli(args);
  };
  // Not an identification verb: the message lists the ones that are.
  CliResult r = run({"--method", "frf", "--out", path("x.json")});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "not an identification verb")) << r.err;
  EXPECT_TRUE(contains(r.err, "n4sid")) << r.err;
  // No method.
  r = run({"--order", "4", "--out", path("x.json")});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "--method")) << r.err;
  // --validate belongs in the manifest.
  r = run({"--method", "n4sid", "--order", "4", "--validate", path("runs/member0.csv"), "--out", path("x.json")});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "'validate' column")) << r.err;
  // An option the method does not know.
  r = run({"--method", "n4sid", "--order", "4", "--na", "4", "--out", path("x.json")});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_TRUE(contains(r.err, "--na")) << r.err;
  // A weight order out of 1..6, a form that does not exist.
  r = run({"--method", "n4sid", "--order", "4", "--weight-order", "7", "--out", path("x.json")});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  r = run({"--method", "n4sid", "--order", "4", "--uncertainty", "relative", "--out", path("x.json")});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_FALSE(std::filesystem::exists(path("x.json")));
}

TEST_F(FamilyApp, BadInputExitsTwoNamingTheManifestLine) {
  // A missing log, on line 3 of its manifest.
  write_text_file(path("missing_log.csv"), "payload_kg,log\n0,runs/member0.csv\n1,runs/no_such_log.csv\n");
  CliResult r = run_cli({"family", path("missing_log.csv"), "--inputs", "u", "--outputs", "y", "--method", "n4sid",
                         "--order", "4", "--out", path("missing.json")});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_TRUE(contains(r.err, "missing_log.csv line 3")) << r.err;
  EXPECT_TRUE(contains(r.err, "no_such_log.csv")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("missing.json")));
  // No 'log' column: the header's line and column.
  write_text_file(path("no_log_column.csv"), "payload_kg,file\n0,runs/member0.csv\n");
  r = run_cli({"family", path("no_log_column.csv"), "--inputs", "u", "--outputs", "y", "--method", "n4sid", "--order",
               "4", "--out", path("nolog.json")});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_TRUE(contains(r.err, "no_log_column.csv:1:1")) << r.err;
  EXPECT_TRUE(contains(r.err, "'log'")) << r.err;
}

TEST_F(FamilyApp, AnExistingOutputIsRefusedBeforeAnyWork) {
  // The manifest names a missing log: had any member been identified, that would
  // be the error. The refusal comes first (exit 2, as every verb's).
  write_text_file(path("taken.json"), "precious\n");
  write_text_file(path("one_missing.csv"), "payload_kg,log\n0,runs/absent.csv\n");
  const CliResult r = run_cli({"family", path("one_missing.csv"), "--inputs", "u", "--outputs", "y", "--method", "n4sid",
                               "--order", "4", "--out", path("taken.json")});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_TRUE(contains(r.err, "already exists")) << r.err;
  EXPECT_TRUE(contains(r.err, "--force")) << r.err;
  EXPECT_FALSE(contains(r.err, "absent.csv")) << r.err;
  EXPECT_EQ(read_text_file(path("taken.json")), "precious\n");
  EXPECT_FALSE(contains(r.out, "family of")) << r.out;
}

}  // namespace test_app_family

namespace test_app_family_time_series {

using namespace sysid::test;

// A time-series method (a disturbance record per member): `--method ar` with ar's
// own --method as the second one; the family compares the noise models and says so.
TEST(FamilyTimeSeries, ArMembersWithTheVerbsOwnMethodOption) {
  TempDir dir;
  const std::string gw = std::string(SYSID_TEST_DATA_DIR) + "/par2_gw.csv";
  write_text_file((dir.path() / "manifest.csv").string(), "log,segment\n" + gw + ",1\n" + gw + ",2\n");
  const std::string out = (dir.path() / "gw_family.json").string();
  const CliResult r = run_cli({"family", (dir.path() / "manifest.csv").string(), "--outputs", "y", "--method", "ar", "--na", "8",
                               "--method", "myw", "--out", out});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "time series: the modes and the bound are those of the noise models")) << r.out;
  EXPECT_TRUE(contains(r.out, "one-step prediction fit")) << r.out;
  const nlohmann::json f = read_json(out);
  EXPECT_EQ(f["members"][0]["model"]["provenance"]["method"], f["members"][1]["model"]["provenance"]["method"]);
  EXPECT_EQ(f["members"][0]["model"]["provenance"]["ar_method"], "myw") << "ar's own --method reached it";
  // Identical members: no spread, so no weight, and a warning says why.
  EXPECT_TRUE(contains(r.err, "do not differ")) << r.err;
}

}  // namespace test_app_family_time_series
