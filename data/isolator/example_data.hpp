#pragma once
// What the example-data generators share: the 8x8 isolator-like structure
// (data/generate_examples.cpp writes avi8x8*.csv from it, generate_isolator.cpp
// in this folder its single-actuator and hammer-tap experiments) and the small
// helpers that write logs, models and measurement noise. Header-only: each
// generator is one translation unit (data/CMakeLists.txt).
#include <sysid/core/discretize.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/model_json.hpp>

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace sysid::example_data {

constexpr int kAviModes = 8;
constexpr int kAviChannels = 8;
constexpr double kAviFs = 1024.0;

/// The continuous modal model of the 8x8 structure: 8 actuators, 8 velocity
/// sensors, 8 lightly damped modes between 18 and 330 Hz. State [q_k; dq_k/dt]
/// per mode k, q'' + 2 zeta w q' + w^2 q = phi_in^T f; column j of C's velocity
/// entries is the mode shapes seen by sensor j.
inline StateSpace avi8x8_continuous() {
  const double freqs[kAviModes] = {18.0, 31.0, 47.0, 66.0, 95.0, 140.0, 210.0, 330.0};
  const double zetas[kAviModes] = {0.010, 0.015, 0.012, 0.020, 0.018, 0.025, 0.020, 0.030};
  std::mt19937_64 rng(8088);
  std::uniform_real_distribution<double> shape(-1.0, 1.0);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * kAviModes, 2 * kAviModes), b = Eigen::MatrixXd::Zero(2 * kAviModes, kAviChannels),
                  c = Eigen::MatrixXd::Zero(kAviChannels, 2 * kAviModes);
  for (int k = 0; k < kAviModes; ++k) {
    const double w = 2.0 * std::numbers::pi * freqs[k];
    a(2 * k, 2 * k + 1) = 1.0;
    a(2 * k + 1, 2 * k) = -w * w;
    a(2 * k + 1, 2 * k + 1) = -2.0 * zetas[k] * w;
    for (int j = 0; j < kAviChannels; ++j) {
      b(2 * k + 1, j) = shape(rng) * 100.0;  // modal participation of actuator j
      c(j, 2 * k + 1) = shape(rng);          // sensor j measures velocity of mode k
    }
  }
  return StateSpace(a, b, c, Eigen::MatrixXd::Zero(kAviChannels, kAviChannels), 0.0);
}

/// The structure sampled with an exact zero-order hold at 1024 Hz, inputs u1..u8,
/// outputs y1..y8.
inline StateSpace avi8x8() {
  StateSpace g = c2d_zoh(avi8x8_continuous(), 1.0 / kAviFs);
  for (int j = 0; j < kAviChannels; ++j) {
    g.input_names.push_back("u" + std::to_string(j + 1));
    g.output_names.push_back("y" + std::to_string(j + 1));
  }
  return g;
}

inline Eigen::MatrixXd gaussian(Eigen::Index rows, Eigen::Index cols, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd x(rows, cols);
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index c = 0; c < cols; ++c) x(r, c) = g(rng);
  return x;
}

/// Adds white measurement noise with the given fraction of each channel's RMS.
inline void add_noise(Eigen::MatrixXd& y, double fraction, std::uint64_t seed) {
  const Eigen::MatrixXd e = gaussian(y.rows(), y.cols(), seed);
  for (Eigen::Index c = 0; c < y.cols(); ++c) {
    const double rms = std::sqrt(y.col(c).squaredNorm() / static_cast<double>(y.rows()));
    y.col(c) += fraction * rms * e.col(c);
  }
}

/// Writes a log: the time column t = k ts, then the blocks' columns under `names`.
inline void write_log(const std::filesystem::path& path, double ts, const std::vector<std::string>& names,
                      const std::vector<const Eigen::MatrixXd*>& blocks) {
  Eigen::Index cols = 1;
  for (const auto* b : blocks) cols += b->cols();
  const Eigen::Index rows = blocks.front()->rows();
  Eigen::MatrixXd table(rows, cols);
  table.col(0) = Eigen::VectorXd::LinSpaced(rows, 0.0, static_cast<double>(rows - 1)) * ts;
  Eigen::Index at = 1;
  for (const auto* b : blocks) {
    table.middleCols(at, b->cols()) = *b;
    at += b->cols();
  }
  std::vector<std::string> all{"t"};
  all.insert(all.end(), names.begin(), names.end());
  write_csv(path.string(), all, table);
  std::cout << "wrote " << path.string() << " (" << rows << " samples)\n";
}

inline void write_model(const std::filesystem::path& path, const StateSpace& g, const std::string& what) {
  ModelFile file;
  file.model = g;
  file.provenance = {{"method", "true model"}, {"source", what}};
  write_model_json(path.string(), file);
  std::cout << "wrote " << path.string() << "\n";
}

}  // namespace sysid::example_data
