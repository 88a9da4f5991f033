// Tests for sysid::fem::modal_analysis (include/sysid/fem/modal_analysis.hpp):
// shift-invert Lanczos against the dense generalised eigensolver.
#include <sysid/core/errors.hpp>
#include <sysid/fem/modal_analysis.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fem_cases.hpp"

namespace test_unit_fem_modal_analysis {

namespace {

using sysid::fem::modal_analysis;
using sysid::fem::ModalAnalysisOptions;

TEST(FemModalAnalysis, LowestModesMatchTheDenseEigensolver) {
  const auto model = sysid::test::beam_on_isolators(30);  // 62 DOFs
  ModalAnalysisOptions o;
  o.modes = 8;
  const auto r = modal_analysis(model, o);
  const auto dense = sysid::test::dense_modes(model);
  ASSERT_EQ(r.eigenvalues.size(), 8);
  for (int i = 0; i < 8; ++i) EXPECT_NEAR(r.eigenvalues(i) / dense.eigenvalues(i), 1.0, 1e-9) << "mode " << i;
  // Mass-orthonormal shapes, each an eigenvector.
  const Eigen::MatrixXd gram = r.mode_shapes.transpose() * (model.mass * r.mode_shapes);
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(8, 8)).norm(), 1e-9);
  EXPECT_LT(r.max_relative_residual, 1e-12);
  EXPECT_LT(r.shift, 0.0);
  EXPECT_EQ(r.rigid_body_modes, 0);
  EXPECT_GT(r.operator_applications, 0);
  // Each shape spans the same line as the dense one (sign-free comparison).
  for (int i = 0; i < 8; ++i) {
    const double cosine = std::abs(r.mode_shapes.col(i).dot(model.mass * dense.shapes.col(i)));
    EXPECT_NEAR(cosine, 1.0, 1e-7) << "mode " << i;
  }
}

TEST(FemModalAnalysis, FreeFreeBeamHasTwoRigidBodyModes) {
  sysid::fem::BeamOptions bo;
  bo.elements = 20;
  sysid::fem::StructureBuilder b(bo);
  const auto model = b.finish({{"F", 0, "N"}}, {{"x", 0, sysid::fem::Quantity::displacement, "m"}});
  ModalAnalysisOptions o;
  o.modes = 4;
  const auto r = modal_analysis(model, o);
  EXPECT_EQ(r.rigid_body_modes, 2);
  EXPECT_EQ(r.natural_frequencies_hz(0), 0.0);
  EXPECT_EQ(r.natural_frequencies_hz(1), 0.0);
  EXPECT_TRUE(std::isnan(r.damping_ratios(0)));
  // First free-free flexural mode: (4.7300407 )^2 / (2 pi) for the unit beam.
  EXPECT_NEAR(r.natural_frequencies_hz(2) / (4.7300407 * 4.7300407 / (2.0 * std::numbers::pi)), 1.0, 1e-4);
}

TEST(FemModalAnalysis, DampingInModalCoordinates) {
  auto model = sysid::test::beam_on_isolators(20);
  ModalAnalysisOptions o;
  o.modes = 5;
  // Rayleigh: zeta_i = alpha / (2 omega_i) + beta omega_i / 2, and Phi^T C Phi diagonal.
  model.damping.kind = sysid::fem::DampingKind::rayleigh;
  model.damping.alpha = 3.0;
  model.damping.beta = 2e-5;
  auto r = modal_analysis(model, o);
  for (int i = 0; i < 5; ++i) {
    const double w = 2.0 * std::numbers::pi * r.natural_frequencies_hz(i);
    EXPECT_NEAR(r.damping_ratios(i), 3.0 / (2.0 * w) + 2e-5 * w / 2.0, 1e-9);
  }
  EXPECT_LT((r.modal_damping - Eigen::MatrixXd(r.modal_damping.diagonal().asDiagonal())).norm(),
            1e-9 * r.modal_damping.norm());
  model.damping.kind = sysid::fem::DampingKind::modal_ratio;
  model.damping.ratio = 0.02;
  r = modal_analysis(model, o);
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(r.damping_ratios(i), 0.02, 1e-12);
}

TEST(FemModalAnalysis, RejectsImpossibleRequestsAndMasslessDofs) {
  auto model = sysid::test::beam_on_isolators(4);  // 10 DOFs
  ModalAnalysisOptions o;
  o.modes = 10;
  EXPECT_THROW(modal_analysis(model, o), std::invalid_argument);
  o.modes = 0;
  EXPECT_THROW(modal_analysis(model, o), std::invalid_argument);
  o.modes = 3;
  // A DOF with no mass: M singular.
  model.mass.coeffRef(0, 0) = 0.0;
  model.mass.coeffRef(0, 1) = model.mass.coeffRef(1, 0) = 0.0;
  model.mass.coeffRef(0, 2) = model.mass.coeffRef(2, 0) = 0.0;
  model.mass.coeffRef(0, 3) = model.mass.coeffRef(3, 0) = 0.0;
  EXPECT_THROW(modal_analysis(model, o), sysid::NumericalError);
}

}  // namespace

}  // namespace test_unit_fem_modal_analysis
