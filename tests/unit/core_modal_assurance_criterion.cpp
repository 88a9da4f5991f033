// Tests for sysid::modal_assurance_criterion (include/sysid/core/modal_assurance_criterion.hpp).
#include <sysid/core/modal_assurance_criterion.hpp>

#include <gtest/gtest.h>

#include <complex>

namespace test_unit_core_modal_assurance_criterion {

using cd = std::complex<double>;

TEST(ModalAssuranceCriterion, OneForTheSameShapeZeroForOrthogonalOnes) {
  Eigen::VectorXcd a(3), b(3);
  a << cd(1, 0), cd(0, 2), cd(-1, 1);
  EXPECT_NEAR(sysid::modal_assurance_criterion(a, a), 1.0, 1e-15);
  EXPECT_NEAR(sysid::modal_assurance_criterion(a, cd(0.0, -3.0) * a), 1.0, 1e-15);  // complex scaling: the same shape
  b << cd(0, 2), cd(1, 0), cd(0, 0);
  b -= (a.dot(b) / a.squaredNorm()) * a;  // orthogonal to a
  EXPECT_NEAR(sysid::modal_assurance_criterion(a, b), 0.0, 1e-15);
  // Between: |a^H b|^2 / (|a|^2 |b|^2) by hand for two real shapes.
  Eigen::VectorXcd c(2), e(2);
  c << 1.0, 0.0;
  e << 1.0, 1.0;
  EXPECT_NEAR(sysid::modal_assurance_criterion(c, e), 0.5, 1e-15);
}

TEST(ModalAssuranceCriterion, ZeroOrMismatchedShapesGiveZero) {
  Eigen::VectorXcd a = Eigen::VectorXcd::Ones(3);
  EXPECT_EQ(sysid::modal_assurance_criterion(a, Eigen::VectorXcd::Zero(3)), 0.0);
  EXPECT_EQ(sysid::modal_assurance_criterion(a, Eigen::VectorXcd::Ones(2)), 0.0);
  EXPECT_EQ(sysid::modal_assurance_criterion(Eigen::VectorXcd(), Eigen::VectorXcd()), 0.0);
}

}  // namespace test_unit_core_modal_assurance_criterion
