// sysid.filter, sysid.chirp, sysid.multisine, sysid.prbs: Butterworth filtering and
// excitation design (signal/), as `sysid filter` and `sysid excite` compute them.
#include <sysid/signal/butterworth.hpp>
#include <sysid/signal/excitation.hpp>
#include <sysid/signal/sos_filter.hpp>

#include <nanobind/stl/pair.h>

#include "bindings.hpp"

namespace sysid::python {

namespace {

Eigen::MatrixXd butterworth_filter(const SampleArray& x, double Ts, std::optional<double> lowpass,
                                   std::optional<double> highpass, std::optional<std::pair<double, double>> bandpass,
                                   int order, bool zero_phase) {
  if (!(Ts > 0.0)) throw std::invalid_argument("filter: Ts must be > 0");
  if ((lowpass.has_value() + highpass.has_value() + bandpass.has_value()) != 1)
    throw std::invalid_argument("filter: give exactly one of lowpass, highpass, bandpass");
  const double fs = 1.0 / Ts;
  const SecondOrderSections f = lowpass    ? butterworth(order, BandType::lowpass, *lowpass, 0.0, fs)
                                : highpass ? butterworth(order, BandType::highpass, *highpass, 0.0, fs)
                                           : butterworth(order, BandType::bandpass, bandpass->first, bandpass->second, fs);
  const StridedMap view = sample_view(x, "x");
  nb::gil_scoped_release release;
  return zero_phase ? filtfilt(f, view) : sos_filter(f, view);
}

Eigen::VectorXd chirp_signal(double fs_hz, double f0_hz, double f1_hz, double duration_s, double amplitude,
                             const std::string& sweep) {
  if (sweep != "linear" && sweep != "log") throw std::invalid_argument("sweep: expected 'linear' or 'log', found '" + sweep + "'");
  ChirpOptions o;
  o.fs_hz = fs_hz;
  o.f0_hz = f0_hz;
  o.f1_hz = f1_hz;
  o.duration_s = duration_s;
  o.amplitude = amplitude;
  o.sweep = sweep == "log" ? ChirpSweep::logarithmic : ChirpSweep::linear;
  return chirp(o);
}

Eigen::MatrixXd multisine_signal(double fs_hz, double f_min_hz, double f_max_hz, Eigen::Index samples, Eigen::Index period,
                                 Eigen::Index inputs, double rms, std::uint64_t seed) {
  MultisineOptions o;
  o.fs_hz = fs_hz;
  o.f_min_hz = f_min_hz;
  o.f_max_hz = f_max_hz;
  o.samples = samples;
  o.period = period;
  o.inputs = inputs;
  o.rms = rms;
  o.seed = seed;
  nb::gil_scoped_release release;
  return multisine(o);
}

Eigen::VectorXd prbs_signal(int register_bits, Eigen::Index samples, int clock_divider, double amplitude, std::uint64_t seed) {
  PrbsOptions o;
  o.register_bits = register_bits;
  o.samples = samples;
  o.clock_divider = clock_divider;
  o.amplitude = amplitude;
  o.seed = seed;
  return prbs(o);
}

}  // namespace

void bind_signal(nb::module_& m) {
  m.def("filter", &butterworth_filter, nb::arg("x"), nb::arg("Ts"), nb::kw_only(), nb::arg("lowpass") = nb::none(),
        nb::arg("highpass") = nb::none(), nb::arg("bandpass") = nb::none(), nb::arg("order") = 4,
        nb::arg("zero_phase") = false,
        "Butterworth filtering of each column of x (`sysid filter`): one of lowpass=Hz, highpass=Hz,\n"
        "bandpass=(lo, hi); zero_phase runs it forwards and backwards (filtfilt, twice the order in\n"
        "magnitude, no delay).");
  m.def("chirp", &chirp_signal, nb::arg("fs_hz"), nb::arg("f0_hz"), nb::arg("f1_hz"), nb::arg("duration_s"),
        nb::kw_only(), nb::arg("amplitude") = 1.0, nb::arg("sweep") = "linear",
        "Swept sine from f0 to f1 Hz over duration_s at fs_hz ('linear' or 'log' sweep), starting at zero.");
  m.def("multisine", &multisine_signal, nb::arg("fs_hz"), nb::arg("f_min_hz"), nb::arg("f_max_hz"), nb::arg("samples"),
        nb::kw_only(), nb::arg("period") = 0, nb::arg("inputs") = 1, nb::arg("rms") = 1.0, nb::arg("seed") = 1,
        "Random-phase multisine (samples x inputs): flat amplitude on the DFT lines k fs/period in [f_min, f_max],\n"
        "independent phases per input, each column of RMS `rms` over a period (period 0: the whole record).");
  m.def("prbs", &prbs_signal, nb::arg("register_bits"), nb::arg("samples"), nb::kw_only(), nb::arg("clock_divider") = 1,
        nb::arg("amplitude") = 1.0, nb::arg("seed") = 1,
        "Maximum-length binary sequence (+-amplitude) of an n-bit shift register, each bit held clock_divider samples.");
}

}  // namespace sysid::python
