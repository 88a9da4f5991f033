#include "cli_common.hpp"

#include <sysid/core/discretize.hpp>
#include <sysid/core/errors.hpp>
#include <sysid/core/format_number.hpp>
#include <sysid/io/atomic_file.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>

namespace sysid::cli {

namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

}  // namespace

void add_log_options(CLI::App& cmd, LogArgs& args, const LogOptionSpec& spec) {
  CLI::Option* in = cmd.add_option("--inputs", args.inputs, spec.inputs_help);
  if (spec.inputs_required) in->required();
  CLI::Option* out = cmd.add_option("--outputs", args.outputs, spec.outputs_help);
  if (spec.outputs_required) out->required();
  cmd.add_option("--ts", args.ts,
                 "sample time in seconds; required when the log has no time column, checked against it otherwise")
      ->check(CLI::PositiveNumber);
  cmd.add_option("--time-column", args.time_column, "name of the time column ('none': ignore any time column)")
      ->capture_default_str();
  cmd.add_option("--nan-policy", args.nan_policy,
                 "NaN/Inf/empty cells: error (default), drop (leading/trailing rows only), interpolate (linear)")
      ->check(CLI::IsMember({"error", "drop", "interpolate"}))
      ->capture_default_str();
  add_csv_layout_options(cmd);
}

namespace {
std::string g_time_unit;            // --time-unit ("" when not given)
std::string g_delimiter, g_decimal;  // --delimiter, --decimal ("" when not given: detected)
}  // namespace

void add_csv_layout_options(CLI::App& cmd) {
  cmd.add_option("--time-unit", g_time_unit,
                 "what the time column counts: s, ms or us (default: the unit its name states, as in t_ms or "
                 "'time [ms]', else s)")
      ->check(CLI::IsMember({"s", "ms", "us"}));
  cmd.add_option("--delimiter", g_delimiter,
                 "field delimiter of the log: ',', ';', 'tab' or 'space' (default: detected from the header row)")
      ->check(CLI::IsMember({",", ";", "tab", "space"}));
  cmd.add_option("--decimal", g_decimal,
                 "decimal mark of the log: '.' or ',' (default: '.' in comma-separated files, else detected)")
      ->check(CLI::IsMember({".", ","}));
}

CsvFormat selected_csv_format() {
  CsvFormat f;
  if (g_delimiter == "tab") f.delimiter = '\t';
  else if (g_delimiter == "space") f.delimiter = ' ';
  else if (!g_delimiter.empty()) f.delimiter = g_delimiter[0];
  if (!g_decimal.empty()) f.decimal = g_decimal[0];
  if (f.decimal == ',' && f.delimiter == ',')
    throw CLI::ValidationError("--decimal", "a decimal comma needs another delimiter (--delimiter ';', tab or space)");
  return f;
}

std::optional<TimeUnit> selected_time_unit() { return time_unit_from_symbol(g_time_unit); }

std::vector<std::string> split_names(const std::string& list, const std::string& option_name) {
  std::vector<std::string> names;
  if (trim(list).empty()) return names;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = list.find(',', start);
    const std::string item = trim(list.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (item.empty()) throw CLI::ValidationError(option_name, "empty column name in '" + list + "'");
    names.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return names;
}

LogOptions make_log_options(const LogArgs& args, std::vector<std::string> inputs, std::vector<std::string> outputs) {
  LogOptions o;
  o.inputs = std::move(inputs);
  o.outputs = std::move(outputs);
  o.time_column = args.time_column == "none" ? std::string() : args.time_column;
  o.ts = args.ts;
  o.time_unit = selected_time_unit();
  o.nan_policy = nan_policy_from_name(args.nan_policy);
  return o;
}

LoadedLog load_log(const std::string& path, const LogOptions& options) {
  LoadedLog out;
  out.data = log_from_table(read_csv(path, selected_csv_format()), options, &out.time);
  if (out.time.size() == 0) return out;
  out.time_name = options.time_column;
  out.seconds_per_time_unit = seconds_per(time_unit_of(options, options.time_column));
  return out;
}

ModelFile load_model(const std::string& path, bool allow_augmented) {
  ModelFile m = read_model_json(path);
  if (m.type == "augmented" && !allow_augmented) throw DataError(path, 0, 0, "augmented models are not supported yet");
  return m;
}

namespace {
std::string g_hold = "zoh";  // --hold
bool g_hold_given = false;
}  // namespace

void add_hold_option(CLI::App& cmd) {
  cmd.add_option("--hold", g_hold,
                 "how a continuous-time model is sampled (at the log's rate; reduce --fem: at --ts): zoh (inputs held "
                 "between samples, e.g. by a DAC) or foh (first-order hold: smooth signals that were only sampled, "
                 "where zoh lags by half a sample)")
      ->check(CLI::IsMember({"zoh", "foh"}))
      ->capture_default_str()
      ->each([](const std::string&) { g_hold_given = true; });
}

Hold selected_hold() { return hold_from_name(g_hold); }

StateSpace model_for_sample_time(const ModelFile& file, double ts, const std::string& model_path, const std::string& verb) {
  if (file.model.is_discrete() && g_hold_given)
    warn(verb, model_path + " is a discrete-time model: --hold applies only to continuous-time models and is ignored");
  if (!file.model.is_discrete()) {
    note(verb, model_path + " is a continuous-time model: discretised with a " +
                   (selected_hold() == Hold::foh ? "first" : "zero") + "-order hold at Ts = " + fmt(ts) + " s");
  }
  return model_at_sample_time(file.model, ts, selected_hold(), model_path);
}

std::vector<std::string> model_input_names(const ModelFile& file) {
  return file.model.input_names_or_defaults();
}

std::vector<std::string> model_output_names(const ModelFile& file) {
  return file.model.output_names_or_defaults();
}

std::pair<double, double> parse_range(const std::string& text, const std::string& option_name) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) throw CLI::ValidationError(option_name, "expected LO:HI, found '" + text + "'");
  try {
    std::size_t used_lo = 0, used_hi = 0;
    const std::string a = trim(text.substr(0, colon)), b = trim(text.substr(colon + 1));
    const double lo = std::stod(a, &used_lo), hi = std::stod(b, &used_hi);
    if (used_lo != a.size() || used_hi != b.size() || !std::isfinite(lo) || !std::isfinite(hi))
      throw CLI::ValidationError(option_name, "expected LO:HI with two numbers, found '" + text + "'");
    if (!(lo < hi)) throw CLI::ValidationError(option_name, "need LO < HI, found '" + text + "'");
    return {lo, hi};
  } catch (const std::logic_error&) {  // std::stod: invalid_argument / out_of_range
    throw CLI::ValidationError(option_name, "expected LO:HI with two numbers, found '" + text + "'");
  }
}

CLI::Validator range_validator() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        try {
          parse_range(s, "");
        } catch (const CLI::ValidationError& e) {
          return "expected LO:HI with numbers LO < HI, found '" + s + "'";
        }
        return {};
      },
      "LO:HI");
}

std::string fmt(double value, int digits) {
  if (std::isnan(value)) return "n/a";
  return format_number(value, digits);
}

std::string join(const std::vector<std::string>& items, const std::string& separator) {
  std::string s;
  for (std::size_t k = 0; k < items.size(); ++k) s += (k ? separator : "") + items[k];
  return s;
}

std::string format_fit_lines(const Eigen::VectorXd& fit, const std::vector<std::string>& names) {
  std::string s;
  char buf[256];
  for (Eigen::Index i = 0; i < fit.size(); ++i) {
    const std::string name = i < static_cast<Eigen::Index>(names.size()) ? names[static_cast<std::size_t>(i)]
                                                                         : "y" + std::to_string(i + 1);
    if (std::isnan(fit(i)))
      std::snprintf(buf, sizeof buf, "  %s: n/a\n", name.c_str());
    else
      std::snprintf(buf, sizeof buf, "  %s: %.2f\n", name.c_str(), fit(i));
    s += buf;
  }
  return s;
}

void warn(const std::string& verb, const std::string& message) { std::cerr << "sysid " << verb << ": warning: " << message << "\n"; }

namespace {
bool g_replace_existing_outputs = false;
}  // namespace

void add_force_flag(CLI::App& cmd) {
  cmd.add_flag("--force", g_replace_existing_outputs, "replace output files that already exist (never an input file)");
}

void claim_outputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs) {
  try {
    check_output_paths(outputs, inputs, g_replace_existing_outputs, "pass --force to replace it");
  } catch (const OutputConflictError& e) {  // contradicting options: a usage error (exit 1)
    throw CLI::ValidationError("outputs", e.what());
  }
}

void note(const std::string& verb, const std::string& message) { std::cerr << "sysid " << verb << ": " << message << "\n"; }

void add_validation_options(CLI::App& cmd, std::string& validate, std::optional<double>& split) {
  CLI::Option* val =
      cmd.add_option("--validate", validate, "validation log (same columns): identify on LOG, report the fit on FILE");
  CLI::Option* spl = cmd.add_option("--split", split, "identify on the first fraction F of LOG, validate on the rest (0 < F < 1)")
                         ->check(CLI::Validator(
                             [](std::string& s) -> std::string {
                               try {
                                 const double f = std::stod(s);
                                 if (f > 0.0 && f < 1.0) return {};
                               } catch (const std::exception&) {
                               }
                               return "expected a fraction 0 < F < 1, found '" + s + "'";
                             },
                             "F"));
  val->excludes(spl);
}

EstimationData load_estimation_data(const std::string& log_path, const std::string& validate, std::optional<double> split,
                                    const LogOptions& options) {
  EstimationData out;
  IoData all = load_log(log_path, options).data;
  if (split) {
    DataSplit parts = sysid::split(all, *split);
    all = IoData();  // free the samples: both parts hold copies
    out.estimation = std::move(parts.estimation);
    out.validation = std::move(parts.validation);
    out.validation_label = "last " + fmt(100.0 * (1.0 - *split), 3) + "% of samples";
    out.split = split;
    return out;
  }
  const double ts = all.Ts;
  out.estimation = std::move(all);
  if (!validate.empty()) {
    IoData v = load_log(validate, options).data;
    if (std::abs(v.Ts - ts) > 1e-6 * ts)
      throw DataError(validate, 0, 0, "sample time " + fmt(v.Ts, 9) + " s differs from the estimation log's " + fmt(ts, 9) + " s");
    out.validation = std::move(v);
    out.validation_label = validate;
  }
  return out;
}

ModelChannels model_channels(const LogArgs& args, const ModelFile& file, bool with_outputs) {
  ModelChannels ch;
  ch.inputs = split_names(args.inputs, "--inputs");
  if (ch.inputs.empty()) ch.inputs = model_input_names(file);
  if (static_cast<Eigen::Index>(ch.inputs.size()) != file.model.inputs())
    throw std::invalid_argument("the model has " + std::to_string(file.model.inputs()) + " input(s), --inputs names " +
                                std::to_string(ch.inputs.size()));
  if (!with_outputs) return ch;
  ch.outputs = split_names(args.outputs, "--outputs");
  if (ch.outputs.empty()) ch.outputs = model_output_names(file);
  if (static_cast<Eigen::Index>(ch.outputs.size()) != file.model.outputs())
    throw std::invalid_argument("the model has " + std::to_string(file.model.outputs()) + " output(s), --outputs names " +
                                std::to_string(ch.outputs.size()));
  return ch;
}

CompareOptions compare_options_for(const ModelFile& file, const std::string& x0_mode, const std::string& model_path) {
  CompareOptions o;
  o.estimate_x0 = x0_mode == "estimate";
  if (x0_mode == "model") {
    if (file.x0.size() == 0) throw DataError(model_path, 0, 0, "--x0 model: the model file has no x0");
    o.x0 = file.x0;
  }
  o.input_offset = file.input_offset;
  o.output_offset = file.output_offset;
  return o;
}

void add_welch_options(CLI::App& cmd, WelchArgs& args) {
  cmd.add_option("--nfft", args.nfft, "segment (FFT) length; halved until it fits the log")
      ->capture_default_str()
      ->check(CLI::Range(Eigen::Index{8}, Eigen::Index{1} << 26));
  cmd.add_option("--overlap", args.overlap, "fraction of a segment shared with the next, 0 <= overlap < 1")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.99));
  cmd.add_option("--window", args.window, "segment taper")
      ->capture_default_str()
      ->check(CLI::IsMember({"hann", "hamming", "rectangular", "blackman-harris", "flattop"}));
  cmd.add_option("--detrend", args.detrend, "removed from every segment before the window")
      ->capture_default_str()
      ->check(CLI::IsMember({"none", "mean", "linear"}));
}

WelchOptions welch_options(const WelchArgs& args) {
  WelchOptions o;
  o.nfft = args.nfft;
  o.overlap = args.overlap;
  o.window = parse_window(args.window);
  o.detrend = detrend_from_name(args.detrend);
  return o;
}

}  // namespace sysid::cli
