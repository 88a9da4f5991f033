// End-to-end: sysid filter applies the designed Butterworth filter (causal or
// zero-phase), detrends and decimates, keeps the other columns and the time
// column, and leaves no file on bad input.
#include <sysid/signal/butterworth.hpp>
#include <sysid/signal/detrend.hpp>
#include <sysid/signal/resample.hpp>
#include <sysid/signal/sos_filter.hpp>

#include <gtest/gtest.h>

#include <filesystem>

#include "run_cli.hpp"

namespace test_app_filter {

using namespace sysid;
using namespace sysid::test;

namespace {

/// Par2-like log at 2 kHz: t, u, y, and an untouched column "temp".
CsvTable write_log(const std::string& path, Eigen::Index n) {
  Eigen::MatrixXd table(n, 4);
  table << Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) / 2000.0, white_noise(n, 3, 21, 1.0);
  write_csv(path, {"t", "u", "y", "temp"}, table);
  return read_csv(path);
}

}  // namespace

TEST(FilterApp, Par2LowPassIsTheDesignedCausalFilter) {
  TempDir dir;
  const CsvTable in = write_log(dir / "log.csv", 6000);
  const CliResult r = run_cli({"filter", dir / "log.csv", "--columns", "u,y", "--lowpass", "100", "--order", "5", "--out", dir / "lp.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const CsvTable out = read_csv(dir / "lp.csv");
  ASSERT_EQ(out.names, in.names);
  ASSERT_EQ(out.values.rows(), in.values.rows());
  EXPECT_EQ(out.values.col(0), in.values.col(0));  // time column kept bit for bit
  EXPECT_EQ(out.values.col(3), in.values.col(3));  // untouched column
  // The CSV round trip is exact, so the program's result equals the library's.
  const SecondOrderSections f = butterworth(5, BandType::lowpass, 100.0, 0.0, 2000.0);
  const Eigen::MatrixXd want = sos_filter(f, in.values.middleCols(1, 2));
  EXPECT_EQ(out.values.middleCols(1, 2), want);
  // And it is a low-pass: far less variance than the white input (power ~ 100/1000).
  EXPECT_LT(out.values.col(1).squaredNorm(), 0.15 * in.values.col(1).squaredNorm());
}

TEST(FilterApp, ZeroPhaseBandPassDetrendAndDecimate) {
  TempDir dir;
  const CsvTable in = write_log(dir / "log.csv", 4001);
  CliResult r = run_cli({"filter", dir / "log.csv", "--columns", "y", "--bandpass", "20:200", "--order", "3", "--zero-phase",
                         "--out", dir / "bp.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const CsvTable bp = read_csv(dir / "bp.csv");
  const SecondOrderSections f = butterworth(3, BandType::bandpass, 20.0, 200.0, 2000.0);
  EXPECT_EQ(bp.values.col(2), filtfilt(f, in.values.col(2)));
  EXPECT_EQ(bp.values.col(1), in.values.col(1));

  // Default columns: all but t. Linear detrend, then decimation by 4.
  r = run_cli({"filter", dir / "log.csv", "--detrend", "linear", "--decimate", "4", "--out", dir / "dec.csv"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const CsvTable dec = read_csv(dir / "dec.csv");
  ASSERT_EQ(dec.values.rows(), 1001);  // ceil(4001 / 4)
  for (Eigen::Index k = 0; k < dec.values.rows(); ++k) ASSERT_EQ(dec.values(k, 0), in.values(4 * k, 0));
  const Eigen::MatrixXd want = decimate(detrend(Eigen::MatrixXd(in.values.rightCols(3)), TrendType::linear), 4);
  // Equal up to the rounding of Eigen's product kernels (which may differ between
  // the program's and this test's memory layouts): values are O(1).
  EXPECT_LT((dec.values.rightCols(3) - want).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(FilterApp, BadInputAndUsage) {
  TempDir dir;
  write_log(dir / "log.csv", 500);
  const std::string out = dir / "f.csv";
  // Missing column, cutoff above Nyquist: bad data (exit 2), no file.
  for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
           {"filter", dir / "log.csv", "--columns", "nope", "--lowpass", "100", "--out", out},
           {"filter", dir / "log.csv", "--columns", "u", "--lowpass", "1500", "--out", out},
           {"filter", dir / "log.csv", "--columns", "u", "--lowpass", "100", "--out", dir / "log.csv"},
       }) {
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << describe(r);
    EXPECT_FALSE(std::filesystem::exists(out));
  }
  // Usage: two band types, nothing to do, time column filtered, bad --bandpass.
  for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
           {"filter", dir / "log.csv", "--lowpass", "100", "--highpass", "10", "--out", out},
           {"filter", dir / "log.csv", "--out", out},
           {"filter", dir / "log.csv", "--columns", "t", "--lowpass", "100", "--out", out},
           {"filter", dir / "log.csv", "--bandpass", "200:20", "--out", out},
           {"filter", dir / "log.csv", "--zero-phase", "--detrend", "linear", "--out", out},
       }) {
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.exit_code, 1) << describe(r);
    EXPECT_FALSE(std::filesystem::exists(out));
  }
  const CliResult help = run_cli({"filter", "--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--lowpass 100 --order 5"), std::string::npos) << help.out;
}

}  // namespace test_app_filter
