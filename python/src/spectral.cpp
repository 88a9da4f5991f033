// sysid.frf and sysid.psd: Welch spectra and H1/H2 frequency responses with
// coherence and confidence bounds, as `sysid frf` and `sysid psd` compute them.
#include <sysid/spectral/frf.hpp>
#include <sysid/spectral/welch.hpp>
#include <sysid/spectral/window.hpp>

#include <nanobind/stl/pair.h>

#include "bindings.hpp"

namespace sysid::python {

namespace {

WelchOptions welch_options(Eigen::Index nfft, double overlap, const std::string& window, const std::string& detrend) {
  WelchOptions o;
  o.nfft = nfft;
  o.overlap = overlap;
  o.window = parse_window(window);
  o.detrend = detrend_from_name(detrend);
  return o;
}

nb::dict frf_estimate(const SampleArray& u, const SampleArray& y, double Ts, Eigen::Index nfft, double overlap,
                      const std::string& window, const std::string& detrend, const std::string& estimator, double confidence) {
  IoData data = io_data(u, y, Ts, {}, {});
  FrfOptions o;
  o.welch = welch_options(nfft, overlap, window, detrend);
  if (estimator != "h1" && estimator != "h2") throw std::invalid_argument("estimator: expected 'h1' or 'h2', found '" + estimator + "'");
  o.estimator = estimator == "h2" ? FrfEstimator::h2 : FrfEstimator::h1;
  o.confidence = confidence;
  FrfResult r;
  {
    nb::gil_scoped_release release;
    r = frf(data, o);
  }
  nb::dict out;
  out["freq_hz"] = r.freq_hz;
  out["H"] = stack_matrices(r.H);
  out["coherence"] = stack_matrices(r.coherence);
  out["magnitude_lower"] = stack_matrices(r.magnitude_lower);
  out["magnitude_upper"] = stack_matrices(r.magnitude_upper);
  out["phase_halfwidth_rad"] = stack_matrices(r.phase_halfwidth_rad);
  out["input_psd"] = r.input_psd;
  out["output_psd"] = r.output_psd;
  out["nfft"] = r.nfft;
  return out;
}

std::pair<Eigen::VectorXd, Eigen::MatrixXd> psd_estimate(const SampleArray& x, double Ts, Eigen::Index nfft, double overlap,
                                                         const std::string& window, const std::string& detrend,
                                                         const std::string& scaling) {
  if (!(Ts > 0.0)) throw std::invalid_argument("psd: Ts must be > 0");
  WelchOptions o = welch_options(nfft, overlap, window, detrend);
  if (scaling != "density" && scaling != "spectrum")
    throw std::invalid_argument("scaling: expected 'density' or 'spectrum', found '" + scaling + "'");
  o.scaling = scaling == "spectrum" ? SpectralScaling::spectrum : SpectralScaling::density;
  const StridedMap view = sample_view(x, "x");
  PowerSpectrum r;
  {
    nb::gil_scoped_release release;
    r = welch_psd(view, 1.0 / Ts, o);
  }
  return {std::move(r.freq_hz), std::move(r.psd)};
}

}  // namespace

void bind_spectral(nb::module_& m) {
  const WelchOptions defaults;
  m.def("frf", &frf_estimate, nb::arg("u"), nb::arg("y"), nb::arg("Ts"), nb::kw_only(), nb::arg("nfft") = defaults.nfft,
        nb::arg("overlap") = defaults.overlap, nb::arg("window") = "hann", nb::arg("detrend") = "mean",
        nb::arg("estimator") = "h1", nb::arg("confidence") = FrfOptions{}.confidence,
        "Frequency response by Welch averaging (`sysid frf`): a dict with freq_hz, H (frequencies x outputs x\n"
        "inputs, complex), coherence, magnitude_lower/upper and phase_halfwidth_rad (the confidence bounds),\n"
        "input_psd, output_psd and nfft. estimator: 'h1' (noise on the outputs) or 'h2' (on the inputs).");
  m.def("psd", &psd_estimate, nb::arg("x"), nb::arg("Ts"), nb::kw_only(), nb::arg("nfft") = defaults.nfft,
        nb::arg("overlap") = defaults.overlap, nb::arg("window") = "hann", nb::arg("detrend") = "mean",
        nb::arg("scaling") = "density",
        "One-sided Welch power spectrum of each column of x (`sysid psd`): (freq_hz, psd), psd frequencies x\n"
        "channels in units^2/Hz ('density') or units^2 ('spectrum'). window: 'hann', 'hamming',\n"
        "'blackman-harris', 'flattop', 'rectangular'.");
}

}  // namespace sysid::python
