// sysid.Model: a model file (DESIGN.md "Model files") in memory, the very object
// the command line reads and writes (sysid::ModelFile), so to_json() and write()
// give the command line's bytes and read_model() takes its files.
#include <sysid/core/modal_table.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/diagnose/augmented_model.hpp>
#include <sysid/io/augmented_model_file.hpp>
#include <sysid/io/mat_file.hpp>
#include <sysid/io/model_json.hpp>

#include <nanobind/stl/complex.h>

#include "bindings.hpp"

namespace sysid::python {

namespace {

std::optional<Eigen::MatrixXd> optional_matrix(const Eigen::MatrixXd& m) {
  if (m.size() == 0) return std::nullopt;
  return m;
}

std::optional<Eigen::VectorXd> optional_vector(const Eigen::VectorXd& v) {
  if (v.size() == 0) return std::nullopt;
  return v;
}

/// The model's response to u (samples x inputs): offsets as the model file states
/// them (input_offset subtracted, output_offset added, as `sysid simulate` does),
/// from x0 (None: zero). Augmented models run with their physics blocks.
Eigen::MatrixXd simulate_model(const ModelFile& file, const SampleArray& u, const std::optional<Eigen::VectorXd>& x0) {
  const StridedMap u_view = sample_view(u, "u");
  if (u_view.cols() != file.model.inputs())
    throw std::invalid_argument("simulate: u has " + std::to_string(u_view.cols()) + " channels, the model has " +
                                std::to_string(file.model.inputs()) + " inputs");
  nb::gil_scoped_release release;
  if (file.type == "augmented") {
    AugmentedModel augmented = augmented_model_from_file(file, "model");
    if (x0) augmented.x0 = *x0;
    return simulate_augmented(augmented, Eigen::MatrixXd(u_view));  // applies both offsets itself
  }
  Eigen::MatrixXd y_hat;
  const Eigen::VectorXd initial = x0 ? *x0 : Eigen::VectorXd();
  if (file.input_offset.size() != 0) {
    Eigen::MatrixXd centred = u_view;
    centred.rowwise() -= file.input_offset.transpose();
    y_hat = simulate(file.model, centred, initial);
  } else {
    y_hat = simulate(file.model, u_view, initial);
  }
  if (file.output_offset.size() != 0) y_hat.rowwise() += file.output_offset.transpose();
  return y_hat;
}

nb::object to_control(const ModelFile& file) {
  nb::object control;
  try {
    control = nb::module_::import_("control");
  } catch (nb::python_error& e) {
    e.restore();
    PyErr_Clear();
    throw nb::import_error("Model.to_control() needs python-control: pip install control");
  }
  const StateSpace& s = file.model;
  return control.attr("ss")(s.A, s.B, s.C, s.D, s.Ts, nb::arg("inputs") = s.input_names_or_defaults(),
                            nb::arg("outputs") = s.output_names_or_defaults());
}

std::string model_repr(const ModelFile& file) {
  const StateSpace& s = file.model;
  std::string text = "<sysid.Model " + file.type + ": " + std::to_string(s.order()) + " states, " +
                     std::to_string(s.inputs()) + " input(s), " + std::to_string(s.outputs()) + " output(s), ";
  text += s.is_discrete() ? "Ts " + nlohmann::json(s.Ts).dump() + " s" : std::string("continuous");
  if (file.provenance.contains("method")) text += ", " + file.provenance["method"].dump();
  return text + ">";
}

}  // namespace

void bind_model(nb::module_& m) {
  nb::class_<ModelFile>(m, "Model",
                        "A linear model as the command line writes it: state space A, B, C, D at sample time Ts\n"
                        "(0: continuous), with the optional Kalman gain K, initial state x0, offsets, channel names\n"
                        "and provenance. Polynomial models (arx, armax, oe, ar, arma) carry their coefficient lists in\n"
                        "`extra`; augmented models (from diagnose) their physics blocks.")
      .def(
          "__init__",
          [](ModelFile* self, Eigen::MatrixXd A, Eigen::MatrixXd B, Eigen::MatrixXd C, Eigen::MatrixXd D, double Ts,
             std::optional<std::vector<std::string>> inputs, std::optional<std::vector<std::string>> outputs,
             std::optional<Eigen::MatrixXd> K, std::optional<Eigen::VectorXd> x0) {
            ModelFile file;
            file.model = StateSpace(std::move(A), std::move(B), std::move(C), std::move(D), Ts);
            if (inputs) file.model.input_names = *inputs;
            if (outputs) file.model.output_names = *outputs;
            file.model.validate();
            if (K) file.K = *K;
            if (x0) file.x0 = *x0;
            model_to_json_string(file);  // the file's own checks (K n x l, x0 n, finite) before it is a Model
            new (self) ModelFile(std::move(file));
          },
          nb::arg("A"), nb::arg("B"), nb::arg("C"), nb::arg("D"), nb::arg("Ts"), nb::arg("inputs") = nb::none(),
          nb::arg("outputs") = nb::none(), nb::arg("K") = nb::none(), nb::arg("x0") = nb::none(),
          "A state-space model x[k+1] = A x[k] + B u[k], y[k] = C x[k] + D u[k] (Ts > 0), or dx/dt = A x + B u (Ts = 0).")
      .def_prop_ro("type", [](const ModelFile& f) { return f.type; }, "'state-space', 'polynomial' or 'augmented'")
      .def_prop_ro("A", [](const ModelFile& f) { return f.model.A; }, "n x n state matrix (a copy)")
      .def_prop_ro("B", [](const ModelFile& f) { return f.model.B; }, "n x m input matrix (a copy)")
      .def_prop_ro("C", [](const ModelFile& f) { return f.model.C; }, "l x n output matrix (a copy)")
      .def_prop_ro("D", [](const ModelFile& f) { return f.model.D; }, "l x m feedthrough (a copy)")
      .def_prop_ro("Ts", [](const ModelFile& f) { return f.model.Ts; }, "sample time in seconds (0: continuous time)")
      .def_prop_ro("K", [](const ModelFile& f) { return optional_matrix(f.K); }, "n x l Kalman gain, or None")
      .def_prop_ro("noise_covariance", [](const ModelFile& f) { return optional_matrix(f.noise_covariance); },
                   "l x l innovation covariance, or None")
      .def_prop_ro("x0", [](const ModelFile& f) { return optional_vector(f.x0); }, "initial state of the estimation record, or None")
      .def_prop_ro("input_offset", [](const ModelFile& f) { return optional_vector(f.input_offset); },
                   "input means removed before identification, or None")
      .def_prop_ro("output_offset", [](const ModelFile& f) { return optional_vector(f.output_offset); },
                   "output means removed before identification, or None")
      .def_prop_ro("inputs", [](const ModelFile& f) { return f.model.input_names_or_defaults(); }, "input names (u1.. when unnamed)")
      .def_prop_ro("outputs", [](const ModelFile& f) { return f.model.output_names_or_defaults(); }, "output names (y1.. when unnamed)")
      .def_prop_ro("order", [](const ModelFile& f) { return f.model.order(); }, "number of states")
      .def_prop_ro("provenance", [](const ModelFile& f) { return to_python(f.provenance); },
                   "how the model was made (method, order, fits ...): a dict, a copy")
      .def_prop_ro("extra", [](const ModelFile& f) { return to_python(f.extra); },
                   "the file's other keys (polynomial coefficients, augmented blocks): a dict, a copy")
      .def(
          "simulate", &simulate_model, nb::arg("u"), nb::arg("x0") = nb::none(),
          "The output (samples x outputs) for the input u (samples x inputs, or 1-D for one input), from x0\n"
          "(None: zero). The input offset is subtracted and the output offset added, as `sysid simulate` does.")
      .def("poles", [](const ModelFile& f) { return Eigen::VectorXcd(poles(f.model)); }, "eigenvalues of A")
      .def(
          "modes",
          [](const ModelFile& f) {
            nb::list out;
            for (const Mode& mode : modal_table(f.model)) {
              nb::dict d;
              d["freq_hz"] = mode.freq_hz;
              d["damping"] = mode.damping;
              d["pole"] = mode.pole;
              d["complex_pair"] = mode.complex_pair;
              d["stable"] = mode.stable;
              out.append(d);
            }
            return out;
          },
          "one dict per mode (freq_hz, damping ratio, pole, complex_pair, stable), by frequency, as `sysid show` lists them")
      .def("to_json", [](const ModelFile& f) { return model_to_json_string(f); },
           "the model file's text, byte for byte what the command line writes")
      .def("write", [](const ModelFile& f, const Path& path) { write_model_json(path.string(), f); }, nb::arg("path"),
           "write the model file (atomically: a failed write leaves no half-written file)")
      .def(
          "write_mat", [](const ModelFile& f, const Path& path) { write_mat_file(path.string(), model_mat_variables(f)); },
          nb::arg("path"),
          "write the model as MATLAB variables (MAT v5: A B C D Ts, K x0 InputName OutputName where present), the\n"
          "file `sysid export --mat` writes")
      .def("to_control", &to_control, "a control.StateSpace (python-control) with the same matrices, Ts and channel names")
      .def("__repr__", &model_repr);

  m.def("read_model", [](const Path& path) { return read_model_json(path.string()); }, nb::arg("path"), "A model file (any the command line writes) as a Model.");
  m.def(
      "model_from_json", [](const std::string& text) { return model_from_json_string(text, "<text>"); }, nb::arg("text"),
      "A Model from a model file's text.");
}

}  // namespace sysid::python
