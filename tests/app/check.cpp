// End-to-end: sysid check on the bundled Par2 log and on hand-made bad logs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <string>

#include "run_cli.hpp"

namespace test_app_check {

using namespace sysid::test;

namespace {

const std::string kData = std::string(SYSID_TEST_DATA_DIR) + "/";

}  // namespace

TEST(CheckApp, Par2ChirpLogReportsEveryPart) {
  const CliResult r = run_cli({"check", kData + "par2_gu.csv", "--inputs", "u", "--outputs", "y"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  for (const char* part : {"excitation order", "SNR", "feedback test", "sampling: median step", "findings"})
    EXPECT_TRUE(contains(r.out, part)) << part << "\n" << r.out;
  EXPECT_FALSE(contains(r.out, "LIKELY FEEDBACK")) << r.out;  // an open-loop chirp experiment
  EXPECT_TRUE(contains(r.out, "excitation order 60")) << r.out;  // a chirp excites every order
  EXPECT_TRUE(contains(r.out, "findings: none")) << r.out;
}

TEST(CheckApp, OpenLoopEightByEightMultisineLogHasNoClosedLoopWarning) {
  // Eight independent random-phase multisines (2-450 Hz at 1024 Hz) into the 8x8
  // isolator-like structure: 64 pairs, 25 lags each, all open loop.
  const CliResult r = run_cli({"check", kData + "avi8x8.csv", "--inputs", "u1,u2,u3,u4,u5,u6,u7,u8", "--outputs",
                               "y1,y2,y3,y4,y5,y6,y7,y8"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.out, "feedback test")) << r.out;
  EXPECT_FALSE(contains(r.out, "LIKELY FEEDBACK")) << r.out;
  EXPECT_FALSE(contains(r.out, "closed-loop")) << r.out;
}

/// A 7 Hz sine log at 1 kHz, 6 000 samples; with `gap`, ten samples lost in the middle.
void write_sine_log(const std::string& path, bool gap) {
  std::ofstream f(path);
  f << "t,u,y\n" << std::setprecision(17);
  double t = 0.0;
  for (int k = 0; k < 6000; ++k) {
    if (gap && k == 3000) t += 0.01;
    f << t << "," << std::sin(2.0 * M_PI * 7.0 * t) << "," << 0.5 * std::sin(2.0 * M_PI * 7.0 * t - 0.3) + 1e-3 * std::sin(1.7 * k)
      << "\n";
    t += 0.001;
  }
}

TEST(CheckApp, SingleSineLogIsNotPersistentlyExciting) {
  TempDir tmp;
  write_sine_log(tmp / "sine.csv", false);
  const CliResult r = run_cli({"check", tmp / "sine.csv", "--inputs", "u", "--outputs", "y"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.out, "persistently exciting of order 2")) << r.out;
  EXPECT_TRUE(contains(r.out, "gaps 0")) << r.out;
}

TEST(CheckApp, LostSamplesAreReportedAsAGap) {
  TempDir tmp;
  write_sine_log(tmp / "gap.csv", true);
  const CliResult r = run_cli({"check", tmp / "gap.csv", "--inputs", "u", "--outputs", "y"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_TRUE(contains(r.out, "1 gap(s)")) << r.out;
}

TEST(CheckApp, MissingColumnIsAUsageErrorNamingIt) {
  const CliResult r = run_cli({"check", kData + "par2_gu.csv", "--inputs", "nope", "--outputs", "y"});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_TRUE(contains(r.err, "nope")) << r.err;
}

}  // namespace test_app_check
