#pragma once
// The many-sensor structure of issue 34 (order selection and the stabilisation
// diagram for tens of outputs and tens of modes), built with the project's FE
// tools: a free beam on two isolator mounts, 12 modes from 14.6 Hz to 1.2 kHz
// (true order 24), two shakers with white-noise force, 28 accelerometers with 2 %
// sensor noise, sampled at 4 096 Hz. Used by tests/acceptance/subspace_many_sensors.cpp
// and bench/stabilization_bench.cpp.
#include <sysid/core/io_data.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/fem/beam_model.hpp>
#include <sysid/fem/modal_model.hpp>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "random_matrices.hpp"

namespace sysid::test {

inline constexpr int kSensors = 28;
inline constexpr int kModes = 12;
inline constexpr double kFs = 4096.0;

/// The beam of tests/support/fem_cases.hpp (1 m, EI = 100 N m^2, rhoA = 2 kg/m) on
/// two soft mounts, Rayleigh damping (0.3 % to 1 % in band), shakers at 0.3 and
/// 0.77 m, accelerometers spread evenly over the 41 nodes.
inline fem::SecondOrderModel many_sensor_structure() {
  fem::BeamOptions o;
  o.elements = 40;
  o.flexural_rigidity = 100.0;
  o.mass_per_length = 2.0;
  fem::StructureBuilder b(o);
  b.add_spring_to_ground(b.translation_dof(b.node_at(0.1)), 2e4);
  b.add_spring_to_ground(b.translation_dof(b.node_at(0.9)), 2e4);
  std::vector<fem::DofOutput> sensors;
  for (int k = 0; k < kSensors; ++k) {
    const int node = static_cast<int>(std::lround(k * 40.0 / (kSensors - 1)));
    sensors.push_back({"a" + std::to_string(k + 1), b.translation_dof(node), fem::Quantity::acceleration, "m/s^2"});
  }
  auto model = b.finish({{"F1", b.translation_dof(b.node_at(0.3)), "N"}, {"F2", b.translation_dof(b.node_at(0.77)), "N"}},
                        sensors);
  model.damping.kind = fem::DampingKind::rayleigh;
  model.damping.alpha = 1.0;
  model.damping.beta = 2e-6;
  return model;
}

struct ManySensorCase {
  fem::ModalModelResult truth;
  IoData data;
};

inline ManySensorCase simulate_many_sensor_case(Eigen::Index samples, std::uint64_t seed) {
  fem::ModalAnalysisOptions ao;
  ao.modes = kModes;
  fem::ModalModelOptions mo;
  mo.Ts = 1.0 / kFs;
  ManySensorCase c{fem::modal_model(many_sensor_structure(), ao, mo), {}};
  const Eigen::MatrixXd u = test::white_noise(samples, 2, seed);
  Eigen::MatrixXd y = simulate(c.truth.model, u);
  // 2 % white sensor noise on each accelerometer.
  const Eigen::MatrixXd noise = test::white_noise(samples, kSensors, seed + 1);
  for (Eigen::Index r = 0; r < kSensors; ++r) {
    const double rms = std::sqrt(y.col(r).squaredNorm() / static_cast<double>(samples));
    y.col(r) += 0.02 * rms * noise.col(r);
  }
  c.data.Ts = 1.0 / kFs;
  Experiment e;
  e.u = u;
  e.y = y;
  c.data.experiments.push_back(std::move(e));
  return c;
}

/// The case the acceptance tests use (8 500 samples, seed 2026), simulated once per executable.
inline const ManySensorCase& acceptance_many_sensor_case() {
  static const ManySensorCase c = simulate_many_sensor_case(8500, 2026);
  return c;
}

}  // namespace sysid::test
