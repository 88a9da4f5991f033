#include <sysid/core/format_number.hpp>
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/median.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/spectral/model_spectrum.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sysid {

namespace {

void check_noise_model(const StateSpace& model, const Eigen::MatrixXd& K, const Eigen::MatrixXd& lambda) {
  const Eigen::Index n = model.A.rows(), l = model.C.rows();
  if (K.size() == 0 && lambda.size() == 0) return;
  if (K.rows() != n || K.cols() != l || lambda.rows() != l || lambda.cols() != l)
    throw std::invalid_argument("model_output_spectrum: need K " + std::to_string(n) + "x" + std::to_string(l) +
                                " and the innovation covariance " + std::to_string(l) + "x" + std::to_string(l) +
                                " (or neither)");
  if (!K.allFinite() || !lambda.allFinite() || (lambda - lambda.transpose()).cwiseAbs().maxCoeff() > 1e-12 * lambda.cwiseAbs().maxCoeff() ||
      (lambda.diagonal().array() < 0.0).any())
    throw std::invalid_argument("model_output_spectrum: the innovation covariance must be finite, symmetric, with a non-negative diagonal");
}

}  // namespace

ModelSpectrum model_output_spectrum(const StateSpace& model, const Eigen::MatrixXd& K, const Eigen::MatrixXd& noise_covariance,
                                    const Eigen::VectorXd& freq_hz, const std::vector<Eigen::MatrixXcd>& input_csd) {
  model.validate();
  if (!(model.Ts > 0.0)) throw std::invalid_argument("model_output_spectrum: need a discrete model (Ts > 0); discretise it first");
  check_noise_model(model, K, noise_covariance);
  const Eigen::Index n = model.A.rows(), m = model.B.cols(), l = model.C.rows(), nf = freq_hz.size();
  const bool has_noise = K.size() > 0, has_input = m > 0 && !input_csd.empty();
  if (!has_noise && m == 0)
    throw std::invalid_argument("model_output_spectrum: the model has neither inputs nor a disturbance model (K, noise covariance)");
  if (!input_csd.empty() && static_cast<Eigen::Index>(input_csd.size()) != nf)
    throw std::invalid_argument("model_output_spectrum: need one input spectral matrix per frequency");
  const double nyquist = 0.5 / model.Ts;
  for (Eigen::Index k = 0; k < nf; ++k)
    if (!(freq_hz(k) >= 0.0 && freq_hz(k) <= nyquist * (1.0 + 1e-12)))
      throw std::invalid_argument("model_output_spectrum: frequencies must lie in [0, fs/2]");

  // One frequency response for [G H]: inputs [u e], feedthrough [D I].
  Eigen::MatrixXd Bx(n, m + (has_noise ? l : 0)), Dx(l, m + (has_noise ? l : 0));
  Bx.leftCols(m) = model.B;
  Dx.leftCols(m) = model.D;
  if (has_noise) {
    Bx.rightCols(l) = K;
    Dx.rightCols(l) = Eigen::MatrixXd::Identity(l, l);
  }
  const std::vector<Eigen::MatrixXcd> response = frequency_response(StateSpace(model.A, Bx, model.C, Dx, model.Ts), freq_hz);

  ModelSpectrum out;
  out.freq_hz = freq_hz;
  if (n > 0) {
    const double radius = poles(model).cwiseAbs().maxCoeff();
    if (!(radius < 1.0))
      out.warnings.push_back("the model is unstable (spectral radius " + format_number(radius) +
                             "): it has no stationary output, so its curve is not a spectrum");
  }
  out.output_psd = Eigen::MatrixXd::Zero(nf, l);
  out.disturbance_psd = Eigen::MatrixXd::Zero(nf, l);
  for (Eigen::Index k = 0; k < nf; ++k) {
    const Eigen::MatrixXcd& GH = response[static_cast<std::size_t>(k)];
    if (has_noise) {
      // One-sided: every bin but DC and Nyquist carries the power of -f as well.
      const bool edge = freq_hz(k) == 0.0 || std::abs(freq_hz(k) - nyquist) <= 1e-12 * nyquist;
      const double c = (edge ? 1.0 : 2.0) * model.Ts;
      const Eigen::MatrixXcd H = GH.rightCols(l);
      out.disturbance_psd.row(k) = c * (H * noise_covariance * H.adjoint()).diagonal().real().transpose();
    }
    out.output_psd.row(k) = out.disturbance_psd.row(k);
    if (has_input) {
      const Eigen::MatrixXcd& S = input_csd[static_cast<std::size_t>(k)];
      if (S.rows() != m || S.cols() != m)
        throw std::invalid_argument("model_output_spectrum: each input spectral matrix must be " + std::to_string(m) + "x" +
                                    std::to_string(m));
      const Eigen::MatrixXcd G = GH.leftCols(m);
      // S(i, j) = S_{u_i u_j} with the conjugate on u_i (welch_csd): Phi_y = G S^T G^H.
      out.output_psd.row(k) += (G * S.transpose() * G.adjoint()).diagonal().real().transpose();
    }
  }
  return out;
}

SpectrumAgreement spectrum_agreement(const Eigen::VectorXd& estimate, const Eigen::VectorXd& model, const Eigen::VectorXd& freq_hz,
                                     double f_lo, double f_hi, double lo_factor, double hi_factor) {
  if (estimate.size() != model.size() || estimate.size() != freq_hz.size())
    throw std::invalid_argument("spectrum_agreement: the estimate, the model and the frequencies must have equal sizes");
  if (!(f_lo < f_hi)) throw std::invalid_argument("spectrum_agreement: need f_lo < f_hi");
  if (!(lo_factor > 0.0 && lo_factor <= 1.0 && hi_factor >= 1.0))
    throw std::invalid_argument("spectrum_agreement: need 0 < lo_factor <= 1 <= hi_factor");
  std::vector<double> db;
  Eigen::Index inside = 0;
  for (Eigen::Index k = 0; k < freq_hz.size(); ++k) {
    if (freq_hz(k) < f_lo || freq_hz(k) > f_hi) continue;
    const double p = estimate(k), q = model(k);
    if (!(p > 0.0 && q > 0.0 && std::isfinite(p) && std::isfinite(q))) continue;
    db.push_back(10.0 * std::log10(q / p));
    if (q >= lo_factor * p && q <= hi_factor * p) ++inside;
  }
  if (db.empty()) throw std::invalid_argument("spectrum_agreement: no bin with positive spectra in the band");
  SpectrumAgreement a;
  a.bins = static_cast<Eigen::Index>(db.size());
  double sum_abs = 0.0;
  for (const double d : db) sum_abs += std::abs(d);
  a.mean_abs_db = sum_abs / static_cast<double>(db.size());
  a.fraction_inside = static_cast<double>(inside) / static_cast<double>(db.size());
  a.median_db = median(std::move(db));
  return a;
}

}  // namespace sysid
