// Tests for the reference beam structures (include/sysid/fem/beam_model.hpp),
// checked through modal_analysis against Euler-Bernoulli theory.
#include <sysid/fem/beam_model.hpp>
#include <sysid/fem/modal_analysis.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fem_cases.hpp"

namespace test_unit_fem_beam_model {

namespace {

using sysid::fem::BeamOptions;
using sysid::fem::StructureBuilder;

sysid::fem::SecondOrderModel cantilever(const BeamOptions& o) {
  StructureBuilder b(o);
  return b.finish({{"F", b.translation_dof(o.elements), "N"}},
                  {{"x", b.translation_dof(o.elements), sysid::fem::Quantity::displacement, "m"}});
}

TEST(FemBeamModel, CantileverAnalyticRootsAreTheTextbookValues) {
  // beta_i L of cos(bL) cosh(bL) = -1 (Blevins table 8-1), through f = (bL)^2/(2 pi) for
  // a unit beam.
  const BeamOptions unit;
  const Eigen::VectorXd f = sysid::fem::cantilever_frequencies_hz(unit, 5);
  const double roots[5] = {1.87510407, 4.69409113, 7.85475744, 10.99554073, 14.13716839};
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(std::sqrt(2.0 * std::numbers::pi * f(i)), roots[i], 1e-7) << "mode " << i + 1;
}

TEST(FemBeamModel, CantileverFirstFiveModesWithinHalfAPercentOfEulerBernoulli) {
  // The acceptance mesh: 20 elements of an aluminium-like strip, 0.5 m long.
  BeamOptions o;
  o.elements = 20;
  o.length = 0.5;
  o.flexural_rigidity = 70e9 * (0.03 * std::pow(0.005, 3) / 12.0);
  o.mass_per_length = 2700.0 * 0.03 * 0.005;
  o.clamped_left = true;
  const auto model = cantilever(o);
  sysid::fem::ModalAnalysisOptions mo;
  mo.modes = 5;
  const auto modes = sysid::fem::modal_analysis(model, mo);
  const Eigen::VectorXd exact = sysid::fem::cantilever_frequencies_hz(o, 5);
  for (int i = 0; i < 5; ++i) {
    const double relative = modes.natural_frequencies_hz(i) / exact(i) - 1.0;
    EXPECT_LT(std::abs(relative), 0.005) << "mode " << i + 1 << ": " << modes.natural_frequencies_hz(i) << " vs " << exact(i);
    // A consistent mass matrix bounds the eigenvalues from above (Rayleigh-Ritz).
    EXPECT_GT(relative, -1e-9) << "mode " << i + 1;
  }
  EXPECT_EQ(modes.rigid_body_modes, 0);
}

TEST(FemBeamModel, CantileverErrorShrinksLikeTheFourthPowerOfTheElementLength) {
  // Hermite cubics: eigenvalue error O(h^4) for a fixed mode (Strang & Fix ch. 6), so
  // halving h divides the frequency error of mode 3 by about 16.
  BeamOptions o;
  o.clamped_left = true;
  sysid::fem::ModalAnalysisOptions mo;
  mo.modes = 3;
  auto error = [&](int elements) {
    o.elements = elements;
    const auto modes = sysid::fem::modal_analysis(cantilever(o), mo);
    return modes.natural_frequencies_hz(2) / sysid::fem::cantilever_frequencies_hz(o, 3)(2) - 1.0;
  };
  const double coarse = error(6), fine = error(12);
  EXPECT_GT(coarse / fine, 12.0);
  EXPECT_LT(coarse / fine, 20.0);
}

TEST(FemBeamModel, ResonatorAddsOneDofAndItsMode) {
  // A stiff rigid-ish beam on soft springs plus a 0.01 kg, 40 Hz resonator: the model
  // has one more DOF and a mode near 40 Hz that the bare structure lacks.
  auto bare = sysid::test::beam_on_isolators(10);
  BeamOptions o;
  o.elements = 10;
  o.flexural_rigidity = 100.0;
  o.mass_per_length = 2.0;
  StructureBuilder b(o);
  b.add_spring_to_ground(b.translation_dof(b.node_at(0.1)), 2e4);
  b.add_spring_to_ground(b.translation_dof(b.node_at(0.9)), 2e4);
  const double k = 0.01 * std::pow(2.0 * std::numbers::pi * 40.0, 2);
  const Eigen::Index r = b.add_resonator(b.translation_dof(10), 0.01, k);
  EXPECT_EQ(r, bare.dofs());
  const auto with = b.finish({{"F", 2, "N"}}, {{"x", r, sysid::fem::Quantity::displacement, "m"}});
  const auto dense_bare = sysid::test::dense_modes(bare), dense_with = sysid::test::dense_modes(with);
  auto count_near = [](const Eigen::VectorXd& lambda, double lo, double hi) {
    int c = 0;
    for (Eigen::Index i = 0; i < lambda.size(); ++i) {
      const double f = std::sqrt(std::max(lambda(i), 0.0)) / (2.0 * std::numbers::pi);
      c += f > lo && f < hi;
    }
    return c;
  };
  EXPECT_EQ(count_near(dense_with.eigenvalues, 35.0, 45.0), count_near(dense_bare.eigenvalues, 35.0, 45.0) + 1);
}

TEST(FemBeamModel, RejectsBadGeometryAndNodes) {
  BeamOptions o;
  o.elements = 0;
  EXPECT_THROW(StructureBuilder{o}, std::invalid_argument);
  o.elements = 4;
  o.clamped_left = true;
  StructureBuilder b(o);
  EXPECT_THROW(b.translation_dof(0), std::invalid_argument);
  EXPECT_THROW(b.translation_dof(5), std::invalid_argument);
  EXPECT_EQ(b.translation_dof(1), 0);
  EXPECT_THROW(b.add_resonator(0, -1.0, 1.0), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_fem_beam_model
