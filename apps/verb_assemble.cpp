// sysid assemble: stack single-input (SIMO) models, one per excitation
// experiment, into one MIMO model (core/assemble.hpp).
#include <sysid/config.hpp>
#include <sysid/core/assemble.hpp>
#include <sysid/io/atomic_file.hpp>
#include <sysid/core/errors.hpp>
#include <sysid/io/model_json.hpp>

#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct AssembleArgs {
  std::vector<std::string> models;
  std::string disturbance;
  std::string out;
};

void run_assemble(const AssembleArgs& a) {
  std::vector<std::string> inputs = a.models;
  if (!a.disturbance.empty()) inputs.push_back(a.disturbance);
  claim_outputs({a.out}, inputs);
  std::vector<StateSpace> parts;
  std::vector<ModelFile> files;
  for (const auto& path : a.models) {
    files.push_back(load_model(path));
    parts.push_back(named_model(files.back()));
  }
  if (!a.disturbance.empty()) {
    // The disturbance's inputs w come last; its mean is not part of the plant's offsets.
    const ModelFile d = load_model(a.disturbance);
    try {
      parts.push_back(disturbance_input_model(named_model(d), d.K, d.noise_covariance));
    } catch (const std::invalid_argument& e) {
      throw DataError(a.disturbance, 0, 0, e.what());
    }
  }
  ModelFile out;
  out.model = assemble_inputs(parts);
  // Offsets: the inputs' side by side; the outputs' averaged over the
  // experiments (each experiment measured the same sensors about its own mean).
  const Eigen::Index l = out.model.outputs();
  out.input_offset = Eigen::VectorXd::Zero(out.model.inputs());  // w: zero-mean by construction
  out.output_offset = Eigen::VectorXd::Zero(l);
  Eigen::Index at = 0;
  for (const auto& f : files) {
    if (f.input_offset.size() == f.model.inputs()) out.input_offset.segment(at, f.model.inputs()) = f.input_offset;
    if (f.output_offset.size() == l) out.output_offset += f.output_offset / static_cast<double>(files.size());
    at += f.model.inputs();
  }
  out.provenance["method"] = "assemble";
  out.provenance["parts"] = a.models;
  if (!a.disturbance.empty()) out.provenance["disturbance"] = a.disturbance;
  out.provenance["order"] = out.model.order();
  out.provenance["sysid_version"] = SYSID_VERSION_STRING;
  std::cout << "assembled " << files.size() << (files.size() == 1 ? " model" : " models")
            << (a.disturbance.empty() ? std::string() : " and the disturbance model " + a.disturbance + " (inputs w: unit white noise)")
            << ": order " << out.model.order() << ", " << out.model.inputs() << " inputs ("
            << join(out.model.input_names) << "), " << l << " outputs\n";
  write_model_json(a.out, out);
  note("assemble", "wrote " + a.out);
}

}  // namespace

Verb register_assemble(CLI::App& app) {
  auto args = std::make_shared<AssembleArgs>();
  CLI::App* cmd = app.add_subcommand("assemble", "stack single-input models (one per excitation experiment) into one MIMO model");
  cmd->add_option("models", args->models, "model files (state-space or polynomial), one per experiment, same outputs and Ts")
      ->required()
      ->expected(1, -1);
  cmd->add_option("--disturbance", args->disturbance,
                  "time-series model (AR, ARMA, n4sid without inputs: with K and noise covariance) of the disturbance at "
                  "the same outputs, joined as unit-variance white-noise inputs w_<output>: the generalised plant "
                  "y = G u + H w an H2/H-infinity synthesis takes");
  cmd->add_option("--out", args->out, "assembled model file to write (JSON)")->required();
  cmd->footer(
      "A = blkdiag(A_i), B = blkdiag(B_i), C = [C_1 .. C_k], D = [D_1 .. D_k]: the order is the sum; reduce it next.\n"
      "--disturbance H adds (A_h, K_h L, C_h, L), L L' = the innovation covariance, as the last part.\n"
      "Example:\n  sysid assemble m1.json m2.json m3.json --out avi.json && sysid reduce avi.json --max-error 2% --out avi_r.json\n"
      "  sysid assemble gu.json --disturbance gw_arma.json --out generalised_plant.json");
  return {cmd, [args] { run_assemble(*args); }};
}

}  // namespace sysid::cli
