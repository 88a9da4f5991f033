// MAT v5 files (io/mat_file.hpp): what is written reads back bit-exactly, the
// model's variables are those DESIGN.md names, and failures leave nothing behind.
#include <sysid/core/errors.hpp>
#include <sysid/io/mat_file.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

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

}  // namespace test_unit_io_mat_file
