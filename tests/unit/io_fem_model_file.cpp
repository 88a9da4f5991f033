#include "sysid/io/fem_model_file.hpp"

#include <gtest/gtest.h>

#include "run_cli.hpp"
#include "sparse_bits.hpp"
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "sysid/core/errors.hpp"
#include "sysid/io/matrix_market.hpp"

namespace test_unit_io_fem_model_file {

namespace fs = std::filesystem;
using nlohmann::json;
using sysid::DataError;
using sysid::fem::DampingKind;
using sysid::fem::Quantity;
using sysid::fem::SecondOrderModel;
using Sparse = Eigen::SparseMatrix<double>;

namespace {

using sysid::test::bits;
using sysid::test::identical;
using sysid::test::TempDir;  // tests/support/run_cli.hpp

/// Restores the working directory however the test ends.
class WorkingDirectory {
 public:
  explicit WorkingDirectory(const fs::path& dir) : m_old(fs::current_path()) { fs::current_path(dir); }
  ~WorkingDirectory() {
    std::error_code ec;
    fs::current_path(m_old, ec);
  }

 private:
  fs::path m_old;
};

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// A chain of n masses and springs (fixed at one end) with awkward numbers, so
/// the round trip has every digit to lose: masses 1/3 .. , stiffnesses 1e5 / 7 ...
SecondOrderModel chain(int n, DampingKind kind) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> jitter(0.5, 1.5);
  std::vector<Eigen::Triplet<double>> m, k, c;
  for (int i = 0; i < n; ++i) {
    m.emplace_back(i, i, jitter(rng) / 3.0);
    const double ki = 1e5 / 7.0 * jitter(rng), ci = 1e-300 * jitter(rng) + 0.1 * jitter(rng);
    k.emplace_back(i, i, ki);
    c.emplace_back(i, i, ci);
    if (i > 0) {
      k.emplace_back(i - 1, i - 1, ki);
      k.emplace_back(i, i - 1, -ki);
      k.emplace_back(i - 1, i, -ki);
      c.emplace_back(i, i - 1, -0.0);  // an explicit signed zero must survive too
      c.emplace_back(i - 1, i, -0.0);
    }
  }
  SecondOrderModel model;
  model.mass.resize(n, n);
  model.stiffness.resize(n, n);
  model.mass.setFromTriplets(m.begin(), m.end());
  model.stiffness.setFromTriplets(k.begin(), k.end());
  model.damping.kind = kind;
  if (kind == DampingKind::matrix) {
    model.damping_matrix.resize(n, n);
    model.damping_matrix.setFromTriplets(c.begin(), c.end());
  } else if (kind == DampingKind::rayleigh) {
    model.damping.alpha = 1.0 / 3.0;
    model.damping.beta = 1e-6 / 7.0;
  } else if (kind == DampingKind::modal_ratio) {
    model.damping.ratio = 0.02 / 3.0;
  }
  model.inputs = {{"F_tip", n - 1, "N"}, {"F_base", 0, "kN"}};
  model.outputs = {{"x_mid", n / 2, Quantity::displacement, "mm"},
                   {"v_tip", n - 1, Quantity::velocity, "m/s"},
                   {"a_tip", n - 1, Quantity::acceleration, "g"},
                   {"a_no_unit", 1, Quantity::acceleration, ""}};
  return model;
}

void expect_same_model(const SecondOrderModel& a, const SecondOrderModel& b) {
  EXPECT_TRUE(identical(a.mass, b.mass));
  EXPECT_TRUE(identical(a.stiffness, b.stiffness));
  EXPECT_EQ(a.damping.kind, b.damping.kind);
  EXPECT_EQ(bits(a.damping.alpha), bits(b.damping.alpha));
  EXPECT_EQ(bits(a.damping.beta), bits(b.damping.beta));
  EXPECT_EQ(bits(a.damping.ratio), bits(b.damping.ratio));
  if (a.damping.kind == DampingKind::matrix) {
    EXPECT_TRUE(identical(a.damping_matrix, b.damping_matrix));
  }
  ASSERT_EQ(a.inputs.size(), b.inputs.size());
  for (std::size_t i = 0; i < a.inputs.size(); ++i) {
    EXPECT_EQ(a.inputs[i].name, b.inputs[i].name);
    EXPECT_EQ(a.inputs[i].dof, b.inputs[i].dof);
    EXPECT_EQ(a.inputs[i].unit, b.inputs[i].unit);
  }
  ASSERT_EQ(a.outputs.size(), b.outputs.size());
  for (std::size_t i = 0; i < a.outputs.size(); ++i) {
    EXPECT_EQ(a.outputs[i].name, b.outputs[i].name);
    EXPECT_EQ(a.outputs[i].dof, b.outputs[i].dof);
    EXPECT_EQ(a.outputs[i].quantity, b.outputs[i].quantity);
    EXPECT_EQ(a.outputs[i].unit, b.outputs[i].unit);
  }
}

/// Writes a 3-DOF model's matrices (M = diag, K = tridiagonal) into `dir` and
/// returns a valid FE JSON naming them, for the error cases to break.
json valid_json(const fs::path& dir) {
  SecondOrderModel m = chain(3, DampingKind::none);
  sysid::write_matrix_market((dir / "M.mtx").string(), m.mass, true);
  sysid::write_matrix_market((dir / "K.mtx").string(), m.stiffness, true);
  return json{{"type", "fem"},
              {"mass", "M.mtx"},
              {"stiffness", "K.mtx"},
              {"inputs", {{{"name", "F"}, {"dof", 2}}}},
              {"outputs", {{{"name", "y"}, {"dof", 1}, {"quantity", "displacement"}}}}};
}

/// read_fem_model on `j` must throw a DataError naming the JSON file with `word`.
void expect_error(const fs::path& dir, const json& j, const std::string& word) {
  const std::string path = (dir / "bad.json").string();
  write_text(path, j.dump(2));
  SCOPED_TRACE(j.dump());
  try {
    sysid::read_fem_model(path);
    ADD_FAILURE() << "no DataError";
  } catch (const DataError& e) {
    EXPECT_EQ(e.file(), path) << e.what();
    EXPECT_NE(e.message().find(word), std::string::npos) << "'" << word << "' not in: " << e.what();
  }
}

}  // namespace

TEST(FemModelFile, RoundTripEveryDampingKindIsBitExact) {
  TempDir dir;
  for (DampingKind kind : {DampingKind::none, DampingKind::matrix, DampingKind::rayleigh, DampingKind::modal_ratio}) {
    SCOPED_TRACE(static_cast<int>(kind));
    const SecondOrderModel model = chain(12, kind);
    const fs::path sub = dir.path() / ("kind" + std::to_string(static_cast<int>(kind)));
    fs::create_directories(sub);
    const fs::path json_path = sub / "beam.json";
    sysid::write_fem_model(json_path.string(), model, "a 12-DOF chain");
    expect_same_model(model, sysid::read_fem_model(json_path.string()));

    // Matrix names are relative, symmetric storage is used, C only for matrix damping.
    const json j = json::parse(read_text(json_path));
    EXPECT_EQ(j["type"], "fem");
    EXPECT_EQ(j["description"], "a 12-DOF chain");
    EXPECT_EQ(j["mass"], "beam.M.mtx");
    EXPECT_EQ(j["stiffness"], "beam.K.mtx");
    EXPECT_EQ(read_text(sub / "beam.M.mtx").rfind("%%MatrixMarket matrix coordinate real symmetric", 0), 0u);
    EXPECT_EQ(fs::exists(sub / "beam.C.mtx"), kind == DampingKind::matrix);
    EXPECT_EQ(j.contains("damping"), kind != DampingKind::none);
    if (kind == DampingKind::matrix) {
      EXPECT_EQ(j["damping"]["matrix"], "beam.C.mtx");
    }
    EXPECT_EQ(j["outputs"][2]["quantity"], "acceleration");
  }
}

TEST(FemModelFile, NearlySymmetricMatrixIsStoredGeneralAndUnaltered) {
  TempDir dir;
  SecondOrderModel model = chain(5, DampingKind::none);
  // 1e-14 relative asymmetry: inside validate()'s 1e-10 tolerance, so legal, but
  // symmetric storage would silently drop it.
  model.stiffness.coeffRef(0, 1) *= 1.0 + 1e-14;
  ASSERT_NO_THROW(model.validate());
  const fs::path json_path = dir.path() / "near.json";
  sysid::write_fem_model(json_path.string(), model);
  EXPECT_EQ(read_text(dir.path() / "near.K.mtx").rfind("%%MatrixMarket matrix coordinate real general", 0), 0u);
  expect_same_model(model, sysid::read_fem_model(json_path.string()));
  EXPECT_FALSE(json::parse(read_text(json_path)).contains("description"));
}

TEST(FemModelFile, MatrixPathsAreRelativeToTheJsonFile) {
  TempDir dir;
  fs::create_directories(dir.path() / "model");
  fs::create_directories(dir.path() / "elsewhere");
  const SecondOrderModel model = chain(6, DampingKind::matrix);
  sysid::write_fem_model((dir.path() / "model" / "plate.json").string(), model);
  {
    WorkingDirectory cwd(dir.path() / "elsewhere");
    expect_same_model(model, sysid::read_fem_model("../model/plate.json"));
  }
  // An absolute matrix name is used as it is.
  json j = json::parse(read_text(dir.path() / "model" / "plate.json"));
  j["mass"] = (dir.path() / "model" / "plate.M.mtx").string();
  write_text(dir.path() / "elsewhere" / "abs.json", j.dump());
  fs::copy(dir.path() / "model" / "plate.K.mtx", dir.path() / "elsewhere" / "plate.K.mtx");
  fs::copy(dir.path() / "model" / "plate.C.mtx", dir.path() / "elsewhere" / "plate.C.mtx");
  expect_same_model(model, sysid::read_fem_model((dir.path() / "elsewhere" / "abs.json").string()));
}

TEST(FemModelFile, DefaultUnitsFollowTheLengthUnit) {
  TempDir dir;
  json j = valid_json(dir.path());
  j["length_unit"] = "mm";
  j["description"] = "units test";
  j["damping"] = {{"rayleigh", {{"beta", 2e-5}}}};
  j["outputs"] = {{{"name", "x"}, {"dof", 0}, {"quantity", "displacement"}},
                  {{"name", "v"}, {"dof", 1}, {"quantity", "velocity"}},
                  {{"name", "a"}, {"dof", 2}, {"quantity", "acceleration"}},
                  {{"name", "a_g"}, {"dof", 2}, {"quantity", "acceleration"}, {"unit", "g"}}};
  write_text(dir.path() / "u.json", j.dump());
  const SecondOrderModel m = sysid::read_fem_model((dir.path() / "u.json").string());
  EXPECT_EQ(m.inputs[0].unit, "N");
  EXPECT_EQ(m.outputs[0].unit, "mm");
  EXPECT_EQ(m.outputs[1].unit, "mm/s");
  EXPECT_EQ(m.outputs[2].unit, "mm/s^2");
  EXPECT_EQ(m.outputs[3].unit, "g");
  EXPECT_EQ(m.outputs[1].quantity, Quantity::velocity);
  EXPECT_EQ(m.damping.kind, DampingKind::rayleigh);
  EXPECT_EQ(m.damping.alpha, 0.0);  // absent coefficient = 0
  EXPECT_EQ(m.damping.beta, 2e-5);

  j.erase("length_unit");
  write_text(dir.path() / "u.json", j.dump());
  EXPECT_EQ(sysid::read_fem_model((dir.path() / "u.json").string()).outputs[2].unit, "m/s^2");
}

TEST(FemModelFileErrors, StructureAndValues) {
  TempDir dir;
  const json good = valid_json(dir.path());
  {
    write_text(dir.path() / "good.json", good.dump());
    EXPECT_NO_THROW(sysid::read_fem_model((dir.path() / "good.json").string()));
  }
  auto with = [&](const std::string& key, const json& value) {
    json j = good;
    j[key] = value;
    return j;
  };
  auto without = [&](const std::string& key) {
    json j = good;
    j.erase(key);
    return j;
  };
  expect_error(dir.path(), json::array(), "top level");
  expect_error(dir.path(), with("type", "state-space"), "type: expected \"fem\"");
  expect_error(dir.path(), without("type"), "missing required key 'type'");
  expect_error(dir.path(), without("mass"), "missing required key 'mass'");
  expect_error(dir.path(), with("stiffness", 3), "stiffness: expected a non-empty string");
  expect_error(dir.path(), with("dampign", json::object()), "dampign: unknown key");
  expect_error(dir.path(), with("inputs", json::array()), "inputs: expected a non-empty list");

  json bad_dof = good;
  bad_dof["inputs"].push_back({{"name", "G"}, {"dof", -3}});
  expect_error(dir.path(), bad_dof, "inputs[1].dof: expected a non-negative integer");
  bad_dof["inputs"][1]["dof"] = 2.5;
  expect_error(dir.path(), bad_dof, "inputs[1].dof: expected a non-negative integer");
  bad_dof["inputs"][1]["dof"] = "2";
  expect_error(dir.path(), bad_dof, "inputs[1].dof");
  bad_dof["inputs"][1] = {{"name", "G"}, {"DOF", 1}};
  expect_error(dir.path(), bad_dof, "inputs[1].DOF: unknown key");

  json no_quantity = good;
  no_quantity["outputs"][0].erase("quantity");
  expect_error(dir.path(), no_quantity, "outputs[0]: missing required key 'quantity'");
  json strain = good;
  strain["outputs"][0]["quantity"] = "strain";
  expect_error(dir.path(), strain, "outputs[0].quantity: expected displacement, velocity or acceleration");

  expect_error(dir.path(), with("damping", {{"rayleigh", {{"alpha", 1.0}}}, {"modal_ratio", 0.02}}),
               "damping: expected exactly one of matrix, rayleigh, modal_ratio");
  expect_error(dir.path(), with("damping", json::object()), "damping: expected exactly one of");
  expect_error(dir.path(), with("damping", {{"modal_ratio", -0.01}}), "damping.modal_ratio: expected a number >= 0");
  expect_error(dir.path(), with("damping", {{"rayleigh", {{"gamma", 1.0}}}}), "damping.rayleigh.gamma: unknown key");
}

TEST(FemModelFileErrors, ValidationBecomesDataErrorNamingTheJson) {
  TempDir dir;
  json j = valid_json(dir.path());
  j["outputs"][0]["dof"] = 99;  // the matrices are 3 x 3
  expect_error(dir.path(), j, "outside 0..2");

  j = valid_json(dir.path());
  j["outputs"][0]["name"] = "F";  // same name as the input
  expect_error(dir.path(), j, "duplicate");

  // A non-symmetric stiffness (general storage) is read, then refused by validate().
  write_text(dir.path() / "Kbad.mtx", "%%MatrixMarket matrix coordinate real general\n3 3 4\n1 1 1\n2 2 1\n3 3 1\n1 2 5\n");
  j = valid_json(dir.path());
  j["stiffness"] = "Kbad.mtx";
  expect_error(dir.path(), j, "not symmetric");

  // M and K of different sizes.
  write_text(dir.path() / "K2.mtx", "%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 1 1\n2 2 1\n");
  j["stiffness"] = "K2.mtx";
  expect_error(dir.path(), j, "K must be 3 x 3");
}

TEST(FemModelFileErrors, InvalidJsonHasLineAndColumn) {
  TempDir dir;
  const std::string path = (dir.path() / "syntax.json").string();
  write_text(path, "{\n  \"type\": \"fem\",\n  \"mass\": oops\n}\n");
  try {
    sysid::read_fem_model(path);
    ADD_FAILURE() << "no DataError";
  } catch (const DataError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.line(), 3) << e.what();
    EXPECT_EQ(e.column(), 11) << e.what();  // the 'o' of oops
    EXPECT_NE(e.message().find("invalid JSON"), std::string::npos) << e.what();
  }
}

TEST(FemModelFileErrors, MatrixMarketErrorsKeepTheirOwnPosition) {
  TempDir dir;
  const json j = valid_json(dir.path());
  const std::string json_path = (dir.path() / "m.json").string();
  write_text(json_path, j.dump());
  // An upper-triangle entry in a symmetric file: the error names M.mtx, line 3, column 1.
  write_text(dir.path() / "M.mtx", "%%MatrixMarket matrix coordinate real symmetric\n3 3 1\n1 2 1.0\n");
  try {
    sysid::read_fem_model(json_path);
    ADD_FAILURE() << "no DataError";
  } catch (const DataError& e) {
    EXPECT_EQ(fs::path(e.file()), dir.path() / "M.mtx") << e.what();
    EXPECT_EQ(e.line(), 3) << e.what();
    EXPECT_EQ(e.column(), 1) << e.what();
    EXPECT_NE(e.message().find("upper triangle"), std::string::npos) << e.what();
  }
  // A missing matrix file is named.
  fs::remove(dir.path() / "M.mtx");
  try {
    sysid::read_fem_model(json_path);
    ADD_FAILURE() << "no DataError";
  } catch (const DataError& e) {
    EXPECT_EQ(fs::path(e.file()), dir.path() / "M.mtx") << e.what();
  }
}

TEST(FemModelFile, WriteRefusesAnInvalidModel) {
  TempDir dir;
  SecondOrderModel model = chain(4, DampingKind::none);
  model.outputs.clear();
  EXPECT_THROW(sysid::write_fem_model((dir.path() / "x.json").string(), model), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir.path() / "x.json"));
  EXPECT_FALSE(fs::exists(dir.path() / "x.M.mtx"));
}

}  // namespace test_unit_io_fem_model_file
