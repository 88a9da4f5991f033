#pragma once
/// @file
/// Purpose: CSV logs in and out (DESIGN.md "CSV logs"): a fast, strict parser that
/// names file:line:column for every problem, column selection by name, sample time
/// from a time column or from the user, and explicit policies for missing values.
///
/// Accepted format:
/// - A header row of column names is required: the first line that is neither
///   blank nor a comment. Names are trimmed; one pair of surrounding double quotes
///   is removed ("t" -> t). Quoting is not otherwise supported (no delimiters inside
///   fields).
/// - Delimiter (CsvFormat), detected from the header unless given: ';' if the
///   header holds more ';' than ',' (European locale exports), else ',' if it holds
///   one, else TAB if it holds one, else runs of spaces/tabs (so a whitespace-aligned
///   file needs a header aligned with spaces only). Around ',', ';' and TAB
///   delimiters, spaces are ignored.
/// - Decimal mark (CsvFormat), detected unless given: '.' in comma-separated files;
///   otherwise ',' if the first data line holding a '.' or a ',' holds a ','.
/// - A line whose first non-blank character is '#' is a comment. Comments are
///   whole-line only: "1,2 # note" is an error, so a stray '#' is never silently
///   taken as the end of the data on a line.
/// - Blank lines are skipped; LF and CRLF line ends; a leading UTF-8 BOM is skipped.
/// - Cells are decimal or scientific numbers (a leading '+' is allowed), or
///   nan / inf / infinity (any case, optional sign). An empty cell (comma and tab
///   files) is read as NaN. What happens to NaN/Inf is decided later by NanPolicy.
#include <Eigen/Dense>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sysid/core/io_data.hpp"

namespace sysid {

/// A parsed CSV file: every column, all values as doubles.
struct CsvTable {
  std::string source;              ///< file name (or the name given for in-memory text), for messages
  std::vector<std::string> names;  ///< column names, in file order
  Eigen::MatrixXd values;          ///< rows x columns, samples in rows
  std::vector<long> line_numbers;  ///< 1-based file line of each data row (for messages)
  long header_line = 1;            ///< 1-based file line of the header row

  /// Index of the column called `name`, or -1 if absent.
  Eigen::Index column(const std::string& name) const;
};

/// How a CSV file's text is laid out; 0 (the default) detects each from the file.
struct CsvFormat {
  /// ',', ';', '\t', or ' ' for runs of spaces and tabs; 0: detected from the header.
  char delimiter = 0;
  /// '.' or ','; 0: detected (see the file comment). ',' needs a delimiter other than ','.
  char decimal = 0;
};

/// Purpose: read a whole CSV file.
///
/// Method: the file is mapped (io/mapped_file.hpp; pipes and the like are read
/// whole) and parsed in a single pass; numbers are parsed in place with
/// fast_float::from_chars (correctly rounded, no per-cell allocation) straight into
/// the column-major result, pre-sized from a newline count (one memchr pass), so
/// there is neither a second buffer nor a transpose. Both passes hand the text
/// behind them back to the system in 8 MB steps, so the file's bytes and the parsed
/// table are never in memory together (10^6 rows x 17 columns, 191 MB of text:
/// peak ~150 MB instead of ~340 MB).
///
/// Errors: sysid::DataError with file, 1-based line and 1-based column (field
/// index) for: a non-number ("expected a number, found 'abc'", with the likely
/// cause when the field holds a ';' or a decimal comma), a row with the
/// wrong number of fields ("expected 3 fields, found 2"; the column is that of the
/// first missing or first extra field), an empty or duplicate column name, a
/// header row made only of numbers (header missing), an empty file, no data rows,
/// and an unreadable file.
///
/// Numerical aspects: O(bytes). On the 2-core development VM (preset bench),
/// about 600 MB/s for a 100 MB, 17-column file from the page cache, mapping
/// included (bench/csv_parse_bench.cpp); fast_float is about half of it.
///
/// Preconditions (std::invalid_argument): `format` holds allowed values.
CsvTable read_csv(const std::string& path, const CsvFormat& format = {});

/// Same parser on in-memory text (tests, fuzzing, stdin). `source_name` is used in
/// messages in place of a file name.
CsvTable read_csv_string(const std::string& text, const std::string& source_name, const CsvFormat& format = {});

/// What to do with NaN, Inf and empty cells in the selected columns (inputs,
/// outputs and the time column when it is used). Inf is treated as missing too:
/// in a log it is an overflow marker, not a value.
enum class NanPolicy {
  /// Any NaN/Inf/empty cell is a DataError naming file:line:column. The default:
  /// silently repairing data changes the identified model.
  error,
  /// Remove rows that contain a NaN in a selected column, but only leading and
  /// trailing ones (a logger starting or stopping). Dropping a row in the middle
  /// would make the sampling non-uniform (and the time column would then be
  /// rejected or, worse, absent and the gap invisible), so a NaN row with valid
  /// rows on both sides is a DataError pointing at it.
  drop_rows,
  /// Linear interpolation across each run of NaNs inside a channel (by sample
  /// index, which equals interpolation in time for uniform sampling). A run that
  /// touches the first or last sample has nothing to interpolate from: DataError.
  interpolate,
};

/// "error", "drop" (drop_rows), "interpolate" (the command line's --nan-policy,
/// Python's nan_policy=); std::invalid_argument otherwise.
NanPolicy nan_policy_from_name(const std::string& name);

/// What a time column counts.
enum class TimeUnit { seconds, milliseconds, microseconds };

/// Seconds per `unit`.
double seconds_per(TimeUnit unit);

/// The unit a symbol names: "s" or "sec", "ms" or "msec", "us", "usec" or "µs";
/// any case. Empty for anything else.
std::optional<TimeUnit> time_unit_from_symbol(std::string_view symbol);

/// The unit a time column's name states, if it states one: a last word that is a
/// unit symbol (time_unit_from_symbol) after '_', ' ' or '.', or in brackets or
/// parentheses ("t_ms", "time [ms]", "Time (us)", "t.s").
std::optional<TimeUnit> time_unit_in_name(const std::string& name);

/// Which columns make a log, and how to get the sample time.
struct LogOptions {
  std::vector<std::string> inputs;   ///< input column names (may be empty: time series)
  std::vector<std::string> outputs;  ///< output column names
  /// Time column; used when present in the file. Empty string: never use one.
  std::string time_column = "t";
  /// Sample time in seconds (--ts). Required when the file has no time column;
  /// when it has one, the two must agree within time_tolerance.
  std::optional<double> ts;
  NanPolicy nan_policy = NanPolicy::error;
  /// What the time column counts (--time-unit). Not given: the unit its name
  /// states (time_unit_in_name), else seconds. Ts is always in seconds.
  std::optional<TimeUnit> time_unit;
  /// Allowed deviation of every time step from the median step, relative to that
  /// step, beyond what the printed digits explain: |dt_k - median(dt)| <=
  /// time_tolerance * median(dt) + the rounding of the stamps (below). The default
  /// 1e-6 is far above double rounding of k*Ts (~1e-16 * t/Ts) yet catches one
  /// lost sample.
  double time_tolerance = 1e-6;
};

/// The unit the time column `column_name` is read in under `options`
/// (options.time_unit, else the unit its name states, else seconds).
TimeUnit time_unit_of(const LogOptions& options, const std::string& column_name);

/// Purpose: read one log file into an IoData with one experiment.
///
/// Method: read_csv, then log_from_table.
IoData read_log(const std::string& path, const LogOptions& options);

/// Purpose: build an IoData (one experiment, source = table.source) from a parsed
/// table: select columns by name, apply the NaN policy, find the sample time.
///
/// Sample time: with a time column, Ts = (t_last - t_first) / (N - 1) after every
/// step was checked against the median step (which is robust to the one bad step
/// being reported), in the column's unit (time_unit_of) and converted to seconds;
/// otherwise options.ts.
///
/// Time stamps as instruments print them: a stamp read from the text is known only
/// to half a unit of its last printed digit (6 decimals at 1024 Hz: steps of
/// 0.000976 and 0.000977 s for 0.0009765625 s), so each step may deviate from the
/// median by the rounding quanta of its two stamps and of the median's besides
/// time_tolerance. The quantum of a stamp is that of the shortest decimal that
/// reads back to it (what the file printed, for up to 15 significant digits;
/// ~1e-16 relative for stamps printed in full). A lost or repeated sample is still
/// refused (a step off by half a sample or more never counts as rounding); stamps
/// printed so coarsely that their rounding could reach half a step are refused too
/// (the sampling cannot be checked: use --ts without the column).
///
/// Preconditions (std::invalid_argument): at least one input or output column; no
/// column selected twice; options.ts > 0 when given; time_tolerance >= 0.
///
/// Errors (sysid::DataError): a missing column (at the header line, listing the
/// available names); NaN/Inf per the policy; fewer than 2 rows with a time column;
/// time stamps not increasing, non-uniform ("non-uniform time stamps: step
/// 0.0011 s at line 57, expected 0.001 s"), printed too coarsely to check, or with
/// a step too large for a double;
/// no time column and no options.ts; time column and options.ts disagreeing.
IoData log_from_table(const CsvTable& table, const LogOptions& options);

/// The same from a table that is consumed: its values become the log's outputs
/// (their columns gathered and the rest cut off in place) and only the inputs
/// (and time) are copied, so a large log is not held twice (read_log uses it).
/// `time_stamps`, when given, receives the kept rows' time stamps as the file has
/// them, in the column's unit (empty without a time column), repaired by the
/// interpolate policy like the signals.
IoData log_from_table(CsvTable&& table, const LogOptions& options, Eigen::VectorXd* time_stamps = nullptr);

/// Several logs of the same machine as separate experiments (never concatenated:
/// the end of one record is not followed by the start of the next). All must give
/// the same Ts (within time_tolerance), else DataError naming the file that differs.
IoData read_logs(const std::vector<std::string>& paths, const LogOptions& options);

/// Purpose: CSV text with a header row and one row per sample, numbers in the
/// shortest form that reads back to the same double (std::to_chars), so
/// format_csv -> read_csv_string is bit-exact. NaN and Inf are written as nan, inf.
///
/// Preconditions (std::invalid_argument): names.size() == values.cols(); names
/// non-empty, unique, without ',', ';', '"', line breaks, surrounding spaces, or '#'
/// or a UTF-8 byte-order mark at the start; not all of them numbers; a single
/// name also without spaces or tabs.
std::string format_csv(const std::vector<std::string>& names, const Eigen::MatrixXd& values);

/// format_csv written with write_file_atomically (DataError if it cannot be written).
void write_csv(const std::string& path, const std::vector<std::string>& names, const Eigen::MatrixXd& values);

}  // namespace sysid
