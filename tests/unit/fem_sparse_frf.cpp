// Tests for sysid::fem::sparse_frf (include/sysid/fem/sparse_frf.hpp).
#include <sysid/fem/sparse_frf.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "fem_cases.hpp"

namespace test_unit_fem_sparse_frf {

namespace {

using sysid::fem::sparse_frf;
using Complex = std::complex<double>;

double relative_difference(const Eigen::MatrixXcd& a, const Eigen::MatrixXcd& b) { return (a - b).norm() / b.norm(); }

TEST(FemSparseFrf, EqualsTheFullModalSumWithRayleighDamping) {
  // The acceptance check: with every mode kept, the modal sum
  //   H_d(w) = sum_r phi_r(d) phi_r(f) / (w_r^2 - w^2 + j w (alpha + beta w_r^2))
  // is exact for proportional damping; the sparse solve must agree to 1e-8.
  auto model = sysid::test::beam_on_isolators(24);
  model.damping.kind = sysid::fem::DampingKind::rayleigh;
  model.damping.alpha = 2.0;
  model.damping.beta = 1e-5;
  const auto dense = sysid::test::dense_modes(model);
  Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(300, 0.5, 2000.0);
  const auto r = sparse_frf(model, f);
  ASSERT_EQ(r.H.size(), 300u);
  EXPECT_EQ(r.symbolic_factorisations, 1);
  EXPECT_EQ(r.numeric_factorisations, 300);
  const Eigen::Index force = model.inputs[0].dof;
  double worst = 0.0;
  for (Eigen::Index k = 0; k < f.size(); ++k) {
    const double w = 2.0 * std::numbers::pi * f(k);
    Eigen::MatrixXcd modal = Eigen::MatrixXcd::Zero(3, 1);
    for (Eigen::Index q = 0; q < dense.eigenvalues.size(); ++q) {
      const double wr2 = dense.eigenvalues(q);
      const Complex denominator(wr2 - w * w, w * (2.0 + 1e-5 * wr2));
      for (int i = 0; i < 3; ++i) {
        const auto& out = model.outputs[static_cast<std::size_t>(i)];
        const Complex factor = sysid::fem::quantity_factor(out.quantity, w);
        modal(i, 0) += factor * dense.shapes(out.dof, q) * dense.shapes(force, q) / denominator;
      }
    }
    for (int i = 0; i < 3; ++i)
      worst = std::max(worst, std::abs(r.H[static_cast<std::size_t>(k)](i, 0) - modal(i, 0)) / std::abs(modal(i, 0)));
  }
  EXPECT_LT(worst, 1e-8);
  EXPECT_TRUE(r.warnings.empty());
}

TEST(FemSparseFrf, NonProportionalDampersMatchTheDenseSolveAndReuseChangesNothing) {
  const auto model = sysid::test::beam_on_isolators(16, /*dampers=*/true);
  Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(40, 0.0, 500.0);
  const auto reused = sparse_frf(model, f);
  sysid::fem::SparseFrfOptions scratch_options;
  scratch_options.reuse_symbolic = false;
  const auto scratch = sparse_frf(model, f, scratch_options);
  EXPECT_EQ(reused.symbolic_factorisations, 1);
  EXPECT_EQ(scratch.symbolic_factorisations, 40);
  for (Eigen::Index k = 0; k < f.size(); ++k) {
    const auto b = static_cast<std::size_t>(k);
    EXPECT_LT(relative_difference(reused.H[b], sysid::test::dense_response(model, f(k))), 1e-9) << f(k) << " Hz";
    EXPECT_LT(relative_difference(reused.H[b], scratch.H[b]), 1e-12) << f(k) << " Hz";
  }
  EXPECT_GT(reused.min_rcond, 0.0);
}

TEST(FemSparseFrf, FreeFloatingStructureIsSingularAtZeroHertzAndSaysSo) {
  sysid::fem::BeamOptions o;
  o.elements = 8;
  sysid::fem::StructureBuilder b(o);
  auto model = b.finish({{"F", 0, "N"}}, {{"x", 16, sysid::fem::Quantity::displacement, "m"}});
  model.damping.kind = sysid::fem::DampingKind::rayleigh;
  model.damping.beta = 1e-4;
  const Eigen::VectorXd f = (Eigen::VectorXd(3) << 0.0, 5.0, 50.0).finished();
  const auto r = sparse_frf(model, f);
  EXPECT_TRUE(std::isnan(r.H[0](0, 0).real()));
  EXPECT_TRUE(std::isfinite(r.H[1](0, 0).real()));
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("singular"), std::string::npos);
}

TEST(FemSparseFrf, ModalDampingRatioIsStructuralDampingAndWarns) {
  // With structural damping eta = 2 zeta the full modal sum is exact:
  //   H = sum_r phi_r phi_r^T / (w_r^2 (1 + j eta) - w^2).
  auto model = sysid::test::beam_on_isolators(12);
  model.damping.kind = sysid::fem::DampingKind::modal_ratio;
  model.damping.ratio = 0.01;
  const auto dense = sysid::test::dense_modes(model);
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(60, 1.0, 600.0);
  const auto r = sparse_frf(model, f);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings[0].find("structural"), std::string::npos);
  const Eigen::Index force = model.inputs[0].dof, tip = model.outputs[0].dof;
  for (Eigen::Index k = 0; k < f.size(); ++k) {
    const double w = 2.0 * std::numbers::pi * f(k);
    Complex modal = 0.0;
    for (Eigen::Index q = 0; q < dense.eigenvalues.size(); ++q)
      modal += dense.shapes(tip, q) * dense.shapes(force, q) / (dense.eigenvalues(q) * Complex(1.0, 0.02) - w * w);
    EXPECT_LT(std::abs(r.H[static_cast<std::size_t>(k)](0, 0) - modal), 1e-8 * std::abs(modal)) << f(k) << " Hz";
  }
}

TEST(FemSparseFrf, RejectsNegativeFrequencies) {
  const auto model = sysid::test::beam_on_isolators(4);
  EXPECT_THROW(sparse_frf(model, (Eigen::VectorXd(2) << 1.0, -1.0).finished()), std::invalid_argument);
}

}  // namespace

}  // namespace test_unit_fem_sparse_frf
