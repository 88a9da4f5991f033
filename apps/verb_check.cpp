// sysid check: pre-flight report on a log before any identification
// (diagnose/data_check.hpp).
#include <sysid/diagnose/data_check.hpp>

#include <iostream>
#include <limits>
#include <memory>

#include "cli_common.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct CheckArgs {
  std::string log_path;
  LogArgs log;
  int max_order = 60;
};

void run_check(const CheckArgs& a) {
  const std::vector<std::string> inputs = split_names(a.log.inputs, "--inputs");
  const std::vector<std::string> outputs = split_names(a.log.outputs, "--outputs");
  LogOptions lo = make_log_options(a.log, inputs, outputs);
  // The check reports irregular time stamps itself instead of refusing the log.
  lo.time_tolerance = std::numeric_limits<double>::infinity();
  const LoadedLog log = load_log(a.log_path, lo);
  DataCheckOptions o;
  o.max_excitation_order = a.max_order;
  const DataCheckResult r = check_data(log.data, log.time * log.seconds_per_time_unit, o);
  std::cout << "pre-flight check of " << a.log_path << " (Ts " << fmt(log.data.Ts) << " s)\n" << r.report();
}

}  // namespace

Verb register_check(CLI::App& app) {
  auto args = std::make_shared<CheckArgs>();
  CLI::App* cmd = app.add_subcommand(
      "check", "Pre-flight report on a log: excitation order, signal-to-noise, offsets, trends, clipping, sampling, feedback");
  cmd->add_option("log", args->log_path, "CSV log with the input and output columns")->required();
  add_log_options(*cmd, args->log, {});
  cmd->add_option("--max-order", args->max_order, "largest excitation order tested (columns of the input's Hankel matrix)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->footer(
      "Each finding comes with its consequence for identification. Nothing is written.\n"
      "Example:\n"
      "  sysid check par2_gu.csv --inputs u --outputs y");
  return {cmd, [args] { run_check(*args); }};
}

}  // namespace sysid::cli
