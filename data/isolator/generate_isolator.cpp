// Generates the isolator reproduction's experiments (data/isolator/README.md):
// the 8x8 structure of avi8x8.csv (example_data.hpp) excited one actuator at a
// time by a periodic linear chirp, and struck by a hammer at three points.
// Deterministic: fixed seeds, std::mt19937_64 (libstdc++ distributions).
//
//   sysid_generate_isolator OUTDIR
//
// writes into OUTDIR:
//   exp1.csv .. exp8.csv   t, u<j>, y1..y8: actuator j driven, the others off
//   avi8x8_true.json       the true 8x8 model (the same as data/avi8x8_true.json)
//   tap1.csv .. tap3.csv   t, f<k>, y1..y8: hammer taps at point k
//   taps_true.json         the true model from the three tap forces to y1..y8
#include <sysid/core/simulate.hpp>
#include <sysid/signal/excitation.hpp>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "example_data.hpp"

namespace {

using namespace sysid::example_data;
using sysid::StateSpace;

// Chirp experiments. One sweep 1 -> 500 Hz lasts kSweep samples (4 s), repeated
// kSweeps times: a sweep is short enough that every 2048-tap regressor of the
// LMS spans a quarter of the band (the input looks broadband to the adaptive
// filter, where one slow sweep would let it forget the low band while it learns
// the high one), and periodic so that the H1 estimate over one period with a
// rectangular window has no leakage once the start-up transient has decayed.
constexpr Eigen::Index kSweep = 4096;
constexpr int kSweeps = 8;
constexpr double kNoise = 0.01;  // white output noise, fraction of each output's RMS

// Hammer taps: a half-sine force pulse of 4 Ts (3.9 ms; its samples are
// sin(pi k / 4), k = 1..3), kTaps taps kTapSpacing apart in each record, the
// first after 0.25 s of rest; 5 s of ringing decays the slowest mode (18 Hz,
// zeta 1 %) to 0.4 % before the next tap.
constexpr int kTaps = 4;
constexpr Eigen::Index kTapSpacing = 5 * 1024;
constexpr Eigen::Index kTapStart = 256;
constexpr double kTapPeak = 100.0;
// The struck points: next to sensors 1, 2 and 8, so each tap's modal
// participations are the mode shapes at that sensor (reciprocity), and its
// response at that sensor is a driving-point response. Chosen: of the 56 triples
// of sensor points, only 3 let three order-8 models reduce from 24 to 10 states
// with an HSV ratio below 3 % even from exact Markov parameters (README.md).
constexpr int kTapSensors[3] = {1, 2, 8};

/// The structure with the hammer forces as inputs f1..f3 (force at the point of
/// sensor s: participation of mode k = mode shape of mode k at sensor s, times
/// the actuators' scale 100), ZOH at 1024 Hz.
StateSpace tap_model() {
  StateSpace cont = avi8x8_continuous();
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(cont.order(), 3);
  for (int k = 0; k < 3; ++k) b.col(k) = 100.0 * cont.C.row(kTapSensors[k] - 1).transpose();
  cont.B = b;
  cont.D = Eigen::MatrixXd::Zero(cont.outputs(), 3);
  StateSpace g = sysid::c2d_zoh(cont, 1.0 / kAviFs);
  for (int k = 0; k < 3; ++k) g.input_names.push_back("f" + std::to_string(k + 1));
  for (int j = 0; j < kAviChannels; ++j) g.output_names.push_back("y" + std::to_string(j + 1));
  return g;
}

/// The force of one tap record: kTaps half-sine pulses, peaks kTapPeak times a
/// factor uniform in [0.8, 1.2] (a hand-held hammer does not repeat exactly).
Eigen::MatrixXd tap_force(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> scatter(0.8, 1.2);
  Eigen::MatrixXd f = Eigen::MatrixXd::Zero(kTapStart + kTaps * kTapSpacing, 1);
  for (int t = 0; t < kTaps; ++t) {
    const double peak = kTapPeak * scatter(rng);
    for (int k = 1; k <= 3; ++k) f(kTapStart + t * kTapSpacing + k, 0) = peak * std::sin(std::numbers::pi * k / 4.0);
  }
  return f;
}

std::vector<std::string> outputs() {
  std::vector<std::string> names;
  for (int j = 0; j < kAviChannels; ++j) names.push_back("y" + std::to_string(j + 1));
  return names;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: sysid_generate_isolator OUTDIR\n";
    return 1;
  }
  try {
    const std::filesystem::path out = argv[1];
    std::filesystem::create_directories(out);
    const double ts = 1.0 / kAviFs;

    const StateSpace avi = avi8x8();
    sysid::ChirpOptions c;
    c.fs_hz = kAviFs;
    c.f0_hz = 1.0;
    c.f1_hz = 500.0;
    c.duration_s = static_cast<double>(kSweep) / kAviFs;
    c.amplitude = 1.0;
    const Eigen::VectorXd sweep = sysid::chirp(c);
    const Eigen::VectorXd chirp = sweep.replicate(kSweeps, 1);
    for (int j = 0; j < kAviChannels; ++j) {
      Eigen::MatrixXd u = Eigen::MatrixXd::Zero(chirp.size(), kAviChannels);
      u.col(j) = chirp;
      Eigen::MatrixXd y = sysid::simulate(avi, u);
      add_noise(y, kNoise, 500 + static_cast<std::uint64_t>(j));
      const Eigen::MatrixXd uj = u.col(j);
      std::vector<std::string> names{avi.input_names[static_cast<std::size_t>(j)]};
      for (const auto& n : outputs()) names.push_back(n);
      write_log(out / ("exp" + std::to_string(j + 1) + ".csv"), ts, names, {&uj, &y});
    }
    write_model(out / "avi8x8_true.json", avi, "8x8 modal model, data/isolator/example_data.hpp");

    const StateSpace taps = tap_model();
    for (int k = 0; k < 3; ++k) {
      const Eigen::MatrixXd f = tap_force(600 + static_cast<std::uint64_t>(k));
      Eigen::MatrixXd u = Eigen::MatrixXd::Zero(f.rows(), 3);
      u.col(k) = f.col(0);
      Eigen::MatrixXd y = sysid::simulate(taps, u);
      add_noise(y, kNoise, 700 + static_cast<std::uint64_t>(k));
      std::vector<std::string> names{taps.input_names[static_cast<std::size_t>(k)]};
      for (const auto& n : outputs()) names.push_back(n);
      write_log(out / ("tap" + std::to_string(k + 1) + ".csv"), ts, names, {&f, &y});
    }
    write_model(out / "taps_true.json", taps, "8x8 structure, hammer forces at sensors 1, 2, 8; data/isolator/generate_isolator.cpp");
  } catch (const std::exception& ex) {
    std::cerr << "sysid_generate_isolator: " << ex.what() << "\n";
    return 1;
  }
  return 0;
}
