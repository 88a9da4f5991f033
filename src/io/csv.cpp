#include "sysid/io/csv.hpp"

#include <fast_float/fast_float.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string_view>
#include <unordered_set>

#include "sysid/core/errors.hpp"
#include "sysid/core/format_number.hpp"
#include "sysid/core/median.hpp"
#include "sysid/io/atomic_file.hpp"
#include "sysid/io/mapped_file.hpp"

namespace sysid {
namespace {

/// The delimiter of runs of spaces and tabs (whitespace-aligned files).
constexpr char kWhitespace = ' ';

inline bool is_blank(char c) { return c == ' ' || c == '\t'; }

/// UTF-8 byte-order mark, as written by Excel and some Windows tools.
constexpr std::string_view k_utf8_bom = "\xEF\xBB\xBF";

/// Field text for an error message: trimmed, and cut so a runaway line (a binary
/// file, a missing newline) does not flood the terminal.
std::string excerpt(const char* b, const char* e) {
  constexpr std::ptrdiff_t max_len = 40;
  if (e - b > max_len) return std::string(b, b + max_len) + "...";
  return std::string(b, e);
}

/// fast_float with the file's decimal mark ('.' or ',').
inline fast_float::from_chars_result from_chars(const char* b, const char* e, double& v, char decimal) {
  return fast_float::from_chars_advanced(b, e, v, fast_float::parse_options(fast_float::chars_format::general, decimal));
}

/// Parses one number occupying exactly [b, e) (already trimmed). Returns false
/// when the text is not a number. A leading '+' is accepted (std::from_chars and
/// fast_float reject it, but loggers write it).
inline bool parse_number(const char* b, const char* e, double& v, char decimal) {
  if (b < e && *b == '+') {
    ++b;
    if (b < e && (*b == '-' || *b == '+')) return false;
  }
  if (b == e) return false;
  const auto r = from_chars(b, e, v, decimal);
  return r.ec == std::errc() && r.ptr == e;
}

/// The field delimiter a header row implies (CsvFormat::delimiter's rule).
char detect_delimiter(const char* b, const char* e) {
  const auto commas = std::count(b, e, ','), semicolons = std::count(b, e, ';');
  if (semicolons > commas) return ';';
  if (commas > 0) return ',';
  if (std::memchr(b, '\t', static_cast<std::size_t>(e - b))) return '\t';
  return kWhitespace;
}

class CsvParser {
 public:
  /// `file`, when given, holds [begin, end): the parser releases the text behind it as it goes.
  CsvParser(const char* begin, const char* end, const std::string& source, const CsvFormat& format,
            MappedFile* file = nullptr)
      : m_p(begin), m_end(end), m_source(source), m_file(file), m_delimiter(format.delimiter), m_decimal(format.decimal) {
    if (m_delimiter != 0 && m_delimiter != ',' && m_delimiter != ';' && m_delimiter != '\t' && m_delimiter != kWhitespace)
      throw std::invalid_argument("read_csv: the delimiter must be ',', ';', TAB or ' ' (whitespace)");
    if (m_decimal != 0 && m_decimal != '.' && m_decimal != ',')
      throw std::invalid_argument("read_csv: the decimal mark must be '.' or ','");
    if (m_decimal == ',' && m_delimiter == ',')
      throw std::invalid_argument("read_csv: a decimal comma needs another delimiter (';', TAB or whitespace)");
    if (std::string_view(m_p, static_cast<std::size_t>(m_end - m_p)).starts_with(k_utf8_bom)) m_p += k_utf8_bom.size();
  }

  CsvTable parse() {
    CsvTable table;
    table.source = m_source;
    const char* b;
    const char* e;
    if (!next_content_line(b, e)) throw DataError(m_source, 0, 0, "empty file: no header row");
    table.header_line = m_line;
    if (m_delimiter == 0) m_delimiter = detect_delimiter(b, e);
    if (m_decimal == 0) m_decimal = detect_decimal();
    if (m_decimal == ',' && m_delimiter == ',')
      throw DataError(m_source, m_line, 0, "the header row is comma-separated, so ',' cannot be the decimal mark");
    parse_header(b, e, table.names);
    m_columns = table.names.size();

    // Parse straight into the column-major result, sized from an upper bound on
    // the number of data rows: the newline count (memchr runs an order of magnitude
    // faster than parsing), capped by the bytes a row needs at least (one per
    // field, counting delimiters and the line end), so a file of blank lines cannot
    // make it allocate much more than 8 bytes per byte of text. When there are no
    // blank or comment lines among the data the bound is exact and no copy is made.
    const auto rest = static_cast<std::size_t>(m_end - m_p);
    std::size_t newlines = 0;
    for (const char *chunk = m_p, *chunk_end; chunk < m_end; chunk = chunk_end) {
      chunk_end = chunk + std::min<std::ptrdiff_t>(kReleaseBytes, m_end - chunk);
      for (const char* q = chunk;
           (q = static_cast<const char*>(std::memchr(q, '\n', static_cast<std::size_t>(chunk_end - q)))); ++q)
        ++newlines;
      if (m_file) m_file->release(chunk, chunk_end);
    }
    const std::size_t line_bound = newlines + (rest > 0 && m_end[-1] != '\n' ? 1 : 0);
    m_capacity = static_cast<Eigen::Index>(std::min(line_bound, rest / m_columns + 1));
    table.values.resize(m_capacity, static_cast<Eigen::Index>(m_columns));
    table.line_numbers.reserve(static_cast<std::size_t>(m_capacity));

    Eigen::Index rows = 0;
    const char* released = m_p;
    while (next_content_line(b, e)) {
      if (m_file && b - released >= kReleaseBytes) {
        m_file->release(released, b);
        released = b;
      }
      if (rows == m_capacity) {  // cannot happen (the bound is an upper bound); kept for safety
        m_capacity = 2 * m_capacity + 1;
        table.values.conservativeResize(m_capacity, Eigen::NoChange);
      }
      double* row = table.values.data() + rows;  // element (rows, 0); columns are m_capacity apart
      if (m_delimiter == kWhitespace)
        parse_row_whitespace(b, e, row);
      else
        parse_row_delimited(b, e, row, m_delimiter);
      table.line_numbers.push_back(m_line);
      ++rows;
    }
    if (rows == 0) throw DataError(m_source, table.header_line, 0, "no data rows after the header");
    if (rows < m_capacity) table.values = table.values.topRows(rows).eval();
    return table;
  }

 private:
  /// Advances to the next line that is neither blank nor a comment; [b, e) is its
  /// content without the line end. Returns false at the end of the text.
  bool next_content_line(const char*& b, const char*& e) {
    while (m_p < m_end) {
      ++m_line;
      const char* nl = static_cast<const char*>(std::memchr(m_p, '\n', static_cast<std::size_t>(m_end - m_p)));
      const char* line_end = nl ? nl : m_end;
      b = m_p;
      e = line_end;
      m_p = nl ? nl + 1 : m_end;
      if (e > b && e[-1] == '\r') --e;
      const char* q = b;
      while (q < e && is_blank(*q)) ++q;
      if (q == e || *q == '#') continue;
      return true;
    }
    return false;
  }

  /// The decimal mark when not given (CsvFormat::decimal's rule): '.' in
  /// comma-separated files; otherwise ',' if the first data line that holds a '.'
  /// or a ',' (of the first kDecimalScanLines) holds a ','. Reads ahead without
  /// consuming.
  char detect_decimal() const {
    if (m_delimiter == ',') return '.';
    constexpr int kDecimalScanLines = 1000;
    const char* p = m_p;
    for (int lines = 0; p < m_end && lines < kDecimalScanLines; ++lines) {
      const char* nl = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(m_end - p)));
      const char* e = nl ? nl : m_end;
      const char* q = p;
      while (q < e && is_blank(*q)) ++q;
      if (q < e && *q != '#') {
        for (; q < e; ++q) {
          if (*q == ',') return ',';
          if (*q == '.') return '.';
        }
      }
      p = nl ? nl + 1 : m_end;
    }
    return '.';
  }

  [[noreturn]] void fail(std::size_t field, const std::string& message) const {
    throw DataError(m_source, m_line, static_cast<long>(field + 1), message);
  }

  /// "expected a number, found '...'", with the likely cause when the field looks
  /// like another layout (a decimal comma, another delimiter).
  [[noreturn]] void fail_number(std::size_t field, const char* b, const char* e) const {
    std::string message = "expected a number, found '" + excerpt(b, e) + "'";
    const std::string_view text(b, static_cast<std::size_t>(e - b));
    if (m_delimiter != ';' && text.find(';') != std::string_view::npos)
      message += " (a ';'-separated file? give the delimiter ';', with --delimiter ';' on the command line)";
    else if (m_decimal == '.' && text.find(',') != std::string_view::npos)
      message += " (a decimal comma? give the decimal mark ',', with --decimal ',' on the command line)";
    fail(field, message);
  }

  void parse_header(const char* b, const char* e, std::vector<std::string>& names) {
    std::vector<std::pair<const char*, const char*>> fields;
    if (m_delimiter == kWhitespace) {
      const char* q = b;
      for (;;) {
        while (q < e && is_blank(*q)) ++q;
        if (q == e) break;
        const char* f = q;
        while (q < e && !is_blank(*q)) ++q;
        fields.emplace_back(f, q);
      }
    } else {
      const char delim = m_delimiter;
      const char* q = b;
      for (;;) {
        const char* f = q;
        while (q < e && *q != delim) ++q;
        const char* fb = f;
        const char* fe = q;
        while (fb < fe && is_blank(*fb)) ++fb;
        while (fe > fb && is_blank(fe[-1])) --fe;
        fields.emplace_back(fb, fe);
        if (q == e) break;
        ++q;
      }
    }

    std::unordered_set<std::string> seen;
    bool all_numbers = true;
    for (std::size_t k = 0; k < fields.size(); ++k) {
      auto [fb, fe] = fields[k];
      double dummy;
      all_numbers = all_numbers && parse_number(fb, fe, dummy, m_decimal);
      if (fe - fb >= 2 && *fb == '"' && fe[-1] == '"') {
        ++fb;
        --fe;
      }
      if (fb == fe) fail(k, "empty column name in the header row");
      std::string name(fb, fe);
      if (!seen.insert(name).second) fail(k, "duplicate column name '" + name + "'");
      names.push_back(std::move(name));
    }
    if (all_numbers)
      fail(0, "the first line holds numbers, expected a header row of column names (e.g. t,u,y)");
  }

  [[noreturn]] void fail_count(std::size_t found) const {
    const std::size_t first_bad = std::min(found, m_columns);  // first missing or first extra field
    fail(first_bad, "expected " + std::to_string(m_columns) + " fields, found " + std::to_string(found));
  }

  /// Comma or tab: the hot loop. The common case (a number right at the field
  /// start followed by the delimiter) costs one fast_float call and one compare;
  /// spaces, '+', empty cells and errors take the slower branches.
  void parse_row_delimited(const char* q, const char* e, double* row, char delim) {
    std::size_t col = 0;
    for (;; ++col) {
      while (q < e && *q == ' ') ++q;
      if (delim != '\t')
        while (q < e && is_blank(*q)) ++q;
      double v;
      if (q == e || *q == delim) {
        v = std::numeric_limits<double>::quiet_NaN();  // empty cell
      } else {
        const char* f = q;
        auto r = from_chars(q, e, v, m_decimal);
        if (r.ec == std::errc() && (r.ptr == e || *r.ptr == delim)) {
          q = r.ptr;
        } else {
          // Slow path: find the whole field, trim it, retry (handles '+' and
          // trailing spaces), else report it.
          while (q < e && *q != delim) ++q;
          const char* fe = q;
          while (fe > f && is_blank(fe[-1])) --fe;
          if (!parse_number(f, fe, v, m_decimal)) {
            if (col >= m_columns) fail_count(count_fields_from(col, q, e, delim));
            fail_number(col, f, fe);
          }
        }
      }
      if (col >= m_columns) fail_count(count_fields_from(col, q, e, delim));
      row[static_cast<Eigen::Index>(col) * m_capacity] = v;
      if (q == e) break;
      ++q;  // the delimiter
    }
    if (col + 1 != m_columns) fail_count(col + 1);
  }

  /// Number of fields in the row, given that field `col` ends at q.
  static std::size_t count_fields_from(std::size_t col, const char* q, const char* e, char delim) {
    return col + 1 + static_cast<std::size_t>(std::count(q, e, delim));
  }

  void parse_row_whitespace(const char* q, const char* e, double* row) {
    std::size_t col = 0;
    for (;;) {
      while (q < e && is_blank(*q)) ++q;
      if (q == e) break;
      const char* f = q;
      double v;
      auto r = from_chars(q, e, v, m_decimal);
      if (r.ec == std::errc() && (r.ptr == e || is_blank(*r.ptr))) {
        q = r.ptr;
      } else {
        while (q < e && !is_blank(*q)) ++q;
        if (!parse_number(f, q, v, m_decimal)) {
          if (col >= m_columns) fail_count(count_whitespace_fields_from(col, q, e));
          fail_number(col, f, q);
        }
      }
      if (col >= m_columns) fail_count(count_whitespace_fields_from(col, q, e));
      row[static_cast<Eigen::Index>(col++) * m_capacity] = v;
    }
    if (col != m_columns) fail_count(col);
  }

  static std::size_t count_whitespace_fields_from(std::size_t col, const char* q, const char* e) {
    std::size_t n = col + 1;
    for (;;) {
      while (q < e && is_blank(*q)) ++q;
      if (q == e) return n;
      ++n;
      while (q < e && !is_blank(*q)) ++q;
    }
  }

  const char* m_p;
  const char* m_end;
  const std::string& m_source;
  MappedFile* m_file = nullptr;
  /// Text released in steps of this many bytes (a step costs one madvise).
  static constexpr std::ptrdiff_t kReleaseBytes = 8 << 20;
  long m_line = 0;
  char m_delimiter;  ///< ',', ';', '\t' or kWhitespace (0 until detected)
  char m_decimal;    ///< '.' or ',' (0 until detected)
  std::size_t m_columns = 0;
  Eigen::Index m_capacity = 0;  ///< allocated rows of the result (column stride)
};

std::string format_seconds(double x) { return format_number(x, 6); }

std::string unit_symbol(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::milliseconds: return "ms";
    case TimeUnit::microseconds: return "us";
    case TimeUnit::seconds: break;
  }
  return "s";
}

/// The shortest decimal that reads back to `x` (std::to_chars), as the exponent
/// of its leading digit and the unit of its last digit.
struct ShortestDecimal {
  int exponent = 0;      ///< x = d.ddd * 10^exponent
  double quantum = 0.0;  ///< the unit of the last digit
};

ShortestDecimal shortest_decimal(double x) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::scientific);
  const std::string_view text(buf, static_cast<std::size_t>(r.ptr - buf));  // "-d.ddde-05"
  const std::size_t e = text.find('e'), dot = text.find('.');
  ShortestDecimal d;
  std::from_chars(text.data() + e + 1 + (text[e + 1] == '+' ? 1 : 0), text.data() + text.size(), d.exponent);
  const int decimals = dot == std::string_view::npos ? 0 : static_cast<int>(e - dot - 1);
  d.quantum = std::pow(10.0, d.exponent - decimals);
  return d;
}

/// The rounding quantum of each of the n time stamps `t` as the file printed them.
/// Instruments print time with a fixed number of decimals (quantum q_abs) or of
/// significant digits (a quantum q_rel * 10^exponent growing with the stamp's
/// decade); the model here is their larger, q(t) = max(q_abs, q_rel * 10^e(t)).
/// One stamp's shortest decimal drops trailing zeros (0.500000 reads as 0.5) and
/// so overstates its quantum; the finest of the record does not: q_abs and q_rel
/// are the minima over the stamps.
std::vector<double> printed_quanta(const double* t, Eigen::Index n) {
  std::vector<ShortestDecimal> d(static_cast<std::size_t>(n));
  double q_abs = std::numeric_limits<double>::infinity(), q_rel = q_abs;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (t[k] == 0.0) continue;  // "0" carries no digits to go by
    d[static_cast<std::size_t>(k)] = shortest_decimal(t[k]);
    q_abs = std::min(q_abs, d[static_cast<std::size_t>(k)].quantum);
    q_rel = std::min(q_rel, d[static_cast<std::size_t>(k)].quantum / std::pow(10.0, d[static_cast<std::size_t>(k)].exponent));
  }
  std::vector<double> q(static_cast<std::size_t>(n));
  for (Eigen::Index k = 0; k < n; ++k)
    q[static_cast<std::size_t>(k)] =
        t[k] == 0.0 ? q_abs : std::max(q_abs, q_rel * std::pow(10.0, d[static_cast<std::size_t>(k)].exponent));
  return q;
}

std::string join(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t k = 0; k < names.size(); ++k) s += (k ? ", " : "") + names[k];
  return s;
}

}  // namespace

Eigen::Index CsvTable::column(const std::string& name) const {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<Eigen::Index>(it - names.begin());
}

NanPolicy nan_policy_from_name(const std::string& name) {
  if (name == "error") return NanPolicy::error;
  if (name == "drop") return NanPolicy::drop_rows;
  if (name == "interpolate") return NanPolicy::interpolate;
  throw std::invalid_argument("nan_policy: expected 'error', 'drop' or 'interpolate', found '" + name + "'");
}

double seconds_per(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::milliseconds: return 1e-3;
    case TimeUnit::microseconds: return 1e-6;
    case TimeUnit::seconds: break;
  }
  return 1.0;
}

std::optional<TimeUnit> time_unit_from_symbol(std::string_view symbol) {
  std::string word;
  for (char c : symbol) word += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (word == "s" || word == "sec") return TimeUnit::seconds;
  if (word == "ms" || word == "msec") return TimeUnit::milliseconds;
  if (word == "us" || word == "usec" || word == "\xC2\xB5s" || word == "\xCE\xBCs") return TimeUnit::microseconds;  // µs: micro sign or Greek mu
  return std::nullopt;
}

std::optional<TimeUnit> time_unit_in_name(const std::string& name) {
  std::string_view n = name;
  while (!n.empty() && (n.back() == ' ' || n.back() == ']' || n.back() == ')')) n.remove_suffix(1);
  // The last word: after '_', ' ', '.', '[' or '('.
  const std::size_t cut = n.find_last_of("_ .[(");
  if (cut == std::string_view::npos) return std::nullopt;
  return time_unit_from_symbol(n.substr(cut + 1));
}

TimeUnit time_unit_of(const LogOptions& options, const std::string& column_name) {
  if (options.time_unit) return *options.time_unit;
  return time_unit_in_name(column_name).value_or(TimeUnit::seconds);
}

CsvTable read_csv_string(const std::string& text, const std::string& source_name, const CsvFormat& format) {
  return CsvParser(text.data(), text.data() + text.size(), source_name, format).parse();
}

CsvTable read_csv(const std::string& path, const CsvFormat& format) {
  MappedFile file(path);
  const std::string_view text = file.text();
  return CsvParser(text.data(), text.data() + text.size(), path, format, &file).parse();
}

namespace {

/// log_from_table's work. `owned_values`, when given, are the table's values
/// moved out of it (`table` then supplies only names, lines and source): the
/// selected output columns are gathered at its front and it becomes y itself, so
/// the log costs one copy of the inputs (and time) instead of all its columns.
IoData make_log(const CsvTable& table, Eigen::MatrixXd* owned_values, const LogOptions& options,
                Eigen::VectorXd* time_stamps) {
  if (options.inputs.empty() && options.outputs.empty())
    throw std::invalid_argument("read_log: need at least one input or output column (inputs.size() + outputs.size() >= 1)");
  if (options.ts && !(*options.ts > 0.0 && std::isfinite(*options.ts)))
    throw std::invalid_argument("read_log: need ts > 0 (sample time in seconds)");
  if (!(options.time_tolerance >= 0.0)) throw std::invalid_argument("read_log: need time_tolerance >= 0");

  const std::string& src = table.source;
  auto find_column = [&](const std::string& name) {
    const Eigen::Index c = table.column(name);
    if (c < 0)
      throw DataError(src, table.header_line, 0, "no column '" + name + "'; the columns are: " + join(table.names));
    return c;
  };
  std::vector<std::string> seen;
  for (const auto* list : {&options.inputs, &options.outputs})
    for (const auto& name : *list) {
      if (std::find(seen.begin(), seen.end(), name) != seen.end())
        throw std::invalid_argument("read_log: column '" + name + "' selected twice");
      seen.push_back(name);
    }

  // The selected columns, straight into the matrices handed to IoData.
  const Eigen::MatrixXd& values = owned_values ? *owned_values : table.values;
  const Eigen::Index n_rows = values.rows();
  const auto m = static_cast<Eigen::Index>(options.inputs.size());
  const auto l = static_cast<Eigen::Index>(options.outputs.size());
  std::vector<Eigen::Index> u_cols, y_cols;
  for (const auto& name : options.inputs) u_cols.push_back(find_column(name));
  for (const auto& name : options.outputs) y_cols.push_back(find_column(name));
  const Eigen::Index time_col = options.time_column.empty() ? -1 : table.column(options.time_column);
  const bool time_is_signal = std::find(u_cols.begin(), u_cols.end(), time_col) != u_cols.end() ||
                              std::find(y_cols.begin(), y_cols.end(), time_col) != y_cols.end();
  Eigen::VectorXd t;
  if (time_col >= 0 && !time_is_signal) t = values.col(time_col);
  Eigen::MatrixXd u(n_rows, m), y;
  for (Eigen::Index j = 0; j < m; ++j) u.col(j) = values.col(u_cols[static_cast<std::size_t>(j)]);
  if (owned_values) {
    // Column swaps that bring the output columns, in order, to the front
    // (position[c]: where file column c is now), then the tail is cut off in place.
    Eigen::MatrixXd& v = *owned_values;
    std::vector<Eigen::Index> position(static_cast<std::size_t>(v.cols())), holds(position.size());
    for (std::size_t c = 0; c < position.size(); ++c) position[c] = holds[c] = static_cast<Eigen::Index>(c);
    for (Eigen::Index i = 0; i < l; ++i) {
      const Eigen::Index from = position[static_cast<std::size_t>(y_cols[static_cast<std::size_t>(i)])];
      if (from == i) continue;
      v.col(i).swap(v.col(from));
      std::swap(holds[static_cast<std::size_t>(i)], holds[static_cast<std::size_t>(from)]);
      position[static_cast<std::size_t>(holds[static_cast<std::size_t>(i)])] = i;
      position[static_cast<std::size_t>(holds[static_cast<std::size_t>(from)])] = from;
    }
    v.conservativeResize(Eigen::NoChange, l);
    y = std::move(v);
  } else {
    y.resize(n_rows, l);
    for (Eigen::Index i = 0; i < l; ++i) y.col(i) = values.col(y_cols[static_cast<std::size_t>(i)]);
  }
  // Every selected column as (data, file column), so the NaN policy treats inputs,
  // outputs and time alike.
  std::vector<std::pair<double*, Eigen::Index>> sel;
  for (Eigen::Index j = 0; j < m; ++j) sel.emplace_back(u.col(j).data(), u_cols[static_cast<std::size_t>(j)]);
  for (Eigen::Index i = 0; i < l; ++i) sel.emplace_back(y.col(i).data(), y_cols[static_cast<std::size_t>(i)]);
  std::size_t time_sel = sel.size();  // index into sel of the time column
  if (time_col >= 0) {
    const auto it = std::find_if(sel.begin(), sel.end(), [&](const auto& s) { return s.second == time_col; });
    if (it != sel.end()) {
      time_sel = static_cast<std::size_t>(it - sel.begin());  // also selected as a signal: one copy serves both
    } else {
      sel.emplace_back(t.data(), time_col);
    }
  }

  const std::vector<long>& lines = table.line_numbers;
  // A non-finite cell of selected column k in row r, at its file line and column.
  auto bad_cell = [&](Eigen::Index r, std::size_t k, const std::string& why) {
    const Eigen::Index c = sel[k].second;
    return DataError(src, lines[static_cast<std::size_t>(r)], static_cast<long>(c + 1),
                     std::string(std::isnan(sel[k].first[r]) ? "NaN or empty cell" : "Inf") + " in column '" +
                         table.names[static_cast<std::size_t>(c)] + "'" + why);
  };
  auto column_finite = [&](std::size_t k) { return Eigen::Map<const Eigen::VectorXd>(sel[k].first, n_rows).allFinite(); };
  auto row_finite = [&](Eigen::Index r) {
    return std::all_of(sel.begin(), sel.end(), [r](const auto& s) { return std::isfinite(s.first[r]); });
  };
  bool all_finite = true;
  for (std::size_t k = 0; k < sel.size(); ++k) all_finite = all_finite && column_finite(k);

  Eigen::Index first = 0, last = n_rows;  // rows kept
  if (!all_finite) {
    switch (options.nan_policy) {
      case NanPolicy::error:
        // Row by row, so the first problem in file order is reported.
        for (Eigen::Index r = 0; r < n_rows; ++r)
          for (std::size_t k = 0; k < sel.size(); ++k)
            if (!std::isfinite(sel[k].first[r])) throw bad_cell(r, k, " (choose a NaN policy to drop or interpolate)");
        break;
      case NanPolicy::drop_rows:
        while (first < n_rows && !row_finite(first)) ++first;
        if (first == n_rows) throw DataError(src, 0, 0, "every row has a NaN or Inf in the selected columns");
        while (last > first && !row_finite(last - 1)) --last;
        for (Eigen::Index r = first; r < last; ++r)
          if (!row_finite(r)) {
            std::size_t k = 0;
            while (std::isfinite(sel[k].first[r])) ++k;
            throw bad_cell(r, k,
                           " inside the record: dropping the row would make the sampling non-uniform "
                           "(drop_rows only trims leading and trailing rows; use interpolate)");
          }
        break;
      case NanPolicy::interpolate:
        for (std::size_t k = 0; k < sel.size(); ++k) {
          double* x = sel[k].first;
          for (Eigen::Index r = 0; r < n_rows; ++r) {
            if (std::isfinite(x[r])) continue;
            Eigen::Index end = r;
            while (end < n_rows && !std::isfinite(x[end])) ++end;
            if (r == 0 || end == n_rows)
              throw bad_cell(r, k,
                             std::string(" at the ") + (r == 0 ? "start" : "end") +
                                 " of the record: nothing to interpolate from (use drop_rows to trim it)");
            const double a = x[r - 1], b = x[end];
            const double span = static_cast<double>(end - r + 1);
            // std::lerp, not a + (b - a) w: b - a overflows for values of opposite
            // sign near the double range, which would put Inf into the data.
            for (Eigen::Index i = r; i < end; ++i) x[i] = std::lerp(a, b, static_cast<double>(i - r + 1) / span);
            r = end;
          }
        }
        break;
    }
  }
  const Eigen::Index n = last - first;
  auto line_of = [&](Eigen::Index r) { return lines[static_cast<std::size_t>(first + r)]; };  // r: kept row

  double ts = 0.0;
  if (time_col >= 0) {
    const TimeUnit unit = time_unit_of(options, options.time_column);
    const std::string symbol = unit_symbol(unit);
    const auto in_unit = [&](double x) { return format_seconds(x) + " " + symbol; };
    const double* tk = sel[time_sel].first + first;
    if (n < 2)
      throw DataError(src, line_of(0), static_cast<long>(time_col + 1),
                      "need at least 2 samples to find the sample time from column '" + options.time_column + "'");
    std::vector<double> steps(static_cast<std::size_t>(n - 1));
    for (Eigen::Index r = 1; r < n; ++r) {
      steps[static_cast<std::size_t>(r - 1)] = tk[r] - tk[r - 1];
      if (!(tk[r] > tk[r - 1]))
        throw DataError(src, line_of(r), static_cast<long>(time_col + 1),
                        "time stamps not increasing: " + in_unit(tk[r]) + " after " + in_unit(tk[r - 1]) +
                            (tk[r] == tk[r - 1] ? " (a repeated sample; or stamps printed with too few digits for "
                                                  "the sample rate: then give the sample time with --ts and "
                                                  "--time-column none)"
                                                : ""));
      // Both finite, yet the difference can overflow (-1e308 then 1e308): an
      // infinite step would pass the uniformity test below (Inf - Inf is NaN).
      if (!std::isfinite(steps[static_cast<std::size_t>(r - 1)]))
        throw DataError(src, line_of(r), static_cast<long>(time_col + 1),
                        "time step from " + in_unit(tk[r - 1]) + " to " + in_unit(tk[r]) + " is too large for a double");
    }
    const double median_step = median(steps);
    // The printed digits' rounding, computed only if a step needs it.
    std::vector<double> quantum;
    double coarsest = 0.0;
    const auto rounding = [&]() {
      if (quantum.empty()) {
        quantum = printed_quanta(tk, n);
        coarsest = *std::max_element(quantum.begin(), quantum.end());
      }
    };
    for (Eigen::Index r = 1; r < n; ++r) {
      const double step = steps[static_cast<std::size_t>(r - 1)];
      const double deviation = std::abs(step - median_step), tight = options.time_tolerance * median_step;
      if (deviation <= tight) continue;
      // Each stamp is off by up to half its quantum; the median step, a
      // difference of two stamps somewhere in the record, by up to the coarsest.
      rounding();
      const double explained =
          0.5 * (quantum[static_cast<std::size_t>(r - 1)] + quantum[static_cast<std::size_t>(r)]) + coarsest;
      // A step off by half a sample or more is never taken for rounding.
      if (deviation > tight + explained || deviation >= 0.5 * median_step)
        throw DataError(src, line_of(r), static_cast<long>(time_col + 1),
                        "non-uniform time stamps: step " + in_unit(step) + " at line " + std::to_string(line_of(r)) +
                            ", expected " + in_unit(median_step) + " (a lost or repeated sample, or a gap)");
      // Rounding that could reach half a step could also hide a lost sample.
      if (explained >= 0.5 * median_step)
        throw DataError(src, line_of(r), static_cast<long>(time_col + 1),
                        "time stamps printed too coarsely to check the sampling: step " + in_unit(step) +
                            " against " + in_unit(median_step) + ", while the printed digits are only good to " +
                            in_unit(explained) + "; give the sample time with --ts and --time-column none");
    }
    // Every step is finite, yet their sum can overflow (steps of 1e308 from
    // -1e308 to 1e308): then divide before subtracting (exact enough there, and
    // finite since |tk| / (n - 1) <= DBL_MAX / 2 for n >= 3; n = 2 is one step).
    const double span = tk[n - 1] - tk[0];
    const auto intervals = static_cast<double>(n - 1);
    ts = (std::isfinite(span) ? span / intervals : tk[n - 1] / intervals - tk[0] / intervals) * seconds_per(unit);
    if (options.ts && std::abs(*options.ts - ts) > options.time_tolerance * *options.ts) {
      // The end stamps' rounding, spread over the record.
      rounding();
      const double explained = coarsest / intervals * seconds_per(unit);
      if (std::abs(*options.ts - ts) > options.time_tolerance * *options.ts + explained)
        throw DataError(src, 0, 0,
                        "time column '" + options.time_column + "' gives a sample time of " + format_seconds(ts) +
                            " s but " + format_seconds(*options.ts) + " s was given" +
                            (unit == TimeUnit::seconds ? " (a time column in ms or us? give --time-unit)" : ""));
    }
  } else if (options.ts) {
    ts = *options.ts;
  } else {
    throw DataError(src, 0, 0, "no time column '" + options.time_column + "' and no --ts given");
  }

  // The kept rows' time stamps (repaired by the interpolate policy), before the
  // rows are cut (sel points into u, y and t as they are now).
  if (time_stamps) {
    if (time_col >= 0) *time_stamps = Eigen::Map<const Eigen::VectorXd>(sel[time_sel].first + first, n);
    else time_stamps->resize(0);
  }
  if (first > 0 || last < n_rows) {
    // A time series has no input columns: Eigen would form the block of that
    // empty matrix as its null data pointer plus an offset (undefined behaviour).
    auto keep_rows = [&](Eigen::MatrixXd& x) {
      if (x.cols() == 0) x.resize(n, 0);
      else x = x.middleRows(first, n).eval();
    };
    keep_rows(u);
    keep_rows(y);
  }
  return IoData(std::move(u), std::move(y), ts, options.inputs, options.outputs, src);
}

}  // namespace

IoData log_from_table(const CsvTable& table, const LogOptions& options) { return make_log(table, nullptr, options, nullptr); }

IoData log_from_table(CsvTable&& table, const LogOptions& options, Eigen::VectorXd* time_stamps) {
  Eigen::MatrixXd values = std::move(table.values);
  return make_log(table, &values, options, time_stamps);
}

IoData read_log(const std::string& path, const LogOptions& options) { return log_from_table(read_csv(path), options); }

IoData read_logs(const std::vector<std::string>& paths, const LogOptions& options) {
  if (paths.empty()) throw std::invalid_argument("read_logs: need at least one file (paths.size() >= 1)");
  IoData all = read_log(paths.front(), options);
  for (std::size_t k = 1; k < paths.size(); ++k) {
    IoData next = read_log(paths[k], options);
    if (std::abs(next.Ts - all.Ts) > options.time_tolerance * all.Ts)
      throw DataError(paths[k], 0, 0,
                      "sample time " + format_seconds(next.Ts) + " s differs from " + format_seconds(all.Ts) + " s of " +
                          paths.front());
    all.add_experiment(std::move(next.experiments.front()));
  }
  return all;
}

std::string format_csv(const std::vector<std::string>& names, const Eigen::MatrixXd& values) {
  if (static_cast<Eigen::Index>(names.size()) != values.cols())
    throw std::invalid_argument("format_csv: need names.size() == values.cols(), have " + std::to_string(names.size()) +
                                " names for " + std::to_string(values.cols()) + " columns");
  if (names.empty()) throw std::invalid_argument("format_csv: need at least one column");
  std::unordered_set<std::string> seen;
  bool all_numbers = true;
  for (const auto& n : names) {
    if (n.empty()) throw std::invalid_argument("format_csv: empty column name");
    // A leading byte-order mark would be skipped by the reader (it marks the encoding).
    // No ';' either: a header with more ';' than ',' reads as ';'-separated.
    if (n.find_first_of(",;\"\r\n") != std::string::npos || n.front() == '#' || is_blank(n.front()) ||
        is_blank(n.back()) || n.starts_with(k_utf8_bom))
      throw std::invalid_argument("format_csv: column name '" + n +
                                  "' cannot be written (no ',', ';', '\"', line breaks, leading '#' or byte-order mark, "
                                  "or surrounding spaces)");
    if (names.size() == 1 && n.find_first_of(" \t") != std::string::npos)
      throw std::invalid_argument("format_csv: a single column name cannot contain spaces ('" + n + "')");
    if (!seen.insert(n).second) throw std::invalid_argument("format_csv: duplicate column name '" + n + "'");
    double dummy;
    all_numbers = all_numbers && parse_number(n.data(), n.data() + n.size(), dummy, '.');
  }
  if (all_numbers) throw std::invalid_argument("format_csv: column names must not all be numbers");

  std::string out;
  // ~24 bytes is the longest shortest-round-trip double ("-2.2250738585072014e-308").
  out.reserve(static_cast<std::size_t>(values.size()) * 24 + 64);
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (k) out += ',';
    out += names[k];
  }
  out += '\n';
  char buf[64];
  for (Eigen::Index r = 0; r < values.rows(); ++r) {
    for (Eigen::Index c = 0; c < values.cols(); ++c) {
      if (c) out += ',';
      const auto res = std::to_chars(buf, buf + sizeof buf, values(r, c));
      out.append(buf, res.ptr);
    }
    out += '\n';
  }
  return out;
}

void write_csv(const std::string& path, const std::vector<std::string>& names, const Eigen::MatrixXd& values) {
  write_file_atomically(path, format_csv(names, values));
}

}  // namespace sysid
