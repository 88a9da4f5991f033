// sysid filter: Butterworth filtering (causal or zero-phase), detrending and
// decimation of columns of a log, written as a log with the same columns.
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/signal/butterworth.hpp>
#include <sysid/signal/detrend.hpp>
#include <sysid/signal/resample.hpp>
#include <sysid/signal/sos_filter.hpp>

#include <iostream>
#include <memory>
#include <optional>

#include "cli_common.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct FilterArgs {
  std::string log_path;
  std::string columns;
  std::optional<double> ts;
  std::string time_column = "t";
  std::optional<double> lowpass, highpass;
  std::string bandpass;
  int order = 4;
  bool zero_phase = false;
  std::string detrend;
  int decimate = 1;
  std::string out;
};

void run_filter(const FilterArgs& a) {
  const std::string verb = "filter";
  const bool band = a.lowpass || a.highpass || !a.bandpass.empty();
  if (!band && a.detrend.empty() && a.decimate == 1)
    throw CLI::ValidationError("--lowpass/--highpass/--bandpass/--detrend/--decimate", "nothing to do: give a filter, --detrend or --decimate");
  if (a.zero_phase && !band) throw CLI::ValidationError("--zero-phase", "needs --lowpass, --highpass or --bandpass");
  claim_outputs({a.out}, {a.log_path});

  const CsvTable table = read_csv(a.log_path, selected_csv_format());
  const std::string time_name = a.time_column == "none" ? std::string() : a.time_column;
  const Eigen::Index time_col = time_name.empty() ? -1 : table.column(time_name);
  std::vector<std::string> columns = split_names(a.columns, "--columns");
  if (columns.empty())  // default: every column but the time column
    for (const auto& n : table.names)
      if (n != time_name) columns.push_back(n);
  for (const auto& c : columns)
    if (c == time_name && time_col >= 0) throw CLI::ValidationError("--columns", "the time column '" + c + "' cannot be filtered");
  // The log reader checks the columns (present, finite) and finds the sample time.
  LogOptions lo;
  lo.outputs = columns;
  lo.time_column = time_name;
  lo.ts = a.ts;
  lo.time_unit = selected_time_unit();
  const IoData data = log_from_table(table, lo);
  const double fs = 1.0 / data.Ts;
  Eigen::MatrixXd x = data.experiments.front().y;

  std::string what;
  if (!a.detrend.empty()) {
    x = detrend(x, parse_trend_type(a.detrend));
    what += a.detrend + " trend removed; ";
  }
  if (band) {
    SecondOrderSections f;
    if (a.lowpass) {
      f = butterworth(a.order, BandType::lowpass, *a.lowpass, 0.0, fs);
      what += "low-pass " + fmt(*a.lowpass) + " Hz";
    } else if (a.highpass) {
      f = butterworth(a.order, BandType::highpass, *a.highpass, 0.0, fs);
      what += "high-pass " + fmt(*a.highpass) + " Hz";
    } else {
      const auto [f1, f2] = parse_range(a.bandpass, "--bandpass");
      f = butterworth(a.order, BandType::bandpass, f1, f2, fs);
      what += "band-pass " + fmt(f1) + ".." + fmt(f2) + " Hz";
    }
    what += ", Butterworth order " + std::to_string(a.order) + " at fs " + fmt(fs) + " Hz, " +
            (a.zero_phase ? "zero-phase (forward-backward: magnitude squared, -6 dB at the cutoff)" : "causal");
    x = a.zero_phase ? filtfilt(f, x) : sos_filter(f, x);
  }

  Eigen::MatrixXd values = table.values;
  for (std::size_t c = 0; c < columns.size(); ++c) values.col(table.column(columns[c])) = x.col(static_cast<Eigen::Index>(c));
  if (a.decimate > 1) {
    // Anti-alias filter on the processed columns; the others (and the time column)
    // are only sub-sampled, so say which those are.
    const Eigen::MatrixXd xd = decimate(x, a.decimate);
    Eigen::MatrixXd kept(xd.rows(), values.cols());
    for (Eigen::Index k = 0; k < xd.rows(); ++k) kept.row(k) = values.row(k * a.decimate);
    for (std::size_t c = 0; c < columns.size(); ++c) kept.col(table.column(columns[c])) = xd.col(static_cast<Eigen::Index>(c));
    values = std::move(kept);
    what += std::string(what.empty() ? "" : "; ") + "decimated by " + std::to_string(a.decimate) +
            " (8th-order zero-phase anti-alias low-pass at " + fmt(0.8 * fs / (2.0 * a.decimate)) + " Hz)";
    std::vector<std::string> untouched;
    for (const auto& n : table.names)
      if (n != time_name && std::find(columns.begin(), columns.end(), n) == columns.end()) untouched.push_back(n);
    if (!untouched.empty()) warn(verb, "columns sub-sampled without anti-alias filter: " + join(untouched));
  }
  write_csv(a.out, table.names, values);
  note(verb, what);
  note(verb, "wrote " + std::to_string(values.rows()) + " rows, " + std::to_string(columns.size()) + " column(s) processed, to " + a.out);
}

}  // namespace

Verb register_filter(CLI::App& app) {
  auto args = std::make_shared<FilterArgs>();
  CLI::App* cmd = app.add_subcommand(
      "filter", "Butterworth-filter, detrend or decimate columns of a log; writes a log with the same columns");
  cmd->add_option("log", args->log_path, "CSV log")->required();
  cmd->add_option("--columns", args->columns, "columns to process, comma-separated (default: all but the time column)");
  cmd->add_option("--ts", args->ts, "sample time in seconds; required when the log has no time column")->check(CLI::PositiveNumber);
  cmd->add_option("--time-column", args->time_column, "name of the time column, kept as it is ('none': no time column)")
      ->capture_default_str();
  add_csv_layout_options(*cmd);
  CLI::Option* lp = cmd->add_option("--lowpass", args->lowpass, "low-pass cutoff in Hz (-3 dB of the designed filter)")
                        ->check(CLI::PositiveNumber);
  CLI::Option* hp = cmd->add_option("--highpass", args->highpass, "high-pass cutoff in Hz")->check(CLI::PositiveNumber);
  CLI::Option* bp = cmd->add_option("--bandpass", args->bandpass, "band-pass edges LO:HI in Hz")->check(range_validator());
  lp->excludes(hp)->excludes(bp);
  hp->excludes(bp);
  cmd->add_option("--order", args->order, "Butterworth order (band-pass: of the low-pass prototype)")
      ->capture_default_str()
      ->check(CLI::Range(1, 40));
  cmd->add_flag("--zero-phase", args->zero_phase,
                "forward-backward filtering: no phase shift or delay, magnitude squared (twice the order's attenuation)");
  cmd->add_option("--detrend", args->detrend, "remove a constant or linear trend from each column first")
      ->check(CLI::IsMember({"constant", "linear"}));
  cmd->add_option("--decimate", args->decimate, "keep every R-th row after an anti-alias low-pass of the processed columns")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--out", args->out, "output CSV log (same columns; written atomically)")->required();
  cmd->footer(
      "Butterworth design by the bilinear transform with prewarping, as second-order sections.\n"
      "Order of operations: --detrend, then the filter, then --decimate.\n"
      "Example (the Par2 paper's pre-filter: 5th-order 100 Hz low-pass at 2 kHz):\n"
      "  sysid filter par2_gu.csv --columns u,y --lowpass 100 --order 5 --out par2_lp.csv\n"
      "  sysid filter log.csv --columns y --bandpass 5:200 --order 4 --zero-phase --out y_bp.csv");
  return {cmd, [args] { run_filter(*args); }};
}

}  // namespace sysid::cli
