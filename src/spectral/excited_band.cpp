#include <sysid/spectral/excited_band.hpp>
#include <sysid/spectral/welch.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sysid {

std::pair<double, double> excited_band(const Eigen::Ref<const Eigen::MatrixXd>& u, double fs_hz, double dynamic_range_db) {
  if (u.cols() < 1) throw std::invalid_argument("excited_band: need at least one input column");
  WelchOptions wo;
  wo.nfft = std::min<Eigen::Index>(4096, std::max<Eigen::Index>(64, u.rows() / 8));
  const PowerSpectrum ps = welch_psd(u, fs_hz, wo);
  const Eigen::VectorXd total = ps.psd.rowwise().sum();
  const double threshold = total.maxCoeff() * std::pow(10.0, -dynamic_range_db / 10.0);
  Eigen::Index lo = 0, hi = total.size() - 1;
  while (lo < hi && total(lo) < threshold) ++lo;
  while (hi > lo && total(hi) < threshold) --hi;
  return {ps.freq_hz(lo), ps.freq_hz(hi)};
}

}  // namespace sysid
