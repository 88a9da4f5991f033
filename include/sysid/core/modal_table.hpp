#pragma once
/// @file
/// Purpose: the modes of a model as a vibration engineer reads them: natural
/// frequency (Hz) and damping ratio of every complex-conjugate pole pair and
/// every real pole.
///
/// Method: for a discrete model each pole z is mapped to its continuous-time
/// equivalent s = log(z) / Ts (principal logarithm: the inverse of the exact
/// ZOH pole map z = exp(s Ts), valid for |Im s| < pi / Ts); then
/// wn = |s|, f = wn / (2 pi), zeta = -Re(s) / |s|.
/// Special cases:
/// - a real negative discrete pole z < 0 has no real logarithm; it is taken as
///   s = (ln|z| + j pi) / Ts, an oscillation exactly at the Nyquist frequency
///   1/(2 Ts) (its natural frequency |s|/(2 pi) is >= Nyquist);
/// - z = 0 (a pure delay state) gives s = -Inf, freq_hz = Inf, damping = 1;
/// - s = 0 (integrator) gives freq_hz = 0 and damping 0 (marginal).
/// Preconditions: a valid StateSpace.
/// Numerical aspects: O(n^3) for the poles (see poles()); the map itself is exact
/// up to rounding for poles not clustered at z = 0.
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/state_space.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace sysid {

struct Mode {
  std::complex<double> pole;  ///< discrete z (or s if continuous); for a pair, the one with Im > 0
  std::complex<double> s;     ///< continuous-time equivalent: log(z)/Ts (= pole if continuous)
  double freq_hz = 0.0;       ///< natural frequency |s| / (2 pi)
  double damping = 0.0;       ///< damping ratio -Re(s) / |s| (a ratio: 0.02, not 2 %)
  bool complex_pair = false;  ///< true: stands for the conjugate pair pole, conj(pole)
  bool stable = false;        ///< |z| < 1 (discrete) or Re(s) < 0 (continuous)
};

namespace detail {

inline Mode make_mode(std::complex<double> p, double Ts, bool pair) {
  constexpr double pi = std::numbers::pi;
  Mode md;
  md.pole = p;
  md.complex_pair = pair;
  if (Ts > 0.0) {
    md.stable = std::abs(p) < 1.0;
    if (p == 0.0) {
      md.s = {-std::numeric_limits<double>::infinity(), 0.0};
      md.freq_hz = std::numeric_limits<double>::infinity();
      md.damping = 1.0;
      return md;
    }
    // A real negative pole: take the branch Im(s) = +pi / Ts explicitly, so the sign
    // of a zero imaginary part cannot flip it to -pi.
    md.s = (!pair && p.real() < 0.0) ? std::complex<double>(std::log(-p.real()), pi) / Ts : std::log(p) / Ts;
  } else {
    md.stable = p.real() < 0.0;
    md.s = p;
  }
  const double wn = std::abs(md.s);
  md.freq_hz = wn / (2.0 * pi);
  md.damping = wn > 0.0 ? -md.s.real() / wn : 0.0;
  return md;
}

}  // namespace detail

/// Purpose: one Mode per complex-conjugate pole pair (the pole with positive
/// imaginary part) and per real pole, sorted by natural frequency (then damping).
/// Method: poles() (eigenvalues of the balanced A, conjugate pairs exact), then the
/// map in the file comment. A pole is real when its imaginary part is exactly
/// zero, which is how the real Schur form returns real eigenvalues; a pair
/// returned from a 2x2 block with tiny imaginary part stays a pair.
/// Preconditions: a valid StateSpace.
inline std::vector<Mode> modal_table(const StateSpace& sys) {
  const Eigen::VectorXcd p = poles(sys);
  std::vector<Mode> modes;
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    if (p[i].imag() < 0.0) continue;  // represented by its conjugate
    modes.push_back(detail::make_mode(p[i], sys.Ts, p[i].imag() > 0.0));
  }
  std::stable_sort(modes.begin(), modes.end(), [](const Mode& a, const Mode& b) {
    if (a.freq_hz != b.freq_hz) return a.freq_hz < b.freq_hz;
    return a.damping < b.damping;
  });
  return modes;
}

/// Purpose: aligned ASCII table of modes: #, natural frequency (Hz), damping ratio,
/// pole, type ("pair" or "real"; "real (Nyquist)" for a negative real discrete
/// pole; ", unstable" appended when not stable).
/// The pole column is headed "pole (s)" when every mode's pole equals its s (a
/// continuous model), "pole (z)" otherwise.
inline std::string format_modal_table(const std::vector<Mode>& modes) {
  bool continuous = !modes.empty();
  for (const Mode& md : modes) continuous = continuous && md.pole == md.s;
  std::vector<std::string> poles_text;
  std::size_t pole_width = 8;
  char buf[160];
  for (const Mode& md : modes) {
    if (md.complex_pair)
      std::snprintf(buf, sizeof buf, "%.6g +/- %.6gj", md.pole.real(), md.pole.imag());
    else
      std::snprintf(buf, sizeof buf, "%.6g", md.pole.real());
    poles_text.emplace_back(buf);
    pole_width = std::max(pole_width, poles_text.back().size());
  }
  const int pw = static_cast<int>(pole_width);
  std::string out;
  std::snprintf(buf, sizeof buf, "%4s  %12s  %10s  %-*s  %s\n", "#", "freq [Hz]", "damping", pw,
                continuous ? "pole (s)" : "pole (z)", "type");
  out += buf;
  for (std::size_t i = 0; i < modes.size(); ++i) {
    const Mode& md = modes[i];
    std::string type = md.complex_pair ? "pair" : "real";
    if (!md.complex_pair && !continuous && md.pole.real() < 0.0) type += " (Nyquist)";
    if (!md.stable) type += ", unstable";
    std::snprintf(buf, sizeof buf, "%4zu  %12.6g  %10.4g  %-*s  %s\n", i + 1, md.freq_hz, md.damping, pw,
                  poles_text[i].c_str(), type.c_str());
    out += buf;
  }
  return out;
}

}  // namespace sysid
