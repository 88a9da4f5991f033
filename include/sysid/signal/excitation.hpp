#pragma once
/// @file
/// Purpose: deterministic, seeded excitation signals for identification experiments:
/// swept sine (chirp), random-phase multisine, and maximum-length PRBS.
///
/// Every generator is a pure function of its options: the same options (and seed)
/// give the same samples on every platform that has IEEE doubles, so an experiment
/// can be regenerated from its options alone. std::mt19937_64 is fully specified by
/// the C++ standard; the uniform phases are drawn from its raw output (not through
/// std::uniform_real_distribution, whose algorithm is implementation-defined).
#include <sysid/core/math_constants.hpp>

#include <Eigen/Dense>
#include <unsupported/Eigen/FFT>

#include <algorithm>
#include <bit>
#include <cmath>
#include <complex>
#include <cstdint>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace sysid {

enum class ChirpSweep { linear, logarithmic };

struct ChirpOptions {
  double fs_hz = 1000;       ///< sampling frequency, > 0
  double f0_hz = 0;          ///< instantaneous frequency at t = 0; 0 <= f0 <= fs/2 (> 0 for a log sweep)
  double f1_hz = 100;        ///< instantaneous frequency at t = duration; 0 <= f1 <= fs/2 (> 0 for a log sweep)
  double duration_s = 10;    ///< sweep duration T; N = round(T fs) >= 1 samples
  double amplitude = 1;      ///< peak amplitude, finite
  ChirpSweep sweep = ChirpSweep::linear;
};

/// Purpose: swept sine x[k] = amplitude * sin(phi(t_k)), t_k = k / fs, k = 0..N-1,
/// N = round(duration * fs). Starting with sin (phi(0) = 0) avoids a step at t = 0.
/// Method: phi(t) = 2 pi * integral_0^t f(tau) dtau in closed form:
///   linear:      f(t) = f0 + (f1 - f0) t / T,       phi(t) = 2 pi (f0 t + (f1 - f0) t^2 / (2T));
///   logarithmic: f(t) = f0 (f1/f0)^(t/T),           phi(t) = 2 pi f0 T (r^(t/T) - 1) / ln r, r = f1/f0
///                (phi(t) = 2 pi f0 t when r = 1).
/// The log sweep spends equal time per octave, hence equal energy per octave.
/// Preconditions (std::invalid_argument): fs > 0; duration > 0; round(duration fs) >= 1;
/// 0 <= f0 <= fs/2; 0 <= f1 <= fs/2; log sweep: f0 > 0 and f1 > 0; amplitude finite.
/// Numerical aspects: O(N); phase evaluated directly at each t (no accumulation
/// error); for very long sweeps the phase grows to ~ pi (f0 + f1) T and sin loses
/// ~ log10(phase) digits, e.g. 1e-10 relative at 1e6 rad.
inline Eigen::VectorXd chirp(const ChirpOptions& o) {
  const auto bad = [](const std::string& what) { return std::invalid_argument("chirp: need " + what); };
  if (!(o.fs_hz > 0.0) || !std::isfinite(o.fs_hz)) throw bad("0 < fs < infinity");
  if (!(o.duration_s > 0.0) || !std::isfinite(o.duration_s)) throw bad("0 < duration < infinity");
  if (!(o.f0_hz >= 0.0)) throw bad("f0 >= 0");
  if (!(o.f1_hz >= 0.0)) throw bad("f1 >= 0");
  if (!(o.f0_hz <= 0.5 * o.fs_hz)) throw bad("f0 <= fs/2");
  if (!(o.f1_hz <= 0.5 * o.fs_hz)) throw bad("f1 <= fs/2");
  if (o.sweep == ChirpSweep::logarithmic && !(o.f0_hz > 0.0)) throw bad("f0 > 0 for a logarithmic sweep");
  if (o.sweep == ChirpSweep::logarithmic && !(o.f1_hz > 0.0)) throw bad("f1 > 0 for a logarithmic sweep");
  if (!std::isfinite(o.amplitude)) throw bad("finite amplitude");
  const double samples = std::round(o.duration_s * o.fs_hz);
  if (!(samples >= 1.0)) throw bad("round(duration * fs) >= 1");

  const auto n = static_cast<Eigen::Index>(samples);
  const double T = o.duration_s;
  Eigen::VectorXd x(n);
  const double ratio = o.f1_hz / o.f0_hz;  // used only for the log sweep, where f0 > 0
  const bool log_sweep = o.sweep == ChirpSweep::logarithmic;
  const double log_ratio = log_sweep ? std::log(ratio) : 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / o.fs_hz;
    double phase;
    if (!log_sweep) {
      phase = kTwoPi * (o.f0_hz * t + (o.f1_hz - o.f0_hz) * t * t / (2.0 * T));
    } else if (log_ratio == 0.0) {
      phase = kTwoPi * o.f0_hz * t;
    } else {
      // expm1 keeps the small-t phase accurate: r^(t/T) - 1 = expm1((t/T) ln r).
      phase = kTwoPi * o.f0_hz * T * std::expm1(t / T * log_ratio) / log_ratio;
    }
    x(k) = o.amplitude * std::sin(phase);
  }
  return x;
}

namespace detail {

/// Largest prime factor of n >= 1 (1 for n = 1), by trial division: O(sqrt n).
inline std::uint64_t largest_prime_factor(std::uint64_t n) {
  std::uint64_t largest = 1;
  for (std::uint64_t p = 2; p * p <= n; ++p)
    while (n % p == 0) largest = p, n /= p;
  return n > 1 ? n : largest;
}

/// Inverse DFT x[n] = (1/P) sum_k X[k] exp(i 2 pi k n / P) of any length P.
/// Eigen's FFT (kissfft) is O(P p) for a prime factor p of P, i.e. O(P^2) for a
/// prime P (minutes at P ~ 1e5). For lengths with a prime factor above 64 the
/// Bluestein chirp-z identity kn = (k^2 + n^2 - (n - k)^2) / 2 turns the DFT into
/// a circular convolution of length M >= 2P - 1, a power of two:
///   x[n] = (1/P) c[n] sum_k (X[k] c[k]) conj(c[n - k]),  c[m] = exp(i pi m^2 / P),
/// with m^2 reduced mod 2P before the exponential so large m lose no phase accuracy
/// (Bluestein 1970; Rabiner, Schafer & Rader, "The chirp z-transform algorithm", 1969).
inline std::vector<std::complex<double>> inverse_dft(const std::vector<std::complex<double>>& X) {
  const std::size_t P = X.size();
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> x;
  if (largest_prime_factor(P) <= 64) {
    fft.inv(x, X);  // Eigen scales by 1/P
    return x;
  }
  std::size_t M = 1;
  while (M < 2 * P - 1) M *= 2;
  std::vector<std::complex<double>> c(P), a(M), b(M);
  for (std::size_t m = 0; m < P; ++m) {
    const std::uint64_t q = (static_cast<std::uint64_t>(m) * m) % (2 * static_cast<std::uint64_t>(P));
    c[m] = std::polar(1.0, std::numbers::pi * static_cast<double>(q) / static_cast<double>(P));
  }
  for (std::size_t k = 0; k < P; ++k) a[k] = X[k] * c[k];
  b[0] = std::conj(c[0]);
  for (std::size_t m = 1; m < P; ++m) b[m] = b[M - m] = std::conj(c[m]);
  std::vector<std::complex<double>> A, B, conv;
  fft.fwd(A, a);
  fft.fwd(B, b);
  for (std::size_t i = 0; i < M; ++i) A[i] *= B[i];
  fft.inv(conv, A);  // circular convolution, scaled by 1/M
  x.resize(P);
  for (std::size_t n = 0; n < P; ++n) x[n] = c[n] * conv[n] / static_cast<double>(P);
  return x;
}

}  // namespace detail

struct MultisineOptions {
  double fs_hz = 1000;        ///< sampling frequency, > 0
  double f_min_hz = 0;        ///< lowest excited frequency (DC is never excited), >= 0
  double f_max_hz = 100;      ///< highest excited frequency, f_min <= f_max < fs/2
  Eigen::Index samples = 4096;  ///< rows of the result, >= 1
  Eigen::Index period = 0;      ///< period P in samples (frequency grid fs/P); 0 means P = samples; P >= 2
  Eigen::Index inputs = 1;      ///< columns (independent phases per column), >= 1
  double rms = 1;               ///< RMS of each column over one period, > 0
  std::uint64_t seed = 1;       ///< seed of std::mt19937_64 for the phases
};

/// Purpose: random-phase multisine, N x inputs: flat amplitude spectrum on the DFT
/// bins k fs / P with f_min <= k fs / P <= f_max, 1 <= k < P/2, zero elsewhere.
/// Method (Pintelon & Schoukens, System Identification: A Frequency Domain Approach,
/// 2nd ed., sec. 5.2): one period x[n] = a * sum_k cos(2 pi k n / P + phi_k), phases
/// phi_k i.i.d. uniform on [0, 2 pi) drawn column after column, bin after bin,
/// from one std::mt19937_64(seed); built by an inverse FFT of its spectrum and
/// repeated periodically to the requested length. With K excited bins the
/// per-period RMS is a sqrt(K/2) exactly (orthogonality of the bins), so
/// a = rms sqrt(2/K).
/// Preconditions (std::invalid_argument): fs > 0; 0 <= f_min <= f_max < fs/2;
/// samples >= 1; period == 0 or period >= 2; inputs >= 1; rms > 0; at least one
/// bin k >= 1 with f_min <= k fs/P <= f_max.
/// Numerical aspects: O(inputs * P log P) for any P (Bluestein for large prime factors). The RMS is exact over whole periods;
/// over a partial period it is close but not exact. Random phases give a crest
/// factor around 3-4 (not minimised).
inline Eigen::MatrixXd multisine(const MultisineOptions& o) {
  const auto bad = [](const std::string& what) { return std::invalid_argument("multisine: need " + what); };
  if (!(o.fs_hz > 0.0) || !std::isfinite(o.fs_hz)) throw bad("0 < fs < infinity");
  if (!(o.f_min_hz >= 0.0)) throw bad("f_min >= 0");
  if (!(o.f_max_hz >= o.f_min_hz)) throw bad("f_min <= f_max");
  if (!(o.f_max_hz < 0.5 * o.fs_hz)) throw bad("f_max < fs/2");
  if (o.samples < 1) throw bad("samples >= 1");
  if (o.period != 0 && o.period < 2) throw bad("period >= 2 (or 0 for period = samples)");
  if (o.inputs < 1) throw bad("inputs >= 1");
  if (!(o.rms > 0.0) || !std::isfinite(o.rms)) throw bad("0 < rms < infinity");
  const Eigen::Index P = o.period == 0 ? o.samples : o.period;
  if (P < 2) throw bad("period >= 2 (samples >= 2 when period = 0)");

  // Excited bins: 1 <= k, 2k < P (strictly below Nyquist), f_min <= k fs/P <= f_max.
  // A relative slack of 1e-12 keeps a bin that lies exactly on f_min or f_max (up to
  // the rounding of k * fs / P) inside the band.
  std::vector<Eigen::Index> bins;
  const double df = o.fs_hz / static_cast<double>(P);
  for (Eigen::Index k = 1; 2 * k < P; ++k) {
    const double f = static_cast<double>(k) * df;
    if (f >= o.f_min_hz * (1.0 - 1e-12) && f <= o.f_max_hz * (1.0 + 1e-12)) bins.push_back(k);
  }
  if (bins.empty()) throw bad("at least one bin k >= 1 with f_min <= k fs/period <= f_max");

  const auto K = static_cast<double>(bins.size());
  const double a = o.rms * std::sqrt(2.0 / K);
  std::mt19937_64 rng(o.seed);
  // Uniform on [0, 1) from the top 53 bits: portable, unlike std::uniform_real_distribution.
  const auto uniform = [&rng]() { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };

  std::vector<std::complex<double>> spectrum(static_cast<std::size_t>(P));
  Eigen::MatrixXd x(o.samples, o.inputs);
  for (Eigen::Index c = 0; c < o.inputs; ++c) {
    std::fill(spectrum.begin(), spectrum.end(), std::complex<double>(0.0, 0.0));
    for (const Eigen::Index k : bins) {
      const double phi = kTwoPi * uniform();
      // x[n] = (1/P) sum X[k] e^{i 2 pi k n / P}: X[k] = X[P-k]* = (P a / 2) e^{i phi}
      // gives a cos(2 pi k n / P + phi).
      const std::complex<double> X = std::polar(0.5 * static_cast<double>(P) * a, phi);
      spectrum[static_cast<std::size_t>(k)] = X;
      spectrum[static_cast<std::size_t>(P - k)] = std::conj(X);
    }
    const std::vector<std::complex<double>> period_signal = detail::inverse_dft(spectrum);
    for (Eigen::Index i = 0; i < o.samples; ++i) x(i, c) = period_signal[static_cast<std::size_t>(i % P)].real();
  }
  return x;
}

struct PrbsOptions {
  int register_bits = 10;         ///< shift-register length n, 2 <= n <= 30; period 2^n - 1 bits
  Eigen::Index samples = 1023;    ///< length of the result, >= 1
  int clock_divider = 1;          ///< hold each bit this many samples, >= 1
  double amplitude = 1;           ///< output levels +amplitude / -amplitude, 0 < amplitude < infinity
  std::uint64_t seed = 1;         ///< initial register state, 0 < seed < 2^n
};

namespace detail {

/// Feedback taps (bit positions 1..n, position n is the output stage) of a
/// maximum-length n-bit LFSR, n = 2..30, from Alfke, "Efficient Shift Registers,
/// LFSR Counters, and Long Pseudo-Random Sequence Generators", Xilinx XAPP052
/// (1996), Table 3 (n = 2: x^2 + x + 1, the only primitive quadratic). The same
/// taps give maximal length with XOR or XNOR feedback; tests/unit/signal_excitation.cpp
/// checks the period 2^n - 1 for every n it can afford.
inline std::uint32_t lfsr_tap_mask(int n) {
  static constexpr int taps[31][4] = {
      {0, 0, 0, 0},      {0, 0, 0, 0},      {2, 1, 0, 0},      {3, 2, 0, 0},      {4, 3, 0, 0},
      {5, 3, 0, 0},      {6, 5, 0, 0},      {7, 6, 0, 0},      {8, 6, 5, 4},      {9, 5, 0, 0},
      {10, 7, 0, 0},     {11, 9, 0, 0},     {12, 6, 4, 1},     {13, 4, 3, 1},     {14, 5, 3, 1},
      {15, 14, 0, 0},    {16, 15, 13, 4},   {17, 14, 0, 0},    {18, 11, 0, 0},    {19, 6, 2, 1},
      {20, 17, 0, 0},    {21, 19, 0, 0},    {22, 21, 0, 0},    {23, 18, 0, 0},    {24, 23, 22, 17},
      {25, 22, 0, 0},    {26, 6, 2, 1},     {27, 5, 2, 1},     {28, 25, 0, 0},    {29, 27, 0, 0},
      {30, 6, 4, 1}};
  std::uint32_t mask = 0;
  for (const int t : taps[n])
    if (t > 0) mask |= std::uint32_t{1} << (t - 1);
  return mask;
}

}  // namespace detail

/// Purpose: maximum-length pseudo-random binary sequence (m-sequence) with levels
/// +-amplitude, each bit held clock_divider samples; period (2^n - 1) * clock_divider.
/// Method: Fibonacci LFSR with XOR feedback of the taps of detail::lfsr_tap_mask
/// (Ljung, System Identification: Theory for the User, 2nd ed., sec. 13.3;
/// Golomb, Shift Register Sequences). The output is the last stage: bit 1 -> +amplitude,
/// bit 0 -> -amplitude. Over one period there are 2^(n-1) ones and 2^(n-1) - 1 zeros,
/// so the mean is amplitude / (2^n - 1), and the periodic autocorrelation (divider 1)
/// is amplitude^2 at lag 0 and -amplitude^2 / (2^n - 1) at every other lag.
/// Preconditions (std::invalid_argument): 2 <= register_bits <= 30; samples >= 1;
/// clock_divider >= 1; 0 < amplitude < infinity; 0 < seed < 2^register_bits
/// (the all-zero state is the lock-up state of XOR feedback).
/// Numerical aspects: O(samples).
inline Eigen::VectorXd prbs(const PrbsOptions& o) {
  const auto bad = [](const std::string& what) { return std::invalid_argument("prbs: need " + what); };
  if (o.register_bits < 2 || o.register_bits > 30) throw bad("2 <= register_bits <= 30");
  if (o.samples < 1) throw bad("samples >= 1");
  if (o.clock_divider < 1) throw bad("clock_divider >= 1");
  if (!(o.amplitude > 0.0) || !std::isfinite(o.amplitude)) throw bad("0 < amplitude < infinity");
  const std::uint64_t states = std::uint64_t{1} << o.register_bits;
  if (o.seed == 0 || o.seed >= states) throw bad("0 < seed < 2^register_bits (nonzero initial register state)");

  const std::uint32_t mask = detail::lfsr_tap_mask(o.register_bits);
  const std::uint32_t full = static_cast<std::uint32_t>(states - 1);
  const int out_bit = o.register_bits - 1;
  auto state = static_cast<std::uint32_t>(o.seed);
  Eigen::VectorXd x(o.samples);
  Eigen::Index i = 0;
  while (i < o.samples) {
    const double level = ((state >> out_bit) & 1u) ? o.amplitude : -o.amplitude;
    for (int h = 0; h < o.clock_divider && i < o.samples; ++h) x(i++) = level;
    // Feedback = parity of the tapped stages; shift towards the output stage.
    const auto feedback = static_cast<std::uint32_t>(std::popcount(state & mask) & 1);
    state = ((state << 1) | feedback) & full;
  }
  return x;
}

}  // namespace sysid
