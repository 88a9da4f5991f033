// The finite-element side: sysid.read_fem (an FE model file with its Matrix Market
// matrices), sysid.fem_modes (the lowest modes by shift-invert Lanczos),
// sysid.fem_reduce (the modal state-space model `sysid reduce --fem` writes) and
// sysid.fem_frf (the sparse frequency response `sysid frf --fem` computes).
#include <sysid/fem/modal_analysis.hpp>
#include <sysid/fem/modal_model.hpp>
#include <sysid/fem/sparse_frf.hpp>
#include <sysid/io/fem_modal_model_file.hpp>
#include <sysid/io/fem_model_file.hpp>

#include "bindings.hpp"

namespace sysid::python {

namespace {

nb::dict modes_of(const fem::SecondOrderModel& model, int modes) {
  fem::ModalAnalysisOptions options;
  options.modes = modes;
  fem::ModalAnalysisResult r;
  {
    nb::gil_scoped_release release;
    r = fem::modal_analysis(model, options);
  }
  issue_warnings(r.warnings);
  nb::dict out;
  out["freq_hz"] = r.natural_frequencies_hz;
  out["damping"] = r.damping_ratios;
  out["mode_shapes"] = r.mode_shapes;
  out["rigid_body_modes"] = r.rigid_body_modes;
  out["max_relative_residual"] = r.max_relative_residual;
  return out;
}

ModelFile reduce_fem(const fem::SecondOrderModel& model, int modes, double Ts, const std::string& hold, bool static_correction) {
  fem::ModalAnalysisOptions analysis;
  analysis.modes = modes;
  fem::ModalModelOptions options;
  options.Ts = Ts;
  options.hold = hold_from_name(hold);
  options.static_correction = static_correction;
  fem::ModalModelResult r;
  {
    nb::gil_scoped_release release;
    r = fem::modal_model(model, analysis, options);
  }
  issue_warnings(r.warnings);
  return fem_modal_model_file(model, r, options);
}

nb::dict frf_of(const fem::SecondOrderModel& model, const Eigen::VectorXd& freq_hz, const std::string& method) {
  fem::SparseFrfOptions options;
  options.method = fem::sparse_frf_method_from_name(method);
  fem::SparseFrfResult r;
  {
    nb::gil_scoped_release release;
    r = fem::sparse_frf(model, freq_hz, options);
  }
  issue_warnings(r.warnings);
  nb::dict out;
  out["freq_hz"] = r.freq_hz;
  out["H"] = stack_matrices(r.H);
  out["inputs"] = nb::cast(r.input_names);
  out["outputs"] = nb::cast(r.output_names);
  out["method"] = fem::sparse_frf_method_name(r.method);
  return out;
}

}  // namespace

void bind_fem(nb::module_& m) {
  nb::class_<fem::SecondOrderModel>(m, "FemModel",
                                    "A sparse second-order structural model M x'' + C x' + K x = F u, y = outputs of DOFs\n"
                                    "(the command line's FE model file with its Matrix Market matrices).")
      .def_prop_ro("dofs", &fem::SecondOrderModel::dofs)
      .def_prop_ro("inputs", [](const fem::SecondOrderModel& f) {
        std::vector<std::string> names;
        for (const auto& i : f.inputs) names.push_back(i.name);
        return names;
      })
      .def_prop_ro("outputs", [](const fem::SecondOrderModel& f) {
        std::vector<std::string> names;
        for (const auto& o : f.outputs) names.push_back(o.name);
        return names;
      })
      .def("__repr__", [](const fem::SecondOrderModel& f) {
        return "<sysid.FemModel: " + std::to_string(f.dofs()) + " DOFs, " + std::to_string(f.inputs.size()) + " input(s), " +
               std::to_string(f.outputs.size()) + " output(s)>";
      });
  m.def("read_fem", [](const Path& path) { return read_fem_model(path.string()); }, nb::arg("path"), "An FE model file (JSON naming its .mtx matrices) as a FemModel.");
  m.def("fem_modes", &modes_of, nb::arg("fem"), nb::kw_only(), nb::arg("modes") = fem::ModalAnalysisOptions{}.modes,
        "The lowest modes (shift-invert Lanczos on CHOLMOD): a dict with freq_hz, damping, mode_shapes\n"
        "(dofs x modes, mass-normalised), rigid_body_modes and max_relative_residual.");
  m.def("fem_reduce", &reduce_fem, nb::arg("fem"), nb::kw_only(), nb::arg("modes"), nb::arg("Ts") = 0.0,
        nb::arg("hold") = "zoh", nb::arg("static_correction") = false,
        "The modal state-space model of the lowest `modes` modes (`sysid reduce --fem`): continuous (Ts = 0) or\n"
        "sampled with a 'zoh' or 'foh' hold; static_correction adds the truncated modes' residual flexibility.");
  m.def("fem_frf", &frf_of, nb::arg("fem"), nb::arg("freq_hz"), nb::kw_only(), nb::arg("method") = "automatic",
        "The frequency response of the FE model at freq_hz (`sysid frf --fem`): a dict with freq_hz, H\n"
        "(frequencies x outputs x inputs), inputs, outputs and the method used ('direct' sparse LU or 'krylov').");
}

}  // namespace sysid::python
