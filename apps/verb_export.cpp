// sysid export: a model file as MATLAB variables (MAT v5, io/mat_file.hpp), for
// MATLAB, Octave and scipy.io.loadmat (DESIGN.md "Model families": `sysid export`).
#include <sysid/io/mat_file.hpp>

#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct ExportArgs {
  std::string model_path;
  std::string mat;
};

void run_export(const ExportArgs& a) {
  claim_outputs({a.mat}, {a.model_path});
  const ModelFile file = load_model(a.model_path, /*allow_augmented=*/true);
  if (file.type == "augmented")
    note("export", a.model_path + " is an augmented model: writing its nominal (linear) part; the physics blocks have no "
                   "MATLAB form");
  const std::vector<MatVariable> variables = model_mat_variables(file);
  write_mat_file(a.mat, variables);
  std::string names;
  for (const MatVariable& v : variables) names += (names.empty() ? "" : " ") + v.name;
  note("export", "wrote " + a.mat + " (" + names + ")");
}

}  // namespace

Verb register_export(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* cmd = app.add_subcommand("export", "Write a model file as MATLAB variables (MAT v5: A B C D Ts K x0 InputName OutputName)");
  cmd->add_option("model", args->model_path, "model file (JSON: state-space, polynomial or augmented)")->required();
  cmd->add_option("--mat", args->mat, "MAT file to write (version 5: MATLAB, Octave, scipy.io.loadmat)")->required();
  add_force_flag(*cmd);
  cmd->footer(
      "In MATLAB: load model.mat; sys = ss(A, B, C, D, Ts, 'InputName', InputName, 'OutputName', OutputName);\n"
      "Example:\n"
      "  sysid export model.json --mat model.mat");
  return {cmd, [args] { run_export(*args); }};
}

}  // namespace sysid::cli
