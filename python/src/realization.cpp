// sysid.okid, sysid.era and sysid.Markov: Markov parameters (impulse responses)
// from records by OKID, and ERA realisations of them, as `sysid okid` / `sysid era`
// compute them; sysid.Markov is the command line's Markov-parameter file in memory.
#include <sysid/config.hpp>
#include <sysid/io/markov_file.hpp>
#include <sysid/realization/era.hpp>
#include <sysid/realization/markov_parameters.hpp>
#include <sysid/realization/okid.hpp>

#include <nanobind/stl/variant.h>

#include <variant>

#include "bindings.hpp"

namespace sysid::python {

namespace {

MarkovFile markov_from_array(const nb::ndarray<const double, nb::ndim<3>, nb::device::cpu>& h, double Ts) {
  std::vector<Eigen::MatrixXd> fir;
  for (std::size_t k = 0; k < h.shape(0); ++k) {
    Eigen::MatrixXd hk(static_cast<Eigen::Index>(h.shape(1)), static_cast<Eigen::Index>(h.shape(2)));
    for (std::size_t i = 0; i < h.shape(1); ++i)
      for (std::size_t j = 0; j < h.shape(2); ++j) hk(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = h(k, i, j);
    fir.push_back(std::move(hk));
  }
  return MarkovFile{markov_from_fir(fir, Ts), nlohmann::json::object()};
}

MarkovFile identify_okid(const SampleArray& u, const SampleArray& y, double Ts, int observer_order, int count,
                         const std::vector<std::string>& inputs, const std::vector<std::string>& outputs) {
  IoData data = io_data(u, y, Ts, inputs, outputs);
  OkidOptions options;
  options.observer_order = observer_order;
  options.markov_count = count;
  OkidResult result;
  {
    nb::gil_scoped_release release;
    for (auto& e : data.experiments) {  // as `sysid okid`: the means removed
      e.u = e.u.rowwise() - e.u.colwise().mean();
      e.y = e.y.rowwise() - e.y.colwise().mean();
    }
    result = okid(data, options);
  }
  issue_warnings(result.warnings);
  return MarkovFile{std::move(result.markov), {{"method", "okid"}, {"observer_order", observer_order},
                                               {"sysid_version", SYSID_VERSION_STRING}}};
}

ModelFile realize_era(const std::variant<MarkovFile, std::vector<MarkovFile>>& markov, std::optional<int> order,
                      int max_order, int row_blocks) {
  std::vector<MarkovParameters> experiments;
  if (const auto* one = std::get_if<MarkovFile>(&markov))
    experiments.push_back(one->markov);
  else
    for (const MarkovFile& f : std::get<std::vector<MarkovFile>>(markov)) experiments.push_back(f.markov);
  EraOptions options;
  if (order) options.order = *order;
  options.max_order = max_order;
  options.row_blocks = row_blocks;
  EraResult result;
  {
    nb::gil_scoped_release release;
    result = era(experiments, options);
  }
  issue_warnings(result.warnings);
  ModelFile file;
  file.model = result.model;
  file.provenance = {{"method", "era"}, {"order", result.order}, {"order_rule", result.order_rule},
                     {"sysid_version", SYSID_VERSION_STRING}};
  return file;
}

}  // namespace

void bind_realization(nb::module_& m) {
  nb::class_<MarkovFile>(m, "Markov",
                         "Markov parameters h[0] = D, h[k] = C A^(k-1) B (an impulse response) with their sample time and\n"
                         "channel names: the command line's Markov-parameter file (from `sysid lms` or `sysid okid`).")
      .def(
          "__init__",
          [](MarkovFile* self, const nb::ndarray<const double, nb::ndim<3>, nb::device::cpu>& h, double Ts) {
            new (self) MarkovFile(markov_from_array(h, Ts));
          },
          nb::arg("h"), nb::arg("Ts"), "From an array (count, outputs, inputs), h[0] = D.")
      .def_prop_ro("h", [](const MarkovFile& f) { return stack_matrices(f.markov.h); }, nb::rv_policy::move,
                   "(count, outputs, inputs) array, a copy")
      .def_prop_ro("Ts", [](const MarkovFile& f) { return f.markov.Ts; })
      .def_prop_ro("inputs", [](const MarkovFile& f) {
        std::vector<std::string> names;
        for (Eigen::Index j = 0; j < f.markov.inputs(); ++j) names.push_back(f.markov.input_name(j));
        return names;
      })
      .def_prop_ro("outputs", [](const MarkovFile& f) {
        std::vector<std::string> names;
        for (Eigen::Index i = 0; i < f.markov.outputs(); ++i) names.push_back(f.markov.output_name(i));
        return names;
      })
      .def_prop_ro("provenance", [](const MarkovFile& f) { return to_python(f.provenance); })
      .def("write", [](const MarkovFile& f, const Path& path) { write_markov_file(path.string(), f); }, nb::arg("path"),
           "write the Markov-parameter file (JSON, type markov) the command line reads")
      .def("__repr__", [](const MarkovFile& f) {
        return "<sysid.Markov: " + std::to_string(f.markov.count()) + " matrices " + std::to_string(f.markov.outputs()) + "x" +
               std::to_string(f.markov.inputs()) + ", Ts " + nlohmann::json(f.markov.Ts).dump() + " s>";
      });
  m.def("read_markov", [](const Path& path) { return read_markov_file(path.string()); }, nb::arg("path"), "A Markov-parameter file (from `sysid lms` or `sysid okid`).");
  m.def("okid", &identify_okid, nb::arg("u"), nb::arg("y"), nb::arg("Ts"), nb::kw_only(),
        nb::arg("observer_order") = OkidOptions{}.observer_order, nb::arg("count") = 0,
        nb::arg("inputs") = std::vector<std::string>{}, nb::arg("outputs") = std::vector<std::string>{},
        "Observer/Kalman filter identification (Juang et al. 1993): the system's Markov parameters from a record\n"
        "(means removed). observer_order: p, with p * outputs >= the order; count: Markov parameters returned\n"
        "(0: 4 p). Returns a Markov; realise it with sysid.era(markov, order=...).");
  m.def("era", &realize_era, nb::arg("markov"), nb::kw_only(), nb::arg("order") = nb::none(), nb::arg("max_order") = 0,
        nb::arg("row_blocks") = 0,
        "Eigensystem realisation (Juang & Pappa 1985) of one Markov or a list realised together.\n"
        "order: None for the largest gap of the Hankel singular values (at most max_order; give one for\n"
        "OKID's parameters, whose gap may be the observer's order). Returns a balanced state-space Model.");
}

}  // namespace sysid::python
