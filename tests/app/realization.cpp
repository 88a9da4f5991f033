// End-to-end: the isolator path on the bundled 8x8 log: sysid okid -> era ->
// compare, one experiment per input via lms -> era -> assemble, then hsv and
// reduce with their error figures; bad requests exit 2 and write nothing.
#include <sysid/io/model_json.hpp>

#include <gtest/gtest.h>

#include <filesystem>

#include "run_cli.hpp"

namespace test_app_realization {

using namespace sysid;
using namespace sysid::test;

namespace {
const std::string kData = SYSID_TEST_DATA_DIR;
const std::string kInputs = "u1,u2,u3,u4,u5,u6,u7,u8", kOutputs = "y1,y2,y3,y4,y5,y6,y7,y8";
}  // namespace

TEST(RealizationApp, OkidEraRecoversTheIsolatorModel) {
  TempDir dir;
  const std::string markov = dir / "markov.json", model = dir / "era.json";
  const CliResult o = run_cli({"okid", kData + "/avi8x8.csv", "--inputs", kInputs, "--outputs", kOutputs, "--observer-order", "10",
                               "--out", markov});
  ASSERT_EQ(o.exit_code, 0) << describe(o);
  const CliResult e = run_cli({"era", markov, "--order", "16", "--out", model});
  ASSERT_EQ(e.exit_code, 0) << describe(e);
  const CliResult c = run_cli({"compare", model, kData + "/avi8x8_val.csv", "--inputs", kInputs, "--outputs", kOutputs});
  ASSERT_EQ(c.exit_code, 0) << describe(c);
  // The true model reaches about 99 % on this log (1 % output noise).
  for (int i = 1; i <= 8; ++i) EXPECT_GT(fit_after(c.out, "fit [%]", "y" + std::to_string(i)), 97.0) << c.out;
}

TEST(RealizationApp, LmsPerInputAssembleHsvAndReduce) {
  TempDir dir;
  std::vector<std::string> parts;
  for (int j = 1; j <= 2; ++j) {
    const std::string fir = dir / ("fir" + std::to_string(j) + ".json"), part = dir / ("m" + std::to_string(j) + ".json");
    const CliResult l = run_cli({"lms", kData + "/avi8x8.csv", "--inputs", "u" + std::to_string(j), "--outputs", kOutputs, "--taps",
                                 "128", "--steps", "3", "--gamma", "0.5,0.3,0.2", "--mu", "1.0", "--out", fir});
    ASSERT_EQ(l.exit_code, 0) << describe(l);
    const CliResult e = run_cli({"era", fir, "--order", "16", "--out", part});
    ASSERT_EQ(e.exit_code, 0) << describe(e);
    parts.push_back(part);
  }
  const std::string all = dir / "all.json";
  const CliResult a = run_cli({"assemble", parts[0], parts[1], "--out", all});
  ASSERT_EQ(a.exit_code, 0) << describe(a);
  const ModelFile assembled = read_model_json(all);
  EXPECT_EQ(assembled.model.order(), 32);
  EXPECT_EQ(assembled.model.inputs(), 2);
  EXPECT_EQ(assembled.model.outputs(), 8);

  const CliResult h = run_cli({"hsv", all});
  ASSERT_EQ(h.exit_code, 0) << describe(h);
  EXPECT_NE(h.out.find("ratio if cut"), std::string::npos) << h.out;

  const std::string reduced = dir / "reduced.json";
  const CliResult r = run_cli({"reduce", all, "--max-error", "2%", "--out", reduced});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const double ratio = number_after(r.out, "discarded HSV ratio");
  EXPECT_LE(ratio, 0.02) << r.out;
  const double bound = number_after(r.out, "H-inf bound 2*sum(discarded HSV) =");
  // "H-inf error (grid of N points) E at F Hz": the measured error never exceeds the bound.
  const std::string after = r.out.substr(r.out.find("points)") + 7);
  const double measured = std::stod(after);
  EXPECT_LE(measured, bound * (1.0 + 1e-6)) << r.out;
  const ModelFile small = read_model_json(reduced);
  EXPECT_LT(small.model.order(), 32);
  EXPECT_GT(bound, 0.0);
  EXPECT_EQ(small.provenance["order"].get<int>(), small.model.order());
}

TEST(RealizationApp, BadRequestsExitTwoAndWriteNothing) {
  TempDir dir;
  const std::string out = dir / "out.json";
  const std::string model = kData + "/avi8x8_true.json";
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"reduce", model, "--order", "4", "--max-error", "2%", "--out", out},
           {"reduce", model, "--max-error", "abc", "--out", out},
           {"reduce", model, "--max-error", "150%", "--out", out},
           {"lms", kData + "/avi8x8.csv", "--inputs", "u1", "--outputs", "y1", "--steps", "3", "--gamma", "0.5,0.6,0.2", "--out", out},
           {"era", model, "--order", "4", "--out", out},
           {"assemble", model, model, "--out", out}}) {
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << describe(r);
    EXPECT_FALSE(r.err.empty());
    EXPECT_FALSE(std::filesystem::exists(out)) << args[0];
  }
}

}  // namespace test_app_realization
