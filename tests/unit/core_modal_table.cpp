// Tests for sysid::modal_table / format_modal_table (include/sysid/core/modal_table.hpp).
#include <sysid/core/discretize.hpp>
#include <sysid/core/modal_table.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include "random_matrices.hpp"

namespace test_unit_core_modal_table {

namespace {

using Eigen::MatrixXd;
using sysid::test::kPi;

/// Chain of masses m_i, springs k_i (to the previous mass / ground), dampers
/// c_i, force on mass 0, position of the last mass measured.
sysid::StateSpace mass_spring_damper(const Eigen::VectorXd& m, const Eigen::VectorXd& k, const Eigen::VectorXd& c) {
  const Eigen::Index q = m.size();
  MatrixXd K = MatrixXd::Zero(q, q), Cd = MatrixXd::Zero(q, q);
  for (Eigen::Index i = 0; i < q; ++i) {
    K(i, i) += k[i];
    Cd(i, i) += c[i];
    if (i > 0) {
      K(i - 1, i - 1) += k[i];
      K(i - 1, i) -= k[i];
      K(i, i - 1) -= k[i];
      Cd(i - 1, i - 1) += c[i];
      Cd(i - 1, i) -= c[i];
      Cd(i, i - 1) -= c[i];
    }
  }
  const MatrixXd Mi = m.cwiseInverse().asDiagonal();
  MatrixXd A = MatrixXd::Zero(2 * q, 2 * q);
  A.topRightCorner(q, q).setIdentity();
  A.bottomLeftCorner(q, q) = -Mi * K;
  A.bottomRightCorner(q, q) = -Mi * Cd;
  MatrixXd B = MatrixXd::Zero(2 * q, 1);
  B(q, 0) = 1.0 / m[0];
  MatrixXd C = MatrixXd::Zero(1, 2 * q);
  C(0, q - 1) = 1.0;
  return sysid::StateSpace(A, B, C, MatrixXd::Zero(1, 1), 0.0);
}

TEST(CoreModalTable, DiscretisedMassSpringDamperGivesAnalyticWnZeta) {
  // Single DOF: wn = sqrt(k/m), zeta = c / (2 sqrt(k m)). ZOH maps poles exactly
  // (z = e^(s Ts)) and the table inverts that map, so only rounding separates them
  // (relative error ~ eps / (|s| Ts) ~ 1e-14 here).
  for (double Ts : {1e-4, 1e-3, 5e-3}) {
    const double m = 2.0, k = 8.0e3, c = 3.0;
    Eigen::VectorXd mv(1), kv(1), cv(1);
    mv << m;
    kv << k;
    cv << c;
    const sysid::StateSpace sd = sysid::c2d_zoh(mass_spring_damper(mv, kv, cv), Ts);
    const std::vector<sysid::Mode> modes = sysid::modal_table(sd);
    ASSERT_EQ(modes.size(), 1u);
    const double wn = std::sqrt(k / m), zeta = c / (2.0 * std::sqrt(k * m));
    EXPECT_TRUE(modes[0].complex_pair);
    EXPECT_TRUE(modes[0].stable);
    EXPECT_NEAR(modes[0].freq_hz / (wn / (2 * kPi)), 1.0, 1e-10) << "Ts=" << Ts;
    EXPECT_NEAR(modes[0].damping / zeta, 1.0, 1e-9) << "Ts=" << Ts;
    EXPECT_GT(modes[0].pole.imag(), 0.0);
  }
}

TEST(CoreModalTable, TwoDofModesSortedAndMatchContinuousEigenvalues) {
  Eigen::VectorXd m(2), k(2), c(2);
  m << 1.0, 0.5;
  k << 4.0e4, 1.0e4;
  c << 2.0, 0.5;
  const sysid::StateSpace sc = mass_spring_damper(m, k, c);
  const std::vector<sysid::Mode> mc = sysid::modal_table(sc);
  const std::vector<sysid::Mode> md = sysid::modal_table(sysid::c2d_zoh(sc, 1e-3));
  ASSERT_EQ(mc.size(), 2u);
  ASSERT_EQ(md.size(), 2u);
  EXPECT_LT(mc[0].freq_hz, mc[1].freq_hz);
  const Eigen::VectorXcd ev = sc.A.eigenvalues();
  for (std::size_t i = 0; i < 2; ++i) {
    // every mode's s is an eigenvalue of the continuous A, discrete or not
    EXPECT_LT((ev.array() - mc[i].s).abs().minCoeff(), 1e-9 * std::abs(mc[i].s));
    EXPECT_LT((ev.array() - md[i].s).abs().minCoeff(), 1e-9 * std::abs(md[i].s));
    EXPECT_NEAR(md[i].freq_hz / mc[i].freq_hz, 1.0, 1e-10);
    EXPECT_NEAR(md[i].damping / mc[i].damping, 1.0, 1e-8);
    EXPECT_EQ(mc[i].pole, mc[i].s);  // continuous: the pole is s
  }
}

TEST(CoreModalTable, RealPolesNyquistAndUnstable) {
  // Discrete diag(0.5, -0.5, 1.2, 0): positive real pole -> damping 1;
  // negative real pole -> oscillation at Nyquist; 1.2 -> unstable (damping -1);
  // z = 0 -> infinite frequency.
  const double Ts = 0.01;
  const Eigen::Vector4d p(0.5, -0.5, 1.2, 0.0);
  const MatrixXd A = p.asDiagonal();
  const sysid::StateSpace s(A, MatrixXd::Ones(4, 1), MatrixXd::Ones(1, 4), MatrixXd::Zero(1, 1), Ts);
  const std::vector<sysid::Mode> modes = sysid::modal_table(s);
  ASSERT_EQ(modes.size(), 4u);
  // sorted: 1.2 (|ln 1.2|), 0.5 (|ln 0.5|), -0.5 (sqrt(ln^2 0.5 + pi^2)), 0 (inf)
  EXPECT_DOUBLE_EQ(modes[0].pole.real(), 1.2);
  EXPECT_NEAR(modes[0].freq_hz, std::log(1.2) / (2 * kPi * Ts), 1e-12);
  EXPECT_NEAR(modes[0].damping, -1.0, 1e-15);
  EXPECT_FALSE(modes[0].stable);
  EXPECT_DOUBLE_EQ(modes[1].pole.real(), 0.5);
  EXPECT_NEAR(modes[1].damping, 1.0, 1e-15);
  EXPECT_TRUE(modes[1].stable);
  EXPECT_DOUBLE_EQ(modes[2].pole.real(), -0.5);
  EXPECT_NEAR(modes[2].s.imag(), kPi / Ts, 1e-9);  // exactly at Nyquist 1/(2 Ts) = 50 Hz
  EXPECT_NEAR(modes[2].freq_hz, std::hypot(std::log(0.5), kPi) / (2 * kPi * Ts), 1e-9);
  EXPECT_FALSE(modes[2].complex_pair);
  EXPECT_TRUE(std::isinf(modes[3].freq_hz));
  EXPECT_EQ(modes[3].damping, 1.0);

  const std::string table = sysid::format_modal_table(modes);
  std::istringstream in(table);
  std::string line;
  int lines = 0;
  while (std::getline(in, line)) ++lines;
  EXPECT_EQ(lines, 5);  // header + 4 modes
  EXPECT_NE(table.find("pole (z)"), std::string::npos);
  EXPECT_NE(table.find("real (Nyquist)"), std::string::npos);
  EXPECT_NE(table.find("real, unstable"), std::string::npos);
}

TEST(CoreModalTable, FormatIsAlignedAndShowsDampingAsRatio) {
  // One pair with zeta = 0.0123 at 10 Hz, continuous.
  const double wn = 2 * kPi * 10.0, zeta = 0.0123;
  const MatrixXd A = (MatrixXd(2, 2) << 0, 1, -wn * wn, -2 * zeta * wn).finished();
  const sysid::StateSpace s(A, (MatrixXd(2, 1) << 0, 1).finished(), (MatrixXd(1, 2) << 1, 0).finished(), MatrixXd::Zero(1, 1), 0.0);
  const std::vector<sysid::Mode> modes = sysid::modal_table(s);
  ASSERT_EQ(modes.size(), 1u);
  EXPECT_NEAR(modes[0].damping, zeta, 1e-14);
  const std::string table = sysid::format_modal_table(modes);
  EXPECT_NE(table.find("0.0123"), std::string::npos) << table;
  EXPECT_NE(table.find("pole (s)"), std::string::npos) << table;
  EXPECT_NE(table.find("pair"), std::string::npos);
  EXPECT_EQ(table.find("unstable"), std::string::npos);
  // aligned: every line has the "type" column starting at the same offset
  std::istringstream in(table);
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  EXPECT_EQ(header.find("type"), row.find("pair"));
}

}  // namespace

}  // namespace test_unit_core_modal_table
