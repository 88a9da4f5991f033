// sysid assemble --disturbance: the Par2 paper's complete model (Fig. 4), the piezo
// path G_U identified from its chirp log and the disturbance G_W as an ARMA model
// of the stop-point record, joined into one model with inputs [u, w]: w enters as
// unit-variance white noise through the ARMA model's innovation form.
#include <gtest/gtest.h>

#include <cmath>

#include "run_cli.hpp"

namespace test_app_assemble {

using namespace sysid::test;

namespace {
const std::string kData = SYSID_TEST_DATA_DIR;
}

TEST(AssembleDisturbance, GeneralisedPlantHasThePlantAndTheUnitNoiseDisturbanceInputs) {
  TempDir dir;
  const std::string gu = (dir.path() / "gu.json").string(), gw = (dir.path() / "gw.json").string(),
                    gp = (dir.path() / "gp.json").string();
  ASSERT_EQ(run_cli({"n4sid", kData + "/par2_gu.csv", "--inputs", "u", "--outputs", "y", "--order", "10", "--out", gu}).exit_code, 0);
  ASSERT_EQ(run_cli({"arma", kData + "/par2_gw.csv", "--outputs", "y", "--na", "4", "--nc", "4", "--out", gw}).exit_code, 0);
  const CliResult r = run_cli({"assemble", gu, "--disturbance", gw, "--out", gp});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json plant = read_json(gp), noise = read_json(gw);
  EXPECT_EQ(plant["inputs"], nlohmann::json({"u", "w_y"}));
  EXPECT_EQ(plant["A"].size(), 14u);  // 10 + the ARMA(4,4) innovation form's 4
  // D's w column is the innovation's standard deviation: w has unit variance.
  const double lambda = noise["state_space"]["noise_covariance"][0][0].get<double>();
  EXPECT_NEAR(plant["D"][0][1].get<double>(), std::sqrt(lambda), 1e-12 * std::sqrt(lambda));
  EXPECT_EQ(plant["provenance"]["disturbance"], gw);
}

TEST(AssembleDisturbance, AModelWithoutNoiseDescriptionOrWithInputsIsBadInput) {
  TempDir dir;
  const std::string gu = (dir.path() / "gu.json").string(), gw = (dir.path() / "gw.json").string(),
                    gp = (dir.path() / "gp.json").string();
  ASSERT_EQ(run_cli({"n4sid", kData + "/par2_gu.csv", "--inputs", "u", "--outputs", "y", "--order", "4", "--out", gu}).exit_code, 0);
  ASSERT_EQ(run_cli({"ar", kData + "/par2_gw.csv", "--outputs", "y", "--na", "4", "--out", gw}).exit_code, 0);
  nlohmann::json stripped = read_json(gw);
  stripped["state_space"].erase("K");
  const std::string bad = (dir.path() / "no_noise.json").string();
  write_text_file(bad, stripped.dump());
  CliResult r = run_cli({"assemble", gu, "--disturbance", bad, "--out", gp});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.err, "no_noise.json") && contains(r.err, "Kalman gain")) << r.err;
  r = run_cli({"assemble", gu, "--disturbance", gu, "--out", gp});  // a plant is not a disturbance model
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(contains(r.err, "time-series model")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(gp));
}

}  // namespace test_app_assemble
