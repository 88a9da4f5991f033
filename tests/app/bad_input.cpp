// End-to-end: bad input data and model files give exit 2 with a message naming
// the problem (file:line:column for CSV problems) and leave no output file;
// usage errors give exit 1.
#include <sysid/core/simulate.hpp>

#include <gtest/gtest.h>

#include <set>

#include "run_cli.hpp"

namespace test_app_bad_input {

using namespace sysid;
using namespace sysid::test;

namespace {

/// Lines of a valid log "t,u,y" (header + rows), from the 4th-order test plant.
std::vector<std::string> valid_log_lines(Eigen::Index rows) {
  const StateSpace plant = four_mode_plant();
  const Eigen::MatrixXd u = white_noise(rows, 1, 5, 1.0);
  const Eigen::MatrixXd y = simulate(plant, u) + white_noise(rows, 1, 6, 0.01);
  Eigen::MatrixXd table(rows, 3);
  table.col(0) = Eigen::VectorXd::LinSpaced(rows, 0.0, static_cast<double>(rows - 1)) * 0.001;
  table.col(1) = u;
  table.col(2) = y;
  const std::string text = format_csv({"t", "u", "y"}, table);
  std::vector<std::string> lines;
  std::istringstream s(text);
  for (std::string line; std::getline(s, line);) lines.push_back(line);
  return lines;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

/// Replaces field `field` (0-based) of data row `row` (0-based: file line row + 2).
void set_cell(std::vector<std::string>& lines, std::size_t row, std::size_t field, const std::string& value) {
  std::string& line = lines[row + 1];
  std::vector<std::string> cells;
  std::istringstream s(line);
  for (std::string c; std::getline(s, c, ',');) cells.push_back(c);
  cells[field] = value;
  line.clear();
  for (std::size_t k = 0; k < cells.size(); ++k) line += (k ? "," : "") + cells[k];
}

std::set<std::string> listing(const std::filesystem::path& dir) {
  std::set<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

}  // namespace

/// A fixture has the linkage of the TEST_F classes derived from it: it stays out of
/// the anonymous namespace (-Wsubobject-linkage in a unity translation unit).
class BadInput : public ::testing::Test {
 protected:
  TempDir dir;

  /// Runs sysid; expects exit 2, every key word in stderr, and no file added to the directory.
  void expect_data_error(const std::vector<std::string>& args, const std::vector<std::string>& key_words) {
    const std::set<std::string> before = listing(dir.path());
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << describe(r);
    EXPECT_NE(r.err.find("error:"), std::string::npos) << r.err;
    for (const auto& k : key_words) EXPECT_NE(r.err.find(k), std::string::npos) << "missing '" << k << "' in: " << r.err;
    EXPECT_EQ(listing(dir.path()), before) << "an output (or temporary) file was left behind";
  }

  std::string write_log(const std::string& name, const std::vector<std::string>& lines) {
    const std::string p = dir / name;
    write_text_file(p, join_lines(lines));
    return p;
  }

  std::vector<std::string> n4sid_args(const std::string& log) {
    return {"n4sid", log, "--inputs", "u", "--outputs", "y", "--out", dir / "model.json"};
  }
};

TEST_F(BadInput, TextCell) {
  auto lines = valid_log_lines(400);
  set_cell(lines, 10, 2, "abc");
  const std::string log = write_log("text.csv", lines);
  expect_data_error(n4sid_args(log), {log + ":12:3", "abc"});
}

TEST_F(BadInput, MissingColumn) {
  const std::string log = write_log("log.csv", valid_log_lines(400));
  expect_data_error({"n4sid", log, "--inputs", "u", "--outputs", "z", "--out", dir / "model.json"},
                    {log + ":1", "no column 'z'", "t, u, y"});
}

TEST_F(BadInput, NanCell) {
  auto lines = valid_log_lines(400);
  set_cell(lines, 20, 1, "nan");
  const std::string log = write_log("nan.csv", lines);
  expect_data_error(n4sid_args(log), {log + ":22:2", "NaN", "'u'"});
  // An empty cell is missing too.
  set_cell(lines, 20, 1, "");
  const std::string log2 = write_log("empty.csv", lines);
  expect_data_error(n4sid_args(log2), {log2 + ":22:2", "NaN or empty"});
}

TEST_F(BadInput, NonUniformTime) {
  auto lines = valid_log_lines(400);
  set_cell(lines, 50, 0, "0.0503");  // should be 0.05
  const std::string log = write_log("time.csv", lines);
  expect_data_error(n4sid_args(log), {log + ":52:1", "non-uniform time stamps"});
}

TEST_F(BadInput, TooFewSamplesForTheHorizon) {
  const std::string log = write_log("short.csv", valid_log_lines(30));
  auto args = n4sid_args(log);
  args.insert(args.end(), {"--horizon", "20", "--order", "4"});
  expect_data_error(args, {"30 samples", "horizon"});
}

TEST_F(BadInput, ConstantInput) {
  auto lines = valid_log_lines(400);
  for (std::size_t r = 0; r < 400; ++r) set_cell(lines, r, 1, "1.5");
  const std::string log = write_log("const.csv", lines);
  expect_data_error(n4sid_args(log), {"input 'u' is constant"});
}

TEST_F(BadInput, UnreadableModelFile) {
  const std::string log = write_log("log.csv", valid_log_lines(100));
  const std::string missing = dir / "missing.json";
  expect_data_error({"simulate", missing, log, "--out", dir / "sim.csv"}, {missing});
  expect_data_error({"compare", missing, log}, {missing});
  expect_data_error({"show", missing}, {missing});

  // Invalid JSON: the message points at the line.
  const std::string broken = dir / "broken.json";
  write_text_file(broken, "{\n  \"Ts\": 0.001,\n  \"A\": [[0.5]\n");
  expect_data_error({"simulate", broken, log, "--out", dir / "sim.csv"}, {broken + ":"});
  expect_data_error({"show", broken}, {broken + ":"});

  // Valid JSON, missing a required matrix.
  const std::string no_d = dir / "no_d.json";
  write_text_file(no_d, R"({"type": "state-space", "Ts": 0.001, "A": [[0.5]], "B": [[1]], "C": [[1]]})");
  expect_data_error({"compare", no_d, log}, {no_d, "D"});
}

// simulate, show and diagnose run augmented models (tests/app/diagnose.cpp); the
// verbs that cannot yet refuse them with exit 2 instead of ignoring the blocks.
TEST_F(BadInput, AugmentedModelsAreRefusedWhereNotSupported) {
  const std::string log = write_log("log.csv", valid_log_lines(100));
  const std::string model = dir / "aug.json";
  ModelFile f;
  f.type = "augmented";
  f.model = four_mode_plant();
  write_model_json(model, f);
  expect_data_error({"resid", model, log, "--out", dir / "resid.csv"}, {"augmented models are not supported yet"});
}

TEST_F(BadInput, OutputThatIsAnInputIsRefused) {
  const std::string log = write_log("log.csv", valid_log_lines(400));
  const std::string before = read_text_file(log);
  const CliResult r = run_cli({"n4sid", log, "--inputs", "u", "--outputs", "y", "--out", log});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_EQ(read_text_file(log), before);
}

TEST_F(BadInput, UsageErrorsExitOne) {
  const std::string log = write_log("log.csv", valid_log_lines(400));
  const std::set<std::string> before = listing(dir.path());
  CliResult r = run_cli({"n4sid", log, "--inputs", "u", "--outputs", "y", "--bogus", "--out", dir / "model.json"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_NE(r.err.find("--bogus"), std::string::npos) << r.err;
  r = run_cli({"n4sid", log, "--inputs", "u", "--outputs", "y", "--method", "pem", "--out", dir / "model.json"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  r = run_cli({"n4sid", log, "--inputs", "u", "--outputs", "y", "--order", "6:2", "--out", dir / "model.json"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  r = run_cli({"n4sid", log, "--outputs", "y", "--out", dir / "model.json"});  // --inputs missing
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_NE(r.err.find("--inputs"), std::string::npos) << r.err;
  r = run_cli({"frobnicate"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_NE(r.err.find("unknown verb 'frobnicate'"), std::string::npos) << r.err;
  // With --help too: a script must be able to tell that the verb does not exist.
  r = run_cli({"frobnicate", "--help"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_NE(r.err.find("unknown verb 'frobnicate'; the verbs are: n4sid,"), std::string::npos) << r.err;
  r = run_cli({"n4sid", "--help"});
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(listing(dir.path()), before);
}

}  // namespace test_app_bad_input
