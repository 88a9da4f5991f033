// libFuzzer target for the CSV log reader (include/sysid/io/csv.hpp):
// read_csv_string, then log_from_table with options chosen by the input.
//
// Input layout: byte 0 chooses the LogOptions, byte 1 the column roles, the rest
// is the CSV text (so a seed is a CSV file with two option bytes in front).
//
// Error contract checked: bad text or data -> sysid::DataError (caught, the
// normal outcome for most inputs). Every LogOptions built here satisfies the
// documented preconditions, so std::invalid_argument (or anything else) escaping
// is a bug and aborts. Properties checked on success:
//  - the table is consistent (names x values x line numbers, lines increasing);
//  - format_csv -> read_csv_string gives back the same names and the same values
//    bit for bit (the round trip csv.hpp promises), whenever format_csv accepts
//    the names;
//  - a log that reads has Ts > 0 and finite, finite samples, and the channels asked for;
//  - the consuming log_from_table (CsvTable&&) gives the same log bit for bit, one
//    time stamp per sample when a time column is used, or the same error.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "fuzz_check.hpp"
#include "sysid/core/errors.hpp"
#include "sysid/io/csv.hpp"

namespace {

using sysid::fuzz::check;

void check_table(const sysid::CsvTable& table) {
  const auto cols = static_cast<Eigen::Index>(table.names.size());
  check(cols >= 1 && table.values.cols() == cols, "table: one column of values per name");
  check(table.values.rows() >= 1, "table: at least one data row (else DataError)");
  check(static_cast<Eigen::Index>(table.line_numbers.size()) == table.values.rows(), "table: one line number per row");
  long previous = table.header_line;
  for (const long line : table.line_numbers) {
    check(line > previous, "table: data lines after the header, increasing");
    previous = line;
  }
}

/// format_csv -> read_csv_string must reproduce the table, when the names can be
/// written at all (format_csv refuses, by std::invalid_argument, names the
/// reader accepts but cannot read back unchanged, e.g. with '"' or a leading '#').
void check_round_trip(const sysid::CsvTable& table) {
  std::string text;
  try {
    text = sysid::format_csv(table.names, table.values);
  } catch (const std::invalid_argument&) {
    return;
  }
  sysid::CsvTable back;
  try {
    back = sysid::read_csv_string(text, "round-trip.csv");
  } catch (const sysid::DataError& e) {
    sysid::fuzz::property_violated(std::string("format_csv wrote text read_csv_string refuses: ") + e.what());
  }
  check(back.names == table.names, "round trip: same column names");
  check(sysid::fuzz::same_bits(back.values, table.values), "round trip: same values, bit for bit");
}

/// Byte 0: bits 0-1 NaN policy, bits 2-3 time column, bits 4-5 --ts, bit 6
/// tolerance, bit 7 ask for a column the file lacks. Byte 1: two bits per column
/// for the first four columns (01 input, 10 output, else unused).
sysid::LogOptions make_options(std::uint8_t how, std::uint8_t roles, const sysid::CsvTable& table) {
  sysid::LogOptions o;
  constexpr sysid::NanPolicy policies[] = {sysid::NanPolicy::error, sysid::NanPolicy::drop_rows,
                                           sysid::NanPolicy::interpolate, sysid::NanPolicy::error};
  o.nan_policy = policies[how & 3u];
  switch ((how >> 2) & 3u) {
    case 0: o.time_column = "t"; break;           // the default
    case 1: o.time_column.clear(); break;         // never use one: --ts decides
    case 2: o.time_column = table.names.front(); break;
    default: o.time_column = "time"; break;
  }
  constexpr std::optional<double> sample_times[] = {std::nullopt, 1e-3, 1.0, 0.5};
  o.ts = sample_times[(how >> 4) & 3u];
  o.time_tolerance = (how & 0x40u) ? 1e-2 : 1e-6;
  for (std::size_t c = 0; c < 4 && c < table.names.size(); ++c) {
    const unsigned role = (roles >> (2 * c)) & 3u;
    if (role == 1) o.inputs.push_back(table.names[c]);
    if (role == 2) o.outputs.push_back(table.names[c]);
  }
  if (o.inputs.empty() && o.outputs.empty()) o.outputs.push_back(table.names.back());
  // A column the file lacks (DataError); only when absent, as selecting a column
  // twice violates a precondition.
  if ((how & 0x80u) && table.column("no such column") < 0) o.inputs.push_back("no such column");
  return o;
}

/// The unit of the last digit of the shortest decimal that reads back to `x`
/// (0 for 0, and for values that are not finite).
double shortest_decimal_unit(double x) {
  if (x == 0.0 || !std::isfinite(x)) return 0.0;
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::scientific);
  const std::string text(buf, r.ptr);
  const std::size_t e = text.find('e'), dot = text.find('.');
  const int decimals = dot == std::string::npos ? 0 : static_cast<int>(e - dot - 1);
  return std::pow(10.0, std::stoi(text.substr(e + 1)) - decimals);
}

void check_log(const sysid::IoData& data, const sysid::LogOptions& o, const sysid::CsvTable& table) {
  check(data.Ts > 0.0 && std::isfinite(data.Ts), "log: Ts > 0 and finite");
  check(data.experiments.size() == 1, "log: one experiment");
  const auto& e = data.experiments.front();
  check(e.u.cols() == static_cast<Eigen::Index>(o.inputs.size()) &&
            e.y.cols() == static_cast<Eigen::Index>(o.outputs.size()),
        "log: the channels asked for");
  check(e.u.rows() == e.y.rows() && e.y.rows() >= 1, "log: same samples in u and y, at least one");
  check(e.u.allFinite() && e.y.allFinite(), "log: finite samples after the NaN policy");
  const bool time_column_used = !o.time_column.empty() && table.column(o.time_column) >= 0;
  check(time_column_used || o.ts, "log: without a time column, --ts is required");
  if (!time_column_used) check(data.Ts == *o.ts, "log: Ts is --ts when no time column is used");
  else if (o.ts) {
    // Within time_tolerance, plus the end stamps' rounding spread over the record
    // (csv.hpp: a stamp is known to half a unit of its last printed digit). An
    // independent upper bound on that rounding: the coarsest last digit of any
    // stamp's shortest decimal in the whole column.
    const Eigen::Index t_col = table.column(o.time_column);
    double coarsest = 0.0;
    for (Eigen::Index r = 0; r < table.values.rows(); ++r)
      coarsest = std::max(coarsest, shortest_decimal_unit(table.values(r, t_col)));
    const double rounding = coarsest * sysid::seconds_per(sysid::time_unit_of(o, o.time_column)) /
                            static_cast<double>(std::max<Eigen::Index>(1, e.y.rows() - 1));
    check(std::abs(data.Ts - *o.ts) <= o.time_tolerance * *o.ts + rounding * (1.0 + 1e-9),
          "log: time column and --ts agree within the tolerance and the stamps' rounding");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  if (size < 2) return 0;
  const std::string text(reinterpret_cast<const char*>(bytes) + 2, size - 2);

  sysid::CsvTable table;
  try {
    table = sysid::read_csv_string(text, "fuzz.csv");
  } catch (const sysid::DataError&) {
    return 0;
  }
  check_table(table);
  check_round_trip(table);

  const sysid::LogOptions options = make_options(bytes[0], bytes[1], table);
  // The copying and the consuming readers must agree: the same log, bit for bit,
  // or the same error.
  std::optional<sysid::IoData> copied;
  std::string copied_error;
  try {
    copied = sysid::log_from_table(table, options);
    check_log(*copied, options, table);
  } catch (const sysid::DataError& e) {
    copied_error = e.what();
  }
  try {
    Eigen::VectorXd stamps;
    const sysid::IoData consumed = sysid::log_from_table(sysid::CsvTable(table), options, &stamps);
    check(copied.has_value(), "consuming log_from_table accepts what the copying one refuses");
    const auto& a = copied->experiments.front();
    const auto& b = consumed.experiments.front();
    check(sysid::fuzz::same_bits(a.u, b.u) && sysid::fuzz::same_bits(a.y, b.y) && copied->Ts == consumed.Ts,
          "consuming log_from_table: the same log, bit for bit");
    const bool time_column_used = !options.time_column.empty() && table.column(options.time_column) >= 0;
    check(stamps.size() == (time_column_used ? b.samples() : 0), "consuming log_from_table: one time stamp per sample");
  } catch (const sysid::DataError& e) {
    check(!copied.has_value() && copied_error == e.what(), "consuming log_from_table: the same error as the copying one");
  }
  return 0;
}
