// sysid compare: fit % of a model on a log, by simulation or k-step prediction.
#include <sysid/validate/compare.hpp>

#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct CompareArgs {
  std::string model_path, log_path;
  LogArgs log;
  int predict = 0;
  std::string x0 = "estimate";
  // Room for the frequency-domain comparison (issue 3): --band LO:HI will restrict
  // the fit to a band (both signals band-pass filtered); not implemented yet.
};

void run_compare(const CompareArgs& a) {
  const std::string verb = "compare";
  const ModelFile file = load_model(a.model_path);
  if (a.predict > 0 && file.K.size() == 0)
    throw DataError(a.model_path, 0, 0,
                    "--predict needs the model's Kalman gain K, and this model file has none (identify an innovation "
                    "model, e.g. with sysid n4sid)");
  std::vector<std::string> inputs = split_names(a.log.inputs, "--inputs");
  if (inputs.empty()) inputs = model_input_names(file);
  std::vector<std::string> outputs = split_names(a.log.outputs, "--outputs");
  if (outputs.empty()) outputs = model_output_names(file);
  if (static_cast<Eigen::Index>(inputs.size()) != file.model.inputs())
    throw std::invalid_argument("the model has " + std::to_string(file.model.inputs()) + " input(s), --inputs names " +
                                std::to_string(inputs.size()));
  if (static_cast<Eigen::Index>(outputs.size()) != file.model.outputs())
    throw std::invalid_argument("the model has " + std::to_string(file.model.outputs()) + " output(s), --outputs names " +
                                std::to_string(outputs.size()));
  const LoadedLog log = load_log(a.log_path, make_log_options(a.log, inputs, outputs));
  const StateSpace model = model_for_sample_time(file, log.data.Ts, a.model_path, verb);

  CompareOptions o;
  o.predict_steps = a.predict;
  o.estimate_x0 = a.x0 == "estimate";
  if (a.x0 == "model") {
    if (file.x0.size() == 0) throw DataError(a.model_path, 0, 0, "--x0 model: the model file has no x0");
    o.x0 = file.x0;
  }
  o.input_offset = file.input_offset;
  o.output_offset = file.output_offset;
  const CompareResult r = compare(model, file.K, log.data.experiments.front(), o);

  const std::string how = a.predict == 0 ? std::string("simulation") : std::to_string(a.predict) + "-step-ahead prediction";
  std::cout << "fit [%] of " << a.model_path << " on " << a.log_path << " (" << how << ", x0 "
            << (a.x0 == "estimate" ? "estimated" : a.x0 == "model" ? "from the model file" : "zero") << ", "
            << log.data.total_samples() << " samples):\n"
            << format_fit_lines(r.fit_percent, outputs);
}

}  // namespace

Verb register_compare(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand("compare", "Fit % of a model on a log (simulation, or k-step-ahead prediction)");
  cmd->add_option("model", args->model_path, "model file (JSON)")->required();
  cmd->add_option("log", args->log_path, "CSV log with the input and output columns")->required();
  LogOptionSpec spec;
  spec.inputs_required = false;
  spec.outputs_required = false;
  spec.inputs_help = "input columns of the log, in the model's input order (default: the model's input names)";
  spec.outputs_help = "output columns of the log, in the model's output order (default: the model's output names)";
  add_log_options(*cmd, args->log, spec);
  cmd->add_option("--predict", args->predict,
                  "K >= 1: fit of the K-step-ahead Kalman predictor (needs the model's K) instead of simulation")
      ->check(CLI::Range(1, 1000000000));
  cmd->add_option("--x0", args->x0, "initial state: estimate (least squares on this log), zero, model (stored x0)")
      ->capture_default_str()
      ->check(CLI::IsMember({"estimate", "zero", "model"}));
  // --band LO:HI (frequency-domain fit, issue 3) goes here.
  cmd->footer(
      "Fit % = 100 (1 - |y - y_hat| / |y - mean(y)|) per output; 100 is perfect, 0 is as good as the mean.\n"
      "Example:\n"
      "  sysid compare model.json fresh.csv --inputs u --outputs y\n"
      "  sysid compare model.json fresh.csv --predict 10");
  return {cmd, [args] { run_compare(*args); }};
}

}  // namespace sysid::cli
