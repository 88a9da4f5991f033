// Generates the model-family example (data/family/README.md): a Par2-like
// flexible arm driven by a piezo patch, logged at 15 operating conditions
// (payload 0-2 kg x stop position Pos1-Pos3), for `sysid family`.
// Deterministic: fixed seeds, std::mt19937_64 (libstdc++ normal distribution for
// the noise, sysid::multisine's own portable phases).
//
//   sysid_generate_family OUTDIR
//
// writes into OUTDIR:
//   manifest.csv                  log,validate,payload_kg,stop_position; one row per member
//   <member>.csv                  t,u,y: linear chirp 0.5 -> 100 Hz, 10 s, +-10 V
//   <member>_val.csv              t,u,y: random-phase multisine 0.5-100 Hz, 5 s, RMS 7.07 V
//   truth/<member>_true.json      the member's true model (exact ZOH, Ts = 0.5 ms)
//   modes_true.csv                member,payload_kg,stop_position,mode,freq_hz,damping
// with <member> = p<payload, one decimal>_<position>, e.g. p0.5_Pos2.
//
// The log writers and the noise are shared with the other generators
// (isolator/example_data.hpp).
#include <sysid/core/discretize.hpp>
#include <sysid/core/modal_table.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/io/atomic_file.hpp>
#include <sysid/signal/excitation.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "../isolator/example_data.hpp"

namespace {

using namespace sysid::example_data;
using sysid::StateSpace;

constexpr int kModes = 4;
constexpr double kFs = 2000.0;  // Ts = 0.5 ms, as the Par2 logs
constexpr double kNoise = 0.01;  // white output noise, fraction of the noise-free output's RMS

// The nominal arm (payload 0 kg, stop position Pos2): natural frequencies (Hz),
// damping ratios, and each mode's static compliance s_k (um/V): its contribution
// s_k w_k^2 / (s^2 + 2 zeta_k w_k s + w_k^2) to y/u, whose peak is ~ s_k / (2 zeta_k).
// All four residues have one sign (a collocated-like sensor): an anti-resonance
// between every two modes, DC gain sum s_k > 0.
constexpr std::array<double, kModes> kFreqHz = {28.0, 64.0, 88.0, 205.0};
constexpr std::array<double, kModes> kZeta = {0.030, 0.025, 0.035, 0.020};
constexpr std::array<double, kModes> kCompliance = {0.12, 0.06, 0.07, 0.016};
// Modal masses of the payload: w_k(p) = w_k(0) / sqrt(1 + p / M_k) (the payload
// adds p to mode k's modal mass M_k, its stiffness unchanged), so the static
// compliance s_k does not depend on the payload.
constexpr std::array<double, kModes> kModalMassKg = {4.0, 6.0, 9.0, 12.0};
// Damping grows with the payload: zeta_k(p) = zeta_k (1 + kZetaPerKg p).
constexpr double kZetaPerKg = 0.1;

constexpr std::array<double, 5> kPayloadsKg = {0.0, 0.5, 1.0, 1.5, 2.0};

// The stop position changes the arm's stiffness along modes 2 and 3 (frequency
// factors) and where the patch and the sensor sit on the mode shapes
// (compliance factors); modes 1 and 4 keep their frequency.
struct Position {
  const char* name;
  std::array<double, kModes> freq_factor;
  std::array<double, kModes> gain_factor;
};
constexpr std::array<Position, 3> kPositions = {{
    {"Pos1", {1.0, 0.96, 0.96, 1.0}, {1.1, 0.6, 1.25, 1.0}},
    {"Pos2", {1.0, 1.00, 1.00, 1.0}, {1.0, 1.0, 1.00, 1.0}},
    {"Pos3", {1.0, 1.05, 1.05, 1.0}, {0.9, 1.3, 0.80, 1.0}},
}};

struct Member {
  std::string name;  // p<payload>_<position>
  double payload_kg = 0.0;
  std::string position;
  std::array<double, kModes> freq_hz{}, zeta{}, compliance{};
};

/// The payload with one decimal ("0.5"), as in the member names and the manifest.
std::string one_decimal(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", x);
  return buf;
}

/// Shortest round-trip text of a double (std::to_chars), as the CSV writer does.
std::string shortest(double x) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

Member member(double payload_kg, const Position& pos) {
  Member m;
  m.name = "p" + one_decimal(payload_kg) + "_" + pos.name;
  m.payload_kg = payload_kg;
  m.position = pos.name;
  for (int k = 0; k < kModes; ++k) {
    const auto i = static_cast<std::size_t>(k);
    m.freq_hz[i] = kFreqHz[i] / std::sqrt(1.0 + payload_kg / kModalMassKg[i]) * pos.freq_factor[i];
    m.zeta[i] = kZeta[i] * (1.0 + kZetaPerKg * payload_kg);
    m.compliance[i] = kCompliance[i] * pos.gain_factor[i];
  }
  return m;
}

/// The member's continuous modal model, input u (V), output y (um). State
/// [q_k; q_k' / w_k] per mode: q_k'' + 2 zeta_k w_k q_k' + w_k^2 q_k = w_k^2 u,
/// y = sum_k s_k q_k (both states of a mode of order w_k: well scaled).
StateSpace continuous_model(const Member& m) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * kModes, 2 * kModes), b = Eigen::MatrixXd::Zero(2 * kModes, 1),
                  c = Eigen::MatrixXd::Zero(1, 2 * kModes);
  for (int k = 0; k < kModes; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const double w = 2.0 * std::numbers::pi * m.freq_hz[i];
    a(2 * k, 2 * k + 1) = w;
    a(2 * k + 1, 2 * k) = -w;
    a(2 * k + 1, 2 * k + 1) = -2.0 * m.zeta[i] * w;
    b(2 * k + 1, 0) = w;
    c(0, 2 * k) = m.compliance[i];
  }
  StateSpace g(a, b, c, Eigen::MatrixXd::Zero(1, 1), 0.0);
  g.input_names = {"u"};
  g.output_names = {"y"};
  return g;
}

/// |G(j 2 pi f)| of the continuous modal sum.
double gain(const Member& m, double f_hz) {
  const std::complex<double> s(0.0, 2.0 * std::numbers::pi * f_hz);
  std::complex<double> g = 0.0;
  for (std::size_t i = 0; i < kModes; ++i) {
    const double w = 2.0 * std::numbers::pi * m.freq_hz[i];
    g += m.compliance[i] * w * w / (s * s + 2.0 * m.zeta[i] * w * s + w * w);
  }
  return std::abs(g);
}

/// The family's promises (README.md), checked on every run: modes at least 15 %
/// apart, the three in-band peaks within 20 dB of each other, a nonzero DC gain,
/// and the discretised model's modes equal to the continuous ones.
void check(const Member& m, const StateSpace& discrete) {
  const auto fail = [&m](const std::string& what) { return std::runtime_error(m.name + ": " + what); };
  for (std::size_t i = 1; i < kModes; ++i)
    if (m.freq_hz[i] < 1.15 * m.freq_hz[i - 1]) throw fail("modes " + std::to_string(i) + " and " + std::to_string(i + 1) + " closer than 15 %");
  if (m.freq_hz[2] * (1.0 + m.zeta[2]) > 100.0) throw fail("mode 3 not inside the excited band 0-100 Hz");
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (std::size_t i = 0; i < 3; ++i) lo = std::min(lo, gain(m, m.freq_hz[i])), hi = std::max(hi, gain(m, m.freq_hz[i]));
  if (20.0 * std::log10(hi / lo) > 20.0) throw fail("in-band peaks more than 20 dB apart");
  if (!(gain(m, 0.0) > 0.0)) throw fail("zero DC gain");
  const std::vector<sysid::Mode> modes = sysid::modal_table(discrete);
  if (modes.size() != kModes) throw fail("discrete model has " + std::to_string(modes.size()) + " modes");
  for (std::size_t i = 0; i < kModes; ++i)
    if (std::abs(modes[i].freq_hz / m.freq_hz[i] - 1.0) > 1e-9 || std::abs(modes[i].damping / m.zeta[i] - 1.0) > 1e-7)
      throw fail("discrete mode " + std::to_string(i + 1) + " differs from the continuous one");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: sysid_generate_family OUTDIR\n";
    return 1;
  }
  try {
    const std::filesystem::path out = argv[1];
    std::filesystem::create_directories(out / "truth");
    const double ts = 1.0 / kFs;

    // Estimation input, the same for every member: linear chirp 0.5 -> 100 Hz, 10 s, +-10 V.
    sysid::ChirpOptions c;
    c.fs_hz = kFs;
    c.f0_hz = 0.5;
    c.f1_hz = 100.0;
    c.duration_s = 10.0;
    c.amplitude = 10.0;
    const Eigen::MatrixXd u = sysid::chirp(c);

    std::string manifest = "log,validate,payload_kg,stop_position\n";
    std::string modes = "member,payload_kg,stop_position,mode,freq_hz,damping\n";
    std::printf("%-10s %27s %27s %27s %9s %9s\n", "member", "mode 1 (Hz, zeta, dB)", "mode 2", "mode 3", "mode 4 Hz",
                "DC dB");
    std::uint64_t index = 0;  // the member's row in the manifest: its seeds
    for (const Position& pos : kPositions) {
      for (const double p : kPayloadsKg) {
        const Member m = member(p, pos);
        const StateSpace g = sysid::c2d_zoh(continuous_model(m), ts);
        check(m, g);

        Eigen::MatrixXd y = sysid::simulate(g, u);
        add_noise(y, kNoise, 800 + index);
        write_log(out / (m.name + ".csv"), ts, {"u", "y"}, {&u, &y});

        // Validation input: random-phase multisine 0.5-100 Hz (0.2 Hz grid), one
        // 5 s period, the chirp's RMS; own phases per member.
        sysid::MultisineOptions ms;
        ms.fs_hz = kFs;
        ms.f_min_hz = 0.5;
        ms.f_max_hz = 100.0;
        ms.samples = 10000;
        ms.period = 10000;
        ms.rms = 10.0 / std::sqrt(2.0);
        ms.seed = 900 + index;
        const Eigen::MatrixXd u_val = sysid::multisine(ms);
        Eigen::MatrixXd y_val = sysid::simulate(g, u_val);
        add_noise(y_val, kNoise, 1000 + index);
        write_log(out / (m.name + "_val.csv"), ts, {"u", "y"}, {&u_val, &y_val});

        write_model(out / "truth" / (m.name + "_true.json"), g,
                    "Par2-like arm, payload " + one_decimal(p) + " kg, stop position " + m.position +
                        "; data/family/generate_family.cpp");

        manifest += m.name + ".csv," + m.name + "_val.csv," + one_decimal(p) + "," + m.position + "\n";
        for (std::size_t i = 0; i < kModes; ++i)
          modes += m.name + "," + one_decimal(p) + "," + m.position + "," + std::to_string(i + 1) + "," +
                   shortest(m.freq_hz[i]) + "," + shortest(m.zeta[i]) + "\n";
        std::printf("%-10s", m.name.c_str());
        for (std::size_t i = 0; i < 3; ++i)
          std::printf("   %6.2f %6.4f %6.1f dB", m.freq_hz[i], m.zeta[i], 20.0 * std::log10(gain(m, m.freq_hz[i])));
        std::printf(" %9.2f %9.1f\n", m.freq_hz[3], 20.0 * std::log10(gain(m, 0.0)));
        ++index;
      }
    }
    sysid::write_file_atomically((out / "manifest.csv").string(), manifest);
    std::cout << "wrote " << (out / "manifest.csv").string() << " (" << index << " members)\n";
    sysid::write_file_atomically((out / "modes_true.csv").string(), modes);
    std::cout << "wrote " << (out / "modes_true.csv").string() << "\n";
  } catch (const std::exception& ex) {
    std::cerr << "sysid_generate_family: " << ex.what() << "\n";
    return 1;
  }
  return 0;
}
