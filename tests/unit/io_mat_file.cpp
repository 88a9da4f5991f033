// MAT v5 files (io/mat_file.hpp): what is written reads back bit-exactly (matrices,
// N-D arrays, cell arrays), the model's and the family's variables are those
// DESIGN.md names, and failures leave nothing behind.
#include <sysid/core/errors.hpp>
#include <sysid/io/mat_file.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <variant>

#include "random_systems.hpp"
#include "run_cli.hpp"

namespace test_unit_io_mat_file {

using namespace sysid;
using namespace sysid::test;

const MatVariable* find(const std::vector<MatVariable>& variables, const std::string& name) {
  for (const MatVariable& v : variables)
    if (v.name == name) return &v;
  return nullptr;
}

TEST(MatFile, MatricesAndStringsReadBackExactly) {
  TempDir dir;
  Eigen::MatrixXd a = Eigen::MatrixXd::Random(3, 5);
  a(1, 2) = std::numeric_limits<double>::quiet_NaN();
  a(2, 4) = -std::numeric_limits<double>::infinity();
  const std::vector<MatVariable> written = {MatVariable::matrix("A", a), MatVariable::matrix("empty", Eigen::MatrixXd(4, 0)),
                                            MatVariable::matrix("Ts", Eigen::MatrixXd::Constant(1, 1, 0.0005)),
                                            MatVariable::cell_of_strings("InputName", {"force_1", "", "u"})};
  write_mat_file(dir / "v.mat", written);
  const std::vector<MatVariable> read = read_mat_file(dir / "v.mat");
  ASSERT_EQ(read.size(), 4u);
  const MatVariable* ra = find(read, "A");
  ASSERT_NE(ra, nullptr);
  ASSERT_EQ(ra->values.rows(), 3);
  ASSERT_EQ(ra->values.cols(), 5);
  for (Eigen::Index i = 0; i < 3; ++i)
    for (Eigen::Index j = 0; j < 5; ++j) {
      if (std::isnan(a(i, j))) EXPECT_TRUE(std::isnan(ra->values(i, j)));
      else EXPECT_EQ(ra->values(i, j), a(i, j)) << i << "," << j;
    }
  ASSERT_NE(find(read, "empty"), nullptr);
  EXPECT_EQ(find(read, "empty")->values.rows(), 4);
  EXPECT_EQ(find(read, "empty")->values.cols(), 0);
  EXPECT_EQ(find(read, "Ts")->values(0, 0), 0.0005);
  const MatVariable* names = find(read, "InputName");
  ASSERT_NE(names, nullptr);
  EXPECT_TRUE(names->is_strings);
  EXPECT_EQ(names->strings, (std::vector<std::string>{"force_1", "", "u"}));
}

TEST(MatFile, TheModelsVariablesAreDesignsNames) {
  ModelFile file;
  file.model = StateSpace(Eigen::MatrixXd::Identity(2, 2) * 0.5, Eigen::MatrixXd::Ones(2, 1), Eigen::MatrixXd::Ones(1, 2),
                          Eigen::MatrixXd::Zero(1, 1), 0.01);
  file.model.input_names = {"f"};
  file.K = Eigen::MatrixXd::Constant(2, 1, 0.1);
  std::vector<std::string> names;
  for (const MatVariable& v : model_mat_variables(file)) names.push_back(v.name);
  EXPECT_EQ(names, (std::vector<std::string>{"A", "B", "C", "D", "Ts", "K", "InputName", "OutputName"}));
  const std::vector<MatVariable> v = model_mat_variables(file);
  EXPECT_EQ(find(v, "OutputName")->strings, std::vector<std::string>{"y1"});  // unnamed outputs get the tool's names
  EXPECT_EQ(find(v, "Ts")->values(0, 0), 0.01);
}

TEST(MatFile, FailuresNameTheFileAndLeaveNothing) {
  TempDir dir;
  EXPECT_THROW(write_mat_file(dir / "x.mat", {MatVariable::matrix("2bad", Eigen::MatrixXd::Zero(1, 1))}), std::invalid_argument);
  try {
    write_mat_file(dir / "no_such_folder/x.mat", {MatVariable::matrix("A", Eigen::MatrixXd::Zero(1, 1))});
    FAIL() << "expected a DataError";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_folder/x.mat"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_mat_file(dir / "missing.mat"), DataError);
  {
    std::ofstream junk(dir / "not.mat");
    junk << "this is not a MAT file\n";
  }
  EXPECT_THROW(read_mat_file(dir / "not.mat"), DataError);
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string().find(".partial-"), std::string::npos) << entry.path();
}

// ---- N-D arrays, general cell arrays and a family's variables -----------------

TEST(MatFile, PagesAreAThreeDimensionalArrayThatReadsBackWithItsDims) {
  TempDir dir;
  std::vector<Eigen::MatrixXd> slices;
  for (int k = 0; k < 4; ++k) slices.push_back(Eigen::MatrixXd::Random(2, 3) + Eigen::MatrixXd::Constant(2, 3, 10.0 * k));
  slices[2](1, 0) = std::numeric_limits<double>::quiet_NaN();
  const MatVariable pages = MatVariable::pages("P", slices);
  EXPECT_EQ(pages.dims, (std::vector<std::size_t>{2, 3, 4}));
  write_mat_file(dir / "p.mat", {pages, MatVariable::matrix("M", Eigen::MatrixXd::Identity(2, 2))});
  const std::vector<MatVariable> read = read_mat_file(dir / "p.mat");
  const MatVariable* p = find(read, "P");
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->dims, (std::vector<std::size_t>{2, 3, 4}));
  ASSERT_EQ(p->values.rows(), 2);
  ASSERT_EQ(p->values.cols(), 12);
  for (int k = 0; k < 4; ++k)
    for (Eigen::Index i = 0; i < 2; ++i)
      for (Eigen::Index j = 0; j < 3; ++j) {
        const double want = slices[static_cast<std::size_t>(k)](i, j), got = p->values(i, 3 * k + j);
        if (std::isnan(want)) EXPECT_TRUE(std::isnan(got));
        else EXPECT_EQ(got, want) << "page " << k << " (" << i << "," << j << ")";
      }
  // A 2-D matrix stays 2-D (no dims).
  ASSERT_NE(find(read, "M"), nullptr);
  EXPECT_TRUE(find(read, "M")->dims.empty());
  // Pages of different sizes are refused.
  EXPECT_THROW(MatVariable::pages("Q", {Eigen::MatrixXd::Zero(2, 2), Eigen::MatrixXd::Zero(2, 3)}), std::invalid_argument);
}

TEST(MatFile, GeneralCellArraysOfNumbersAndTextsReadBack) {
  TempDir dir;
  // 2 x 3, column-major: {1.5, "Pos 2"; [2x2 matrix], ""; "x", [] (0 x 0)}.
  Eigen::MatrixXd m(2, 2);
  m << 1.0, -2.0, 3.5, std::numeric_limits<double>::infinity();
  std::vector<MatCellElement> elements(6);
  elements[0].values = Eigen::MatrixXd::Constant(1, 1, 1.5);
  elements[1].values = m;
  elements[2].is_text = true;
  elements[2].text = "Pos 2";
  elements[3].is_text = true;
  elements[3].text = "";
  elements[4].is_text = true;
  elements[4].text = "x";
  elements[5].values = Eigen::MatrixXd(0, 0);
  write_mat_file(dir / "c.mat", {MatVariable::cell_array("C", 2, 3, elements)});
  const std::vector<MatVariable> read = read_mat_file(dir / "c.mat");
  const MatVariable* c = find(read, "C");
  ASSERT_NE(c, nullptr);
  ASSERT_TRUE(c->is_cell);
  EXPECT_FALSE(c->is_strings);
  EXPECT_EQ(c->cell_rows, 2u);
  EXPECT_EQ(c->cell_cols, 3u);
  ASSERT_EQ(c->cell.size(), 6u);
  for (std::size_t k = 0; k < 6; ++k) {
    EXPECT_EQ(c->cell[k].is_text, elements[k].is_text) << k;
    if (elements[k].is_text) {
      EXPECT_EQ(c->cell[k].text, elements[k].text) << k;
    } else {
      EXPECT_EQ(c->cell[k].values.rows(), elements[k].values.rows()) << k;
      EXPECT_EQ(c->cell[k].values.cols(), elements[k].values.cols()) << k;
      EXPECT_EQ(c->cell[k].values, elements[k].values) << k;
    }
  }
  // A cell of texts only reads back as strings.
  write_mat_file(dir / "s.mat", {MatVariable::cell_array("S", 1, 2, {{{}, "a", true}, {{}, "bc", true}})});
  const std::vector<MatVariable> s = read_mat_file(dir / "s.mat");
  ASSERT_EQ(s.size(), 1u);
  EXPECT_TRUE(s[0].is_strings);
  EXPECT_EQ(s[0].strings, (std::vector<std::string>{"a", "bc"}));
}

namespace {

ModelFile modal_file(const std::vector<double>& f, std::uint64_t seed) {
  ModelFile m;
  m.model = rotated_modal_system(f, std::vector<double>(f.size(), 0.02), 1, 2, seed, 0.001);
  return m;
}

/// Three members of orders `orders` (2 per mode), payload (number) and side (label).
FamilyFile family_of_orders(const std::vector<int>& orders) {
  FamilyFile f;
  f.Ts = 0.001;
  f.inputs = {"u"};
  f.outputs = {"y1", "y2"};
  f.condition_names = {"payload_kg", "side"};
  const char* sides[3] = {"left", "right", "left"};
  for (std::size_t k = 0; k < orders.size(); ++k) {
    FamilyFileMember m;
    m.conditions = {0.5 * static_cast<double>(k), std::string(sides[k % 3])};
    m.log = "m" + std::to_string(k) + ".csv";
    std::vector<double> freqs;
    for (int j = 0; j < orders[k] / 2; ++j) freqs.push_back(20.0 * (j + 1) + static_cast<double>(k));
    m.model = modal_file(freqs, 30 + k);
    m.fit_percent = Eigen::Vector2d(90.0 + static_cast<double>(k), 80.0);
    f.members.push_back(std::move(m));
  }
  TrackedMode t;
  t.freq_hz = Eigen::VectorXd::LinSpaced(static_cast<Eigen::Index>(orders.size()), 20.0, 22.0);
  t.damping = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(orders.size()), 0.02);
  t.freq_hz(1) = std::numeric_limits<double>::quiet_NaN();
  t.damping(1) = std::numeric_limits<double>::quiet_NaN();
  f.modes = {t};
  f.nominal_member = 1;
  f.nominal_model = f.members[1].model;
  FamilyFileUncertainty u;
  u.form = "multiplicative-output";
  u.frequency_hz = Eigen::VectorXd::LinSpaced(5, 1.0, 100.0);
  u.bound = Eigen::VectorXd::LinSpaced(5, 0.1, 0.5);
  ModelFile w;
  w.model = StateSpace(Eigen::MatrixXd::Constant(1, 1, 0.5), Eigen::MatrixXd::Ones(1, 1), Eigen::MatrixXd::Ones(1, 1),
                       Eigen::MatrixXd::Ones(1, 1), 0.001);
  u.weight = w;
  f.uncertainty = u;
  return f;
}

}  // namespace

TEST(MatFile, AFamilyOfOneOrderGivesModelArrays) {
  TempDir dir;
  const FamilyFile f = family_of_orders({4, 4, 4});
  write_mat_file(dir / "f.mat", family_mat_variables(f));
  const std::vector<MatVariable> v = read_mat_file(dir / "f.mat");
  // The nominal as a plain model, then the members as n x n x N ... arrays.
  ASSERT_NE(find(v, "A"), nullptr);
  EXPECT_EQ(find(v, "A")->values, f.nominal_model.model.A);
  EXPECT_EQ(find(v, "Ts")->values(0, 0), 0.001);
  const struct {
    const char* name;
    std::size_t rows, cols;
  } arrays[4] = {{"A_members", 4, 4}, {"B_members", 4, 1}, {"C_members", 2, 4}, {"D_members", 2, 1}};
  for (const auto& a : arrays) {
    const MatVariable* m = find(v, a.name);
    ASSERT_NE(m, nullptr) << a.name;
    EXPECT_FALSE(m->is_cell) << a.name;
    EXPECT_EQ(m->dims, (std::vector<std::size_t>{a.rows, a.cols, 3})) << a.name;
  }
  for (Eigen::Index k = 0; k < 3; ++k) {
    const StateSpace& s = f.members[static_cast<std::size_t>(k)].model.model;
    EXPECT_EQ(Eigen::MatrixXd(find(v, "A_members")->values.middleCols(4 * k, 4)), s.A) << k;
    EXPECT_EQ(Eigen::MatrixXd(find(v, "B_members")->values.middleCols(k, 1)), s.B) << k;
    EXPECT_EQ(Eigen::MatrixXd(find(v, "C_members")->values.middleCols(4 * k, 4)), s.C) << k;
    EXPECT_EQ(Eigen::MatrixXd(find(v, "D_members")->values.middleCols(k, 1)), s.D) << k;
  }
  EXPECT_EQ(find(v, "A_nominal")->values, f.nominal_model.model.A);
  EXPECT_EQ(find(v, "A_weight")->values, f.uncertainty->weight->model.A);
  EXPECT_EQ(find(v, "D_weight")->values(0, 0), 1.0);
  EXPECT_EQ(Eigen::VectorXd(find(v, "frequency_hz")->values.col(0)), f.uncertainty->frequency_hz);
  EXPECT_EQ(Eigen::VectorXd(find(v, "bound")->values.col(0)), f.uncertainty->bound);
  // Conditions: a 3 x 2 cell of numbers and labels, member by member.
  const MatVariable* c = find(v, "conditions");
  ASSERT_NE(c, nullptr);
  ASSERT_TRUE(c->is_cell);
  EXPECT_EQ(c->cell_rows, 3u);
  EXPECT_EQ(c->cell_cols, 2u);
  ASSERT_EQ(c->cell.size(), 6u);
  for (std::size_t k = 0; k < 3; ++k) {
    ASSERT_FALSE(c->cell[k].is_text) << k;
    EXPECT_EQ(c->cell[k].values(0, 0), 0.5 * static_cast<double>(k)) << k;
    ASSERT_TRUE(c->cell[3 + k].is_text) << k;
    EXPECT_EQ(c->cell[3 + k].text, std::get<std::string>(f.members[k].conditions[1])) << k;
  }
  EXPECT_EQ(find(v, "condition_names")->strings, (std::vector<std::string>{"payload_kg", "side"}));
  // Modes: N x modes, NaN where a member lacks one.
  const MatVariable* modes = find(v, "mode_freq_hz");
  ASSERT_NE(modes, nullptr);
  ASSERT_EQ(modes->values.rows(), 3);
  ASSERT_EQ(modes->values.cols(), 1);
  EXPECT_EQ(modes->values(0, 0), 20.0);
  EXPECT_TRUE(std::isnan(modes->values(1, 0)));
  EXPECT_EQ(modes->values(2, 0), 22.0);
  EXPECT_TRUE(std::isnan(find(v, "mode_damping")->values(1, 0)));
  // Fits: N x outputs.
  ASSERT_EQ(find(v, "fit_percent")->values.rows(), 3);
  EXPECT_EQ(find(v, "fit_percent")->values(2, 0), 92.0);
  EXPECT_EQ(find(v, "fit_percent")->values(2, 1), 80.0);
}

TEST(MatFile, AFamilyOfSeveralOrdersGivesCellArraysAndNoWeightWithoutOne) {
  TempDir dir;
  FamilyFile f = family_of_orders({4, 6, 2});
  f.uncertainty->weight.reset();
  write_mat_file(dir / "f.mat", family_mat_variables(f));
  const std::vector<MatVariable> v = read_mat_file(dir / "f.mat");
  for (const char* name : {"A_members", "B_members", "C_members", "D_members"}) {
    const MatVariable* m = find(v, name);
    ASSERT_NE(m, nullptr) << name;
    ASSERT_TRUE(m->is_cell) << name;
    EXPECT_EQ(m->cell_rows, 3u) << name;
    EXPECT_EQ(m->cell_cols, 1u) << name;
    ASSERT_EQ(m->cell.size(), 3u) << name;
  }
  for (std::size_t k = 0; k < 3; ++k) {
    const StateSpace& s = f.members[k].model.model;
    EXPECT_EQ(find(v, "A_members")->cell[k].values, s.A) << k;
    EXPECT_EQ(find(v, "B_members")->cell[k].values, s.B) << k;
    EXPECT_EQ(find(v, "C_members")->cell[k].values, s.C) << k;
    EXPECT_EQ(find(v, "D_members")->cell[k].values, s.D) << k;
  }
  EXPECT_EQ(find(v, "A_members")->cell[1].values.rows(), 6);
  EXPECT_EQ(find(v, "A_weight"), nullptr);
  EXPECT_NE(find(v, "bound"), nullptr);
  // Without an uncertainty (one member): no bound either.
  f.uncertainty.reset();
  std::vector<std::string> names;
  for (const MatVariable& m : family_mat_variables(f)) names.push_back(m.name);
  EXPECT_EQ(std::count(names.begin(), names.end(), "bound"), 0);
  EXPECT_EQ(std::count(names.begin(), names.end(), "A_nominal"), 1);
}

}  // namespace test_unit_io_mat_file
