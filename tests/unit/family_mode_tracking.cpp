// Tests for sysid::trackable_modes and sysid::track_modes
// (include/sysid/family/mode_tracking.hpp): which modes of a member a family
// follows, and that each physical mode becomes one track across the members —
// in any member order, absent where a member lacks it, across a large but gradual
// drift, and apart from a neighbour of another shape.
#include <sysid/family/mode_tracking.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <numeric>
#include <random>
#include <stdexcept>
#include <vector>

#include "random_matrices.hpp"

namespace test_unit_family_mode_tracking {

namespace {

using Eigen::MatrixXd;
using sysid::ModeEstimate;
using sysid::test::kPi;

/// One mode of a hand-built modal model: natural frequency (Hz), damping ratio
/// (negative: unstable), and its output column (the mode shape, real).
struct BlockMode {
  double freq_hz;
  double damping;
  Eigen::VectorXd shape;
};

/// Discrete real modal form: per mode a block r [[cos th, sin th], [-sin th, cos th]]
/// with r e^{j th} = exp(s Ts), s = 2 pi f (-zeta + j sqrt(1 - zeta^2)); the block's
/// eigenvector for the pole with Im > 0 is [1, j], so C = [shape, 0] gives the mode
/// shape C v = shape. `real_poles` adds 1x1 blocks.
sysid::StateSpace modal_model(const std::vector<BlockMode>& modes, const std::vector<double>& real_poles, double Ts,
                              Eigen::Index outputs) {
  const auto n = static_cast<Eigen::Index>(2 * modes.size() + real_poles.size());
  MatrixXd A = MatrixXd::Zero(n, n), B = MatrixXd::Ones(n, 1), C = MatrixXd::Zero(outputs, n);
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(2 * k);
    const double w = 2.0 * kPi * modes[k].freq_hz, zeta = modes[k].damping;
    const std::complex<double> z = std::exp(Ts * w * std::complex<double>(-zeta, std::sqrt(1.0 - zeta * zeta)));
    A.block(i, i, 2, 2) << z.real(), z.imag(), -z.imag(), z.real();
    C.col(i) = modes[k].shape;
  }
  for (std::size_t k = 0; k < real_poles.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(2 * modes.size() + k);
    A(i, i) = real_poles[k];
    C(0, i) = 1.0;
  }
  return sysid::StateSpace(A, B, C, MatrixXd::Zero(outputs, 1), Ts);
}

Eigen::VectorXd vec(std::initializer_list<double> v) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(v.size()));
  Eigen::Index k = 0;
  for (double x : v) out(k++) = x;
  return out;
}

/// |a^H b|^2 / (|a|^2 |b|^2).
double mac(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  return std::norm(a.dot(b)) / (a.squaredNorm() * b.squaredNorm());
}

ModeEstimate mode(double f, double zeta, Eigen::VectorXcd shape = {}) {
  ModeEstimate m;
  m.freq_hz = f;
  m.damping = zeta;
  m.shape = std::move(shape);
  return m;
}

/// The track whose entry at `member` equals `f` exactly (-1 if none).
int track_with(const sysid::ModeTrackingResult& r, int member, double f) {
  for (std::size_t j = 0; j < r.modes.size(); ++j)
    if (r.modes[j].freq_hz(member) == f) return static_cast<int>(j);
  return -1;
}

/// Every member's trackable modes point at the track holding them (mode_track).
void expect_consistent_index(const sysid::ModeTrackingResult& r, const std::vector<std::vector<ModeEstimate>>& members) {
  ASSERT_EQ(r.mode_track.size(), members.size());
  ASSERT_EQ(r.tree_parent.size(), members.size());
  EXPECT_EQ(std::count(r.tree_parent.begin(), r.tree_parent.end(), -1), 1) << "one root";
  for (std::size_t k = 0; k < members.size(); ++k) {
    ASSERT_EQ(r.mode_track[k].size(), members[k].size()) << "member " << k;
    for (std::size_t i = 0; i < members[k].size(); ++i) {
      const int t = r.mode_track[k][i];
      ASSERT_GE(t, 0);
      ASSERT_LT(t, static_cast<int>(r.modes.size()));
      EXPECT_EQ(r.modes[static_cast<std::size_t>(t)].freq_hz(static_cast<Eigen::Index>(k)), members[k][i].freq_hz)
          << "member " << k << " mode " << i;
    }
  }
}

}  // namespace

// ---- trackable_modes ---------------------------------------------------------

TEST(FamilyTrackableModes, KeepsStableLightlyDampedPairsInTheBandSortedByFrequency) {
  const double Ts = 1e-3;
  const Eigen::VectorXd s1 = vec({1.0});
  // In order of construction: 80 Hz (kept), 20 Hz (kept), 50 Hz zeta 0.5 (too
  // damped), 300 Hz (above the band), 5 Hz (below it), 120 Hz unstable; and two
  // real poles (never a pair).
  const sysid::StateSpace sys = modal_model({{80.0, 0.01, s1},
                                             {20.0, 0.02, s1},
                                             {50.0, 0.5, s1},
                                             {300.0, 0.02, s1},
                                             {5.0, 0.05, s1},
                                             {120.0, -0.01, s1}},
                                            {0.9, -0.5}, Ts, 1);
  const std::vector<ModeEstimate> m = sysid::trackable_modes(sys, 10.0, 200.0);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_NEAR(m[0].freq_hz, 20.0, 1e-9);
  EXPECT_NEAR(m[0].damping, 0.02, 1e-9);
  EXPECT_NEAR(m[1].freq_hz, 80.0, 1e-9);
  EXPECT_NEAR(m[1].damping, 0.01, 1e-9);
  EXPECT_EQ(m[0].shape.size(), 0) << "one output: no shape";

  // The damping filter is the argument: 0.6 lets the 50 Hz mode in.
  const std::vector<ModeEstimate> loose = sysid::trackable_modes(sys, 10.0, 200.0, 0.6);
  ASSERT_EQ(loose.size(), 3u);
  EXPECT_NEAR(loose[1].freq_hz, 50.0, 1e-9);
  EXPECT_NEAR(loose[1].damping, 0.5, 1e-9);
  // The band edges are inclusive and narrow the set.
  const std::vector<ModeEstimate> narrow = sysid::trackable_modes(sys, 79.0, 400.0);
  ASSERT_EQ(narrow.size(), 2u);
  EXPECT_NEAR(narrow[0].freq_hz, 80.0, 1e-9);
  EXPECT_NEAR(narrow[1].freq_hz, 300.0, 1e-9);
  EXPECT_TRUE(sysid::trackable_modes(sys, 81.0, 119.0).empty());
}

TEST(FamilyTrackableModes, ShapesWithSeveralOutputsAreUnitNormColumnsOfC) {
  const double Ts = 1e-3;
  const Eigen::VectorXd a = vec({1.0, 2.0, -0.5}), b = vec({0.0, -3.0, 4.0}), c = vec({2.0, 0.0, 0.0});
  sysid::StateSpace sys = modal_model({{45.0, 0.03, b}, {15.0, 0.02, a}, {90.0, 0.01, c}}, {0.5}, Ts, 3);
  // A similarity transform must not change the shapes (C v is basis-invariant).
  std::mt19937_64 rng(7);
  const MatrixXd T = sysid::test::well_conditioned(rng, sys.order());
  const MatrixXd Ti = T.inverse();
  sys = sysid::StateSpace(T * sys.A * Ti, T * sys.B, sys.C * Ti, sys.D, Ts);
  const std::vector<ModeEstimate> m = sysid::trackable_modes(sys, 1.0, 400.0);
  ASSERT_EQ(m.size(), 3u);
  const Eigen::VectorXd expected[3] = {a, b, c};
  const double f[3] = {15.0, 45.0, 90.0};
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(m[static_cast<std::size_t>(k)].freq_hz, f[k], 1e-8);
    const Eigen::VectorXcd& shape = m[static_cast<std::size_t>(k)].shape;
    ASSERT_EQ(shape.size(), 3) << "mode " << k;
    EXPECT_NEAR(shape.norm(), 1.0, 1e-12) << "mode " << k;
    // Equal to the column up to a complex factor: MAC 1.
    EXPECT_NEAR(mac(shape, expected[k].cast<std::complex<double>>()), 1.0, 1e-9) << "mode " << k;
  }
  // The shapes are told apart: MAC(a, b) = 8^2 / (5.25 * 25) = 0.49.
  EXPECT_LT(mac(m[0].shape, m[1].shape), 0.5);
}

TEST(FamilyTrackableModes, ContinuousModelsGiveTheirModesToo) {
  // s = -zeta w +- j w sqrt(1 - zeta^2) in a real 2x2 block.
  const double w = 2.0 * kPi * 12.0, zeta = 0.05, wd = w * std::sqrt(1.0 - zeta * zeta);
  MatrixXd A(2, 2);
  A << -zeta * w, wd, -wd, -zeta * w;
  const sysid::StateSpace sys(A, MatrixXd::Ones(2, 1), MatrixXd::Ones(1, 2), MatrixXd::Zero(1, 1), 0.0);
  const std::vector<ModeEstimate> m = sysid::trackable_modes(sys, 1.0, 100.0);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_NEAR(m[0].freq_hz, 12.0, 1e-9);
  EXPECT_NEAR(m[0].damping, 0.05, 1e-9);
}

// ---- track_modes ---------------------------------------------------------------

TEST(FamilyTrackModes, ThreeDriftingModesInAShuffledMemberOrderGiveThreeTracks) {
  // 12 conditions c = 0..1: the modes drift by 8, 6 and 5 % (each step < 1 %);
  // the members are listed in a shuffled order.
  const int n = 12;
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937_64(2024));
  std::vector<std::vector<ModeEstimate>> members(n);
  std::vector<std::array<double, 3>> truth(n);
  for (int k = 0; k < n; ++k) {
    const double c = order[static_cast<std::size_t>(k)] / 11.0;
    truth[static_cast<std::size_t>(k)] = {20.0 * (1 - 0.08 * c), 45.0 * (1 - 0.06 * c), 90.0 * (1 - 0.05 * c)};
    members[static_cast<std::size_t>(k)] = {mode(truth[static_cast<std::size_t>(k)][0], 0.02 + 0.004 * c),
                                            mode(truth[static_cast<std::size_t>(k)][1], 0.03 - 0.005 * c),
                                            mode(truth[static_cast<std::size_t>(k)][2], 0.015)};
  }
  const sysid::ModeTrackingResult r = sysid::track_modes(members);
  ASSERT_EQ(r.modes.size(), 3u);
  for (std::size_t j = 0; j < 3; ++j) {
    ASSERT_EQ(r.modes[j].freq_hz.size(), n);
    ASSERT_EQ(r.modes[j].damping.size(), n);
    EXPECT_EQ(r.modes[j].members_present(), n);
    for (int k = 0; k < n; ++k) {
      EXPECT_EQ(r.modes[j].freq_hz(k), truth[static_cast<std::size_t>(k)][j]) << "mode " << j << " member " << k;
      EXPECT_EQ(r.modes[j].damping(k), members[static_cast<std::size_t>(k)][j].damping) << "mode " << j << " member " << k;
    }
  }
  EXPECT_LT(r.modes[0].mean_freq_hz(), r.modes[1].mean_freq_hz());
  EXPECT_LT(r.modes[1].mean_freq_hz(), r.modes[2].mean_freq_hz());
  expect_consistent_index(r, members);
}

TEST(FamilyTrackModes, AModeAbsentInSomeMembersIsNaNThereAndStillOneTrack) {
  // Three close modes (40, 44, 48.4 Hz: neighbours within the 12 % gate of each
  // other); members 4-6 lack the middle one. It must stay one track, NaN in
  // 4-6, and never take a neighbour's value there.
  const int n = 10;
  std::vector<std::vector<ModeEstimate>> members(n);
  for (int k = 0; k < n; ++k) {
    const double d = 1.0 - 0.004 * k;
    members[static_cast<std::size_t>(k)].push_back(mode(40.0 * d, 0.02));
    if (k < 4 || k > 6) members[static_cast<std::size_t>(k)].push_back(mode(44.0 * d, 0.025));
    members[static_cast<std::size_t>(k)].push_back(mode(48.4 * d, 0.02));
  }
  const sysid::ModeTrackingResult r = sysid::track_modes(members);
  ASSERT_EQ(r.modes.size(), 3u) << "the middle mode split into pieces or merged with a neighbour";
  const sysid::TrackedMode& middle = r.modes[1];
  EXPECT_EQ(middle.members_present(), n - 3);
  for (int k = 0; k < n; ++k) {
    const double d = 1.0 - 0.004 * k;
    EXPECT_EQ(r.modes[0].freq_hz(k), 40.0 * d) << k;
    EXPECT_EQ(r.modes[2].freq_hz(k), 48.4 * d) << k;
    if (k >= 4 && k <= 6) {
      EXPECT_TRUE(std::isnan(middle.freq_hz(k))) << "member " << k << " has " << middle.freq_hz(k);
      EXPECT_TRUE(std::isnan(middle.damping(k))) << k;
    } else {
      EXPECT_EQ(middle.freq_hz(k), 44.0 * d) << k;
      EXPECT_EQ(middle.damping(k), 0.025) << k;
    }
  }
  EXPECT_NEAR(middle.mean_freq_hz(), 44.0 * (1.0 - 0.004 * (0 + 1 + 2 + 3 + 7 + 8 + 9) / 7.0), 1e-12);
  expect_consistent_index(r, members);
}

TEST(FamilyTrackModes, AGradualShiftOfAQuarterBetweenTheExtremesIsOneTrack) {
  // 100 Hz -> 75 Hz over 12 members (|ln 0.75| = 0.29, far beyond the 12 % gate
  // between the extremes, 2.6 % between neighbours), in a shuffled order; a
  // second mode at 200 Hz stays put.
  const int n = 12;
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937_64(11));
  std::vector<std::vector<ModeEstimate>> members(n);
  std::vector<double> moving(n);
  for (int k = 0; k < n; ++k) {
    moving[static_cast<std::size_t>(k)] = 100.0 * std::pow(0.75, order[static_cast<std::size_t>(k)] / 11.0);
    members[static_cast<std::size_t>(k)] = {mode(moving[static_cast<std::size_t>(k)], 0.02), mode(200.0, 0.01)};
  }
  ASSERT_GT(std::abs(std::log(*std::max_element(moving.begin(), moving.end()) /
                              *std::min_element(moving.begin(), moving.end()))),
            0.28);
  const sysid::ModeTrackingResult r = sysid::track_modes(members);
  ASSERT_EQ(r.modes.size(), 2u) << "the moving mode broke into several tracks";
  EXPECT_EQ(r.modes[0].members_present(), n);
  for (int k = 0; k < n; ++k) {
    EXPECT_EQ(r.modes[0].freq_hz(k), moving[static_cast<std::size_t>(k)]) << k;
    EXPECT_EQ(r.modes[1].freq_hz(k), 200.0) << k;
  }
  expect_consistent_index(r, members);
}

TEST(FamilyTrackModes, CloseModesWithOrthogonalShapesAreTrackedApartByMac) {
  // Mode a rises 50 -> 53 Hz with shape e1, mode b falls 53.25 -> 50.25 Hz with
  // shape e2: they cross between members 3 and 4 (51.5 / 51.75 Hz, then 52 /
  // 51.25 Hz), are always within the frequency gate of each other and have the
  // same damping. Across the crossing each is nearer in frequency to the other's
  // previous value, so only the shapes (MAC 0) keep them apart.
  const int n = 7;
  const std::complex<double> j(0.0, 1.0);
  Eigen::VectorXcd e1 = Eigen::VectorXcd::Zero(3), e2 = Eigen::VectorXcd::Zero(3);
  e1(0) = 1.0;
  e2(1) = j;  // a complex phase does not matter to MAC
  std::vector<std::vector<ModeEstimate>> members(n);
  for (int k = 0; k < n; ++k) {
    const double fa = 50.0 + 0.5 * k, fb = 53.25 - 0.5 * k;
    std::vector<ModeEstimate>& m = members[static_cast<std::size_t>(k)];
    m = {mode(fa, 0.02, e1), mode(fb, 0.02, e2)};
    if (fb < fa) std::swap(m[0], m[1]);  // sorted by frequency, as trackable_modes gives them
  }
  const sysid::ModeTrackingResult r = sysid::track_modes(members);
  ASSERT_EQ(r.modes.size(), 2u);
  // Track 0 has the lower mean frequency: a (51.5 Hz) before b (51.75 Hz).
  for (int k = 0; k < n; ++k) {
    EXPECT_EQ(r.modes[0].freq_hz(k), 50.0 + 0.5 * k) << "member " << k;
    EXPECT_EQ(r.modes[1].freq_hz(k), 53.25 - 0.5 * k) << "member " << k;
  }
  expect_consistent_index(r, members);

  // The same modes without shapes are paired by frequency and swap at the
  // crossing: the test above depends on the shapes.
  std::vector<std::vector<ModeEstimate>> unshaped = members;
  for (auto& m : unshaped)
    for (ModeEstimate& e : m) e.shape.resize(0);
  const sysid::ModeTrackingResult by_frequency = sysid::track_modes(unshaped);
  ASSERT_GE(track_with(by_frequency, 0, 50.0), 0);
  EXPECT_NE(track_with(by_frequency, 0, 50.0), track_with(by_frequency, n - 1, 53.0));
}

TEST(FamilyTrackModes, OneMemberGivesTracksOfOneEntry) {
  const std::vector<std::vector<ModeEstimate>> members = {{mode(12.0, 0.01), mode(30.0, 0.02), mode(31.0, 0.2)}};
  const sysid::ModeTrackingResult r = sysid::track_modes(members);
  ASSERT_EQ(r.modes.size(), 3u);
  const double f[3] = {12.0, 30.0, 31.0}, z[3] = {0.01, 0.02, 0.2};
  for (std::size_t j = 0; j < 3; ++j) {
    ASSERT_EQ(r.modes[j].freq_hz.size(), 1);
    EXPECT_EQ(r.modes[j].freq_hz(0), f[j]);
    EXPECT_EQ(r.modes[j].damping(0), z[j]);
  }
  EXPECT_EQ(r.tree_parent, std::vector<int>{-1});
  EXPECT_EQ(r.mode_track, (std::vector<std::vector<int>>{{0, 1, 2}}));
}

TEST(FamilyTrackModes, MembersWithoutModesAndNoMembers) {
  // A member with no trackable mode is NaN in every track; no member at all is refused.
  const std::vector<std::vector<ModeEstimate>> members = {{mode(10.0, 0.02)}, {}, {mode(10.1, 0.02)}};
  const sysid::ModeTrackingResult r = sysid::track_modes(members);
  ASSERT_EQ(r.modes.size(), 1u);
  EXPECT_EQ(r.modes[0].freq_hz(0), 10.0);
  EXPECT_TRUE(std::isnan(r.modes[0].freq_hz(1)));
  EXPECT_EQ(r.modes[0].freq_hz(2), 10.1);
  EXPECT_TRUE(r.mode_track[1].empty());
  EXPECT_THROW(sysid::track_modes({}), std::invalid_argument);
}

TEST(FamilyTrackModes, ANoiseModeBesideAPhysicalOneDoesNotSplitItsTrack) {
  // The generated Par2-like family at automatic orders (data/family, n4sid --order
  // auto): three modes over 15 members, mode 3 running 76..92 Hz, and member 7,
  // identified at order 10, carrying a noise mode at 90.45 Hz beside its physical
  // 83.49 Hz. Members 5, 10 and 11 (88.0, 92.4, 89.9 Hz) used to follow the noise
  // mode into a second track; now mode 3 is one track of 15 members and the noise
  // mode a track of its own. Frequencies and dampings as identified.
  const double f1[15] = {28.00, 26.40, 25.04, 23.88, 22.86, 28.00, 26.40, 25.04, 23.88, 22.86, 28.00, 26.40, 25.04, 23.88, 22.86};
  const double z1[15] = {0.030, 0.031, 0.033, 0.034, 0.036, 0.030, 0.032, 0.033, 0.035, 0.036, 0.030, 0.032, 0.033, 0.034, 0.036};
  const double f2[15] = {61.44, 59.03, 56.88, 54.96, 53.21, 64.00, 61.49, 59.25, 57.24, 55.42, 67.20, 64.56, 62.21, 60.10, 58.20};
  const double z2[15] = {0.025, 0.026, 0.027, 0.029, 0.030, 0.025, 0.026, 0.027, 0.029, 0.030, 0.025, 0.026, 0.027, 0.029, 0.030};
  const double f3[15] = {84.48, 82.23, 80.14, 78.21, 76.42, 88.00, 85.65, 83.49, 81.47, 79.60, 92.40, 89.94, 87.66, 85.54, 83.57};
  const double z3[15] = {0.035, 0.037, 0.038, 0.040, 0.042, 0.035, 0.037, 0.039, 0.040, 0.042, 0.035, 0.037, 0.039, 0.040, 0.042};
  std::vector<std::vector<ModeEstimate>> members;
  for (int k = 0; k < 15; ++k) {
    members.push_back({mode(f1[k], z1[k]), mode(f2[k], z2[k]), mode(f3[k], z3[k])});
    if (k == 7) members.back().push_back(mode(90.45, 0.015));
  }
  const sysid::ModeTrackingResult r = sysid::track_modes(members);
  ASSERT_EQ(r.modes.size(), 4u);
  for (int k = 0; k < 15; ++k) EXPECT_EQ(r.modes[2].freq_hz(k), f3[k]) << "member " << k;
  EXPECT_EQ(r.modes[3].members_present(), 1);
  EXPECT_EQ(r.modes[3].freq_hz(7), 90.45);
  EXPECT_EQ(r.mode_track[7], (std::vector<int>{0, 1, 2, 3}));
}

}  // namespace test_unit_family_mode_tracking
