// sysid simulate: run a model file on the inputs of a log, write the simulated outputs.
#include <sysid/core/simulate.hpp>
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/augmented_model_file.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/validate/compare.hpp>

#include <memory>

#include "cli_common.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct SimulateArgs {
  std::string model_path, log_path, out;
  LogArgs log;
  std::string x0 = "zero";
};

void run_simulate(const SimulateArgs& a) {
  const std::string verb = "simulate";
  claim_outputs({a.out}, {a.model_path, a.log_path});
  const ModelFile file = load_model(a.model_path, /*allow_augmented=*/true);
  if (file.type == "augmented" && a.x0 == "estimate")
    throw DataError(a.model_path, 0, 0, "--x0 estimate is not available for augmented (nonlinear) models; use zero or model");
  // Outputs are read only to estimate x0.
  const auto [inputs, outputs] = model_channels(a.log, file, a.x0 == "estimate");
  const LoadedLog log = load_log(a.log_path, make_log_options(a.log, inputs, outputs));
  const StateSpace model = model_for_sample_time(file, log.data.Ts, a.model_path, verb);
  const Experiment& e = log.data.experiments.front();

  Eigen::MatrixXd u = e.u;
  if (file.input_offset.size() != 0) u.rowwise() -= file.input_offset.transpose();
  Eigen::VectorXd x0;  // empty = zero
  if (a.x0 == "model") {
    if (file.x0.size() == 0) throw DataError(a.model_path, 0, 0, "--x0 model: the model file has no x0");
    x0 = file.x0;
  } else if (a.x0 == "estimate") {
    Eigen::MatrixXd y = e.y;
    if (file.output_offset.size() != 0) y.rowwise() -= file.output_offset.transpose();
    x0 = estimate_initial_state(model, u, y);
  }
  Eigen::MatrixXd y_hat;
  if (file.type == "augmented") {
    AugmentedModel augmented = augmented_model_from_file(file, a.model_path);
    augmented.nominal = model;
    augmented.x0 = x0;
    y_hat = simulate_augmented(augmented, e.u);  // applies both offsets itself
  } else {
    y_hat = simulate(model, u, x0);
    if (file.output_offset.size() != 0) y_hat.rowwise() += file.output_offset.transpose();
  }

  std::vector<std::string> columns;
  Eigen::MatrixXd table(y_hat.rows(), y_hat.cols() + (log.time.size() ? 1 : 0));
  if (log.time.size()) {
    columns.push_back(log.time_name);
    table.col(0) = log.time;
  }
  for (const auto& name : model_output_names(file)) columns.push_back(name);
  table.rightCols(y_hat.cols()) = y_hat;
  write_csv(a.out, columns, table);
  note(verb, "wrote " + std::to_string(y_hat.rows()) + " samples of " + join(model_output_names(file)) + " to " + a.out);
}

}  // namespace

Verb register_simulate(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* cmd = app.add_subcommand("simulate", "Simulate a model file on the inputs of a log and write the outputs as CSV");
  cmd->add_option("model", args->model_path, "model file (JSON: state-space, polynomial or augmented)")->required();
  cmd->add_option("log", args->log_path, "CSV log holding the input columns")->required();
  LogOptionSpec spec;
  spec.inputs_required = false;
  spec.outputs_required = false;
  spec.inputs_help = "input columns of the log, in the model's input order (default: the model's input names)";
  spec.outputs_help = "output columns of the log, for --x0 estimate (default: the model's output names)";
  add_log_options(*cmd, args->log, spec);
  cmd->add_option("--x0", args->x0,
                  "initial state: zero, model (the x0 stored in the model file), estimate (least squares on the log's outputs)")
      ->capture_default_str()
      ->check(CLI::IsMember({"zero", "model", "estimate"}));
  cmd->add_option("--out", args->out, "output CSV: the time column (when the log has one) and one column per model output")
      ->required();
  cmd->footer(
      "The model's input_offset is subtracted from the inputs and its output_offset added to\n"
      "the outputs. Continuous-time models are discretised (zero-order hold) at the log's rate.\n"
      "Example:\n"
      "  sysid simulate model.json log.csv --inputs u --out sim.csv\n"
      "  sysid simulate model.json log.csv --x0 estimate --outputs y --out sim.csv");
  add_hold_option(*cmd);
  return {cmd, [args] { run_simulate(*args); }};
}

}  // namespace sysid::cli
