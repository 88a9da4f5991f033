// End-to-end: sysid excite writes every signal type with the right length,
// column names, sample times and amplitude.
#include <gtest/gtest.h>

#include "run_cli.hpp"

namespace test_app_excite {

using namespace sysid;
using namespace sysid::test;

namespace {

CsvTable excite(const TempDir& dir, std::vector<std::string> args) {
  const std::string out = dir / "u.csv";
  args.insert(args.begin(), "excite");
  args.insert(args.end(), {"--out", out, "--force"});  // tests call it repeatedly in one directory
  const CliResult r = run_cli(args);
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  return read_csv(out);
}

void expect_time_column(const CsvTable& t, double fs) {
  ASSERT_EQ(t.names.front(), "t");
  for (Eigen::Index k = 0; k < t.values.rows(); ++k)
    ASSERT_DOUBLE_EQ(t.values(k, 0), static_cast<double>(k) / fs) << k;
}

}  // namespace

TEST(ExciteApp, LinearChirp) {
  TempDir dir;
  const CsvTable t = excite(dir, {"--signal", "chirp", "--fs", "1000", "--band", "1:100", "--samples", "5000", "--amplitude", "2"});
  ASSERT_EQ(t.names, (std::vector<std::string>{"t", "u"}));
  ASSERT_EQ(t.values.rows(), 5000);
  expect_time_column(t, 1000.0);
  const Eigen::VectorXd u = t.values.col(1);
  // Peak amplitude 2: never exceeded, and reached to within the sampling of the
  // sine (at <= 100 Hz and 1 kHz the largest sample of a cycle is >= 2 cos(pi/10)).
  EXPECT_LE(u.cwiseAbs().maxCoeff(), 2.0);
  EXPECT_GE(u.cwiseAbs().maxCoeff(), 2.0 * std::cos(std::numbers::pi / 10));
  EXPECT_EQ(u(0), 0.0);  // a sine sweep starts at 0 (no step)
}

TEST(ExciteApp, LogChirpByDuration) {
  TempDir dir;
  const CsvTable t = excite(dir, {"--signal", "logchirp", "--fs", "500", "--band", "0.5:50", "--duration", "3"});
  ASSERT_EQ(t.values.rows(), 1500);  // round(3 s * 500 Hz)
  expect_time_column(t, 500.0);
  EXPECT_LE(t.values.col(1).cwiseAbs().maxCoeff(), 1.0);  // default amplitude 1
  EXPECT_GT(t.values.col(1).cwiseAbs().maxCoeff(), 0.95);
}

TEST(ExciteApp, MultisineColumnsAreIndependentWithPeakAmplitude) {
  TempDir dir;
  const CsvTable t = excite(dir, {"--signal", "multisine", "--fs", "1000", "--band", "5:200", "--samples", "4096",
                                  "--inputs", "3", "--amplitude", "0.5", "--seed", "7"});
  ASSERT_EQ(t.names, (std::vector<std::string>{"t", "u1", "u2", "u3"}));
  ASSERT_EQ(t.values.rows(), 4096);
  expect_time_column(t, 1000.0);
  for (Eigen::Index c = 1; c <= 3; ++c) EXPECT_NEAR(t.values.col(c).cwiseAbs().maxCoeff(), 0.5, 1e-15) << c;
  // Independent random phases: sample correlation ~ N(0, 1/sqrt(K)) with K ~ 800 excited bins.
  const Eigen::MatrixXd x = t.values.rightCols(3);
  for (Eigen::Index a = 0; a < 3; ++a)
    for (Eigen::Index b = a + 1; b < 3; ++b) {
      const double corr = x.col(a).dot(x.col(b)) / (x.col(a).norm() * x.col(b).norm());
      EXPECT_LT(std::abs(corr), 0.2) << a << "," << b;
    }
  // The same seed reproduces the signal; another seed changes it.
  const CsvTable again = excite(dir, {"--signal", "multisine", "--fs", "1000", "--band", "5:200", "--samples", "4096",
                                      "--inputs", "3", "--amplitude", "0.5", "--seed", "7"});
  EXPECT_EQ(again.values, t.values);
  const CsvTable other = excite(dir, {"--signal", "multisine", "--fs", "1000", "--band", "5:200", "--samples", "4096",
                                      "--inputs", "3", "--amplitude", "0.5", "--seed", "8"});
  EXPECT_NE(other.values, t.values);
}

TEST(ExciteApp, MultisineCustomNames) {
  TempDir dir;
  const CsvTable t = excite(dir, {"--signal", "multisine", "--fs", "100", "--band", "1:20", "--samples", "300", "--inputs",
                                  "2", "--names", "force,torque"});
  EXPECT_EQ(t.names, (std::vector<std::string>{"t", "force", "torque"}));
}

TEST(ExciteApp, PrbsLevelsAndClockDivider) {
  TempDir dir;
  const CsvTable t = excite(dir, {"--signal", "prbs", "--fs", "1000", "--samples", "3000", "--amplitude", "1.5",
                                  "--prbs-bits", "7", "--clock-divider", "3"});
  ASSERT_EQ(t.names, (std::vector<std::string>{"t", "u"}));
  ASSERT_EQ(t.values.rows(), 3000);
  const Eigen::VectorXd u = t.values.col(1);
  for (Eigen::Index k = 0; k < u.size(); ++k) ASSERT_TRUE(u(k) == 1.5 || u(k) == -1.5) << k << ": " << u(k);
  // Each bit is held 3 samples: every run of equal values (except the last,
  // cut by the record end) has a length that is a multiple of 3.
  Eigen::Index run = 1;
  for (Eigen::Index k = 1; k < u.size(); ++k) {
    if (u(k) == u(k - 1)) {
      ++run;
    } else {
      EXPECT_EQ(run % 3, 0) << "run ending at " << k;
      run = 1;
    }
  }
  // Period (2^7 - 1) * 3 = 381 samples.
  EXPECT_EQ(u.segment(381, 1000), u.head(1000));
}

TEST(ExciteApp, PrbsBandChoosesTheClockDivider) {
  TempDir dir;
  const std::string out = dir / "u.csv";
  // 3 dB band of a PRBS ~ 0.443 fs / D: 100 Hz at 1 kHz gives D = 4.
  const CliResult r = run_cli({"excite", "--signal", "prbs", "--fs", "1000", "--band", "0:100", "--samples", "400", "--out", out});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.err.find("--clock-divider 4"), std::string::npos) << r.err;
}

TEST(ExciteApp, UsageErrors) {
  TempDir dir;
  const std::string out = dir / "u.csv";
  for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
           {"excite", "--signal", "chirp", "--fs", "1000", "--samples", "100", "--out", out},  // no --band
           {"excite", "--signal", "chirp", "--fs", "1000", "--band", "1:10", "--samples", "100", "--inputs", "2", "--out", out},
           {"excite", "--signal", "chirp", "--fs", "1000", "--band", "1:10", "--samples", "100", "--duration", "1", "--out", out},
           {"excite", "--signal", "noise", "--fs", "1000", "--band", "1:10", "--samples", "100", "--out", out},
           {"excite", "--signal", "chirp", "--fs", "1000", "--band", "10:1", "--samples", "100", "--out", out},
           {"excite", "--signal", "multisine", "--fs", "1000", "--band", "1:10", "--samples", "100", "--inputs", "2",
            "--names", "a", "--out", out},
       }) {
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 1) << describe(r);
    EXPECT_FALSE(std::filesystem::exists(out));
  }
  // A band above Nyquist is bad data for the generator (its precondition): exit 2.
  const CliResult r = run_cli({"excite", "--signal", "chirp", "--fs", "100", "--band", "1:80", "--samples", "100", "--out", out});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_NE(r.err.find("fs/2"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(ExciteApp, HelpHasAnExample) {
  const CliResult r = run_cli({"excite", "--help"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.out.find("sysid excite --signal multisine"), std::string::npos) << r.out;
}

}  // namespace test_app_excite
