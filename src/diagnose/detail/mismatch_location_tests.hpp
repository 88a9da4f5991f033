#pragma once
// Internal to src/diagnose: the pieces of locate_mismatch
// (include/sysid/diagnose/mismatch_location.hpp; method, tests 1-8 and
// references in its file comment), shared by the files that implement them:
// - mismatch_spectral_variance.cpp: the variance of linear functionals of a
//   stationary residual from its Welch spectrum (FunctionalVariance), the window's
//   bin correlations, and the autocovariance and square-process spectra;
// - mismatch_tests_spectral.cpp: tests 1 (model-error FRF), 2 (residual peaks)
//   and 8 (asymmetry: partial coherence with even functions of the input);
// - mismatch_tests_time.cpp: tests 3-7 (time windows, amplitude, reversal,
//   position, offset and drift);
// - mismatch_location.cpp: the driver (locate_mismatch_impl) and the report.
// Everything here is in namespace sysid::detail::mismatch: external linkage
// across those files without clashing with other detail names of the library.
#include <sysid/core/distributions.hpp>
#include <sysid/diagnose/mismatch_location.hpp>
#include <sysid/spectral/frf.hpp>
#include <sysid/spectral/window.hpp>

#include <Eigen/Dense>
#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <string>
#include <vector>

namespace sysid::detail::mismatch {

// ---------------------------------------------------------------------------
// Small helpers
// ---------------------------------------------------------------------------

/// Main-lobe half-width of the window's spectrum in bins (number of cosine terms).
inline Eigen::Index mainlobe_halfwidth(WindowType w) {
  switch (w) {
    case WindowType::rectangular: return 1;
    case WindowType::hann:
    case WindowType::hamming: return 2;
    case WindowType::blackman_harris: return 4;
    case WindowType::flattop: return 5;
  }
  return 2;
}

/// Critical value of z^2 for a two-sided t-test at level alpha with nu degrees of
/// freedom: t^2 ~ F(1, nu).
inline double t2_critical(double alpha, double nu) { return f_upper_quantile(alpha, 1.0, std::min(nu, 1e6)); }

/// names[i], or prefix followed by i + 1 ("y2") when the names stop before i.
inline std::string name_or(const std::vector<std::string>& names, Eigen::Index i, const char* prefix) {
  return i < static_cast<Eigen::Index>(names.size()) ? names[static_cast<std::size_t>(i)] : prefix + std::to_string(i + 1);
}

// ---------------------------------------------------------------------------
// Variance of linear functionals of the residual (file comment of the header;
// mismatch_spectral_variance.cpp)
// ---------------------------------------------------------------------------

/// rho_j^2, j = 0..J: squared correlation of the window's DFT at bin spacing j,
/// |sum_n w_n^2 e^{-2 pi i j n / L}|^2 / (sum_n w_n^2)^2 = correlation of |X_k|^2 and
/// |X_{k+j}|^2 for Gaussian noise (rho_0 = 1).
std::vector<double> window_bin_correlation(WindowType type, Eigen::Index L, Eigen::Index J);

struct Moment {
  double value = 0.0;
  double dof = 0.0;  ///< Satterthwaite degrees of freedom of the estimate
};

/// Var(sum_t x_t r_t) = (1/M) sum_m fs S2(f_m) |X_m|^2 for a stationary residual of
/// one-sided density S (Welch bins), S2 its two-sided density linearly interpolated
/// to the M-point grid.
class FunctionalVariance {
 public:
  FunctionalVariance(const Eigen::VectorXd& S, double fs, double nu, const std::vector<double>& rho2, Eigen::Index N);

  /// Half spectrum (M/2 + 1 bins) of x zero-padded to M.
  Eigen::VectorXcd transform(const Eigen::VectorXd& x);

  double covariance(const Eigen::VectorXcd& X, const Eigen::VectorXcd& Y) const;

  /// Variance with Satterthwaite's degrees of freedom: the estimate is sum_k b_k,
  /// b_k the share of Welch bin k; Var(S_hat_k) = 2 S_k^2 / nu_k and adjacent bins
  /// correlate with rho_j^2.
  Moment variance(const Eigen::VectorXcd& X) const;

 private:
  Eigen::Index m_bins = 0, m_M = 0;
  std::vector<double> m_rho2;
  Eigen::VectorXd m_S2, m_nu_bin, m_theta, m_G;
  Eigen::Matrix<Eigen::Index, Eigen::Dynamic, 1> m_k0;
  double m_fs = 1.0;
  Eigen::FFT<double> m_fft;
  std::vector<double> m_buffer;
};

/// Autocovariance R(j), j = 0..L/2, of a process with one-sided Welch density S
/// (bins = L/2 + 1): R(j) = df [S_0 + sum_{0<k<L/2} S_k cos(2 pi k j / L) + S_{L/2} (-1)^j].
Eigen::VectorXd autocovariance_from_psd(const Eigen::VectorXd& S, double fs);

/// One-sided density of z = r^2 for Gaussian r: R_z(j) = 2 R(j)^2 transformed back
/// (a circular convolution of the non-negative S2 with itself, so non-negative).
Eigen::VectorXd square_process_psd(const Eigen::VectorXd& R, double fs);

// ---------------------------------------------------------------------------
// The per-output analyses
// ---------------------------------------------------------------------------

struct Common {
  double fs = 1.0, Ts = 1.0;
  Eigen::Index N = 0, m = 0, nfft = 0, bins = 0, g = 2;
  double nu = 0.0, alpha = 0.01, alpha_f = 0.01;
  std::vector<double> rho2;  // window bin correlations, j = 0..g+1
  const MismatchLocationOptions* o = nullptr;
};

/// Tests 1 and 2 for output i (mismatch_tests_spectral.cpp): the model-error FRF's
/// joint coherence against its Beta quantile, falsified bands; narrow-band residual
/// peaks above the local floor's F quantile.
void spectral_tests(const Common& c, const FrfResult& fr, Eigen::Index i, ChannelLocation& ch, const Eigen::VectorXd& S,
                    bool residual_zero, std::vector<std::string>& warnings);

/// The even functions of the inputs test 8 extends them with, centred: with
/// d_j = u_j - mean(u_j) (even about the operating point, so that an input with
/// an offset does not make |u_j| a copy of u_j), d_j^2 and |d_j| per input while
/// the averages allow n_d - m - p >= 1, else d_j^2 only (or nothing). A constant
/// function is left out, and |d_j| when it is proportional to d_j^2 (a ternary
/// input).
Eigen::MatrixXd even_input_functions(const Eigen::MatrixXd& u, double nd);

/// Test 8 for output i: partial multiple coherence of r_i with the p even functions
/// given u, from the H1 fits on u (test 1's joint coherence, in ch) and on [u f].
void asymmetry_test(const Common& c, const FrfResult& extended, Eigen::Index p, Eigen::Index i, ChannelLocation& ch);

/// Tests 3-7 for output i (mismatch_tests_time.cpp): residual energy per time window,
/// amplitude-dependent gain, behaviour at velocity reversals, position-dependent
/// mean, offset and drift.
void time_window_test(const Common& c, const Eigen::VectorXd& rc, const Eigen::VectorXd& R, ChannelLocation& ch);
void amplitude_test(const Common& c, const Eigen::VectorXd& y, const Eigen::VectorXd& yn, const Eigen::VectorXd& rc,
                    FunctionalVariance& fv, ChannelLocation& ch, std::vector<std::string>& warnings);
void reversal_test(const Common& c, const Eigen::VectorXd& yn, const Eigen::VectorXd& rc, FunctionalVariance& fv,
                   FunctionalVariance& fv2, ChannelLocation& ch, std::vector<std::string>& warnings);
void position_test(const Common& c, const Eigen::VectorXd& yn, const Eigen::VectorXd& r, FunctionalVariance& fv,
                   ChannelLocation& ch);
void offset_test(const Common& c, const Eigen::VectorXd& r, FunctionalVariance& fv, ChannelLocation& ch);

}  // namespace sysid::detail::mismatch
