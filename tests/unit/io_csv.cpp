#include "sysid/io/csv.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <thread>

#include "sysid/core/errors.hpp"
#include "sysid/io/mapped_file.hpp"

namespace test_unit_io_csv {

namespace fs = std::filesystem;
using sysid::CsvTable;
using sysid::DataError;
using sysid::LogOptions;
using sysid::NanPolicy;

namespace {

constexpr double nan_v = std::numeric_limits<double>::quiet_NaN();
constexpr double inf_v = std::numeric_limits<double>::infinity();

/// Runs f, expects a DataError at exactly file:line:column whose message contains
/// `text`; returns the message for further checks.
std::string expect_data_error(const std::function<void()>& f, const std::string& file, long line, long column,
                              const std::string& text) {
  try {
    f();
  } catch (const DataError& e) {
    EXPECT_EQ(e.file(), file) << e.what();
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.column(), column) << e.what();
    EXPECT_NE(e.message().find(text), std::string::npos) << "message: " << e.what() << "\nexpected to contain: " << text;
    return e.message();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected DataError, got: " << e.what();
    return {};
  }
  ADD_FAILURE() << "expected DataError containing '" << text << "', nothing thrown";
  return {};
}

CsvTable parse(const std::string& text) { return sysid::read_csv_string(text, "mem.csv"); }

bool same_bits(double a, double b) {
  std::uint64_t x, y;
  std::memcpy(&x, &a, sizeof x);
  std::memcpy(&y, &b, sizeof y);
  return x == y;
}

/// A log t,u1,u2,y with t = k * ts for k = 0..n-1, u and y simple functions of k.
std::string make_log(int n, double ts, const std::function<double(int)>& t_of = {}) {
  std::string s = "t,u1,u2,y\n";
  char buf[128];
  for (int k = 0; k < n; ++k) {
    const double t = t_of ? t_of(k) : k * ts;
    std::snprintf(buf, sizeof buf, "%.9f,%d,%d,%d\n", t, k, 2 * k, 3 * k + 1);
    s += buf;
  }
  return s;
}

// ---- parsing ------------------------------------------------------------------

TEST(IoCsv, CommaFile) {
  const CsvTable t = parse("t,u,y\n0,1.5,-2\n0.5,2e3,+3\n");
  EXPECT_EQ(t.source, "mem.csv");
  ASSERT_EQ(t.names, (std::vector<std::string>{"t", "u", "y"}));
  ASSERT_EQ(t.values.rows(), 2);
  ASSERT_EQ(t.values.cols(), 3);
  EXPECT_EQ(t.values(0, 1), 1.5);
  EXPECT_EQ(t.values(0, 2), -2.0);
  EXPECT_EQ(t.values(1, 1), 2000.0);
  EXPECT_EQ(t.values(1, 2), 3.0);
  EXPECT_EQ(t.line_numbers, (std::vector<long>{2, 3}));
  EXPECT_EQ(t.header_line, 1);
  EXPECT_EQ(t.column("y"), 2);
  EXPECT_EQ(t.column("t"), 0);
  EXPECT_EQ(t.column("nope"), -1);
}

TEST(IoCsv, TabFileWithSpacesAroundFields) {
  const CsvTable t = parse("time\tu 1\ty\n 0\t 1 \t2\n1\t3\t4  \n");
  ASSERT_EQ(t.names, (std::vector<std::string>{"time", "u 1", "y"}));
  ASSERT_EQ(t.values.rows(), 2);
  EXPECT_EQ(t.values(0, 1), 1.0);
  EXPECT_EQ(t.values(1, 2), 4.0);
}

TEST(IoCsv, WhitespaceFile) {
  // Header aligned with spaces; data may mix spaces and tabs.
  const CsvTable t = parse("  t   u  y \n0 1   2\n \t 1\t\t3 4   \n");
  ASSERT_EQ(t.names, (std::vector<std::string>{"t", "u", "y"}));
  ASSERT_EQ(t.values.rows(), 2);
  EXPECT_EQ(t.values(1, 0), 1.0);
  EXPECT_EQ(t.values(1, 1), 3.0);
  EXPECT_EQ(t.values(1, 2), 4.0);
}

TEST(IoCsv, CommentsAndBlankLinesKeepFileLineNumbers) {
  const CsvTable t = parse("# recorded 2024\n\n  # rig 3\nt,y\n1,2\n\n# pause\n   \n3,4\n");
  EXPECT_EQ(t.header_line, 4);
  ASSERT_EQ(t.values.rows(), 2);
  EXPECT_EQ(t.line_numbers, (std::vector<long>{5, 9}));
  EXPECT_EQ(t.values(1, 1), 4.0);
}

TEST(IoCsv, CrlfBomAndNoFinalNewline) {
  const CsvTable t = parse("\xEF\xBB\xBFt,y\r\n0,1\r\n\r\n1,2");
  ASSERT_EQ(t.names, (std::vector<std::string>{"t", "y"}));  // BOM not part of the first name
  ASSERT_EQ(t.values.rows(), 2);
  EXPECT_EQ(t.values(1, 1), 2.0);
  EXPECT_EQ(t.line_numbers, (std::vector<long>{2, 4}));
}

TEST(IoCsv, QuotedHeaderNames) {
  const CsvTable t = parse("\"t\", \"u\" ,y\n0,1,2\n");
  EXPECT_EQ(t.names, (std::vector<std::string>{"t", "u", "y"}));
}

TEST(IoCsv, SpecialValuesAndEmptyCells) {
  const CsvTable t = parse("a,b,c,d,e\nnan,NaN,inf,-inf,Infinity\n,2,,4,\n1e-320,-0,.5,5.,1E+2\n");
  ASSERT_EQ(t.values.rows(), 3);
  EXPECT_TRUE(std::isnan(t.values(0, 0)));
  EXPECT_TRUE(std::isnan(t.values(0, 1)));
  EXPECT_EQ(t.values(0, 2), inf_v);
  EXPECT_EQ(t.values(0, 3), -inf_v);
  EXPECT_EQ(t.values(0, 4), inf_v);
  EXPECT_TRUE(std::isnan(t.values(1, 0)));  // empty first cell
  EXPECT_EQ(t.values(1, 1), 2.0);
  EXPECT_TRUE(std::isnan(t.values(1, 2)));  // empty middle cell
  EXPECT_TRUE(std::isnan(t.values(1, 4)));  // empty last cell
  EXPECT_EQ(t.values(2, 0), 1e-320);        // subnormal, exactly rounded
  EXPECT_TRUE(std::signbit(t.values(2, 1)));
  EXPECT_EQ(t.values(2, 2), 0.5);
  EXPECT_EQ(t.values(2, 3), 5.0);
  EXPECT_EQ(t.values(2, 4), 100.0);
}

TEST(IoCsv, NumbersAreCorrectlyRounded) {
  // Each is the shortest decimal of a double; strtod is the reference.
  const char* texts[] = {"0.1", "2.2250738585072014e-308", "1.7976931348623157e308", "4.9e-324", "0.30000000000000004",
                         "123456789012345678901234567890", "9007199254740993"};
  std::string csv = "x\n";
  for (const char* s : texts) csv += std::string(s) + "\n";
  const CsvTable t = parse(csv);
  for (std::size_t i = 0; i < std::size(texts); ++i)
    EXPECT_TRUE(same_bits(t.values(static_cast<Eigen::Index>(i), 0), std::strtod(texts[i], nullptr))) << texts[i];
}

TEST(IoCsv, NonNumberErrors) {
  expect_data_error([] { parse("t,u,y\n0,1,2\n0.1,abc,3\n"); }, "mem.csv", 3, 2, "expected a number, found 'abc'");
  expect_data_error([] { parse("t,u,y\n0,1, 2x \n"); }, "mem.csv", 2, 3, "expected a number, found '2x'");
  // A decimal comma where '.' was asked for is named as the likely cause.
  const sysid::CsvFormat dot_decimal{0, '.'};
  expect_data_error([&] { sysid::read_csv_string("t\tu\n0\t1,5\n", "mem.csv", dot_decimal); }, "mem.csv", 2, 2,
                    "found '1,5' (a decimal comma? give the decimal mark ','");
  expect_data_error([] { parse("t u\n0 0x1A\n"); }, "mem.csv", 2, 2, "found '0x1A'");
  expect_data_error([] { parse("a,b\n1.2.3,1\n"); }, "mem.csv", 2, 1, "found '1.2.3'");
  expect_data_error([] { parse("a,b\n1,+-1\n"); }, "mem.csv", 2, 2, "found '+-1'");
  expect_data_error([] { parse("a,b\n1,--1\n"); }, "mem.csv", 2, 2, "found '--1'");
  expect_data_error([] { parse("a,b\n1,1e\n"); }, "mem.csv", 2, 2, "found '1e'");
  expect_data_error([] { parse("a,b\n1,-\n"); }, "mem.csv", 2, 2, "found '-'");
  // Comments are whole-line only: a trailing comment is an error, not silently cut.
  expect_data_error([] { parse("a,b\n1,2 # note\n"); }, "mem.csv", 2, 2, "found '2 # note'");
  // A very long bad field is shortened in the message.
  const std::string msg = expect_data_error([] { parse("a\n" + std::string(500, 'z') + "\n"); }, "mem.csv", 2, 1,
                                            "expected a number");
  EXPECT_LT(msg.size(), 120u);
}

// ---- files as European locales and instruments write them --------------------

TEST(IoCsv, SemicolonFileWithDecimalCommasIsDetected) {
  const CsvTable t = parse("t;u;y\n0;1,5;-2,25e-1\n0,001;+3;4,0\n");
  ASSERT_EQ(t.names, (std::vector<std::string>{"t", "u", "y"}));
  EXPECT_EQ(t.values(0, 1), 1.5);
  EXPECT_EQ(t.values(0, 2), -0.225);
  EXPECT_EQ(t.values(1, 0), 0.001);
  EXPECT_EQ(t.values(1, 2), 4.0);
  // ';' with '.' decimals, and the decimal comma found on a later line (the first
  // data lines hold integers only).
  EXPECT_EQ(parse("a;b\n1;2.5\n").values(0, 1), 2.5);
  EXPECT_EQ(parse("a;b\n1;2\n# note\n3;4,5\n").values(1, 1), 4.5);
  // Tab- and whitespace-separated files with decimal commas.
  EXPECT_EQ(parse("a\tb\n1\t0,5\n").values(0, 1), 0.5);
  EXPECT_EQ(parse("a b\n1 0,5\n").values(0, 1), 0.5);
  // Comma files keep '.' whatever their content.
  EXPECT_EQ(parse("a,b\n1,2\n").values(0, 1), 2.0);
}

TEST(IoCsv, ExplicitLayoutAndItsErrors) {
  const sysid::CsvFormat semicolon_comma{';', ','};
  const CsvTable t = sysid::read_csv_string("a;b\n1;2,5\n", "mem.csv", semicolon_comma);
  EXPECT_EQ(t.values(0, 1), 2.5);
  // Read as comma-separated, a ';' row names that layout as the likely cause.
  const sysid::CsvFormat comma{',', 0};
  expect_data_error([&] { sysid::read_csv_string("t,u\n0;1,5\n", "mem.csv", comma); }, "mem.csv", 2, 1,
                    "found '0;1' (a ';'-separated file? give the delimiter ';'");
  EXPECT_THROW(sysid::read_csv_string("a;b\n1;2\n", "mem.csv", sysid::CsvFormat{',', ','}), std::invalid_argument);
  EXPECT_THROW(sysid::read_csv_string("a;b\n1;2\n", "mem.csv", sysid::CsvFormat{'|', 0}), std::invalid_argument);
  EXPECT_THROW(sysid::read_csv_string("a;b\n1;2\n", "mem.csv", sysid::CsvFormat{0, '_'}), std::invalid_argument);
}

TEST(IoCsv, WrongFieldCountErrors) {
  expect_data_error([] { parse("t,u,y\n0,1,2\n0.1,2\n"); }, "mem.csv", 3, 3, "expected 3 fields, found 2");
  expect_data_error([] { parse("t,u,y\n0,1,2,3\n"); }, "mem.csv", 2, 4, "expected 3 fields, found 4");
  expect_data_error([] { parse("t,u,y\n0,1,2,x,y\n"); }, "mem.csv", 2, 4, "expected 3 fields, found 5");
  expect_data_error([] { parse("t,u,y\n0,1,2,\n"); }, "mem.csv", 2, 4, "expected 3 fields, found 4");
  expect_data_error([] { parse("t\tu\ty\n0\t1\n"); }, "mem.csv", 2, 3, "expected 3 fields, found 2");
  expect_data_error([] { parse("t u y\n\n0 1\n"); }, "mem.csv", 3, 3, "expected 3 fields, found 2");
  expect_data_error([] { parse("t u y\n0 1 2 3 4\n"); }, "mem.csv", 2, 4, "expected 3 fields, found 5");
  expect_data_error([] { parse("t u y\n0 1 2 x\n"); }, "mem.csv", 2, 4, "expected 3 fields, found 4");
}

TEST(IoCsv, HeaderErrors) {
  expect_data_error([] { parse("t,u,t\n0,1,2\n"); }, "mem.csv", 1, 3, "duplicate column name 't'");
  expect_data_error([] { parse("# c\nt,,y\n0,1,2\n"); }, "mem.csv", 2, 2, "empty column name");
  expect_data_error([] { parse("0,1,2\n3,4,5\n"); }, "mem.csv", 1, 1, "expected a header row");
  expect_data_error([] { parse(""); }, "mem.csv", 0, 0, "empty file");
  expect_data_error([] { parse("\xEF\xBB\xBF# only a comment\r\n\r\n"); }, "mem.csv", 0, 0, "empty file");
  expect_data_error([] { parse("\n# c\nt,y\n\n# no data\n"); }, "mem.csv", 3, 0, "no data rows");
}

TEST(IoCsv, ReadFileAndMissingFile) {
  const fs::path p = fs::temp_directory_path() / ("sysid_io_csv_" + std::to_string(::getpid()) + ".csv");
  { std::ofstream(p) << "t,y\n0,1\n1,2\n"; }
  const CsvTable t = sysid::read_csv(p.string());
  EXPECT_EQ(t.source, p.string());
  EXPECT_EQ(t.values(1, 1), 2.0);
  fs::remove(p);
  expect_data_error([&] { sysid::read_csv(p.string()); }, p.string(), 0, 0, "No such file");
}

// ---- logs ---------------------------------------------------------------------

TEST(IoCsv, LogSelectsColumnsAndTsFromTimeColumn) {
  const CsvTable table = parse(make_log(200, 0.001));
  LogOptions o;
  o.inputs = {"u2", "u1"};
  o.outputs = {"y"};
  const sysid::IoData d = sysid::log_from_table(table, o);
  ASSERT_EQ(d.experiments.size(), 1u);
  EXPECT_EQ(d.experiments[0].source, "mem.csv");
  EXPECT_EQ(d.input_names, (std::vector<std::string>{"u2", "u1"}));
  EXPECT_EQ(d.output_names, (std::vector<std::string>{"y"}));
  ASSERT_EQ(d.experiments[0].u.rows(), 200);
  ASSERT_EQ(d.experiments[0].u.cols(), 2);
  EXPECT_EQ(d.experiments[0].u(10, 0), 20.0);
  EXPECT_EQ(d.experiments[0].u(10, 1), 10.0);
  EXPECT_EQ(d.experiments[0].y(199, 0), 598.0);
  // Time stamps are printed with 9 decimals, exact for k * 1e-3: Ts to rounding.
  EXPECT_NEAR(d.Ts, 0.001, 1e-15);
}

TEST(IoCsv, LogTsFromOptions) {
  const CsvTable table = parse("u,y\n1,2\n3,4\n5,6\n");
  LogOptions o;
  o.inputs = {"u"};
  o.outputs = {"y"};
  expect_data_error([&] { sysid::log_from_table(table, o); }, "mem.csv", 0, 0, "no time column 't' and no --ts given");
  o.ts = 0.01;
  const sysid::IoData d = sysid::log_from_table(table, o);
  EXPECT_EQ(d.Ts, 0.01);
  EXPECT_EQ(d.experiments[0].y(2, 0), 6.0);
  // Only outputs (time series) is fine too.
  o.inputs.clear();
  EXPECT_EQ(sysid::log_from_table(table, o).inputs(), 0);
}

TEST(IoCsv, LogTimeColumnAndTsMustAgree) {
  const CsvTable table = parse(make_log(50, 0.002));
  LogOptions o;
  o.outputs = {"y"};
  o.ts = 0.002;
  EXPECT_NEAR(sysid::log_from_table(table, o).Ts, 0.002, 1e-15);
  o.ts = 0.001;
  expect_data_error([&] { sysid::log_from_table(table, o); }, "mem.csv", 0, 0, "gives a sample time of 0.002 s");
  // An empty time_column name ignores the column: then ts is used as given.
  o.time_column = "";
  EXPECT_EQ(sysid::log_from_table(table, o).Ts, 0.001);
  // Another name for the time column.
  o.time_column = "u1";
  o.ts.reset();
  EXPECT_EQ(sysid::log_from_table(table, o).Ts, 1.0);
}

TEST(IoCsv, MissingColumnNamesHeaderLineAndAvailableColumns) {
  const CsvTable table = parse("# a comment\n# another\nt,u1,y\n0,1,2\n1,2,3\n");
  LogOptions o;
  o.inputs = {"u1"};
  o.outputs = {"y2"};
  expect_data_error([&] { sysid::log_from_table(table, o); }, "mem.csv", 3, 0, "no column 'y2'; the columns are: t, u1, y");
}

TEST(IoCsv, NonUniformTimeStamps) {
  // Row k sits on line k + 2; the step into row 55 (line 57) is 1.3 ms instead of
  // 1 ms. (Stamps such as 0.0553 could be printed with 4 decimals, rounded by up
  // to 0.05 ms each: a step of 1.1 ms would be within what such digits explain.)
  const CsvTable table = parse(make_log(100, 0.001, [](int k) { return k * 0.001 + (k >= 55 ? 0.0003 : 0.0); }));
  LogOptions o;
  o.outputs = {"y"};
  expect_data_error([&] { sysid::log_from_table(table, o); }, "mem.csv", 57, 1,
                    "non-uniform time stamps: step 0.0013 s at line 57, expected 0.001 s");
  // A looser tolerance accepts it (40 % of Ts).
  o.time_tolerance = 0.4;
  EXPECT_NO_THROW(sysid::log_from_table(table, o));
}

/// A log t,y at `rate_hz` whose time stamps are printed with printf `format`.
std::string printed_log(int n, double rate_hz, const char* format, const std::string& time_name = "t",
                        const std::function<int(int)>& sample_of = {}) {
  std::string s = time_name + ",y\n";
  char buf[64];
  for (int k = 0; k < n; ++k) {
    std::snprintf(buf, sizeof buf, format, (sample_of ? sample_of(k) : k) / rate_hz);
    s += std::string(buf) + "," + std::to_string(k % 7) + "\n";
  }
  return s;
}

TEST(IoCsv, TimeStampsRoundedAsInstrumentsPrintThem) {
  LogOptions o;
  o.outputs = {"y"};
  // 1024 Hz with 6 decimals: steps of 0.000976 and 0.000977 s for 0.0009765625 s.
  // Ts from the span: the end stamps' rounding (0.5 us each) over 4999 steps, 2e-7 relative at most.
  const sysid::IoData six = sysid::log_from_table(parse(printed_log(5000, 1024.0, "%.6f")), o);
  EXPECT_NEAR(six.Ts * 1024.0, 1.0, 2.1e-7);
  // 10 significant digits, over stamps from 0 to 30 s (the quantum grows tenfold at 1 s and 10 s).
  const sysid::IoData ten = sysid::log_from_table(parse(printed_log(30720, 1024.0, "%.10g")), o);
  EXPECT_NEAR(ten.Ts * 1024.0, 1.0, 1e-9);  // 5e-9 s at 30 s over 30719 steps: 2e-10
  // 4 decimals at 1024 Hz: stamps good to 5e-5 s, still far finer than a sample.
  EXPECT_NO_THROW(sysid::log_from_table(parse(printed_log(3000, 1024.0, "%.4f")), o));
  // --ts given with rounded stamps: they agree within what the digits explain.
  o.ts = 1.0 / 1024.0;
  EXPECT_NO_THROW(sysid::log_from_table(parse(printed_log(300, 1024.0, "%.6f")), o));
  o.ts.reset();
}

TEST(IoCsv, RoundedTimeStampsStillShowALostOrRepeatedSample) {
  LogOptions o;
  o.outputs = {"y"};
  // Sample 2000 lost (row k holds sample k + 1 from row 2000 on; row k is on line k + 2).
  const auto lost = [](int k) { return k < 2000 ? k : k + 1; };
  const std::string m =
      expect_data_error([&] { sysid::log_from_table(parse(printed_log(5000, 1024.0, "%.6f", "t", lost)), o); },
                        "mem.csv", 2002, 1, "non-uniform time stamps: step 0.00195");
  EXPECT_NE(m.find("at line 2002, expected 0.00097"), std::string::npos) << m;
  EXPECT_NE(m.find("(a lost or repeated sample, or a gap)"), std::string::npos) << m;
  const auto repeated = [](int k) { return k <= 2000 ? k : k - 1; };
  expect_data_error([&] { sysid::log_from_table(parse(printed_log(5000, 1024.0, "%.6f", "t", repeated)), o); },
                    "mem.csv", 2003, 1, "(a repeated sample; or stamps printed with too few digits");
  // A gap in integer stamps (ms at 1 kHz) is a gap, though the digits alone
  // would allow a rounding of half a unit.
  o.time_unit = sysid::TimeUnit::milliseconds;
  expect_data_error([&] { sysid::log_from_table(parse("t,y\n0,1\n1,2\n2,3\n4,4\n5,5\n"), o); }, "mem.csv", 5, 1,
                    "step 2 ms at line 5, expected 1 ms");
  o.time_unit.reset();
  // Printed so coarsely that the rounding could reach half a step (3 kHz with 4
  // decimals: steps of 0.0003 and 0.0004 s): the sampling cannot be checked.
  try {
    sysid::log_from_table(parse(printed_log(3000, 3000.0, "%.4f")), o);
    ADD_FAILURE() << "coarse time stamps accepted";
  } catch (const DataError& e) {
    EXPECT_NE(e.message().find("printed too coarsely to check the sampling"), std::string::npos) << e.what();
    EXPECT_NE(e.message().find("--ts and --time-column none"), std::string::npos) << e.what();
  }
}

TEST(IoCsv, TimeColumnInMillisecondsOrMicroseconds) {
  LogOptions o;
  o.outputs = {"y"};
  // Stamped in ms, named so: Ts in seconds.
  o.time_column = "t_ms";
  EXPECT_NEAR(sysid::log_from_table(parse(printed_log(100, 1.0, "%.0f", "t_ms")), o).Ts, 1e-3, 1e-15);
  // Named "t": seconds unless told.
  o.time_column = "t";
  const CsvTable ms = parse(printed_log(100, 1.0, "%.0f"));
  EXPECT_EQ(sysid::log_from_table(ms, o).Ts, 1.0);
  o.ts = 1e-3;
  expect_data_error([&] { sysid::log_from_table(ms, o); }, "mem.csv", 0, 0, "a time column in ms or us? give --time-unit");
  o.ts.reset();
  o.time_unit = sysid::TimeUnit::milliseconds;
  EXPECT_NEAR(sysid::log_from_table(ms, o).Ts, 1e-3, 1e-15);
  o.time_unit = sysid::TimeUnit::microseconds;
  EXPECT_NEAR(sysid::log_from_table(ms, o).Ts, 1e-6, 1e-21);
}

TEST(IoCsv, TimeUnitInTheColumnName) {
  using sysid::TimeUnit;
  EXPECT_EQ(sysid::time_unit_in_name("t_ms"), TimeUnit::milliseconds);
  EXPECT_EQ(sysid::time_unit_in_name("Time [ms]"), TimeUnit::milliseconds);
  EXPECT_EQ(sysid::time_unit_in_name("time (US)"), TimeUnit::microseconds);
  EXPECT_EQ(sysid::time_unit_in_name("t_\xC2\xB5s"), TimeUnit::microseconds);
  EXPECT_EQ(sysid::time_unit_in_name("time.s"), TimeUnit::seconds);
  EXPECT_EQ(sysid::time_unit_in_name("Zeit [s]"), TimeUnit::seconds);
  EXPECT_EQ(sysid::time_unit_in_name("t"), std::nullopt);
  EXPECT_EQ(sysid::time_unit_in_name("t_pos"), std::nullopt);
  EXPECT_EQ(sysid::time_unit_in_name("ms"), std::nullopt);  // a name, not a unit after one
  // The symbols themselves (--time-unit takes the same).
  EXPECT_EQ(sysid::time_unit_from_symbol("MS"), TimeUnit::milliseconds);
  EXPECT_EQ(sysid::time_unit_from_symbol("usec"), TimeUnit::microseconds);
  EXPECT_EQ(sysid::time_unit_from_symbol(""), std::nullopt);
  EXPECT_EQ(sysid::time_unit_from_symbol("min"), std::nullopt);
}

TEST(IoCsv, TimeStampsMustIncrease) {
  const CsvTable table = parse("t,y\n0,1\n1,2\n1,3\n2,4\n");
  LogOptions o;
  o.outputs = {"y"};
  expect_data_error([&] { sysid::log_from_table(table, o); }, "mem.csv", 4, 1, "time stamps not increasing");
  const CsvTable one = parse("t,y\n0,1\n");
  expect_data_error([&] { sysid::log_from_table(one, o); }, "mem.csv", 2, 1, "need at least 2 samples");
}

TEST(IoCsv, NanPolicyErrorNamesTheCell) {
  const CsvTable table = parse("t,u,y,junk\n0,1,2,nan\n1,2,,3\n2,3,4,5\n");
  LogOptions o;
  o.inputs = {"u"};
  o.outputs = {"y"};
  // The NaN in the unselected column "junk" (line 2) does not matter.
  expect_data_error([&] { sysid::log_from_table(table, o); }, "mem.csv", 3, 3, "NaN or empty cell in column 'y'");
  const CsvTable with_inf = parse("t,u,y\n0,1,2\n1,-inf,2\n");
  expect_data_error([&] { sysid::log_from_table(with_inf, o); }, "mem.csv", 3, 2, "Inf in column 'u'");
  const CsvTable nan_time = parse("t,u,y\n0,1,2\nnan,2,3\n2,3,4\n");
  expect_data_error([&] { sysid::log_from_table(nan_time, o); }, "mem.csv", 3, 1, "column 't'");
}

TEST(IoCsv, NanPolicyDropRowsTrimsEndsOnly) {
  const CsvTable table = parse("t,u,y\n0,nan,1\n0.5,1,\n1,2,3\n1.5,3,4\n2,4,5\n2.5,nan,nan\n");
  LogOptions o;
  o.inputs = {"u"};
  o.outputs = {"y"};
  o.nan_policy = NanPolicy::drop_rows;
  const sysid::IoData d = sysid::log_from_table(table, o);
  ASSERT_EQ(d.experiments[0].samples(), 3);
  EXPECT_EQ(d.experiments[0].u(0, 0), 2.0);
  EXPECT_EQ(d.experiments[0].y(2, 0), 5.0);
  EXPECT_EQ(d.Ts, 0.5);

  const CsvTable middle = parse("t,u,y\n0,1,1\n0.5,1,2\n1,nan,3\n1.5,3,4\n");
  expect_data_error([&] { sysid::log_from_table(middle, o); }, "mem.csv", 4, 2, "non-uniform");
  const CsvTable all_bad = parse("t,u,y\n0,nan,1\n0.5,nan,2\n");
  expect_data_error([&] { sysid::log_from_table(all_bad, o); }, "mem.csv", 0, 0, "every row");
}

TEST(IoCsv, NanPolicyDropRowsOnATimeSeries) {
  // No input column: trimming the rows must leave an N x 0 input matrix (found by
  // tests/fuzz: Eigen formed the row block of the empty matrix from a null pointer,
  // which the asan-ubsan preset reports as undefined behaviour).
  const CsvTable table = parse("t,y\n0,nan\n1,2\n2,3\n3,nan\n");
  LogOptions o;
  o.outputs = {"y"};
  o.nan_policy = NanPolicy::drop_rows;
  const sysid::IoData d = sysid::log_from_table(table, o);
  const auto& e = d.experiments[0];
  ASSERT_EQ(e.samples(), 2);
  EXPECT_EQ(e.u.rows(), 2);
  EXPECT_EQ(e.u.cols(), 0);
  EXPECT_EQ(e.y(0, 0), 2.0);
  EXPECT_EQ(e.y(1, 0), 3.0);
}

TEST(IoCsv, NanPolicyInterpolate) {
  const CsvTable table = parse("t,u,y\n0,0,10\n1,1,nan\n2,nan,nan\n3,3,40\n4,inf,50\n5,5,60\n");
  LogOptions o;
  o.inputs = {"u"};
  o.outputs = {"y"};
  o.nan_policy = NanPolicy::interpolate;
  const sysid::IoData d = sysid::log_from_table(table, o);
  const auto& e = d.experiments[0];
  ASSERT_EQ(e.samples(), 6);
  EXPECT_EQ(e.u(2, 0), 2.0);
  EXPECT_EQ(e.u(4, 0), 4.0);
  EXPECT_DOUBLE_EQ(e.y(1, 0), 20.0);
  EXPECT_DOUBLE_EQ(e.y(2, 0), 30.0);
  EXPECT_EQ(d.Ts, 1.0);

  // A gap in the time column is interpolated too (exactly: the grid is linear).
  const CsvTable time_gap = parse("t,y\n0,1\nnan,2\n2,3\n");
  o.inputs.clear();
  EXPECT_EQ(sysid::log_from_table(time_gap, o).Ts, 1.0);

  const CsvTable at_start = parse("t,u,y\n0,1,nan\n1,2,3\n2,3,4\n");
  o.inputs = {"u"};
  expect_data_error([&] { sysid::log_from_table(at_start, o); }, "mem.csv", 2, 3, "start of the record");
  const CsvTable at_end = parse("t,u,y\n0,1,1\n1,2,3\n2,nan,4\n3,nan,5\n");
  expect_data_error([&] { sysid::log_from_table(at_end, o); }, "mem.csv", 4, 2, "end of the record");
}

TEST(IoCsv, NanPolicyInterpolateAcrossOppositeExtremes) {
  // a + (b - a) w overflowed for a = -1e308, b = 1e308 and put Inf into the data,
  // which IoData then refused with std::invalid_argument instead of a result.
  const CsvTable table = parse("t,y\n0,-1e308\n1,nan\n2,1e308\n");
  LogOptions o;
  o.outputs = {"y"};
  o.nan_policy = NanPolicy::interpolate;
  const sysid::IoData d = sysid::log_from_table(table, o);
  EXPECT_EQ(d.experiments[0].y(1, 0), 0.0);
}

TEST(IoCsv, TimeStepTooLargeForADouble) {
  // Both stamps are finite but their difference is not: Inf - Inf passed the
  // uniformity test and Ts = Inf reached IoData (std::invalid_argument).
  const CsvTable table = parse("t,y\n-1e308,1\n1e308,2\n");
  LogOptions o;
  o.outputs = {"y"};
  expect_data_error([&] { sysid::log_from_table(table, o); }, "mem.csv", 3, 1, "too large for a double");
}

TEST(IoCsv, HugeFiniteStepsWhoseSpanOverflows) {
  // Each step (about 1e308) is a double, the span -1e308 .. 1e308 is not: the
  // median step and Ts overflowed to Inf (found by fuzz.csv). The steps are
  // uniform within 1 %, so the log reads with a finite Ts.
  const CsvTable table = parse("t,y\n-1e308,2\n307,1\n1e308,2\n");
  LogOptions o;
  o.outputs = {"y"};
  o.time_tolerance = 1e-2;
  const sysid::IoData d = sysid::log_from_table(table, o);
  EXPECT_TRUE(std::isfinite(d.Ts));
  EXPECT_NEAR(d.Ts, 1e308, 1e-12 * 1e308);
}

TEST(IoCsv, LogPreconditions) {
  const CsvTable table = parse(make_log(10, 0.1));
  LogOptions o;
  EXPECT_THROW(sysid::log_from_table(table, o), std::invalid_argument);
  o.inputs = {"u1"};
  o.outputs = {"u1"};
  EXPECT_THROW(sysid::log_from_table(table, o), std::invalid_argument);
  o.outputs = {"y"};
  o.ts = -1.0;
  EXPECT_THROW(sysid::log_from_table(table, o), std::invalid_argument);
}

class IoCsvFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    m_dir = fs::temp_directory_path() / ("sysid_io_csv_" + std::to_string(::getpid()) + "_" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(m_dir);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(m_dir, ec);
  }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = m_dir / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  fs::path m_dir;
};

TEST_F(IoCsvFiles, ReadLogsBuildsSeparateExperiments) {
  const std::string a = write("a.csv", make_log(30, 0.01));
  const std::string b = write("b.csv", make_log(45, 0.01, [](int k) { return 7.0 + k * 0.01; }));
  LogOptions o;
  o.inputs = {"u1"};
  o.outputs = {"y"};
  const sysid::IoData d = sysid::read_logs({a, b}, o);
  ASSERT_EQ(d.experiments.size(), 2u);
  EXPECT_EQ(d.experiments[0].samples(), 30);
  EXPECT_EQ(d.experiments[1].samples(), 45);
  EXPECT_EQ(d.experiments[1].source, b);
  EXPECT_EQ(d.experiments[1].u(44, 0), 44.0);
  EXPECT_NEAR(d.Ts, 0.01, 1e-14);

  const std::string c = write("c.csv", make_log(20, 0.02));
  expect_data_error([&] { sysid::read_logs({a, c}, o); }, c, 0, 0, "sample time 0.02 s differs");
  // A bad second file reports its own name.
  const std::string bad = write("bad.csv", "t,u1,y\n0,1,2\n0.01,x,3\n");
  expect_data_error([&] { sysid::read_logs({a, bad}, o); }, bad, 3, 2, "found 'x'");
}

TEST(IoCsv, ConsumingTheTableGivesTheSameLogAndTheTimeStamps) {
  // Output columns in every order relative to the file (the in-place gathering
  // swaps columns), the time column also selected as a signal, and the NaN
  // policies that trim or repair rows.
  const std::string text =
      "t,a,b,c,d\n"
      "0,1,2,3,4\n"
      "0.1,5,nan,7,8\n"
      "0.2,9,10,11,nan\n"
      "nan,13,14,15,16\n"
      "0.4,17,18,19,20\n"
      "0.5,21,22,23,24\n";
  struct Case {
    std::vector<std::string> inputs, outputs;
    NanPolicy policy;
  };
  const std::vector<Case> cases = {
      {{"a"}, {"c", "b"}, NanPolicy::interpolate},  {{"c"}, {"b", "a"}, NanPolicy::interpolate},
      {{}, {"d", "c", "b", "a"}, NanPolicy::interpolate}, {{"b"}, {"a", "t"}, NanPolicy::interpolate},
      {{"a"}, {"c"}, NanPolicy::drop_rows},
  };
  for (const Case& c : cases) {
    LogOptions o;
    o.inputs = c.inputs;
    o.outputs = c.outputs;
    o.nan_policy = c.policy;
    std::string body = text;
    if (c.policy == NanPolicy::drop_rows) body = "t,a,b,c,d\n0,1,2,3,4\n0.1,5,6,7,8\n0.2,9,nan,11,12\n";
    const CsvTable table = parse(body);
    const sysid::IoData copied = sysid::log_from_table(table, o);
    Eigen::VectorXd stamps;
    const sysid::IoData consumed = sysid::log_from_table(parse(body), o, &stamps);
    const auto& a = copied.experiments.front();
    const auto& b = consumed.experiments.front();
    EXPECT_EQ(a.u, b.u);
    EXPECT_EQ(a.y, b.y);
    EXPECT_EQ(copied.Ts, consumed.Ts);
    EXPECT_EQ(consumed.output_names, c.outputs);
    ASSERT_EQ(stamps.size(), b.samples());
    for (Eigen::Index k = 0; k < stamps.size(); ++k) EXPECT_NEAR(stamps(k), stamps(0) + k * consumed.Ts, 1e-12);
  }
  // Outputs gathered from file columns 3, 1, 4 keep their values.
  LogOptions o;
  o.outputs = {"c", "a", "d"};
  o.ts = 0.1;
  o.time_column.clear();
  const sysid::IoData d = sysid::log_from_table(parse("t,a,b,c,d\n0,1,2,3,4\n1,5,6,7,8\n"), o);
  Eigen::MatrixXd want(2, 3);
  want << 3, 1, 4, 7, 5, 8;
  EXPECT_EQ(d.experiments.front().y, want);
}

TEST_F(IoCsvFiles, LargeFileReadThroughTheMappingEqualsTheInMemoryParse) {
  // ~22 MB: both passes release the text behind them several times (8 MB steps);
  // the released pages are read again only if touched, so the result must be
  // the in-memory parse's bit for bit, and an error near the end must still
  // name its line and column.
  const std::string text = "# comment before the header\n" + make_log(600000, 0.001) + "\n# trailing comment\n";
  ASSERT_GT(text.size(), 20u << 20);
  const std::string path = write("big.csv", text);
  {
    sysid::MappedFile file(path);
    EXPECT_TRUE(file.mapped());
    EXPECT_EQ(file.text(), text);
    file.release(file.text().data() + 100, file.text().data() + file.text().size() / 2);  // released pages read back unchanged
    EXPECT_EQ(file.text(), text);
  }
  const CsvTable from_file = sysid::read_csv(path);
  const CsvTable from_memory = parse(text);
  ASSERT_EQ(from_file.values.rows(), 600000);
  EXPECT_EQ(from_file.values, from_memory.values);
  EXPECT_EQ(from_file.line_numbers, from_memory.line_numbers);
  EXPECT_EQ(from_file.header_line, 2);
  EXPECT_EQ(from_file.values(599999, 3), 3.0 * 599999 + 1);

  std::string bad = text;
  const std::size_t at = bad.rfind("\n", bad.size() - 30);  // the last data line
  bad.replace(at + 1, 1, "x");
  const std::string bad_path = write("bad_big.csv", bad);
  expect_data_error([&] { sysid::read_csv(bad_path); }, bad_path, 600002, 1, "expected a number");
}

TEST_F(IoCsvFiles, EmptyFileFifoAndDirectoryGiveTheUsualAnswers) {
  const std::string empty = write("empty.csv", "");
  expect_data_error([&] { sysid::read_csv(empty); }, empty, 0, 0, "empty file");
  expect_data_error([&] { sysid::read_csv(m_dir.string()); }, m_dir.string(), 0, 0, "directory");
  // A FIFO cannot be mapped: it is read whole, as before.
  const std::string fifo = (m_dir / "pipe.csv").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::thread writer([&] { std::ofstream(fifo) << "t,y\n0,1\n1,2\n"; });
  const CsvTable t = sysid::read_csv(fifo);
  writer.join();
  ASSERT_EQ(t.values.rows(), 2);
  EXPECT_EQ(t.values(1, 1), 2.0);
}

TEST_F(IoCsvFiles, WriteCsvRoundTripsThroughTheFile) {
  Eigen::MatrixXd v(3, 2);
  v << 0.1, -2.5e-7, 1.0 / 3.0, 1e300, -0.0, 42;
  const std::string p = (m_dir / "out.csv").string();
  sysid::write_csv(p, {"t", "y"}, v);
  const CsvTable t = sysid::read_csv(p);
  EXPECT_EQ(t.names, (std::vector<std::string>{"t", "y"}));
  for (Eigen::Index i = 0; i < v.size(); ++i) EXPECT_TRUE(same_bits(t.values(i), v(i))) << i;
  EXPECT_THROW(sysid::write_csv((m_dir / "missing" / "out.csv").string(), {"t", "y"}, v), DataError);
}

// ---- writing ------------------------------------------------------------------

TEST(IoCsv, FormatCsvRoundTripIsBitExact) {
  std::mt19937_64 rng(20240611);
  std::uniform_int_distribution<std::uint64_t> bits;
  std::normal_distribution<double> normal;
  const Eigen::Index rows = 400, cols = 5;
  Eigen::MatrixXd v(rows, cols);
  for (Eigen::Index r = 0; r < rows; ++r) {
    // Column 0: arbitrary bit patterns (all exponents, subnormals; NaN patterns
    // replaced since only "NaN-ness" survives text); the others: typical signals.
    std::uint64_t b = bits(rng);
    double x;
    std::memcpy(&x, &b, sizeof x);
    v(r, 0) = std::isnan(x) ? 0.0 : x;
    v(r, 1) = normal(rng);
    v(r, 2) = normal(rng) * 1e-300;
    v(r, 3) = std::ldexp(normal(rng), -1060);  // subnormal range
    v(r, 4) = static_cast<double>(r) * 0.001;
  }
  const double specials[] = {0.0, -0.0, 1e-300, 1e300, std::numeric_limits<double>::max(),
                             std::numeric_limits<double>::min(), std::numeric_limits<double>::denorm_min(),
                             -std::numeric_limits<double>::denorm_min(), inf_v, -inf_v};
  for (std::size_t i = 0; i < std::size(specials); ++i) v(static_cast<Eigen::Index>(i), 1) = specials[i];
  v(20, 2) = nan_v;

  const std::vector<std::string> names{"a", "b", "c", "d", "t"};
  const std::string text = sysid::format_csv(names, v);
  const CsvTable t = parse(text);
  ASSERT_EQ(t.names, names);
  ASSERT_EQ(t.values.rows(), rows);
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index c = 0; c < cols; ++c) {
      if (std::isnan(v(r, c)))
        EXPECT_TRUE(std::isnan(t.values(r, c)));
      else
        EXPECT_TRUE(same_bits(t.values(r, c), v(r, c))) << r << "," << c << ": " << v(r, c) << " vs " << t.values(r, c);
    }
  // Shortest form: 0.1 is written as "0.1", not 0.10000000000000001.
  EXPECT_EQ(sysid::format_csv({"x"}, Eigen::MatrixXd::Constant(1, 1, 0.1)), "x\n0.1\n");
}

TEST(IoCsv, FormatCsvPreconditions) {
  const Eigen::MatrixXd v = Eigen::MatrixXd::Zero(2, 2);
  EXPECT_THROW(sysid::format_csv({"a"}, v), std::invalid_argument);
  EXPECT_THROW(sysid::format_csv({"a", "a"}, v), std::invalid_argument);
  EXPECT_THROW(sysid::format_csv({"a", "b,c"}, v), std::invalid_argument);
  EXPECT_THROW(sysid::format_csv({"a", ""}, v), std::invalid_argument);
  EXPECT_THROW(sysid::format_csv({"#a", "b"}, v), std::invalid_argument);
  EXPECT_THROW(sysid::format_csv({"1", "2"}, v), std::invalid_argument);
  EXPECT_THROW(sysid::format_csv({"two words"}, Eigen::MatrixXd::Zero(2, 1)), std::invalid_argument);
  // The reader skips a byte-order mark at the start of the text, so a first name
  // beginning with one would not read back (found by tests/fuzz).
  EXPECT_THROW(sysid::format_csv({"\xEF\xBB\xBF" "a", "b"}, v), std::invalid_argument);
  // Spaces inside names are fine with several columns (comma-delimited header).
  const CsvTable t = parse(sysid::format_csv({"force x", "y"}, v));
  EXPECT_EQ(t.names, (std::vector<std::string>{"force x", "y"}));
}

}  // namespace

}  // namespace test_unit_io_csv
