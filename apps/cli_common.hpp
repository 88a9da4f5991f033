#pragma once
// Shared pieces of the sysid verbs: the log options every data-reading verb takes
// (--inputs/--outputs/--ts/--time-column/--nan-policy), loading a log with its time
// column, model files, number formatting and messages. No algorithm lives here.
#include <sysid/core/discretize.hpp>
#include <sysid/core/errors.hpp>
#include <sysid/core/io_data.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/model_json.hpp>
#include <sysid/spectral/welch.hpp>
#include <sysid/validate/compare.hpp>

#include <CLI/CLI.hpp>
#include <Eigen/Dense>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sysid::cli {

/// The log-reading options as typed on the command line.
struct LogArgs {
  std::string inputs;   ///< comma-separated column names
  std::string outputs;  ///< comma-separated column names
  std::optional<double> ts;
  std::string time_column = "t";
  std::string nan_policy = "error";
};

/// Which of the log options a verb offers, and their help texts.
struct LogOptionSpec {
  bool inputs_required = true;
  bool outputs_required = true;
  std::string inputs_help = "input columns of the log, comma-separated (e.g. u1,u2)";
  std::string outputs_help = "output columns of the log, comma-separated (e.g. y1,y2)";
};

/// Adds --inputs, --outputs, --ts, --time-column and --nan-policy to `cmd`, and
/// the file-layout options of add_csv_layout_options.
void add_log_options(CLI::App& cmd, LogArgs& args, const LogOptionSpec& spec);

/// Adds --time-unit s|ms|us, --delimiter and --decimal (how the log's file is
/// written: DESIGN.md "CSV logs") to a verb that reads a log. Like --hold, a
/// process-wide setting: one verb runs per process. load_log and make_log_options
/// apply them.
void add_csv_layout_options(CLI::App& cmd);
/// The delimiter and decimal mark chosen (0: detected from the file).
CsvFormat selected_csv_format();
/// The time unit chosen by --time-unit (empty: from the column's name, else s).
std::optional<TimeUnit> selected_time_unit();

/// "a,b,c" -> {"a","b","c"} (trimmed); empty string -> {}. An empty item is a usage error.
std::vector<std::string> split_names(const std::string& list, const std::string& option_name);

/// LogOptions from the typed options (and --time-unit), with explicit channel lists.
LogOptions make_log_options(const LogArgs& args, std::vector<std::string> inputs, std::vector<std::string> outputs);

/// A log and its time column (empty when the log has none or it is not used),
/// aligned with the samples kept after the NaN policy.
struct LoadedLog {
  IoData data;
  Eigen::VectorXd time;
  std::string time_name;
  double seconds_per_time_unit = 1.0;  ///< time * this = seconds (--time-unit, or the column's name)

  /// The time of sample `row` of the first experiment in seconds: its stamp when
  /// the log has a time column, else row * Ts.
  double seconds_at(Eigen::Index row) const {
    return time.size() == data.experiments.front().samples() ? time(row) * seconds_per_time_unit
                                                             : static_cast<double>(row) * data.Ts;
  }
};

/// read_csv (with --delimiter/--decimal) + log_from_table, keeping the time
/// stamps (in the column's unit) for writing them back.
LoadedLog load_log(const std::string& path, const LogOptions& options);

/// read_model_json; refuses "augmented" models (DataError) for the verbs that
/// cannot run them yet.
ModelFile load_model(const std::string& path, bool allow_augmented = false);

/// The model's state-space part ready to run on data sampled every `ts` seconds:
/// a continuous model (Ts = 0) is discretised with the hold of --hold (zero-order
/// by default; with a note on stderr); a discrete model whose Ts differs from the
/// log's by more than 1e-6 relative is a DataError (a model runs only at its own rate).
StateSpace model_for_sample_time(const ModelFile& file, double ts, const std::string& model_path, const std::string& verb);

/// Adds --hold zoh|foh (how a continuous model is sampled, read by
/// model_for_sample_time) to a verb that runs a model on a log. Like --force, a
/// process-wide setting: one verb runs per process.
void add_hold_option(CLI::App& cmd);
/// The hold chosen by --hold (zoh when not given).
Hold selected_hold();

/// The model's channel names: the given list, else the model's names (u1.., y1.. when absent).
std::vector<std::string> model_input_names(const ModelFile& file);
std::vector<std::string> model_output_names(const ModelFile& file);

/// Adds --force (replace existing output files) to a verb that writes files. The
/// flag is the one process-wide setting claim_outputs() reads: one verb runs per process.
void add_force_flag(CLI::App& cmd);

/// check_output_paths (io/atomic_file.hpp) with the --force setting: every verb that
/// writes calls this first, with all the files it may write and all it reads, so a
/// refused output costs nothing and leaves nothing half-done.
void claim_outputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs);

/// "lo:hi" -> (lo, hi); throws CLI::ValidationError naming the option otherwise.
std::pair<double, double> parse_range(const std::string& text, const std::string& option_name);

/// CLI11 validator for "lo:hi" with numbers lo < hi.
CLI::Validator range_validator();

/// printf("%.*g") of a number.
std::string fmt(double value, int digits = 6);

/// "a, b, c".
std::string join(const std::vector<std::string>& items, const std::string& separator = ", ");

/// Per-output fit lines "  <name>: 97.53".
std::string format_fit_lines(const Eigen::VectorXd& fit, const std::vector<std::string>& names);

/// "sysid <verb>: warning: <message>" on stderr.
void warn(const std::string& verb, const std::string& message);

/// "sysid <verb>: <message>" on stderr (progress notes, files written).
void note(const std::string& verb, const std::string& message);

/// The log columns a model runs on: --inputs / --outputs as typed, else the
/// model's channel names; their number must match the model's (std::invalid_argument).
/// Outputs are resolved only when `with_outputs`.
struct ModelChannels {
  std::vector<std::string> inputs, outputs;
};
ModelChannels model_channels(const LogArgs& args, const ModelFile& file, bool with_outputs);

/// CompareOptions for --x0 estimate|zero|model and the model file's offsets
/// (DataError naming `model_path` when "model" is asked and the file has no x0).
CompareOptions compare_options_for(const ModelFile& file, const std::string& x0_mode, const std::string& model_path);

/// The Welch segment options shared by the spectral verbs.
struct WelchArgs {
  Eigen::Index nfft = 1024;
  double overlap = 0.5;
  std::string window = "hann";
  std::string detrend = "mean";
};
/// Adds --nfft, --overlap, --window and --detrend.
void add_welch_options(CLI::App& cmd, WelchArgs& args);
/// WelchOptions from the typed options (other fields at their defaults).
WelchOptions welch_options(const WelchArgs& args);

/// Estimation data and, when the user asked for it, validation data.
struct EstimationData {
  IoData estimation;
  std::optional<IoData> validation;
  std::string validation_label;  ///< the validation file, or "last 30% of samples"
  std::optional<double> split;   ///< the split fraction used, if any
};

/// --validate FILE and --split F (mutually exclusive) on an identification verb.
void add_validation_options(CLI::App& cmd, std::string& validate, std::optional<double>& split);

/// Loads LOG; with `split`, its first fraction is the estimation data and the rest
/// validation; with `validate`, that file (same columns, same sample time, else
/// DataError) is the validation data. The log's samples are moved, not copied.
EstimationData load_estimation_data(const std::string& log_path, const std::string& validate, std::optional<double> split,
                                    const LogOptions& options);

}  // namespace sysid::cli
