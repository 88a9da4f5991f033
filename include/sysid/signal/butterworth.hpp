#pragma once
/// @file
/// Purpose: digital Butterworth filter design (lowpass, highpass, bandpass) as
/// second-order sections, their frequency response, and their state-space form
/// for band-limiting a model by series connection.
///
/// Method: the classical analog-prototype route (Oppenheim & Schafer, Discrete-Time
/// Signal Processing, 3rd ed., sec. 7.2-7.3; Parks & Burrus, Digital Filter Design,
/// ch. 7):
///   1. normalised prototype poles p_k = exp(i pi (2k + n + 1) / (2n)), k = 0..n-1,
///      i.e. the left half of the unit circle (cutoff 1 rad/s);
///   2. prewarping of the cutoff(s), W = 2 fs tan(pi f / fs), so that after the
///      bilinear transform the -3 dB points land exactly on f1 (and f2);
///   3. analog frequency transformation: lowpass s = W p, highpass s = W / p,
///      bandpass s^2 - B p s + W0^2 = 0 with W0 = sqrt(W1 W2), B = W2 - W1;
///   4. bilinear transform z = (1 + s/(2 fs)) / (1 - s/(2 fs)); analog zeros at
///      s = infinity go to z = -1, zeros at s = 0 go to z = +1;
///   5. one section per conjugate pole pair (a first-order section for the real
///      prototype pole of an odd-order low/highpass), each section scaled to unit
///      magnitude at the reference frequency (DC, Nyquist, or the prewarped band
///      centre), so the cascade has unity passband gain and no section has a
///      large gain that the next one must undo.
///
/// The poles are mapped one by one and the transfer function is never expanded
/// into a single polynomial: high orders and narrow bands keep full accuracy.
#include <sysid/core/state_space.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

enum class BandType { lowpass, highpass, bandpass };

/// A cascade of biquads, one row per section, in scipy's "sos" layout.
struct SecondOrderSections {
  /// rows [b0 b1 b2 a0 a1 a2] of H_k(z) = (b0 + b1 z^-1 + b2 z^-2) / (a0 + a1 z^-1 + a2 z^-2);
  /// a0 = 1 for every section this library designs. A first-order section has b2 = a2 = 0.
  Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> sos;
  double fs_hz = 0.0;  ///< sampling frequency the sections were designed for (> 0)

  Eigen::Index sections() const { return sos.rows(); }
};

namespace detail {

inline void check_sos(const SecondOrderSections& f, const char* who) {
  if (f.sos.rows() < 1) throw std::invalid_argument(std::string(who) + ": need sections >= 1");
  if (!f.sos.allFinite()) throw std::invalid_argument(std::string(who) + ": section coefficients must be finite");
  for (Eigen::Index k = 0; k < f.sos.rows(); ++k)
    if (f.sos(k, 3) == 0.0) throw std::invalid_argument(std::string(who) + ": need a0 != 0 in every section");
}

inline void check_fs(double fs_hz, const char* who) {
  if (!(fs_hz > 0.0) || !std::isfinite(fs_hz)) throw std::invalid_argument(std::string(who) + ": need 0 < fs < infinity");
}

/// Bilinear transform of one analog pole or zero: z = (1 + s/(2 fs)) / (1 - s/(2 fs)).
inline std::complex<double> bilinear(std::complex<double> s, double fs_hz) {
  const std::complex<double> h = s / (2.0 * fs_hz);
  return (1.0 + h) / (1.0 - h);
}

/// Complex response of one section at z^-1 = zinv.
inline std::complex<double> section_response(const SecondOrderSections& f, Eigen::Index k, std::complex<double> zinv) {
  const auto& s = f.sos;
  const std::complex<double> num = s(k, 0) + zinv * (s(k, 1) + zinv * s(k, 2));
  const std::complex<double> den = s(k, 3) + zinv * (s(k, 4) + zinv * s(k, 5));
  return num / den;
}

}  // namespace detail

/// Purpose: poles of the normalised analog Butterworth lowpass prototype
/// (|H(j w)|^2 = 1 / (1 + w^(2n)), cutoff 1 rad/s).
/// Method: p_k = exp(i pi (2k + n + 1) / (2n)), k = 0..n-1 (Oppenheim & Schafer eq. 7.23):
/// equally spaced on the left half of the unit circle. Entries k and n-1-k are
/// complex conjugates; for odd n the middle entry is exactly -1.
/// Preconditions: order >= 1.
inline Eigen::VectorXcd butterworth_analog_poles(int order) {
  if (order < 1) throw std::invalid_argument("butterworth_analog_poles: need order >= 1");
  Eigen::VectorXcd p(order);
  for (int k = 0; k < order; ++k) {
    const double theta = std::numbers::pi * (2.0 * k + order + 1.0) / (2.0 * order);
    p(k) = std::polar(1.0, theta);
  }
  // The real pole of an odd order is set exactly, so it yields a true first-order section.
  if (order % 2 == 1) p(order / 2) = std::complex<double>(-1.0, 0.0);
  return p;
}

/// Purpose: complex frequency response prod_k H_k(exp(i 2 pi f / fs)) of the cascade.
/// Preconditions: sections >= 1, a0 != 0, fs > 0.
/// Numerical aspects: O(sections); evaluated section by section (no polynomial expansion).
inline std::complex<double> sos_frequency_response(const SecondOrderSections& filter, double f_hz) {
  detail::check_sos(filter, "sos_frequency_response");
  detail::check_fs(filter.fs_hz, "sos_frequency_response");
  const std::complex<double> zinv = std::polar(1.0, -2.0 * std::numbers::pi * f_hz / filter.fs_hz);
  std::complex<double> h(1.0, 0.0);
  for (Eigen::Index k = 0; k < filter.sos.rows(); ++k) h *= detail::section_response(filter, k, zinv);
  return h;
}

/// Purpose: digital Butterworth filter of the given order as second-order sections.
/// Method: see the file comment. Lowpass and highpass of order n give ceil(n/2)
/// sections; a bandpass of order n (prototype order n, 2n poles) gives n sections,
/// each with numerator (1 - z^-2) up to its gain.
/// Preconditions (std::invalid_argument): order >= 1; 0 < fs < infinity;
/// 0 < f1 < fs/2; for bandpass additionally f1 < f2 < fs/2 (f2 ignored otherwise).
/// Numerical aspects: O(order). With prewarping |H| = 1/sqrt(2) at f1 (and f2)
/// up to rounding; the passband gain is exactly 1 at DC (lowpass), Nyquist
/// (highpass) or the prewarped centre 2 fs atan(sqrt(W1 W2)/(2 fs)) / (2 pi) (bandpass).
/// Very low cutoffs (f1/fs < 1e-5 or so) put poles within ~1e-5 of z = 1; the
/// sections remain well conditioned, but filtering then needs long transients.
/// Example: butterworth(5, BandType::lowpass, 100.0, 0.0, 2000.0).
inline SecondOrderSections butterworth(int order, BandType type, double f1_hz, double f2_hz, double fs_hz) {
  if (order < 1) throw std::invalid_argument("butterworth: need order >= 1");
  detail::check_fs(fs_hz, "butterworth");
  const double nyquist = 0.5 * fs_hz;
  if (!(f1_hz > 0.0)) throw std::invalid_argument("butterworth: need f1 > 0");
  if (!(f1_hz < nyquist)) throw std::invalid_argument("butterworth: need f1 < fs/2");
  if (type == BandType::bandpass) {
    if (!(f2_hz > f1_hz)) throw std::invalid_argument("butterworth: bandpass needs f1 < f2");
    if (!(f2_hz < nyquist)) throw std::invalid_argument("butterworth: bandpass needs f2 < fs/2");
  }

  using C = std::complex<double>;
  const double pi = std::numbers::pi;
  // Prewarped analog band edges (rad/s): the bilinear map sends analog W to digital f exactly here.
  const double w1 = 2.0 * fs_hz * std::tan(pi * f1_hz / fs_hz);
  const Eigen::VectorXcd proto = butterworth_analog_poles(order);
  const int pairs = order / 2;  // prototype poles 0..pairs-1 lie in the upper half plane
  const bool has_real = (order % 2) == 1;

  SecondOrderSections out;
  out.fs_hz = fs_hz;

  // Reference point for the gain: z^-1 at DC, Nyquist or band centre.
  C zref_inv(1.0, 0.0);
  if (type == BandType::highpass) zref_inv = C(-1.0, 0.0);

  // Analog poles grouped per section: {s, conj(s)} or a real pair / single real pole.
  struct Group {
    C s1;
    C s2;
    bool second_order;
  };
  std::vector<Group> groups;

  if (type == BandType::lowpass || type == BandType::highpass) {
    auto map = [&](C p) { return type == BandType::lowpass ? w1 * p : w1 / p; };
    for (int k = 0; k < pairs; ++k) {
      const C s = map(proto(k));
      groups.push_back({s, std::conj(s), true});
    }
    if (has_real) groups.push_back({C(map(proto(order / 2)).real(), 0.0), C(0.0, 0.0), false});
  } else {
    const double w2 = 2.0 * fs_hz * std::tan(pi * f2_hz / fs_hz);
    const double w0sq = w1 * w2;
    const double bw = w2 - w1;
    // Each prototype pole p splits into the two roots of s^2 - bw p s + w0^2 = 0.
    auto split = [&](C p) {
      const C half = 0.5 * bw * p;
      const C root = std::sqrt(half * half - w0sq);
      return std::pair<C, C>{half + root, half - root};
    };
    for (int k = 0; k < pairs; ++k) {
      const auto [sa, sb] = split(proto(k));
      groups.push_back({sa, std::conj(sa), true});
      groups.push_back({sb, std::conj(sb), true});
    }
    if (has_real) {
      // The real prototype pole gives a real quadratic: its roots are a conjugate or a real pair.
      const auto [sa, sb] = split(C(-1.0, 0.0));
      groups.push_back({sa, sb, true});
    }
    // Prewarped centre: analog W0 maps to digital angle 2 atan(W0 / (2 fs)).
    zref_inv = std::polar(1.0, -2.0 * std::atan(std::sqrt(w0sq) / (2.0 * fs_hz)));
  }

  out.sos.resize(static_cast<Eigen::Index>(groups.size()), 6);
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const auto row = static_cast<Eigen::Index>(g);
    const Group& gr = groups[g];
    double b[3];
    double a[3];
    if (gr.second_order) {
      const C z1 = detail::bilinear(gr.s1, fs_hz);
      const C z2 = detail::bilinear(gr.s2, fs_hz);
      // (1 - z1 z^-1)(1 - z2 z^-1); the pair is conjugate or real, so the coefficients are real.
      a[0] = 1.0;
      a[1] = -(z1 + z2).real();
      a[2] = (z1 * z2).real();
      if (type == BandType::lowpass) {
        b[0] = 1.0, b[1] = 2.0, b[2] = 1.0;  // double zero at z = -1 (analog zeros at infinity)
      } else if (type == BandType::highpass) {
        b[0] = 1.0, b[1] = -2.0, b[2] = 1.0;  // double zero at z = +1 (analog zeros at s = 0)
      } else {
        b[0] = 1.0, b[1] = 0.0, b[2] = -1.0;  // one zero at z = +1 and one at z = -1
      }
    } else {
      const double z1 = detail::bilinear(gr.s1, fs_hz).real();
      a[0] = 1.0, a[1] = -z1, a[2] = 0.0;
      if (type == BandType::lowpass) {
        b[0] = 1.0, b[1] = 1.0, b[2] = 0.0;
      } else {
        b[0] = 1.0, b[1] = -1.0, b[2] = 0.0;
      }
    }
    out.sos.row(row) << b[0], b[1], b[2], a[0], a[1], a[2];
    const double gain = std::abs(detail::section_response(out, row, zref_inv));
    // The numerator zeros are away from the reference point (lowpass: none at DC,
    // highpass: none at Nyquist, bandpass: zeros at DC and Nyquist only), so gain > 0.
    out.sos.block<1, 3>(row, 0) /= gain;
  }
  return out;
}

/// Purpose: the cascade as one discrete SISO state-space model (Ts = 1/fs), for
/// band-limiting a model by series connection (e.g. measured output = filter * plant).
/// Method: each section in transposed direct form II,
///   y = b0 u + x1,  x1' = -a1 x1 + x2 + (b1 - a1 b0) u,  x2' = -a2 x1 + (b2 - a2 b0) u
/// (one state for a first-order section, b2 = a2 = 0), coefficients divided by a0;
/// sections in series: A = [A1 0; B2 C1 A2], B = [B1; B2 D1], C = [D2 C1  C2], D = D2 D1.
/// Preconditions: sections >= 1, a0 != 0, fs > 0.
/// Numerical aspects: order = 2 * (second-order sections) + (first-order sections);
/// the block lower-triangular A has exactly the filter poles as eigenvalues.
inline StateSpace sos_to_state_space(const SecondOrderSections& filter) {
  detail::check_sos(filter, "sos_to_state_space");
  detail::check_fs(filter.fs_hz, "sos_to_state_space");
  Eigen::MatrixXd A(0, 0), B(0, 1), C(1, 0), D = Eigen::MatrixXd::Ones(1, 1);
  for (Eigen::Index k = 0; k < filter.sos.rows(); ++k) {
    const Eigen::Matrix<double, 1, 6> r = filter.sos.row(k) / filter.sos(k, 3);
    const bool first_order = (r(2) == 0.0 && r(5) == 0.0);
    const Eigen::Index ns = first_order ? 1 : 2;
    Eigen::MatrixXd As(ns, ns), Bs(ns, 1), Cs = Eigen::MatrixXd::Zero(1, ns);
    if (first_order) {
      As << -r(4);
      Bs << r(1) - r(4) * r(0);
    } else {
      As << -r(4), 1.0, -r(5), 0.0;
      Bs << r(1) - r(4) * r(0), r(2) - r(5) * r(0);
    }
    Cs(0, 0) = 1.0;
    const double Ds = r(0);

    const Eigen::Index n = A.rows();
    Eigen::MatrixXd An = Eigen::MatrixXd::Zero(n + ns, n + ns);
    An.topLeftCorner(n, n) = A;
    An.bottomLeftCorner(ns, n) = Bs * C;
    An.bottomRightCorner(ns, ns) = As;
    Eigen::MatrixXd Bn(n + ns, 1);
    Bn.topRows(n) = B;
    Bn.bottomRows(ns) = Bs * D;
    Eigen::MatrixXd Cn(1, n + ns);
    Cn.leftCols(n) = Ds * C;
    Cn.rightCols(ns) = Cs;
    A = std::move(An);
    B = std::move(Bn);
    C = std::move(Cn);
    D *= Ds;
  }
  return StateSpace(A, B, C, D, 1.0 / filter.fs_hz);
}

}  // namespace sysid
