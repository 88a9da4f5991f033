// End-to-end: sysid psd of white noise sits at the theoretical level, inside its
// confidence bounds, with the documented columns.
#include <gtest/gtest.h>

#include <filesystem>

#include "run_cli.hpp"

using namespace sysid;
using namespace sysid::test;

TEST(PsdApp, WhiteNoiseLevelWithinItsBounds) {
  TempDir dir;
  const Eigen::Index n = 100000;
  const double fs = 1000.0, sigma = 2.0;
  Eigen::MatrixXd table(n, 3);
  table << Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) / fs, gaussian(n, 2, 5, sigma);
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
  table << Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) * 0.01, gaussian(n, 1, 1, 1.0);
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
