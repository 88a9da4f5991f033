// Implementation of family/estimation_error.hpp (method in the header).
#include <sysid/family/estimation_error.hpp>
#include <sysid/spectral/excited_band.hpp>
#include <sysid/spectral/welch.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>

namespace sysid {

namespace {

/// Largest (or smallest) eigenvalue of a Hermitian spectral matrix per bin.
Eigen::VectorXd spectral_extreme(const CrossSpectrum& s, bool largest) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(s.csd.size()));
  for (std::size_t k = 0; k < s.csd.size(); ++k) {
    const Eigen::MatrixXcd h = 0.5 * (s.csd[k] + s.csd[k].adjoint());
    const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd>(h, Eigen::EigenvaluesOnly).eigenvalues();
    out(static_cast<Eigen::Index>(k)) = std::max(largest ? ev.maxCoeff() : ev.minCoeff(), 0.0);
  }
  return out;
}

}  // namespace

Eigen::VectorXd FrequencyResponseError::at(const Eigen::VectorXd& grid_hz) const {
  if (freq_hz.size() == 0) return {};
  Eigen::VectorXd out(grid_hz.size());
  for (Eigen::Index k = 0; k < grid_hz.size(); ++k) {
    const double f = grid_hz(k);
    const auto* upper = std::upper_bound(freq_hz.data(), freq_hz.data() + freq_hz.size(), f);
    const Eigen::Index hi = upper - freq_hz.data();
    if (hi == 0) {
      out(k) = standard_deviation(0);
    } else if (hi >= freq_hz.size()) {
      out(k) = standard_deviation(freq_hz.size() - 1);
    } else {
      const double t = (f - freq_hz(hi - 1)) / (freq_hz(hi) - freq_hz(hi - 1));
      out(k) = (1.0 - t) * standard_deviation(hi - 1) + t * standard_deviation(hi);
    }
  }
  return out;
}

FrequencyResponseError frequency_response_error(const StateSpace& model, const IoData& log, const CompareOptions& offsets) {
  if (!model.is_discrete()) throw std::invalid_argument("frequency_response_error: needs a discrete model");
  const Experiment& e = log.experiments.front();
  const CompareResult sim = compare(model, Eigen::MatrixXd(), e, offsets);
  return frequency_response_error(model.order(), e.u, e.y - sim.y_hat, log.Ts);
}

FrequencyResponseError frequency_response_error(Eigen::Index order, const Eigen::MatrixXd& u, const Eigen::MatrixXd& output_error,
                                                double Ts) {
  if (u.rows() != output_error.rows() || u.cols() < 1)
    throw std::invalid_argument("frequency_response_error: need inputs and an output error of the same length");
  const double fs = 1.0 / Ts;
  WelchOptions wo;
  wo.nfft = std::min<Eigen::Index>(1024, std::max<Eigen::Index>(64, u.rows() / 8));
  const Eigen::VectorXd noise = spectral_extreme(welch_csd(output_error, output_error, fs, wo), true);
  const CrossSpectrum input = welch_csd(u, u, fs, wo);
  const Eigen::VectorXd excitation = spectral_extreme(input, false);
  FrequencyResponseError out;
  out.freq_hz = input.freq_hz;
  const double scale = static_cast<double>(order) / static_cast<double>(u.rows());
  const double floor = excitation.maxCoeff() * 1e-12;
  out.standard_deviation = (scale * noise.array() / excitation.array().max(floor)).sqrt();
  std::tie(out.band_lo_hz, out.band_hi_hz) = excited_band(u, fs);
  return out;
}

}  // namespace sysid
