// sysid export: a model file as MATLAB variables (MAT v5, io/mat_file.hpp), for
// MATLAB, Octave and scipy.io.loadmat (DESIGN.md "Model families": `sysid export`).
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/family_file.hpp>
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
  const nlohmann::json root = parse_json_text(read_whole_file(a.model_path), a.model_path);
  std::vector<MatVariable> variables;
  if (is_family_json(root)) {
    variables = family_mat_variables(family_from_json_value(root, a.model_path));
  } else {
    const ModelFile file = model_from_json_value(root, a.model_path);
    if (file.type == "augmented")
      note("export", a.model_path + " is an augmented model: writing its nominal (linear) part; the physics blocks have no "
                     "MATLAB form");
    variables = model_mat_variables(file);
  }
  write_mat_file(a.mat, variables);
  std::string names;
  for (const MatVariable& v : variables) names += (names.empty() ? "" : " ") + v.name;
  note("export", "wrote " + a.mat + " (" + names + ")");
}

}  // namespace

Verb register_export(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* cmd = app.add_subcommand("export", "Write a model or family file as MATLAB variables (MAT v5: A B C D Ts K x0 InputName OutputName; "
                                     "for a family also the members, nominal, weight and bound)");
  cmd->add_option("model", args->model_path, "model file (JSON: state-space, polynomial or augmented) or family file")->required();
  cmd->add_option("--mat", args->mat, "MAT file to write (version 5: MATLAB, Octave, scipy.io.loadmat)")->required();
  add_force_flag(*cmd);
  cmd->footer(
      "In MATLAB: load model.mat; sys = ss(A, B, C, D, Ts, 'InputName', InputName, 'OutputName', OutputName);\n"
      "A family (sysid family): A_members ... D_members (n x n x N arrays when the members share one order:\n"
      "ss(A_members, B_members, C_members, D_members, Ts) is a model array; cell arrays otherwise), A_nominal ...,\n"
      "A_weight ..., frequency_hz, bound, conditions and condition_names, fit_percent, mode_freq_hz, mode_damping.\n"
      "Example:\n"
      "  sysid export model.json --mat model.mat\n"
      "  sysid export family.json --mat family.mat");
  return {cmd, [args] { run_export(*args); }};
}

}  // namespace sysid::cli
