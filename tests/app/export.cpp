// End-to-end: sysid export writes a model file's MATLAB variables.
#include <sysid/io/mat_file.hpp>
#include <sysid/io/model_json.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "random_systems.hpp"
#include "run_cli.hpp"

namespace test_app_export {

using namespace sysid;
using namespace sysid::test;

const MatVariable& variable(const std::vector<MatVariable>& variables, const std::string& name) {
  for (const MatVariable& v : variables)
    if (v.name == name) return v;
  throw std::runtime_error("no variable " + name);
}

TEST(ExportApp, WritesTheModelsMatricesAndNames) {
  TempDir dir;
  ModelFile f;
  f.model = four_mode_plant();
  f.model.input_names = {"force"};
  f.model.output_names = {"acc"};
  f.K = Eigen::MatrixXd::Constant(f.model.order(), 1, 0.25);
  f.x0 = Eigen::VectorXd::LinSpaced(f.model.order(), -1.0, 1.0);
  write_model_json(dir / "m.json", f);
  const CliResult r = run_cli({"export", dir / "m.json", "--mat", dir / "m.mat"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::vector<MatVariable> v = read_mat_file(dir / "m.mat");
  EXPECT_EQ(variable(v, "A").values, f.model.A);
  EXPECT_EQ(variable(v, "B").values, f.model.B);
  EXPECT_EQ(variable(v, "C").values, f.model.C);
  EXPECT_EQ(variable(v, "D").values, f.model.D);
  EXPECT_EQ(variable(v, "K").values, f.K);
  EXPECT_EQ(variable(v, "x0").values, Eigen::MatrixXd(f.x0));
  EXPECT_EQ(variable(v, "Ts").values(0, 0), f.model.Ts);
  EXPECT_EQ(variable(v, "InputName").strings, std::vector<std::string>{"force"});
  EXPECT_EQ(variable(v, "OutputName").strings, std::vector<std::string>{"acc"});

  // An existing file is kept unless --force; a bad model file is bad input (exit 2).
  const CliResult again = run_cli({"export", dir / "m.json", "--mat", dir / "m.mat"});
  EXPECT_NE(again.exit_code, 0);
  EXPECT_NE(again.err.find("--force"), std::string::npos) << describe(again);
  EXPECT_EQ(run_cli({"export", dir / "m.json", "--mat", dir / "m.mat", "--force"}).exit_code, 0);
  {
    std::ofstream bad(dir / "bad.json");
    bad << "{\"Ts\": 0.1, \"A\": [[1]]}\n";
  }
  const CliResult bad = run_cli({"export", dir / "bad.json", "--mat", dir / "bad.mat"});
  EXPECT_EQ(bad.exit_code, 2) << describe(bad);
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.mat"));
}

}  // namespace test_app_export
