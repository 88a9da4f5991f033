#pragma once
/// @file
/// Purpose: frequency-domain validation of a model against recorded data: per
/// input-output pair, how far the model's frequency response G is from the
/// non-parametric estimate H (H1 by default) inside a frequency band, weighted by
/// how much the estimate can be trusted there (its coherence), and where the worst
/// mismatch is. This is the check the Par2 paper applies to every parametric model.
///
/// Method: H and the ordinary coherence gamma^2 from frf() (spectral/frf.hpp,
/// Bendat & Piersol ch. 6-7), G = frequency_response(model) at the same bins. Over
/// the bins f_k of [f_lo, f_hi] where H is finite, with weights w_k = gamma^2_k:
///   relative_error = sqrt( sum_k w_k |G_k - H_k|^2 / sum_k w_k |H_k|^2 ),
/// a coherence-weighted relative L2 distance (0 for a model that matches the data,
/// ~1 for a model that is as far from H as H is from 0, e.g. a resonance in the
/// wrong place). Coherence weighting follows the variance of H: Var(H)/|H|^2 ~
/// (1 - gamma^2)/(2 n_d gamma^2) (B&P Table 9.6), so bins drowned in noise or not
/// excited (gamma^2 -> 0) contribute nothing, well-measured bins fully.
/// The worst mismatch is the bin maximising gamma^2_k |G_k - H_k| / |H_k| (the
/// coherence-weighted pointwise relative error), reported with that value.
/// For MIMO data H is the full l x m matrix from frf(), which needs all inputs
/// excited (independently) in the data.
///
/// Numerical aspects: cost of frf() plus O(n^3 + bins n^2 m) for the model's
/// response (Hessenberg method). The statistic is noise-biased upwards by about
/// sqrt(mean((1 - gamma^2)/(2 n_d))) (the random error of H itself), which for
/// gamma^2 ~ 0.9 and n_d ~ 30 averages is ~0.04: errors below ~0.05 cannot be
/// distinguished from a perfect model; the `noise_floor` field gives the value for
/// the data at hand.
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/io_data.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/spectral/frf.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

struct FrequencyCompareOptions {
  FrfOptions frf{};         ///< the non-parametric estimate (nfft, window, overlap, H1/H2)
  double f_lo_hz = 0.0;     ///< band [f_lo, f_hi], 0 <= f_lo < f_hi
  double f_hi_hz = std::numeric_limits<double>::infinity();  ///< clipped to fs/2
};

/// One input-output pair.
struct FrequencyComparePair {
  Eigen::Index output = 0, input = 0;
  double relative_error = 0.0;     ///< coherence-weighted relative L2 error over the band (file comment)
  double worst_freq_hz = 0.0;      ///< bin of the largest gamma^2 |G - H| / |H|
  double worst_mismatch = 0.0;     ///< that largest value
  double mean_coherence = 0.0;     ///< mean gamma^2 over the band (how trustworthy H is there)
  /// The value relative_error takes in expectation for the true model because of the
  /// random error of H alone: sqrt(sum w 2 eps^2 |H|^2 / sum w |H|^2), eps from frf().
  double noise_floor = 0.0;
};

struct FrequencyCompareResult {
  std::vector<FrequencyComparePair> pairs;  ///< output-major: (0,0), (0,1), ..., (1,0), ...
  Eigen::Index bins_in_band = 0;            ///< frequencies used
  double f_lo_hz = 0.0, f_hi_hz = 0.0;      ///< band actually used (f_hi clipped to fs/2)
  FrfResult data_frf;                       ///< the non-parametric estimate (whole frequency axis)
  std::vector<Eigen::MatrixXcd> model_frf;  ///< model response at data_frf.freq_hz
  std::vector<std::string> warnings;
};

/// Purpose: model FRF against the non-parametric FRF of `data` in a band (file comment).
/// Preconditions (std::invalid_argument): model discrete with Ts equal to data.Ts
/// (relative 1e-6), or continuous (Ts = 0; evaluated at s = j 2 pi f); model inputs ==
/// data inputs and outputs == data outputs; 0 <= f_lo < f_hi; at least one bin in the
/// band (below fs/2); frf() preconditions.
/// Warnings: band pairs whose mean coherence is below 0.5 (the error is then mostly
/// noise), and those of frf().
/// Example: `auto r = frequency_compare(model, data, {.f_lo_hz = 0, .f_hi_hz = 100});`
/// Purpose: the same comparison for any model given by its frequency response:
/// `model_response(freq_hz)` returns one outputs x inputs matrix per frequency
/// (e.g. a finite-element model's sparse solves, fem/sparse_frf.hpp). NaN entries
/// (frequencies where the model has no finite response) are skipped like
/// undefined estimates.
/// Preconditions (std::invalid_argument): the response has data.outputs() x
/// data.inputs() entries per frequency; 0 <= f_lo < f_hi; at least one bin in the band.
template <class ResponseAt>
FrequencyCompareResult frequency_compare_response(ResponseAt&& model_response, const IoData& data,
                                                  const FrequencyCompareOptions& options = {});

/// Purpose: model FRF against the non-parametric FRF of `data` in a band (file comment).
/// Preconditions (std::invalid_argument): model discrete with Ts equal to data.Ts
/// (relative 1e-6), or continuous (Ts = 0; evaluated at s = j 2 pi f); model inputs ==
/// data inputs and outputs == data outputs; 0 <= f_lo < f_hi; at least one bin in the
/// band (below fs/2); frf() preconditions.
/// Warnings: band pairs whose mean coherence is below 0.5 (the error is then mostly
/// noise), and those of frf().
/// Example: `auto r = frequency_compare(model, data, {.f_lo_hz = 0, .f_hi_hz = 100});`
inline FrequencyCompareResult frequency_compare(const StateSpace& model, const IoData& data,
                                                const FrequencyCompareOptions& options = {}) {
  const std::string who = "frequency_compare";
  model.validate();
  if (model.inputs() != data.inputs() || model.outputs() != data.outputs())
    throw std::invalid_argument(who + ": need model inputs == data inputs and model outputs == data outputs (model " +
                                std::to_string(model.inputs()) + "x" + std::to_string(model.outputs()) + ", data " +
                                std::to_string(data.inputs()) + "x" + std::to_string(data.outputs()) + ")");
  if (model.is_discrete() && std::abs(model.Ts - data.Ts) > 1e-6 * data.Ts)
    throw std::invalid_argument(who + ": need model Ts == data Ts (" + std::to_string(model.Ts) + " vs " +
                                std::to_string(data.Ts) + ")");
  return frequency_compare_response([&](const Eigen::VectorXd& f) { return frequency_response(model, f); }, data, options);
}

template <class ResponseAt>
FrequencyCompareResult frequency_compare_response(ResponseAt&& model_response, const IoData& data,
                                                  const FrequencyCompareOptions& options) {
  const std::string who = "frequency_compare";
  data.validate();
  if (!(options.f_lo_hz >= 0.0) || !(options.f_hi_hz > options.f_lo_hz))
    throw std::invalid_argument(who + ": need 0 <= f_lo < f_hi");

  FrequencyCompareResult r;
  r.data_frf = frf(data, options.frf);
  r.warnings = r.data_frf.warnings;
  const FrfResult& h = r.data_frf;
  r.model_frf = model_response(h.freq_hz);
  if (r.model_frf.size() != static_cast<std::size_t>(h.freq_hz.size()) ||
      (!r.model_frf.empty() && (r.model_frf.front().rows() != data.outputs() || r.model_frf.front().cols() != data.inputs())))
    throw std::invalid_argument(who + ": the model response needs one " + std::to_string(data.outputs()) + " x " +
                                std::to_string(data.inputs()) + " matrix per frequency");
  r.f_lo_hz = options.f_lo_hz;
  r.f_hi_hz = std::min(options.f_hi_hz, 0.5 / data.Ts);

  std::vector<Eigen::Index> bins;
  for (Eigen::Index k = 0; k < h.freq_hz.size(); ++k)
    if (h.freq_hz(k) >= r.f_lo_hz && h.freq_hz(k) <= r.f_hi_hz) bins.push_back(k);
  r.bins_in_band = static_cast<Eigen::Index>(bins.size());
  if (bins.empty())
    throw std::invalid_argument(who + ": need at least one frequency bin in the band (bin spacing " +
                                std::to_string(h.freq_hz.size() > 1 ? h.freq_hz(1) : 0.0) + " Hz)");
  for (Eigen::Index i = 0; i < data.outputs(); ++i)
    for (Eigen::Index j = 0; j < data.inputs(); ++j) {
      FrequencyComparePair p;
      p.output = i;
      p.input = j;
      double num = 0.0, den = 0.0, csum = 0.0, var = 0.0;
      Eigen::Index used = 0;
      for (const Eigen::Index k : bins) {
        const auto b = static_cast<std::size_t>(k);
        const std::complex<double> H = h.H[b](i, j), G = r.model_frf[b](i, j);
        const double w = h.coherence[b](i, j);
        if (!std::isfinite(std::abs(H)) || !std::isfinite(w) || !std::isfinite(std::abs(G))) continue;
        ++used;
        const double d2 = std::norm(G - H), h2 = std::norm(H);
        num += w * d2;
        den += w * h2;
        csum += w;
        // E|H - G_true|^2 = Var(H) = 2 eps^2 |H|^2 with eps frf's normalised random error.
        const double eps = h.random_error[b](i, j);
        if (std::isfinite(eps)) var += w * 2.0 * eps * eps * h2;
        const double pointwise = h2 > 0.0 ? w * std::sqrt(d2 / h2) : 0.0;
        if (pointwise > p.worst_mismatch || used == 1) {
          p.worst_mismatch = pointwise;
          p.worst_freq_hz = h.freq_hz(k);
        }
      }
      const double nan = std::numeric_limits<double>::quiet_NaN();
      p.relative_error = den > 0.0 ? std::sqrt(num / den) : nan;
      p.noise_floor = den > 0.0 ? std::sqrt(var / den) : nan;
      p.mean_coherence = used > 0 ? csum / static_cast<double>(used) : nan;
      if (used == 0 || !(den > 0.0))
        r.warnings.push_back("pair " + data.output_name(i) + " <- " + data.input_name(j) +
                             ": no usable frequency in the band (estimate undefined or zero)");
      else if (p.mean_coherence < 0.5)
        r.warnings.push_back("pair " + data.output_name(i) + " <- " + data.input_name(j) + ": mean coherence " +
                             std::to_string(p.mean_coherence) + " < 0.5 in the band: the error is mostly noise");
      r.pairs.push_back(p);
    }
  return r;
}

}  // namespace sysid
