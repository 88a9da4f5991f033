#pragma once
// Test support for the end-to-end tests of compare and resid: a log from a known
// innovation model, written as the t,u,y CSV the verbs read.
#include <sysid/core/discrete_riccati.hpp>
#include <sysid/core/simulate.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/io/csv.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdint>
#include <string>

#include "run_cli.hpp"

namespace sysid::test {

struct InnovationLog {
  Eigen::MatrixXd K, u, y;
};

/// Data from the innovation model of the SISO `plant`: x+ = A x + B u + K e,
/// y = C x + D u + e, K the steady-state Kalman gain for process noise q I and
/// unit measurement noise, e white with standard deviation sigma, u white with
/// unit variance.
inline InnovationLog innovation_log(const StateSpace& plant, Eigen::Index N, double q, double sigma,
                                    std::uint64_t seed) {
  const Eigen::Index n = plant.order();
  const KalmanFilterResult kf = steady_state_kalman_filter(plant.A, plant.C, q * Eigen::MatrixXd::Identity(n, n),
                                                           Eigen::MatrixXd::Identity(1, 1), Eigen::MatrixXd::Zero(n, 1));
  EXPECT_EQ(kf.status, KalmanFilterResult::Status::converged);
  InnovationLog d;
  d.K = kf.K;
  d.u = white_noise(N, 1, seed, 1.0);
  const Eigen::MatrixXd e = white_noise(N, 1, seed + 1, sigma);
  Eigen::MatrixXd Bx(n, 2), Dx(1, 2), ue(N, 2);
  Bx << plant.B, d.K;
  Dx << plant.D, 1.0;
  ue << d.u, e;
  d.y = simulate(StateSpace(plant.A, Bx, plant.C, Dx, plant.Ts), ue);
  return d;
}

/// A t,u,y log sampled at 1 kHz.
inline void write_siso_log(const std::string& path, const Eigen::MatrixXd& u, const Eigen::MatrixXd& y) {
  Eigen::MatrixXd table(u.rows(), 3);
  table << Eigen::VectorXd::LinSpaced(u.rows(), 0.0, static_cast<double>(u.rows() - 1)) * 0.001, u, y;
  write_csv(path, {"t", "u", "y"}, table);
}

}  // namespace sysid::test
