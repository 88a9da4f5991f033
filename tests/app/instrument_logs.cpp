// End-to-end: logs as instruments write them (DESIGN.md "CSV logs"). The same
// record written as an acquisition system at 1024 Hz exports it (time stamps with
// 6 decimals, or 10 significant digits), with the time in milliseconds, and as a
// European-locale spreadsheet saves it (';' separators, decimal commas): every
// form gives the model the plain file gives, and the forms that cannot be read
// say why and what to do.
#include <sysid/io/model_json.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "run_cli.hpp"

namespace test_app_instrument_logs {

using namespace sysid::test;

constexpr double kRateHz = 1024.0;
constexpr int kSamples = 6000;

/// A 40 Hz resonance (damping 5 %) driven by white noise, sampled at 1024 Hz:
/// (t_k in seconds, u_k, y_k) rows.
struct Record {
  std::vector<double> u, y;
};

Record resonance_record() {
  const double wn = 2.0 * std::numbers::pi * 40.0, zeta = 0.05, ts = 1.0 / kRateHz;
  const double r = std::exp(-zeta * wn * ts), theta = wn * std::sqrt(1.0 - zeta * zeta) * ts;
  const double a1 = 2.0 * r * std::cos(theta), a2 = -r * r;
  const Eigen::MatrixXd u = white_noise(kSamples, 1, 11, 1.0), e = white_noise(kSamples, 1, 12, 1e-3);
  Record rec;
  rec.u.assign(u.data(), u.data() + kSamples);
  rec.y.assign(kSamples, 0.0);
  for (int k = 2; k < kSamples; ++k)
    rec.y[k] = a1 * rec.y[k - 1] + a2 * rec.y[k - 2] + rec.u[k - 1] + 0.5 * rec.u[k - 2];
  for (int k = 0; k < kSamples; ++k) rec.y[k] += e(k, 0);
  return rec;
}

/// The record as text: header `time_name;u;y` (with `sep`), the time printed with
/// printf `time_format` from t_k * `time_scale`, the signals with 9 significant
/// digits and the decimal mark `decimal`.
std::string record_text(const Record& rec, const std::string& time_name, const char* time_format, double time_scale,
                        char sep, char decimal) {
  std::string s = time_name + sep + "u" + sep + "y\n";
  char buf[96];
  for (int k = 0; k < kSamples; ++k) {
    const int n = std::snprintf(buf, sizeof buf, (std::string(time_format) + "%c%.9g%c%.9g\n").c_str(),
                                k / kRateHz * time_scale, sep, rec.u[k], sep, rec.y[k]);
    std::string line(buf, static_cast<std::size_t>(n));
    if (decimal == ',') std::replace(line.begin(), line.end(), '.', ',');
    s += line;
  }
  return s;
}

/// Poles of the model file at `path`, sorted.
std::vector<std::complex<double>> poles_of(const std::string& path) {
  const sysid::ModelFile f = sysid::read_model_json(path);
  const Eigen::VectorXcd p = Eigen::EigenSolver<Eigen::MatrixXd>(f.model.A).eigenvalues();
  std::vector<std::complex<double>> v(p.data(), p.data() + p.size());
  std::sort(v.begin(), v.end(), [](auto a, auto b) { return a.imag() != b.imag() ? a.imag() < b.imag() : a.real() < b.real(); });
  return v;
}

class InstrumentLogs : public ::testing::Test {
 protected:
  TempDir tmp;
  Record rec = resonance_record();

  /// Writes `text` as `name`, runs n4sid (order 2) on it with `extra` options;
  /// returns the result and leaves the model in name + ".json".
  CliResult identify(const std::string& name, const std::string& text, const std::vector<std::string>& extra = {}) {
    write_text_file(tmp / name, text);
    std::vector<std::string> args{"n4sid", tmp / name, "--inputs", "u", "--outputs", "y", "--order", "2", "--out",
                                  tmp / (name + ".json")};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_cli(args);
  }

  /// The model identified from `name` has the plain file's poles and sample time.
  void expect_same_model(const std::string& name, double pole_tolerance) {
    const auto reference = poles_of(tmp / "plain.csv.json"), poles = poles_of(tmp / (name + ".json"));
    ASSERT_EQ(poles.size(), reference.size());
    for (std::size_t k = 0; k < poles.size(); ++k) EXPECT_LT(std::abs(poles[k] - reference[k]), pole_tolerance) << name;
    EXPECT_NEAR(sysid::read_model_json(tmp / (name + ".json")).model.Ts * kRateHz, 1.0, 1e-6) << name;
  }

  void SetUp() override {
    const CliResult r = identify("plain.csv", record_text(rec, "t", "%.17g", 1.0, ',', '.'));
    ASSERT_EQ(r.exit_code, 0) << describe(r);
  }
};

TEST_F(InstrumentLogs, RoundedTimeStampsGiveTheSameModel) {
  for (const char* format : {"%.6f", "%.10g"}) {
    const std::string name = std::string("rounded") + (format[2] == '6' ? "6" : "10") + ".csv";
    const CliResult r = identify(name, record_text(rec, "t", format, 1.0, ',', '.'));
    ASSERT_EQ(r.exit_code, 0) << format << ": " << describe(r);
    expect_same_model(name, 1e-6);
  }
}

TEST_F(InstrumentLogs, MillisecondTimeColumnByNameOrOption) {
  CliResult r = identify("named.csv", record_text(rec, "t_ms", "%.6f", 1e3, ',', '.'), {"--time-column", "t_ms"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  expect_same_model("named.csv", 1e-6);
  r = identify("told.csv", record_text(rec, "t", "%.6f", 1e3, ',', '.'), {"--time-unit", "ms"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  expect_same_model("told.csv", 1e-6);
  // Milliseconds taken for seconds are caught where the user gave the sample time.
  r = identify("untold.csv", record_text(rec, "t", "%.6f", 1e3, ',', '.'), {"--ts", "0.0009765625"});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_NE(r.err.find("give --time-unit"), std::string::npos) << r.err;
}

TEST_F(InstrumentLogs, SemicolonsAndDecimalCommasAreReadDetectedOrTold) {
  const std::string text = record_text(rec, "t", "%.6f", 1.0, ';', ',');
  CliResult r = identify("european.csv", text);
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  expect_same_model("european.csv", 1e-6);
  r = identify("european_told.csv", text, {"--delimiter", ";", "--decimal", ","});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  expect_same_model("european_told.csv", 1e-6);
  // Told the wrong layout: the error names the cell and the likely cause.
  r = identify("european_wrong.csv", text, {"--decimal", "."});
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_NE(r.err.find("european_wrong.csv:2:1: expected a number, found '0,000000' (a decimal comma?"), std::string::npos)
      << r.err;
  r = identify("comma_comma.csv", text, {"--delimiter", ",", "--decimal", ","});
  EXPECT_EQ(r.exit_code, 1) << describe(r);
}

TEST_F(InstrumentLogs, ALostSampleInRoundedStampsIsNamedWithItsLine) {
  std::string text = record_text(rec, "t", "%.6f", 1.0, ',', '.');
  // Drop the data row of sample 3000 (file line 3002).
  std::size_t start = 0;
  for (int line = 1; line < 3002; ++line) start = text.find('\n', start) + 1;
  text.erase(start, text.find('\n', start) + 1 - start);
  const CliResult r = identify("lost.csv", text);
  EXPECT_EQ(r.exit_code, 2) << describe(r);
  EXPECT_NE(r.err.find("lost.csv:3002:1: non-uniform time stamps"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(a lost or repeated sample, or a gap)"), std::string::npos) << r.err;
}

}  // namespace test_app_instrument_logs
