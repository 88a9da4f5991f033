#include "sysid/io/model_json.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>

#include "sysid/core/errors.hpp"

namespace test_unit_io_model_json {

namespace fs = std::filesystem;
using nlohmann::json;
using sysid::DataError;
using sysid::ModelFile;

namespace {

bool same_bits(double a, double b) {
  std::uint64_t x, y;
  std::memcpy(&x, &a, sizeof x);
  std::memcpy(&y, &b, sizeof y);
  return x == y;
}

::testing::AssertionResult same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols())
    return ::testing::AssertionFailure() << "shape " << a.rows() << "x" << a.cols() << " vs " << b.rows() << "x" << b.cols();
  for (Eigen::Index i = 0; i < a.size(); ++i)
    if (!same_bits(a(i), b(i)))
      return ::testing::AssertionFailure() << "entry " << i << ": " << a(i) << " vs " << b(i);
  return ::testing::AssertionSuccess();
}

/// A random model whose entries span many binades, with subnormals, signed zeros
/// and extreme exponents sprinkled in: every bit of every number must survive.
ModelFile random_model(std::mt19937_64& rng, int n, int m, int l) {
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> expo(-60, 60);
  auto fill = [&](Eigen::Index r, Eigen::Index c) {
    Eigen::MatrixXd x(r, c);
    for (Eigen::Index i = 0; i < x.size(); ++i) x(i) = std::ldexp(normal(rng), expo(rng));
    return x;
  };
  ModelFile f;
  f.model.A = fill(n, n);
  f.model.B = fill(n, m);
  f.model.C = fill(l, n);
  f.model.D = fill(l, m);
  f.model.Ts = 1.0 / 3000.0;
  f.model.A(0, 0) = 4.9406564584124654e-324;  // smallest subnormal
  f.model.A(0, 1) = -0.0;
  f.model.A(1, 0) = 1e-300;
  f.model.A(1, 1) = 1e300;
  f.model.B(0, 0) = std::numeric_limits<double>::max();
  f.model.C(0, 0) = std::numeric_limits<double>::min();
  f.model.D(0, 0) = 2.2250738585072009e-308;  // largest subnormal
  for (int j = 0; j < m; ++j) f.model.input_names.push_back("u" + std::to_string(j + 1));
  for (int i = 0; i < l; ++i) f.model.output_names.push_back("force \"y\" " + std::to_string(i + 1));
  f.K = fill(n, l);
  f.noise_covariance = fill(l, l);
  f.x0 = fill(n, 1);
  f.input_offset = fill(m, 1);
  f.output_offset = fill(l, 1);
  f.provenance = {{"method", "n4sid"}, {"order", n}, {"fit_percent", 93.2}};
  return f;
}

void expect_same(const ModelFile& a, const ModelFile& b) {
  EXPECT_EQ(a.type, b.type);
  EXPECT_TRUE(same_bits(a.model.Ts, b.model.Ts));
  EXPECT_TRUE(same_bits(a.model.A, b.model.A));
  EXPECT_TRUE(same_bits(a.model.B, b.model.B));
  EXPECT_TRUE(same_bits(a.model.C, b.model.C));
  EXPECT_TRUE(same_bits(a.model.D, b.model.D));
  EXPECT_TRUE(same_bits(a.K, b.K));
  EXPECT_TRUE(same_bits(a.noise_covariance, b.noise_covariance));
  EXPECT_TRUE(same_bits(a.x0, b.x0));
  EXPECT_TRUE(same_bits(a.input_offset, b.input_offset));
  EXPECT_TRUE(same_bits(a.output_offset, b.output_offset));
  EXPECT_EQ(a.model.input_names, b.model.input_names);
  EXPECT_EQ(a.model.output_names, b.model.output_names);
  EXPECT_EQ(a.provenance, b.provenance);
  EXPECT_EQ(a.extra, b.extra);
}

/// Expects a DataError for `text` naming "m.json" and containing `what`.
void expect_bad(const std::string& text, const std::string& what, long line = 0, long column = 0) {
  try {
    sysid::model_from_json_string(text, "m.json");
    ADD_FAILURE() << "expected DataError containing '" << what << "' for:\n" << text;
  } catch (const DataError& e) {
    EXPECT_EQ(e.file(), "m.json");
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.column(), column) << e.what();
    EXPECT_NE(e.message().find(what), std::string::npos) << "message: " << e.what() << "\nexpected: " << what;
  }
}

const char* const k_minimal = R"({"type": "state-space", "Ts": 0.001,
  "A": [[0.5, 0.1], [0.0, 0.3]], "B": [[1.0], [0.0]], "C": [[1.0, 0.0]], "D": [[0.0]]})";

/// k_minimal with `key` replaced by `value` (or removed when value is null).
std::string minimal_with(const std::string& key, const json& value) {
  json j = json::parse(k_minimal);
  if (value.is_null())
    j.erase(key);
  else
    j[key] = value;
  return j.dump();
}

// ---- round trips ----------------------------------------------------------------

TEST(IoModelJson, DoublesRoundTripBitExactly) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<std::uint64_t> bits;
  Eigen::MatrixXd m(50, 40);
  for (Eigen::Index i = 0; i < m.size(); ++i) {
    std::uint64_t b = bits(rng);
    double x;
    std::memcpy(&x, &b, sizeof x);
    m(i) = std::isfinite(x) ? x : 1.0;  // every exponent, including subnormals
  }
  m(0) = -0.0;
  m(1) = 1e-300;
  m(2) = 1e300;
  m(3) = std::numeric_limits<double>::denorm_min();
  m(4) = 0.1;
  const json j = json::parse(sysid::matrix_to_json(m).dump());
  EXPECT_TRUE(same_bits(sysid::matrix_from_json(j, "M"), m));
}

TEST(IoModelJson, RandomStateSpaceRoundTripsThroughStringAndFile) {
  std::mt19937_64 rng(42);
  const ModelFile f = random_model(rng, 10, 3, 2);
  const std::string text = sysid::model_to_json_string(f);
  const ModelFile g = sysid::model_from_json_string(text, "mem.json");
  expect_same(f, g);
  // Writing the read model again gives the same text (stable, deterministic output).
  EXPECT_EQ(sysid::model_to_json_string(g), text);

  const fs::path p = fs::temp_directory_path() / ("sysid_io_model_" + std::to_string(::getpid()) + ".json");
  sysid::write_model_json(p.string(), f);
  expect_same(f, sysid::read_model_json(p.string()));
  fs::remove(p);
}

TEST(IoModelJson, LayoutIsReadable) {
  ModelFile f;
  f.model = sysid::StateSpace(Eigen::MatrixXd::Identity(2, 2) * 0.5, Eigen::MatrixXd::Ones(2, 1),
                              Eigen::MatrixXd::Ones(1, 2), Eigen::MatrixXd::Zero(1, 1), 0.0005);
  f.model.input_names = {"u"};
  f.model.output_names = {"y"};
  const std::string text = sysid::model_to_json_string(f);
  // Keys in the documented order, one matrix row per line, 2-space indent.
  EXPECT_EQ(text.rfind("{\n  \"type\": \"state-space\",\n  \"Ts\": 0.0005,\n  \"A\": [\n    [0.5, 0.0],\n    [0.0, 0.5]\n  ],", 0),
            0u)
      << text;
  EXPECT_LT(text.find("\"D\""), text.find("\"inputs\""));
  EXPECT_NE(text.find("\"inputs\": [\"u\"]"), std::string::npos) << text;
  EXPECT_EQ(json::parse(text)["Ts"].get<double>(), 0.0005);
}

TEST(IoModelJson, UnknownKeysAreKept) {
  json j = json::parse(k_minimal);
  j["comment"] = "tuned by hand";
  j["rig"] = {{"id", 3}, {"sensors", {1, 2, 3}}, {"gain", 0.1}};
  j["provenance"] = {{"method", "era"}, {"order", 2}};
  const ModelFile f = sysid::model_from_json_string(j.dump(), "m.json");
  EXPECT_EQ(f.extra.size(), 2u);
  EXPECT_EQ(f.extra["comment"], "tuned by hand");
  EXPECT_EQ(f.provenance["method"], "era");
  const json back = json::parse(sysid::model_to_json_string(f));
  EXPECT_EQ(back["rig"], j["rig"]);
  EXPECT_EQ(back["comment"], j["comment"]);
  EXPECT_EQ(back["provenance"], j["provenance"]);
}

TEST(IoModelJson, PolynomialRoundTrip) {
  // An ARX model y[k] = 0.5 y[k-1] + 2 u[k-1]: coefficient lists at top level,
  // the state-space form under "state_space".
  const std::string text = R"({
    "type": "polynomial", "A": [1.0, -0.5], "B": [0.0, 2.0], "C": [1.0], "F": [1.0], "nk": 1,
    "state_space": {"Ts": 0.01, "A": [[0.5]], "B": [[1.0]], "C": [[2.0]], "D": [[0.0]],
                    "inputs": ["u"], "outputs": ["y"], "K": [[0.5]], "solver_note": "observer form"},
    "output_offset": [1.25],
    "provenance": {"method": "arx", "na": 1, "nb": 1}})";
  const ModelFile f = sysid::model_from_json_string(text, "p.json");
  EXPECT_EQ(f.type, "polynomial");
  EXPECT_EQ(f.model.Ts, 0.01);
  EXPECT_EQ(f.model.C(0, 0), 2.0);
  EXPECT_EQ(f.model.output_names, std::vector<std::string>{"y"});
  EXPECT_EQ(f.K(0, 0), 0.5);
  EXPECT_EQ(f.output_offset(0), 1.25);
  // The coefficient lists are not matrices: they stay verbatim in extra.
  EXPECT_EQ(f.extra["A"], json({1.0, -0.5}));
  EXPECT_EQ(f.extra["nk"], 1);
  EXPECT_EQ(f.extra["state_space"]["solver_note"], "observer form");

  const std::string again = sysid::model_to_json_string(f);
  const json a = json::parse(again), b = json::parse(text);
  EXPECT_EQ(a, b);  // same JSON value: every key and number kept
  expect_same(f, sysid::model_from_json_string(again, "p.json"));
}

TEST(IoModelJson, AugmentedKeepsBlocks) {
  json j;
  j["type"] = "augmented";
  j["nominal"] = json::parse(k_minimal);
  j["nominal"].erase("type");
  j["nominal"]["type"] = "state-space";  // an unknown key inside the sub-object: kept
  j["blocks"] = json::array({{{"kind", "missing_mode"}, {"freq_hz", 31.6}, {"damping", 0.012}}});
  j["connections"] = json::array({{{"from", "u"}, {"to", "block0"}}});
  const ModelFile f = sysid::model_from_json_string(j.dump(), "a.json");
  EXPECT_EQ(f.type, "augmented");
  EXPECT_EQ(f.model.order(), 2);
  EXPECT_EQ(json::parse(sysid::model_to_json_string(f)), j);
}

TEST(IoModelJson, StaticGainWithoutStates) {
  ModelFile f;
  f.model.A.resize(0, 0);
  f.model.B.resize(0, 2);
  f.model.C.resize(3, 0);
  f.model.D = Eigen::MatrixXd::Constant(3, 2, 1.5);
  f.model.Ts = 0.1;
  const ModelFile g = sysid::model_from_json_string(sysid::model_to_json_string(f), "g.json");
  EXPECT_EQ(g.model.B.rows(), 0);
  EXPECT_EQ(g.model.B.cols(), 2);
  EXPECT_EQ(g.model.C.rows(), 3);
  EXPECT_EQ(g.model.C.cols(), 0);
  EXPECT_TRUE(same_bits(g.model.D, f.model.D));
}

// ---- errors ---------------------------------------------------------------------

TEST(IoModelJson, MissingKeys) {
  for (const char* key : {"Ts", "A", "B", "C", "D"}) expect_bad(minimal_with(key, nullptr), std::string("missing required key '") + key + "'");
  json p = json::parse(R"({"type": "polynomial", "A": [1.0]})");
  expect_bad(p.dump(), "missing required key 'state_space'");
  p["state_space"] = json::parse(k_minimal);
  p["state_space"].erase("D");
  expect_bad(p.dump(), "missing required key 'state_space.D'");
}

TEST(IoModelJson, WrongShapes) {
  expect_bad(minimal_with("A", json::parse("[[1, 2], [3, 4], [5, 6]]")),
             "A: expected a list of 3 rows of 3 numbers (square: states x states), found 3 rows of 2");
  expect_bad(minimal_with("A", json::parse("[[1, 2], [3]]")), "A: row 2 has 1 numbers, row 1 has 2");
  expect_bad(minimal_with("B", json::parse("[[1], [2], [3]]")), "B: expected a list of 2 rows of 1 number");
  expect_bad(minimal_with("C", json::parse("[[1, 2, 3]]")), "C: expected a list of 1 row of 2 numbers");
  expect_bad(minimal_with("D", json::parse("[[0, 0]]")), "D: expected a list of 1 row of 1 number (outputs x inputs), found 1 row of 2 numbers");
  expect_bad(minimal_with("A", json::parse("[1, 2]")), "A: expected a list of rows");
  expect_bad(minimal_with("A", json::parse("{\"x\": 1}")), "A: expected a list of rows");
  expect_bad(minimal_with("K", json::parse("[[1, 2]]")), "K: expected a list of 2 rows of 1 number");
  expect_bad(minimal_with("x0", json::parse("[1, 2, 3]")), "x0: expected a list of 2 numbers (one per state), found 3");
  expect_bad(minimal_with("input_offset", json::parse("[[1]]")), "input_offset: entry 1 is not a number");
  expect_bad(minimal_with("inputs", json::parse("[\"u1\", \"u2\"]")), "inputs: expected 1 names");
  expect_bad(minimal_with("outputs", json::parse("[3]")), "outputs: entry 1 is not a string");
  expect_bad(minimal_with("provenance", json::parse("[3]")), "provenance: expected an object");
  expect_bad(minimal_with("type", "transfer-function"), "type: expected \"state-space\"");
  expect_bad("[1, 2]", "expected a JSON object");
}

TEST(IoModelJson, NonNumbersAndNonFinite) {
  expect_bad(minimal_with("A", json::parse("[[1, \"x\"], [3, 4]]")), "A: entry (1,2) is not a number (found \"x\")");
  expect_bad(minimal_with("A", json::parse("[[1, null], [3, 4]]")), "A: entry (1,2) is not a number");
  expect_bad(minimal_with("Ts", "fast"), "Ts: expected a number");
  expect_bad(minimal_with("Ts", -1.0), "Ts: expected a sample time >= 0");
  // 1e999 overflows to Inf on reading; JSON has no NaN literal at all.
  std::string text = k_minimal;
  text.replace(text.find("0.3"), 3, "1e999");
  expect_bad(text, "invalid JSON: number overflow parsing '1e999'");
  // A non-finite value reaching matrix_from_json directly is refused as well.
  EXPECT_THROW(sysid::matrix_from_json(json::array({json::array({std::numeric_limits<double>::infinity()})}), "A"),
               DataError);
  std::string nan_text = k_minimal;
  nan_text.replace(nan_text.find("0.3"), 3, "NaN");
  const std::size_t nan_pos = nan_text.find("NaN");
  const std::size_t line_start = nan_text.rfind('\n', nan_pos) + 1;
  expect_bad(nan_text, "invalid JSON", 2, static_cast<long>(nan_pos - line_start + 1));
}

TEST(IoModelJson, InvalidJsonGivesLineAndColumn) {
  // The stray ']' is the 11th character of line 3.
  expect_bad("{\n  \"Ts\": 1,\n  \"A\": [1]],\n}", "invalid JSON", 3, 11);
  expect_bad("{\"Ts\": tru}", "invalid JSON", 1, 11);  // 'tru}' fails at the '}' 
  expect_bad("", "invalid JSON", 1, 1);
  expect_bad("{\"Ts\": 1,\n", "invalid JSON", 2, 1);
}

TEST(IoModelJson, NestingDepthIsLimited) {
  // An unknown key is kept in extra, and nlohmann copies, compares and prints
  // recursively: 100000 nested lists overflowed the stack (found with
  // tests/fuzz). Such a file is refused at the bracket that goes too deep.
  const std::string head = R"({"Ts": 1, "A": [[0.5]], "B": [[1]], "C": [[1]], "D": [[0]], "note": )";
  auto nested = [&](std::size_t depth) { return head + std::string(depth, '[') + std::string(depth, ']') + "}"; };
  // The object is level 1, so the 512th '[' of "note" opens level 513.
  expect_bad(nested(100000), "nested more than 512 deep", 1, static_cast<long>(head.size() + 512));
  expect_bad(nested(512), "nested more than 512 deep", 1, static_cast<long>(head.size() + 512));
  // 512 levels in all are accepted, and brackets inside strings do not count.
  const ModelFile deepest = sysid::model_from_json_string(nested(511), "m.json");
  EXPECT_TRUE(deepest.extra.contains("note"));
  const ModelFile text = sysid::model_from_json_string(head + "\"" + std::string(1000, '[') + "\"}", "m.json");
  EXPECT_EQ(text.extra["note"].get<std::string>().size(), 1000u);
}

TEST(IoModelJson, DimensionMismatchCaughtByValidateNamesFile) {
  // No outputs at all: each matrix has a consistent shape but the model is invalid.
  try {
    json j = json::parse(k_minimal);
    j["C"] = json::parse("[]");
    j["D"] = json::parse("[]");
    sysid::model_from_json_string(j.dump(), "m.json");
    FAIL();
  } catch (const DataError& e) {
    EXPECT_EQ(e.file(), "m.json");
    EXPECT_NE(e.message().find("output"), std::string::npos) << e.what();
  }
}

TEST(IoModelJson, TimeSeriesModelWithoutInputsRoundTrips) {
  // AR/ARMA models have no inputs: B is n x 0 and D is l x 0.
  json j = json::parse(k_minimal);
  j["B"] = json::parse("[[], []]");
  j["D"] = json::parse("[[]]");
  j["K"] = json::parse("[[0.2], [0.1]]");
  const sysid::ModelFile file = sysid::model_from_json_string(j.dump(), "m.json");
  EXPECT_EQ(file.model.inputs(), 0);
  EXPECT_EQ(file.model.outputs(), 1);
  const sysid::ModelFile again = sysid::model_from_json_string(sysid::model_to_json_string(file), "again.json");
  EXPECT_EQ(again.model.inputs(), 0);
  EXPECT_EQ(again.K, file.K);
  EXPECT_EQ(again.model.A, file.model.A);
}

TEST(IoModelJson, FileErrors) {
  const std::string missing = (fs::temp_directory_path() / "sysid_no_such_model.json").string();
  try {
    sysid::read_model_json(missing);
    FAIL();
  } catch (const DataError& e) {
    EXPECT_EQ(e.file(), missing);
    EXPECT_NE(e.message().find("No such file"), std::string::npos) << e.what();
  }
  ModelFile f = sysid::model_from_json_string(k_minimal, "m.json");
  EXPECT_THROW(sysid::write_model_json((fs::temp_directory_path() / "sysid_no_dir" / "m.json").string(), f), DataError);
}

TEST(IoModelJson, WritingRefusesNonFiniteAndBadShapes) {
  ModelFile f = sysid::model_from_json_string(k_minimal, "m.json");
  ModelFile g = f;
  g.model.A(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(sysid::model_to_json_string(g), std::invalid_argument);
  g = f;
  g.K = Eigen::MatrixXd::Constant(2, 1, std::numeric_limits<double>::infinity());
  EXPECT_THROW(sysid::model_to_json_string(g), std::invalid_argument);
  g = f;
  g.K = Eigen::MatrixXd::Zero(1, 2);
  EXPECT_THROW(sysid::model_to_json_string(g), std::invalid_argument);
  g = f;
  g.x0 = Eigen::VectorXd::Zero(3);
  EXPECT_THROW(sysid::model_to_json_string(g), std::invalid_argument);
  g = f;
  g.extra["A"] = 1;
  EXPECT_THROW(sysid::model_to_json_string(g), std::invalid_argument);
  g = f;
  g.type = "other";
  EXPECT_THROW(sysid::model_to_json_string(g), std::invalid_argument);
  EXPECT_THROW(sysid::matrix_to_json(Eigen::MatrixXd::Constant(1, 1, std::nan(""))), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_io_model_json
