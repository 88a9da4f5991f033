#pragma once
/// @file
/// Purpose: the two error channels besides std::invalid_argument (a violated
/// precondition of an algorithm, e.g. "n4sid: need horizon > order").
///
/// - DataError: the user's data or model file is bad (CLI exit 2). Carries file,
///   line and column where known, and formats them as "file:line:column: message".
/// - NumericalError: the computation failed (rank deficiency, no convergence,
///   unstable result; CLI exit 3).
/// Non-convergence of an iterative method is reported as a Status in its Result,
/// not thrown; the CLI turns that status into exit 3.
#include <stdexcept>
#include <string>

namespace sysid {

class DataError : public std::runtime_error {
 public:
  explicit DataError(const std::string& message) : std::runtime_error(message), m_message(message) {}
  DataError(std::string file, long line, long column, const std::string& message)
      : std::runtime_error(format(file, line, column, message)), m_file(std::move(file)), m_line(line), m_column(column),
        m_message(message) {}

  const std::string& file() const { return m_file; }
  long line() const { return m_line; }      ///< 1-based; 0 when not applicable
  long column() const { return m_column; }  ///< 1-based; 0 when not applicable
  const std::string& message() const { return m_message; }

 private:
  static std::string format(const std::string& file, long line, long column, const std::string& message) {
    std::string s = file;
    if (line > 0) s.append(":").append(std::to_string(line));
    if (column > 0) s.append(":").append(std::to_string(column));
    if (s.empty()) return message;
    s.append(": ").append(message);
    return s;
  }
  std::string m_file;
  long m_line = 0;
  long m_column = 0;
  std::string m_message;
};

class NumericalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace sysid
