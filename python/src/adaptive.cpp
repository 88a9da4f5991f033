// sysid.lms: FIR (Markov parameters) of a record by the multi-step normalised LMS,
// as `sysid lms` computes it (adaptive/multistep_nlms.hpp, multistep_nlms_on_record).
#include <sysid/adaptive/multistep_nlms.hpp>
#include <sysid/config.hpp>
#include <sysid/io/markov_file.hpp>
#include <sysid/realization/markov_parameters.hpp>

#include "bindings.hpp"

namespace sysid::python {

namespace {

MarkovFile identify_lms(const SampleArray& u, const SampleArray& y, double Ts, int taps, int steps, double mu,
                        const std::optional<std::vector<double>>& gamma, const std::vector<std::string>& inputs,
                        const std::vector<std::string>& outputs) {
  if (steps < 1) throw std::invalid_argument("lms: steps must be >= 1");
  IoData data = io_data(u, y, Ts, inputs, outputs);
  MultiStepNlmsOptions options;
  options.taps = taps;
  options.mu = mu;
  // K steps with equal weights unless gamma gives them (they must sum to 1), as --gamma.
  options.gamma = gamma ? *gamma : std::vector<double>(static_cast<std::size_t>(steps), 1.0 / steps);
  if (gamma && static_cast<int>(gamma->size()) != steps && steps != 1)
    throw std::invalid_argument("lms: steps " + std::to_string(steps) + " but gamma has " + std::to_string(gamma->size()) + " weights");
  MultiStepNlmsResult result;
  {
    nb::gil_scoped_release release;
    const Experiment& e = data.experiments.front();
    result = multistep_nlms_on_record(e.u, e.y, options);
  }
  issue_warnings(result.warnings);
  return MarkovFile{markov_from_fir(result.fir, data.Ts, data.input_names, data.output_names),
                    {{"method", "lms"}, {"taps", taps}, {"steps", options.gamma.size()}, {"mu", mu},
                     {"sysid_version", SYSID_VERSION_STRING}}};
}

}  // namespace

void bind_adaptive(nb::module_& m) {
  m.def("lms", &identify_lms, nb::arg("u"), nb::arg("y"), nb::arg("Ts"), nb::kw_only(),
        nb::arg("taps") = MultiStepNlmsOptions{}.taps, nb::arg("steps") = 1, nb::arg("mu") = MultiStepNlmsOptions{}.mu,
        nb::arg("gamma") = nb::none(), nb::arg("inputs") = std::vector<std::string>{},
        nb::arg("outputs") = std::vector<std::string>{},
        "FIR of `taps` taps per path by the multi-step normalised LMS (K = steps error terms combined per update,\n"
        "weights gamma summing to 1, equal by default; step size 0 < mu <= 2), means removed. Returns a Markov\n"
        "(h[s] = the coefficient of u(k - s)); realise it with sysid.era.");
}

}  // namespace sysid::python
