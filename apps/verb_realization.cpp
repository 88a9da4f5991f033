// sysid lms | okid | era: Markov parameters from a log (multi-step NLMS FIR,
// or OKID) written as a "markov" file, and their ERA realisation as a
// state-space model (adaptive/multistep_nlms.hpp, realization/okid.hpp,
// realization/era.hpp).
#include <sysid/adaptive/multistep_nlms.hpp>
#include <sysid/config.hpp>
#include <sysid/core/identification_warnings.hpp>
#include <sysid/core/modal_table.hpp>
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/markov_file.hpp>
#include <sysid/io/model_json.hpp>
#include <sysid/realization/era.hpp>
#include <sysid/realization/okid.hpp>

#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>

#include "cli_common.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct LmsArgs {
  std::string log_path;
  LogArgs log;
  int taps = 256;
  int steps = 1;
  std::string gamma;
  double mu = 0.5;
  std::string curve;
  std::string out;
};

std::vector<double> parse_numbers(const std::string& text, const std::string& option) {
  std::vector<double> v;
  for (const std::string& item : split_names(text, option)) {
    std::size_t used = 0;
    double x = 0;
    try {
      x = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size()) throw std::invalid_argument(option + ": expected comma-separated numbers, found '" + item + "'");
    v.push_back(x);
  }
  return v;
}

void run_lms(const LmsArgs& a) {
  claim_outputs({a.out, a.curve}, {a.log_path});
  const LogOptions lo = make_log_options(a.log, split_names(a.log.inputs, "--inputs"), split_names(a.log.outputs, "--outputs"));
  const LoadedLog log = load_log(a.log_path, lo);
  if (log.data.experiments.size() != 1) throw std::invalid_argument("lms: expected one experiment");
  require_varying_inputs(log.data, "lms");
  const Experiment& e = log.data.experiments.front();
  MultiStepNlmsOptions o;
  o.taps = a.taps;
  o.mu = a.mu;
  // K steps with equal weights unless --gamma gives them (they must sum to 1).
  o.gamma = a.gamma.empty() ? std::vector<double>(static_cast<std::size_t>(a.steps), 1.0 / a.steps) : parse_numbers(a.gamma, "--gamma");
  if (!a.gamma.empty() && static_cast<int>(o.gamma.size()) != a.steps && a.steps != 1)
    throw std::invalid_argument("lms: --steps " + std::to_string(a.steps) + " but --gamma has " + std::to_string(o.gamma.size()) + " weights");
  const MultiStepNlmsResult r = multistep_nlms_on_record(e.u, e.y, o);
  const Eigen::RowVectorXd y_mean = e.y.colwise().mean();
  const double y_power = (e.y.rowwise() - y_mean).squaredNorm() / static_cast<double>(e.y.size());
  std::cout << "lms: " << o.taps << " taps, K = " << o.gamma.size() << " steps, mu " << o.mu << ", " << r.info.samples
            << " samples; final a-priori error power " << fmt(r.info.error_power, 4) << " ("
            << fmt(10.0 * std::log10(r.info.error_power / y_power), 3) << " dB of the output power)\n";
  for (const auto& w : r.warnings) warn("lms", w);
  // multistep_nlms works on matrices; the data checks need the log's names.
  for (const auto& w : identification_data_warnings(log.data, o.taps, "an FIR of " + std::to_string(o.taps) + " taps", ""))
    warn("lms", w);
  if (!a.curve.empty()) {
    std::ostringstream csv;
    csv << "sample,error_power\n";
    csv.precision(10);
    for (const auto& p : r.learning_curve) csv << p.sample << "," << p.error_power << "\n";
    write_file_atomically(a.curve, csv.str());
    note("lms", "wrote the learning curve to " + a.curve);
  }
  MarkovFile f{markov_from_fir(r.fir, log.data.Ts, log.data.input_names, log.data.output_names), nlohmann::json::object()};
  f.provenance = {{"method", "lms"}, {"data", a.log_path}, {"taps", o.taps}, {"steps", o.gamma.size()}, {"mu", o.mu},
                  {"sysid_version", SYSID_VERSION_STRING}};
  write_markov_file(a.out, f);
  note("lms", "wrote " + a.out);
}

struct OkidArgs {
  std::string log_path;
  LogArgs log;
  int observer_order = 20;
  int count = 0;
  std::string out;
};

void run_okid(const OkidArgs& a) {
  claim_outputs({a.out}, {a.log_path});
  const LogOptions lo = make_log_options(a.log, split_names(a.log.inputs, "--inputs"), split_names(a.log.outputs, "--outputs"));
  IoData data = load_log(a.log_path, lo).data;
  for (auto& e : data.experiments) {
    e.u = e.u.rowwise() - e.u.colwise().mean();
    e.y = e.y.rowwise() - e.y.colwise().mean();
  }
  OkidOptions o;
  o.observer_order = a.observer_order;
  o.markov_count = a.count;
  const OkidResult r = okid(data, o);
  std::cout << "okid: " << a.observer_order << " observer Markov parameters, " << r.markov.count() - 1
            << " system Markov parameters; regression condition " << fmt(r.condition, 3) << ", residual RMS " << fmt(r.residual_rms, 4)
            << "\n";
  for (const auto& w : r.warnings) warn("okid", w);
  MarkovFile f{r.markov, {{"method", "okid"}, {"data", a.log_path}, {"observer_order", a.observer_order},
                          {"sysid_version", SYSID_VERSION_STRING}}};
  write_markov_file(a.out, f);
  note("okid", "wrote " + a.out);
}

struct EraArgs {
  std::vector<std::string> markov_paths;
  int order = 0;
  int max_order = 0;
  int row_blocks = 0;
  std::string out;
};

void run_era(const EraArgs& a) {
  claim_outputs({a.out}, a.markov_paths);
  std::vector<MarkovParameters> experiments;
  bool from_okid = false;
  for (const auto& p : a.markov_paths) {
    MarkovFile f = read_markov_file(p);
    from_okid = from_okid || f.provenance.value("method", std::string()) == "okid";
    if (from_okid && a.order == 0 && a.max_order == 0)
      warn("era", p + " comes from OKID: the automatic order may pick the observer's order; give --order or --max-order");
    experiments.push_back(std::move(f.markov));
  }
  EraOptions o;
  o.order = a.order;
  o.max_order = a.max_order;
  o.row_blocks = a.row_blocks;
  const EraResult r = era(experiments, o);
  std::cout << "era: order " << r.order << " (" << r.order_rule << "), Hankel " << r.row_blocks << " x " << r.column_blocks
            << " blocks\nHankel singular values:";
  for (Eigen::Index k = 0; k < std::min<Eigen::Index>(r.singular_values.size(), 2 * r.order + 4); ++k)
    std::cout << (k % 8 == 0 ? "\n  " : " ") << fmt(r.singular_values(k), 4);
  std::cout << "\nmodes:\n" << format_modal_table(modal_table(r.model));
  for (const auto& w : r.warnings) warn("era", w);
  ModelFile out;
  out.model = r.model;
  out.provenance = {{"method", "era"}, {"data", a.markov_paths}, {"order", r.order}, {"sysid_version", SYSID_VERSION_STRING}};
  write_model_json(a.out, out);
  note("era", "wrote " + a.out);
}

}  // namespace

Verb register_lms(CLI::App& app) {
  auto args = std::make_shared<LmsArgs>();
  CLI::App* cmd = app.add_subcommand("lms", "FIR (Markov parameters) of every input-output path by multi-step normalised LMS");
  cmd->add_option("log", args->log_path, "CSV log")->required();
  add_log_options(*cmd, args->log, LogOptionSpec{});
  cmd->add_option("--taps", args->taps, "FIR length per path (lag 0 included)")->capture_default_str()->check(CLI::Range(1, 1000000));
  cmd->add_option("--steps", args->steps, "K: error terms combined per update (1 = NLMS)")->capture_default_str()->check(CLI::Range(1, 64));
  cmd->add_option("--gamma", args->gamma, "weights of the K error terms, comma-separated, >= 0, summing to 1 (default equal)");
  cmd->add_option("--mu", args->mu, "step size, 0 < mu <= 2")->capture_default_str();
  cmd->add_option("--curve", args->curve, "write the learning curve (sample, a-priori error power) to this CSV");
  cmd->add_option("--out", args->out, "Markov-parameter file to write (JSON, type markov)")->required();
  cmd->footer("Means are removed first. Then: sysid era fir.json --order 14 --out model.json\nExample:\n"
              "  sysid lms exp5.csv --inputs u5 --outputs y1,y2,y3,y4,y5,y6,y7,y8 --taps 256 --steps 3 --gamma 0.5,0.3,0.2 --out fir5.json");
  return {cmd, [args] { run_lms(*args); }};
}

Verb register_okid(CLI::App& app) {
  auto args = std::make_shared<OkidArgs>();
  CLI::App* cmd = app.add_subcommand("okid", "Markov parameters by observer/Kalman filter identification (for lightly damped systems)");
  cmd->add_option("log", args->log_path, "CSV log")->required();
  add_log_options(*cmd, args->log, LogOptionSpec{});
  cmd->add_option("--observer-order", args->observer_order, "observer Markov parameters p (p x outputs >= the order)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--count", args->count, "system Markov parameters to return (0 = 4 p)")->capture_default_str()->check(CLI::Range(0, 1000000));
  cmd->add_option("--out", args->out, "Markov-parameter file to write (JSON, type markov)")->required();
  cmd->footer("Example:\n  sysid okid log.csv --inputs u --outputs y1,y2 --observer-order 30 --out markov.json");
  return {cmd, [args] { run_okid(*args); }};
}

Verb register_era(CLI::App& app) {
  auto args = std::make_shared<EraArgs>();
  CLI::App* cmd = app.add_subcommand("era", "state-space realisation of Markov parameters (eigensystem realisation algorithm)");
  cmd->add_option("markov", args->markov_paths, "Markov-parameter files (from lms or okid); several are realised together")
      ->required()
      ->expected(1, -1);
  cmd->add_option("--order", args->order, "model order (0 = from the largest gap of the Hankel singular values)")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000));
  cmd->add_option("--max-order", args->max_order, "largest order the automatic choice may return (0 = no limit)")->check(CLI::Range(0, 100000));
  cmd->add_option("--row-blocks", args->row_blocks, "block rows of the Hankel matrix (0 = automatic)")->check(CLI::Range(0, 100000));
  cmd->add_option("--out", args->out, "model file to write (JSON)")->required();
  cmd->footer("Example:\n  sysid era fir5.json --order 14 --out m5.json");
  return {cmd, [args] { run_era(*args); }};
}

}  // namespace sysid::cli
