// io/polynomial_model_file.hpp: the polynomial model file and the noise-model
// parameter counts read back from it (the Ljung-Box p of `sysid resid`).
#include <sysid/core/errors.hpp>
#include <sysid/io/polynomial_model_file.hpp>

#include <gtest/gtest.h>

namespace test_unit_io_polynomial_model_file {

namespace {

/// One output of a SISO polynomial model with the given polynomial lengths.
sysid::PolynomialModel polynomial(int na, int nb, int nc, int nd, int nf) {
  sysid::PolynomialModel m;
  m.A = Eigen::VectorXd::Zero(na + 1);
  m.A(0) = 1.0;
  if (na > 0) m.A(1) = -0.5;
  m.B = {Eigen::VectorXd::Constant(nb, 0.1)};
  m.nk = {1};
  m.F = {Eigen::VectorXd::Zero(nf + 1)};
  m.F[0](0) = 1.0;
  if (nf > 0) m.F[0](1) = -0.3;
  m.C = Eigen::VectorXd::Zero(nc + 1);
  m.C(0) = 1.0;
  m.D = Eigen::VectorXd::Zero(nd + 1);
  m.D(0) = 1.0;
  m.noise_variance = 0.01;
  m.Ts = 0.001;
  return m;
}

TEST(PolynomialModelFile, NoiseModelParameterCountsAreNaPlusNcPlusNdPerOutput) {
  const auto file = sysid::polynomial_model_file({polynomial(4, 4, 2, 0, 0), polynomial(3, 2, 0, 1, 0)}, "mixed", {"u"},
                                                 {"y1", "y2"});
  EXPECT_EQ(sysid::noise_model_parameter_counts(file, "m.json"), (std::vector<Eigen::Index>{6, 4}));
  const auto oe = sysid::polynomial_model_file({polynomial(0, 3, 0, 0, 2)}, "oe", {"u"}, {"y"});
  EXPECT_EQ(sysid::noise_model_parameter_counts(oe, "oe.json"), (std::vector<Eigen::Index>{0}));
}

TEST(PolynomialModelFile, StateSpaceFilesHaveNoCountAndBrokenListsAreDataErrors) {
  auto file = sysid::polynomial_model_file({polynomial(2, 2, 1, 0, 0)}, "armax", {"u"}, {"y"});
  sysid::ModelFile state_space = file;
  state_space.type = "state-space";
  EXPECT_TRUE(sysid::noise_model_parameter_counts(state_space, "ss.json").empty());
  file.extra.erase("C");
  try {
    sysid::noise_model_parameter_counts(file, "broken.json");
    FAIL() << "no error for a missing C list";
  } catch (const sysid::DataError& e) {
    EXPECT_NE(std::string(e.what()).find("broken.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("\"C\""), std::string::npos) << e.what();
  }
  file.extra["C"] = nlohmann::json::array({nlohmann::json::array()});
  EXPECT_THROW(sysid::noise_model_parameter_counts(file, "empty.json"), sysid::DataError);
}

}  // namespace

}  // namespace test_unit_io_polynomial_model_file
