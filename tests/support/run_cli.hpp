#pragma once
// Test support for the end-to-end tests of the sysid program: run the binary
// (SYSID_BINARY) with arguments, capture exit code, stdout and stderr; a
// per-test temporary directory; small file helpers.
#include <sys/wait.h>
#include <unistd.h>

#include <sysid/core/state_space.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/model_json.hpp>

#include <Eigen/Dense>
#include <array>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "random_matrices.hpp"

namespace sysid::test {

struct CliResult {
  int exit_code = -1;  ///< the process exit status (128 + signal if killed by one)
  std::string out;     ///< stdout
  std::string err;     ///< stderr
};

/// A fresh directory under the system temp dir, named after the running test,
/// removed (with its contents) when the object goes out of scope.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    std::string name = "sysid_app";
    if (const auto* info = ::testing::UnitTest::GetInstance()->current_test_info())
      name += std::string("_") + info->test_suite_name() + "_" + info->name();
    for (char& c : name)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
    name += "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
    m_path = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(m_path);
    std::filesystem::create_directories(m_path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(m_path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return m_path; }
  /// Full path of a file inside the directory, as a string for command lines.
  std::string operator/(const std::string& file) const { return (m_path / file).string(); }

 private:
  std::filesystem::path m_path;
};

/// Single-quotes an argument for /bin/sh.
inline std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) {
    if (c == '\'')
      q += "'\\''";
    else
      q += c;
  }
  return q + "'";
}

inline std::string read_text_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

/// Whether `text` contains `part`.
inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// A JSON file (a report, a model), parsed.
inline nlohmann::json read_json(const std::string& path) { return nlohmann::json::parse(read_text_file(path)); }

inline void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  if (!f) throw std::runtime_error("cannot write " + path);
}

/// The header and the first `rows` data rows of a CSV file.
inline std::string first_rows(const std::string& path, int rows) {
  std::ifstream f(path);
  std::string line, text;
  for (int k = 0; k <= rows && std::getline(f, line); ++k) text += line + "\n";
  return text;
}

/// Runs `sysid args...` through /bin/sh: stdout is read through popen, stderr is
/// redirected to a temporary file (unique per call, removed afterwards).
inline CliResult run_cli(const std::vector<std::string>& args) {
#ifndef SYSID_BINARY
  // Built without the command-line program (SYSID_BUILD_APPS=OFF): unit tests that
  // include this header for its file helpers still compile; only app tests, which
  // are not registered then, run the binary.
  (void)args;
  throw std::runtime_error("run_cli: the sysid binary is not built (SYSID_BUILD_APPS=OFF)");
#else
  static std::atomic<int> counter{0};
  const std::filesystem::path err_file = std::filesystem::temp_directory_path() /
                                         ("sysid_cli_stderr_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  std::string cmd = shell_quote(SYSID_BINARY);
  for (const auto& a : args) cmd += " " + shell_quote(a);
  cmd += " 2> " + shell_quote(err_file.string());
  CliResult r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("popen failed for: " + cmd);
  char buf[4096];
  std::size_t got;
  while ((got = std::fread(buf, 1, sizeof buf, pipe)) > 0) r.out.append(buf, got);
  const int status = ::pclose(pipe);
  if (WIFEXITED(status))
    r.exit_code = WEXITSTATUS(status);
  else if (WIFSIGNALED(status))
    r.exit_code = 128 + WTERMSIG(status);
  r.err = read_text_file(err_file.string());
  std::error_code ec;
  std::filesystem::remove(err_file, ec);
  return r;
#endif
}

/// For failure messages: the command's output in full.
inline std::string describe(const CliResult& r) {
  return "exit " + std::to_string(r.exit_code) + "\n--- stdout ---\n" + r.out + "--- stderr ---\n" + r.err;
}

/// The number after `label` in `text` (first match of label followed by a number), or NaN.
inline double number_after(const std::string& text, const std::string& label) {
  const auto pos = text.find(label);
  if (pos == std::string::npos) return std::numeric_limits<double>::quiet_NaN();
  try {
    return std::stod(text.substr(pos + label.size()));
  } catch (const std::exception&) {
    return std::numeric_limits<double>::quiet_NaN();
  }
}

/// The fit printed for `channel` ("  <channel>: 97.53" lines, as the verbs print
/// them) in the first block after the line containing `header`; NaN if absent.
inline double fit_after(const std::string& text, const std::string& header, const std::string& channel) {
  const auto h = text.find(header);
  if (h == std::string::npos) return std::numeric_limits<double>::quiet_NaN();
  return number_after(text.substr(h), "\n  " + channel + ": ");
}

// ---- models and logs for the end-to-end tests ------------------------------

/// One lightly damped mode of a test model: natural frequency, damping ratio,
/// and the gain of its input column.
struct TestMode {
  double freq_hz;
  double damping;
  double gain;
};

/// Discrete-time SISO model (input "u", output "y") in real modal form: one 2x2
/// block r [[cos th, sin th], [-sin th, cos th]] per mode with z = r e^{j th} =
/// exp(s Ts), s = -zeta w + j w sqrt(1 - zeta^2), so the modal table must show
/// exactly freq_hz and damping. B = [0; gain] and C = [1, 0] per block give
/// G_k(z) = gain r sin(th) / (z^2 - 2 r cos(th) z + r^2).
inline StateSpace modal_siso(const std::vector<TestMode>& modes, double Ts, double d = 0.0) {
  const auto n = static_cast<Eigen::Index>(2 * modes.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n), B = Eigen::MatrixXd::Zero(n, 1), C = Eigen::MatrixXd::Zero(1, n);
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(2 * k);
    const double w = 2.0 * std::numbers::pi * modes[k].freq_hz, zeta = modes[k].damping;
    const double r = std::exp(-zeta * w * Ts), th = w * std::sqrt(1.0 - zeta * zeta) * Ts;
    A.block(i, i, 2, 2) << r * std::cos(th), r * std::sin(th), -r * std::sin(th), r * std::cos(th);
    B(i + 1, 0) = modes[k].gain;
    C(0, i) = 1.0;
  }
  StateSpace sys(A, B, C, Eigen::MatrixXd::Constant(1, 1, d), Ts);
  sys.input_names = {"u"};
  sys.output_names = {"y"};
  return sys;
}

/// The 4th-order test plant of the app tests: modes at 50 Hz (zeta 0.02) and
/// 120 Hz (zeta 0.05), sampled at 1 kHz; the gains make both modes visible.
inline StateSpace four_mode_plant() { return modal_siso({{50.0, 0.02, 1.0}, {120.0, 0.05, 3.0}}, 0.001); }

/// Writes a state-space model file (K, offsets, x0 optional).
inline void write_model(const std::string& path, const StateSpace& sys, const Eigen::MatrixXd& K = {},
                        const Eigen::VectorXd& input_offset = {}, const Eigen::VectorXd& output_offset = {},
                        const Eigen::VectorXd& x0 = {}) {
  ModelFile f;
  f.model = sys;
  f.K = K;
  f.input_offset = input_offset;
  f.output_offset = output_offset;
  f.x0 = x0;
  write_model_json(path, f);
}

/// Column `name` of a CSV file (read with the library's reader).
inline Eigen::VectorXd csv_column(const std::string& path, const std::string& name) {
  const CsvTable t = read_csv(path);
  const Eigen::Index c = t.column(name);
  if (c < 0) throw std::runtime_error(path + " has no column " + name);
  return t.values.col(c);
}

}  // namespace sysid::test
