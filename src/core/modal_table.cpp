// Implementation of core/modal_table.hpp (the pole-to-mode map is described there).
#include "core/detail/modal_table.hpp"
#include <sysid/core/modal_table.hpp>
#include <sysid/core/poles_zeros.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

namespace sysid {

namespace detail {

Mode make_mode(std::complex<double> p, double Ts, bool pair) {
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

std::vector<Mode> modal_table(const StateSpace& sys) {
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

std::string format_modal_table(const std::vector<Mode>& modes) {
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
