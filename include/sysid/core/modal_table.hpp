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

#include <complex>
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

/// Purpose: one Mode per complex-conjugate pole pair (the pole with positive
/// imaginary part) and per real pole, sorted by natural frequency (then damping).
/// Method: poles() (eigenvalues of the balanced A, conjugate pairs exact), then the
/// map in the file comment. A pole is real when its imaginary part is exactly
/// zero, which is how the real Schur form returns real eigenvalues; a pair
/// returned from a 2x2 block with tiny imaginary part stays a pair.
/// Preconditions: a valid StateSpace.
std::vector<Mode> modal_table(const StateSpace& sys);

/// Purpose: aligned ASCII table of modes: #, natural frequency (Hz), damping ratio,
/// pole, type ("pair" or "real"; "real (Nyquist)" for a negative real discrete
/// pole; ", unstable" appended when not stable).
/// The pole column is headed "pole (s)" when every mode's pole equals its s (a
/// continuous model), "pole (z)" otherwise.
std::string format_modal_table(const std::vector<Mode>& modes);

}  // namespace sysid
