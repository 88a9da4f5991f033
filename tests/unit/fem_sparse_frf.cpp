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

/// With every mode kept, the modal sum
///   H_df(w) = sum_r phi_r(d) phi_r(f) / (w_r^2 - w^2 + j w (alpha + beta w_r^2))
/// is exact for Rayleigh damping (alpha = beta = 0: none), and with w_r^2 (1 + j eta)
/// for structural damping eta = 2 zeta (a modal ratio). Returns the largest relative
/// difference of an entry of `r` from it over the frequencies, outputs and inputs.
double worst_against_modal_sum(const sysid::fem::SecondOrderModel& model, const sysid::fem::SparseFrfResult& r) {
  const auto dense = sysid::test::dense_modes(model);
  const bool rayleigh = model.damping.kind == sysid::fem::DampingKind::rayleigh;
  const double alpha = rayleigh ? model.damping.alpha : 0.0, beta = rayleigh ? model.damping.beta : 0.0;
  const double eta = model.damping.kind == sysid::fem::DampingKind::modal_ratio ? 2.0 * model.damping.ratio : 0.0;
  const auto outputs = static_cast<Eigen::Index>(model.outputs.size()), inputs = static_cast<Eigen::Index>(model.inputs.size());
  double worst = 0.0;
  for (Eigen::Index k = 0; k < r.freq_hz.size(); ++k) {
    const double w = 2.0 * std::numbers::pi * r.freq_hz(k);
    Eigen::MatrixXcd modal = Eigen::MatrixXcd::Zero(outputs, inputs);
    for (Eigen::Index q = 0; q < dense.eigenvalues.size(); ++q) {
      const double wr2 = dense.eigenvalues(q);
      const Complex denominator(wr2 - w * w, w * (alpha + beta * wr2) + eta * wr2);
      for (Eigen::Index i = 0; i < outputs; ++i)
        for (Eigen::Index j = 0; j < inputs; ++j) {
          const auto& out = model.outputs[static_cast<std::size_t>(i)];
          const Complex factor = sysid::fem::quantity_factor(out.quantity, w);
          modal(i, j) += factor * dense.shapes(out.dof, q) *
                         dense.shapes(model.inputs[static_cast<std::size_t>(j)].dof, q) / denominator;
        }
    }
    worst = std::max(worst, ((r.H[static_cast<std::size_t>(k)] - modal).array() / modal.array()).abs().maxCoeff());
  }
  return worst;
}

sysid::fem::SecondOrderModel rayleigh_beam(int elements) {
  auto model = sysid::test::beam_on_isolators(elements);
  model.damping.kind = sysid::fem::DampingKind::rayleigh;
  model.damping.alpha = 2.0;
  model.damping.beta = 1e-5;
  return model;
}

sysid::fem::SparseFrfOptions with_method(sysid::fem::SparseFrfMethod method) {
  sysid::fem::SparseFrfOptions o;
  o.method = method;
  return o;
}

TEST(FemSparseFrf, EqualsTheFullModalSumWithRayleighDamping) {
  // The acceptance check: the direct sparse solve agrees with the modal sum to 1e-8.
  const auto model = rayleigh_beam(24);
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(300, 0.5, 2000.0);
  const auto r = sparse_frf(model, f);
  ASSERT_EQ(r.H.size(), 300u);
  EXPECT_EQ(r.method, sysid::fem::SparseFrfMethod::direct);  // automatic: a small model
  EXPECT_EQ(r.symbolic_factorisations, 1);
  EXPECT_EQ(r.numeric_factorisations, 300);
  EXPECT_EQ(r.direct_frequencies, 300);
  EXPECT_LT(worst_against_modal_sum(model, r), 1e-8);
  EXPECT_TRUE(r.warnings.empty());
}

TEST(FemSparseFrf, KrylovSweepEqualsTheFullModalSumFromOneFactorisation) {
  // 600 DOFs, 15 modes below 2 kHz, two forces: one Cholesky factorisation and a
  // basis far smaller than the model must serve all 300 frequencies to the same 1e-8.
  const auto model = sysid::test::axial_rod(600);
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(300, 0.5, 2000.0);
  const auto r = sparse_frf(model, f, with_method(sysid::fem::SparseFrfMethod::krylov));
  EXPECT_EQ(r.method, sysid::fem::SparseFrfMethod::krylov);
  EXPECT_EQ(r.symbolic_factorisations, 1);
  EXPECT_EQ(r.numeric_factorisations, 1);
  EXPECT_EQ(r.krylov_frequencies, 300);
  EXPECT_EQ(r.direct_frequencies, 0);
  EXPECT_GT(r.krylov_basis_size, 0);
  EXPECT_LT(r.krylov_basis_size, model.dofs() / 4);
  EXPECT_LE(r.krylov_max_estimated_error, 1e-8);
  EXPECT_TRUE(std::isnan(r.min_rcond));  // nothing solved directly
  EXPECT_LT(worst_against_modal_sum(model, r), 1e-8);
  EXPECT_LT(worst_against_modal_sum(model, sparse_frf(model, f, with_method(sysid::fem::SparseFrfMethod::direct))), 1e-8);
  EXPECT_TRUE(r.warnings.empty());
}

TEST(FemSparseFrf, KrylovSweepEqualsTheModalSumForEveryProportionalDamping) {
  // Rayleigh, a modal ratio (structural damping), no damping at all.
  for (const auto kind : {sysid::fem::DampingKind::rayleigh, sysid::fem::DampingKind::modal_ratio,
                          sysid::fem::DampingKind::none}) {
    auto model = sysid::test::axial_rod(500);
    model.damping.kind = kind;
    model.damping.ratio = 0.02;
    // Not on a natural frequency of the undamped rod (the grid is irrational in Hz).
    const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(120, 1.0 / 3.0, 1500.0 + std::numbers::sqrt2);
    const auto krylov = sparse_frf(model, f, with_method(sysid::fem::SparseFrfMethod::krylov));
    EXPECT_EQ(krylov.krylov_frequencies, 120) << static_cast<int>(kind);
    EXPECT_LT(worst_against_modal_sum(model, krylov), 1e-8) << "damping kind " << static_cast<int>(kind);
  }
}

TEST(FemSparseFrf, KrylovSweepHandsAnIllConditionedBeamToDirectSolvesAndSaysSo) {
  // A 400-element beam: eigenvalues over 11.7 decades, so solves with K - sigma0 M
  // carry round-off of order eps cond. Measured: the direct solve itself differs
  // from the dense modal sum by 5e-5 (13.9 Hz, v_mid) and a Krylov sweep from the
  // direct solve by 2.6e-6. Its floor estimate exceeds the tolerance, so no
  // frequency is taken from the basis.
  const auto model = rayleigh_beam(400);
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(300, 0.5, 2000.0);
  const auto krylov = sparse_frf(model, f, with_method(sysid::fem::SparseFrfMethod::krylov));
  const auto direct = sparse_frf(model, f, with_method(sysid::fem::SparseFrfMethod::direct));
  EXPECT_GT(krylov.krylov_rounding_error, 1e-8);
  EXPECT_EQ(krylov.krylov_frequencies, 0);
  EXPECT_EQ(krylov.direct_frequencies, 300);
  ASSERT_EQ(krylov.warnings.size(), 1u);
  EXPECT_NE(krylov.warnings[0].find("ill-conditioned"), std::string::npos);
  for (std::size_t k = 0; k < 300; ++k) EXPECT_EQ(krylov.H[k], direct.H[k]);
}

TEST(FemSparseFrf, KrylovNeedsProportionalDampingAndAutomaticSolvesDampersDirectly) {
  const auto model = sysid::test::beam_on_isolators(1000, /*dampers=*/true);  // 2 002 DOFs
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(60, 1.0, 500.0);
  EXPECT_THROW(sparse_frf(model, f, with_method(sysid::fem::SparseFrfMethod::krylov)), std::invalid_argument);
  const auto r = sparse_frf(model, f);
  EXPECT_EQ(r.method, sysid::fem::SparseFrfMethod::direct);
  EXPECT_EQ(r.direct_frequencies, 60);
}

TEST(FemSparseFrf, KrylovFrequenciesItCannotCertifyAreSolvedDirectlyAndCounted) {
  // A basis capped at 6 columns cannot hold 15 modes excited by two forces: most
  // frequencies fail the error estimate and come from the direct solves instead.
  const auto model = sysid::test::axial_rod(300);
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(80, 0.5, 2000.0);
  auto o = with_method(sysid::fem::SparseFrfMethod::krylov);
  o.krylov_max_basis = 6;
  const auto r = sparse_frf(model, f, o);
  const auto direct = sparse_frf(model, f, with_method(sysid::fem::SparseFrfMethod::direct));
  EXPECT_EQ(r.krylov_basis_size, 6);
  EXPECT_GT(r.direct_frequencies, 0);
  EXPECT_EQ(r.direct_frequencies + r.krylov_frequencies, 80);
  EXPECT_EQ(r.numeric_factorisations, 1 + r.direct_frequencies);  // Cholesky + one LU per direct frequency
  EXPECT_EQ(r.symbolic_factorisations, 2);                         // CHOLMOD's and UMFPACK's
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("not certified"), std::string::npos);
  double worst = 0.0;
  for (std::size_t k = 0; k < 80; ++k) worst = std::max(worst, relative_difference(r.H[k], direct.H[k]));
  EXPECT_LT(worst, 1e-9);
}

TEST(FemSparseFrf, AutomaticMethodSweepsLargeModelsByKrylovAndSmallRequestsDirectly) {
  const auto model = sysid::test::axial_rod(2000);
  const auto sweep = sparse_frf(model, Eigen::VectorXd::LinSpaced(50, 1.0, 1000.0));
  EXPECT_EQ(sweep.method, sysid::fem::SparseFrfMethod::krylov);
  EXPECT_EQ(sweep.krylov_frequencies, 50);
  const auto few = sparse_frf(model, Eigen::VectorXd::LinSpaced(49, 1.0, 1000.0));
  EXPECT_EQ(few.method, sysid::fem::SparseFrfMethod::direct);
  EXPECT_EQ(few.direct_frequencies, 49);
}

TEST(FemSparseFrf, MethodNamesRoundTripAndBadKrylovOptionsAreRejected) {
  using sysid::fem::SparseFrfMethod;
  for (const auto m : {SparseFrfMethod::automatic, SparseFrfMethod::direct, SparseFrfMethod::krylov})
    EXPECT_EQ(sysid::fem::sparse_frf_method_from_name(sysid::fem::sparse_frf_method_name(m)), m);
  EXPECT_THROW(sysid::fem::sparse_frf_method_from_name("lanczos"), std::invalid_argument);
  const auto model = sysid::test::beam_on_isolators(4);
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(3, 1.0, 10.0);
  auto o = with_method(SparseFrfMethod::krylov);
  o.krylov_tolerance = 0.0;
  EXPECT_THROW(sparse_frf(model, f, o), std::invalid_argument);
  o.krylov_tolerance = 1e-12;
  o.krylov_max_basis = 0;
  EXPECT_THROW(sparse_frf(model, f, o), std::invalid_argument);
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
  // The Krylov sweep factorises K - sigma0 M with sigma0 < 0, which is fine for a
  // free beam, and must hand 0 Hz (rigid-body modes) to the direct solve.
  for (const auto method : {sysid::fem::SparseFrfMethod::direct, sysid::fem::SparseFrfMethod::krylov}) {
    const auto r = sparse_frf(model, f, with_method(method));
    EXPECT_TRUE(std::isnan(r.H[0](0, 0).real())) << sysid::fem::sparse_frf_method_name(method);
    EXPECT_TRUE(std::isfinite(r.H[1](0, 0).real()));
    EXPECT_TRUE(std::isfinite(r.H[2](0, 0).real()));
    ASSERT_FALSE(r.warnings.empty());
    EXPECT_NE(r.warnings.back().find("singular"), std::string::npos);
  }
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
