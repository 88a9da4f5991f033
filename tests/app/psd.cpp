// End-to-end: sysid psd of white noise sits at the theoretical level, inside its
// confidence bounds, with the documented columns; --model scores the spectrum a
// model predicts (input part and disturbance part) against the estimate.
#include <sysid/core/simulate.hpp>

#include <gtest/gtest.h>

#include <filesystem>

#include "run_cli.hpp"

namespace test_app_psd {

using namespace sysid;
using namespace sysid::test;

TEST(PsdApp, WhiteNoiseLevelWithinItsBounds) {
  TempDir dir;
  const Eigen::Index n = 100000;
  const double fs = 1000.0, sigma = 2.0;
  Eigen::MatrixXd table(n, 3);
  table << Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) / fs, white_noise(n, 2, 5, sigma);
  write_csv(dir / "log.csv", {"t", "a", "b"}, table);
  const CliResult r = run_cli({"psd", dir / "log.csv", "--columns", "a,b", "--nfft", "1024", "--out", dir / "psd.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const CsvTable t = read_csv(dir / "psd.csv");
  ASSERT_EQ(t.names, (std::vector<std::string>{"f_hz", "psd_a", "psd_lo_a", "psd_hi_a", "psd_b", "psd_lo_b", "psd_hi_b"}));
  ASSERT_EQ(t.values.rows(), 513);
  // One-sided density of white noise: 2 sigma^2 / fs = 0.008 units^2/Hz.
  const double level = 2.0 * sigma * sigma / fs;
  for (const Eigen::Index c : {Eigen::Index{1}, Eigen::Index{4}}) {
    int inside = 0, bins = 0;
    double mean = 0.0;
    for (Eigen::Index k = 1; k < t.values.rows() - 1; ++k) {
      ++bins;
      mean += t.values(k, c);
      if (level >= t.values(k, c + 1) && level <= t.values(k, c + 2)) ++inside;
    }
    mean /= bins;
    // 511 bins of ~195 segments (nu ~ 350 each): the average over bins has a relative
    // standard deviation ~ sqrt(2 / 350 / 511) ~ 0.3 %; 2 % is > 5 sigma.
    EXPECT_NEAR(mean, level, 0.02 * level) << c;
    // 95 % bounds: ~5 % of the bins outside, binomial sd ~1 %; require >= 90 % inside.
    EXPECT_GE(inside, static_cast<int>(0.9 * bins)) << inside << " of " << bins;
  }
  EXPECT_NE(r.out.find("a: RMS from the PSD 2"), std::string::npos) << r.out;  // 1.99.. or 2.0..
}

TEST(PsdApp, OutputsIsAnAliasAndBadInputLeavesNoFile) {
  TempDir dir;
  const Eigen::Index n = 500;
  Eigen::MatrixXd table(n, 2);
  table << Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) * 0.01, white_noise(n, 1, 1, 1.0);
  write_csv(dir / "log.csv", {"t", "y"}, table);
  const std::string out = dir / "psd.csv";
  CliResult r = run_cli({"psd", dir / "log.csv", "--outputs", "y", "--nfft", "128", "--out", out});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_EQ(read_csv(out).values.rows(), 65);
  std::filesystem::remove(out);
  r = run_cli({"psd", dir / "log.csv", "--columns", "z", "--out", out});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_FALSE(std::filesystem::exists(out));
  r = run_cli({"psd", dir / "log.csv", "--columns", "y", "--window", "kaiser", "--out", out});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  r = run_cli({"psd", dir / "log.csv", "--columns", "y"});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_FALSE(std::filesystem::exists(out));
  r = run_cli({"psd", "--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("Example"), std::string::npos);
}

TEST(PsdApp, ModelSpectrumOfTheTrueModelSitsOnTheEstimate) {
  TempDir dir;
  // y = G u + H e: the four-mode plant driven by white u, plus a coloured disturbance
  // (K) small enough that the input part dominates below 200 Hz.
  const StateSpace plant = four_mode_plant();
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(4, 1);
  K << 0.05, 0.02, -0.03, 0.04;
  const Eigen::Index n = 60000;
  const Eigen::MatrixXd u = white_noise(n, 1, 3, 1.0), e = white_noise(n, 1, 4, 0.05);
  Eigen::MatrixXd ue(n, 2);
  ue << u, e;
  const StateSpace with_noise(plant.A, (Eigen::MatrixXd(4, 2) << plant.B, K).finished(), plant.C,
                              (Eigen::MatrixXd(1, 2) << plant.D, 1.0).finished(), plant.Ts);
  const Eigen::MatrixXd y = simulate(with_noise, ue);
  Eigen::MatrixXd table(n, 3);
  table << Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) * plant.Ts, u, y;
  write_csv(dir / "log.csv", {"t", "u", "y"}, table);
  ModelFile f;
  f.model = plant;
  f.K = K;
  f.noise_covariance = Eigen::MatrixXd::Constant(1, 1, 0.05 * 0.05);
  write_model_json(dir / "true.json", f);
  // The same plant without its input part would be far below the estimate: the
  // disturbance-only model (the plant's K and noise, no inputs).
  ModelFile noise_only = f;
  noise_only.model = StateSpace(plant.A, Eigen::MatrixXd::Zero(4, 0), plant.C, Eigen::MatrixXd::Zero(1, 0), plant.Ts);
  noise_only.model.output_names = {"y"};
  write_model_json(dir / "noise.json", noise_only);

  const CliResult r = run_cli({"psd", dir / "log.csv", "--columns", "y", "--nfft", "1024", "--model", dir / "true.json",
                               "--model", dir / "noise.json", "--band", "1:400", "--out", dir / "psd.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const CsvTable t = read_csv(dir / "psd.csv");
  ASSERT_EQ(t.names, (std::vector<std::string>{"f_hz", "psd_y", "psd_lo_y", "psd_hi_y", "psd_model1_y", "psd_model2_y"}));
  const std::string true_line = r.out.substr(r.out.find("model1 ("));
  EXPECT_LT(std::abs(number_after(true_line, "level ")), 0.3) << r.out;
  EXPECT_LT(number_after(true_line, "shape "), 0.6) << r.out;
  EXPECT_GT(number_after(true_line.substr(true_line.find("shape ")), "dB, "), 85.0) << r.out;  // % of bins inside
  const std::string noise_line = r.out.substr(r.out.find("model2 ("));
  EXPECT_LT(number_after(noise_line, "level "), -10.0) << r.out;
}

TEST(PsdApp, ModelWithoutASpectrumOrItsChannelsIsRefused) {
  TempDir dir;
  const Eigen::Index n = 4000;
  Eigen::MatrixXd table(n, 3);
  table << Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) * 0.001, white_noise(n, 2, 9, 1.0);
  write_csv(dir / "log.csv", {"t", "u", "y"}, table);
  // An input-free model with no disturbance model has no spectrum.
  StateSpace empty(Eigen::MatrixXd::Constant(1, 1, 0.5), Eigen::MatrixXd::Zero(1, 0), Eigen::MatrixXd::Ones(1, 1),
                   Eigen::MatrixXd::Zero(1, 0), 0.001);
  empty.output_names = {"y"};
  write_model(dir / "empty.json", empty);
  const std::string out = dir / "psd.csv";
  CliResult r = run_cli({"psd", dir / "log.csv", "--columns", "y", "--model", dir / "empty.json", "--out", out});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_NE(r.err.find("disturbance model"), std::string::npos) << r.err;
  // The model's output is not among the analysed columns.
  write_model(dir / "plant.json", four_mode_plant());
  r = run_cli({"psd", dir / "log.csv", "--columns", "u", "--model", dir / "plant.json", "--out", out});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_NE(r.err.find("none of the model's outputs"), std::string::npos) << r.err;
  // The model's input is not in the log.
  StateSpace other = four_mode_plant();
  other.input_names = {"force"};
  write_model(dir / "other.json", other);
  r = run_cli({"psd", dir / "log.csv", "--columns", "y", "--model", dir / "other.json", "--out", out});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  // A model spectrum is a density.
  r = run_cli({"psd", dir / "log.csv", "--columns", "y", "--model", dir / "plant.json", "--scaling", "spectrum", "--out", out});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
  EXPECT_FALSE(std::filesystem::exists(out));
  // A plant without K: the input part alone, with a warning.
  r = run_cli({"psd", dir / "log.csv", "--columns", "y", "--model", dir / "plant.json", "--out", out});
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.err.find("input part"), std::string::npos) << r.err;
}

}  // namespace test_app_psd
