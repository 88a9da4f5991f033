#include "sysid/io/matrix_market.hpp"

#include <fast_float/fast_float.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <utility>
#include <vector>

#include "sysid/core/errors.hpp"
#include "sysid/io/atomic_file.hpp"

namespace sysid {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using StorageIndex = SparseMatrix::StorageIndex;
using Triplet = Eigen::Triplet<double, StorageIndex>;

/// Dimensions and entry counts must fit Eigen's sparse index type (int by default).
constexpr long long k_index_limit = std::numeric_limits<StorageIndex>::max();

const char* const k_banner_hint =
    "'%%MatrixMarket matrix coordinate|array real|integer general|symmetric'";

/// Short quote of a token for messages, so a garbled binary file does not flood the terminal.
std::string quote(const char* b, const char* e) {
  constexpr std::ptrdiff_t max_len = 40;
  return "'" + (e - b > max_len ? std::string(b, b + max_len) + "..." : std::string(b, e)) + "'";
}

bool iequals(const char* b, const char* e, const char* word) {
  const std::size_t n = std::strlen(word);
  if (static_cast<std::size_t>(e - b) != n) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (std::tolower(static_cast<unsigned char>(b[i])) != word[i]) return false;
  return true;
}

struct Token {
  const char* b = nullptr;
  const char* e = nullptr;
  long column = 0;  ///< 1-based column of the first character
};

/// The whitespace-separated fields of one line; at most k_max are kept, `count`
/// says how many there were (so "one field too many" can point at the extra one).
struct Fields {
  static constexpr std::size_t k_max = 6;
  std::array<Token, k_max> token;
  std::size_t count = 0;
  long end_column = 1;  ///< 1-based column just past the line's last character
};

class MatrixMarketParser {
 public:
  MatrixMarketParser(const std::string& text, const std::string& source)
      : m_text(text), m_p(text.data()), m_end(text.data() + text.size()), m_source(source) {
    // UTF-8 byte-order mark, as some Windows tools write it.
    if (m_end - m_p >= 3 && static_cast<unsigned char>(m_p[0]) == 0xEF && static_cast<unsigned char>(m_p[1]) == 0xBB &&
        static_cast<unsigned char>(m_p[2]) == 0xBF)
      m_p += 3;
  }

  SparseMatrix parse() {
    read_banner();
    read_size_line();
    std::vector<Triplet> triplets;
    // The announced count is untrusted: reserve no more than the text can hold
    // (an entry takes at least two bytes, "1\n"), so a lying header cannot make us
    // allocate gigabytes before the "fewer entries" error.
    const long long room = static_cast<long long>(m_text.size() / 2) + 1;
    triplets.reserve(static_cast<std::size_t>(std::min(m_entries, room) * (m_symmetric ? 2 : 1)));
    if (m_array)
      read_array(triplets);
    else
      read_coordinates(triplets);
    expect_no_more_entries();
    if (static_cast<long long>(triplets.size()) > k_index_limit)
      throw DataError(m_source, m_size_line, 1,
                      "the matrix has " + std::to_string(triplets.size()) +
                          " stored entries, more than the sparse index limit " + std::to_string(k_index_limit));
    SparseMatrix matrix(static_cast<Eigen::Index>(m_rows), static_cast<Eigen::Index>(m_cols));
    // setFromTriplets sums duplicates (its default functor), which is the
    // assembly FE exporters leave to the reader.
    matrix.setFromTriplets(triplets.begin(), triplets.end());
    matrix.makeCompressed();
    return matrix;
  }

 private:
  [[noreturn]] void fail(long column, const std::string& message) const {
    throw DataError(m_source, m_line, column, message);
  }

  /// Fails at the position an editor shows for the end of the file.
  [[noreturn]] void fail_at_end(const std::string& message) const {
    long line = 1;
    std::size_t line_start = 0;
    for (std::size_t i = 0; i < m_text.size(); ++i)
      if (m_text[i] == '\n') {
        ++line;
        line_start = i + 1;
      }
    throw DataError(m_source, line, static_cast<long>(m_text.size() - line_start) + 1, message);
  }

  /// Advances to the next physical line (without its "\r\n"); false at the end.
  bool next_line() {
    if (m_p == m_end) return false;
    const char* nl = static_cast<const char*>(std::memchr(m_p, '\n', static_cast<std::size_t>(m_end - m_p)));
    m_line_b = m_p;
    m_line_e = nl ? nl : m_end;
    m_p = nl ? nl + 1 : m_end;
    if (m_line_e > m_line_b && m_line_e[-1] == '\r') --m_line_e;
    ++m_line;
    return true;
  }

  /// Advances to the next line that is neither blank nor a % comment.
  bool next_content_line(Fields& fields) {
    while (next_line()) {
      split(fields);
      if (fields.count > 0 && *fields.token[0].b != '%') return true;
    }
    return false;
  }

  void split(Fields& fields) const {
    fields.count = 0;
    const char* q = m_line_b;
    while (true) {
      while (q < m_line_e && (*q == ' ' || *q == '\t')) ++q;
      if (q == m_line_e) break;
      const char* b = q;
      while (q < m_line_e && *q != ' ' && *q != '\t') ++q;
      if (fields.count < Fields::k_max) fields.token[fields.count] = {b, q, static_cast<long>(b - m_line_b) + 1};
      ++fields.count;
    }
    fields.end_column = static_cast<long>(m_line_e - m_line_b) + 1;
  }

  /// Column where a missing field would start, for "expected N fields" messages.
  static long missing_column(const Fields& f) { return f.end_column + (f.count > 0 ? 1 : 0); }

  // ---- banner -----------------------------------------------------------------

  void read_banner() {
    Fields f;
    if (!next_line()) fail_at_end(std::string("empty file: expected the Matrix Market banner ") + k_banner_hint);
    split(f);
    if (f.count == 0 || !iequals(f.token[0].b, f.token[0].e, "%%matrixmarket"))
      fail(1, std::string("expected the Matrix Market banner ") + k_banner_hint + " on the first line, found " +
                  quote(m_line_b, m_line_e));
    auto word = [&](std::size_t i, const char* what) -> const Token& {
      if (f.count <= i)
        fail(missing_column(f), std::string("the banner ends early: expected ") + what + " (banner " + k_banner_hint + ")");
      return f.token[i];
    };

    const Token& object = word(1, "the object 'matrix'");
    if (!iequals(object.b, object.e, "matrix"))
      fail(object.column, "expected the object 'matrix', found " + quote(object.b, object.e) +
                              " (only matrices are supported, not vectors)");

    const Token& format = word(2, "the format 'coordinate' or 'array'");
    if (iequals(format.b, format.e, "array"))
      m_array = true;
    else if (!iequals(format.b, format.e, "coordinate"))
      fail(format.column, "expected the format 'coordinate' (sparse) or 'array' (dense), found " +
                              quote(format.b, format.e));

    const Token& field = word(3, "the field 'real' or 'integer'");
    if (iequals(field.b, field.e, "integer")) {
      m_integer = true;
    } else if (!iequals(field.b, field.e, "real")) {
      const bool known = iequals(field.b, field.e, "complex") || iequals(field.b, field.e, "pattern");
      fail(field.column, (known ? "field " + quote(field.b, field.e) + " is not supported"
                                : "expected the field 'real' or 'integer', found " + quote(field.b, field.e)) +
                             " (supported fields: real, integer)");
    }

    const Token& symmetry = word(4, "the symmetry 'general' or 'symmetric'");
    if (iequals(symmetry.b, symmetry.e, "symmetric")) {
      m_symmetric = true;
    } else if (!iequals(symmetry.b, symmetry.e, "general")) {
      const bool known = iequals(symmetry.b, symmetry.e, "skew-symmetric") || iequals(symmetry.b, symmetry.e, "hermitian");
      fail(symmetry.column, (known ? "symmetry " + quote(symmetry.b, symmetry.e) + " is not supported"
                                   : "expected the symmetry 'general' or 'symmetric', found " +
                                         quote(symmetry.b, symmetry.e)) +
                                " (supported symmetries: general, symmetric)");
    }
    if (f.count > 5)
      fail(f.token[5].column, "unexpected " + quote(f.token[5].b, f.token[5].e) + " after the banner's four words");
  }

  // ---- size line --------------------------------------------------------------

  /// A non-negative integer occupying the whole token; `what` names it in messages.
  long long size_number(const Token& t, const char* what) const {
    long long v = 0;
    const auto r = std::from_chars(t.b, t.e, v);
    if (r.ec == std::errc::result_out_of_range && r.ptr == t.e)
      fail(t.column, std::string("the number of ") + what + " " + quote(t.b, t.e) + " is absurdly large (limit " +
                         std::to_string(k_index_limit) + ")");
    if (r.ec != std::errc() || r.ptr != t.e || v < 0)
      fail(t.column, std::string("expected the number of ") + what + " (a non-negative integer), found " + quote(t.b, t.e));
    if (v > k_index_limit)
      fail(t.column, std::string("the number of ") + what + " " + std::to_string(v) +
                         " exceeds the sparse index limit " + std::to_string(k_index_limit));
    return v;
  }

  void read_size_line() {
    Fields f;
    const char* expected = m_array ? "'rows columns'" : "'rows columns entries'";
    if (!next_content_line(f)) fail_at_end(std::string("the file ends before the size line ") + expected);
    m_size_line = m_line;
    const std::size_t want = m_array ? 2 : 3;
    if (f.count < want)
      fail(missing_column(f), std::string("expected the size line ") + expected + ", found " +
                                  std::to_string(f.count) + (f.count == 1 ? " number" : " numbers"));
    if (f.count > want)
      fail(f.token[want].column, std::string("expected the size line ") + expected + ", found extra text " +
                                     quote(f.token[want].b, f.token[want].e));
    m_rows = size_number(f.token[0], "rows");
    m_cols = size_number(f.token[1], "columns");
    if (m_symmetric && m_rows != m_cols)
      fail(f.token[1].column, "a symmetric matrix must be square, but rows " + std::to_string(m_rows) +
                                  " != columns " + std::to_string(m_cols));
    long long cells = 0;
    if (__builtin_mul_overflow(m_rows, m_cols, &cells))  // cannot happen below the index limit; kept as a guard
      fail(f.token[1].column, "rows x columns overflows a 64-bit integer");
    if (m_array) {
      m_entries = m_symmetric ? m_rows * (m_rows + 1) / 2 : cells;
    } else {
      m_entries = size_number(f.token[2], "entries");
      if (m_entries > cells)
        fail(f.token[2].column, "the size line announces " + std::to_string(m_entries) +
                                    " entries, more than rows x columns = " + std::to_string(cells));
    }
  }

  // ---- entries ----------------------------------------------------------------

  /// A 1-based index in 1..limit occupying the whole token; returns it 0-based.
  StorageIndex index(const Token& t, long long limit, const char* what) const {
    long long v = 0;
    const auto r = std::from_chars(t.b, t.e, v);
    const std::string range = "1.." + std::to_string(limit);
    if (r.ptr != t.e || (r.ec != std::errc() && r.ec != std::errc::result_out_of_range))
      fail(t.column, std::string("expected a ") + what + " index (an integer in " + range + "), found " + quote(t.b, t.e));
    if (r.ec != std::errc() || v < 1 || v > limit)
      fail(t.column, std::string(what) + " index " + quote(t.b, t.e) + " is outside " + range);
    return static_cast<StorageIndex>(v - 1);
  }

  double value(const Token& t) const {
    const char* b = t.b;
    // A leading '+' is legal in the format's C-style numbers; fast_float rejects it.
    if (b < t.e && *b == '+' && b + 1 < t.e && b[1] != '-' && b[1] != '+') ++b;
    if (m_integer) {
      const char* q = (b < t.e && *b == '-') ? b + 1 : b;
      const bool digits = q < t.e && std::all_of(q, t.e, [](char c) { return c >= '0' && c <= '9'; });
      if (!digits)
        fail(t.column, "expected an integer value (the banner says 'integer'), found " + quote(t.b, t.e));
    }
    double v = 0.0;
    const auto r = fast_float::from_chars(b, t.e, v);
    if (r.ec != std::errc() || r.ptr != t.e || b == t.e)
      fail(t.column, "expected a number, found " + quote(t.b, t.e));
    if (!std::isfinite(v))
      fail(t.column, "value " + quote(t.b, t.e) + " is NaN or Inf (or beyond the range of a double); not allowed");
    return v;
  }

  [[noreturn]] void fail_short(long long read) const {
    fail_at_end("the file ends after " + std::to_string(read) + " of the " + std::to_string(m_entries) +
                " entries announced on line " + std::to_string(m_size_line));
  }

  void read_coordinates(std::vector<Triplet>& triplets) {
    Fields f;
    for (long long k = 0; k < m_entries; ++k) {
      if (!next_content_line(f)) fail_short(k);
      if (f.count < 3)
        fail(missing_column(f), "expected an entry 'row column value' (3 fields), found " + std::to_string(f.count) +
                                    (f.count == 1 ? " field" : " fields"));
      if (f.count > 3)
        fail(f.token[3].column, "expected an entry 'row column value', found a 4th field " +
                                    quote(f.token[3].b, f.token[3].e) + " (complex values are not supported)");
      const StorageIndex i = index(f.token[0], m_rows, "row");
      const StorageIndex j = index(f.token[1], m_cols, "column");
      if (m_symmetric && i < j)
        fail(f.token[0].column, "entry (" + std::to_string(i + 1) + ", " + std::to_string(j + 1) +
                                    ") lies in the upper triangle; a symmetric file stores only the lower "
                                    "triangle (row >= column)");
      const double v = value(f.token[2]);
      triplets.emplace_back(i, j, v);
      if (m_symmetric && i != j) triplets.emplace_back(j, i, v);
    }
  }

  void read_array(std::vector<Triplet>& triplets) {
    Fields f;
    long long k = 0;
    for (long long j = 0; j < m_cols; ++j)
      for (long long i = m_symmetric ? j : 0; i < m_rows; ++i, ++k) {
        if (!next_content_line(f)) fail_short(k);
        if (f.count > 1)
          fail(f.token[1].column, "expected one value per line (array format), found a 2nd field " +
                                      quote(f.token[1].b, f.token[1].e));
        const double v = value(f.token[0]);
        if (v == 0.0) continue;  // dense zeros are not stored entries
        triplets.emplace_back(static_cast<StorageIndex>(i), static_cast<StorageIndex>(j), v);
        if (m_symmetric && i != j) triplets.emplace_back(static_cast<StorageIndex>(j), static_cast<StorageIndex>(i), v);
      }
  }

  void expect_no_more_entries() {
    Fields f;
    if (next_content_line(f))
      fail(f.token[0].column, "more entries than the " + std::to_string(m_entries) + " announced on line " +
                                  std::to_string(m_size_line) + " (this is entry " + std::to_string(m_entries + 1) +
                                  ")");
  }

  const std::string& m_text;
  const char* m_p;
  const char* m_end;
  const std::string& m_source;
  const char* m_line_b = nullptr;
  const char* m_line_e = nullptr;
  long m_line = 0;
  long m_size_line = 0;
  bool m_array = false;
  bool m_integer = false;
  bool m_symmetric = false;
  long long m_rows = 0;
  long long m_cols = 0;
  long long m_entries = 0;
};

/// First (row, column) where A(i,j) != A(j,i), if any (rows != cols gives (-1, -1)).
std::optional<std::pair<Eigen::Index, Eigen::Index>> first_asymmetry(const SparseMatrix& a) {
  if (a.rows() != a.cols()) return std::make_pair(Eigen::Index{-1}, Eigen::Index{-1});
  const SparseMatrix transposed = a.transpose();
  // For finite doubles x - y == 0 exactly when x == y (gradual underflow), and
  // NaN or Inf - Inf give NaN != 0: the difference is an exact test.
  const SparseMatrix difference = a - transposed;
  for (Eigen::Index k = 0; k < difference.outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(difference, k); it; ++it)
      if (!(it.value() == 0.0)) return std::make_pair(it.row(), it.col());
  return std::nullopt;
}

}  // namespace

Eigen::SparseMatrix<double> parse_matrix_market(const std::string& text, const std::string& source) {
  return MatrixMarketParser(text, source).parse();
}

Eigen::SparseMatrix<double> read_matrix_market(const std::string& path) {
  return parse_matrix_market(read_whole_file(path), path);
}

bool is_exactly_symmetric(const Eigen::SparseMatrix<double>& matrix) { return !first_asymmetry(matrix).has_value(); }

std::string format_matrix_market(const Eigen::SparseMatrix<double>& matrix, bool symmetric) {
  Eigen::Index count = 0;
  for (Eigen::Index k = 0; k < matrix.outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(matrix, k); it; ++it) {
      if (!std::isfinite(it.value()))
        throw std::invalid_argument("format_matrix_market: entry (" + std::to_string(it.row()) + ", " +
                                    std::to_string(it.col()) + ") is NaN or Inf; the format's readers refuse them");
      if (!symmetric || it.row() >= it.col()) ++count;
    }
  if (symmetric) {
    if (const auto where = first_asymmetry(matrix)) {
      if (where->first < 0)
        throw std::invalid_argument("format_matrix_market: symmetric storage needs rows == cols, have " +
                                    std::to_string(matrix.rows()) + " x " + std::to_string(matrix.cols()));
      char buf[160];
      std::snprintf(buf, sizeof buf, "A(%ld, %ld) = %.17g != A(%ld, %ld) = %.17g", static_cast<long>(where->first),
                    static_cast<long>(where->second), matrix.coeff(where->first, where->second),
                    static_cast<long>(where->second), static_cast<long>(where->first),
                    matrix.coeff(where->second, where->first));
      throw std::invalid_argument(std::string("format_matrix_market: symmetric storage needs an exactly symmetric "
                                              "matrix, but ") + buf + " (0-based)");
    }
  }

  std::string out;
  out.reserve(static_cast<std::size_t>(count) * 36 + 128);
  out += symmetric ? "%%MatrixMarket matrix coordinate real symmetric\n"
                   : "%%MatrixMarket matrix coordinate real general\n";
  out += symmetric ? "% written by sysid: lower triangle, 1-based row column value, %.17g\n"
                   : "% written by sysid: 1-based row column value, %.17g\n";
  out += std::to_string(matrix.rows()) + " " + std::to_string(matrix.cols()) + " " + std::to_string(count) + "\n";
  // Column-major order: the InnerIterator of a ColMajor matrix walks columns.
  char buf[96];
  for (Eigen::Index k = 0; k < matrix.outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(matrix, k); it; ++it) {
      if (symmetric && it.row() < it.col()) continue;
      const int n = std::snprintf(buf, sizeof buf, "%ld %ld %.17g\n", static_cast<long>(it.row() + 1),
                                  static_cast<long>(it.col() + 1), it.value());
      out.append(buf, static_cast<std::size_t>(n));
    }
  return out;
}

void write_matrix_market(const std::string& path, const Eigen::SparseMatrix<double>& matrix, bool symmetric) {
  write_file_atomically(path, format_matrix_market(matrix, symmetric));
}

}  // namespace sysid
