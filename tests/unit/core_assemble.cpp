// Assembly of single-input models into one MIMO model (core/assemble.hpp): the
// assembled frequency response equals the parts' responses placed column by
// column; the order is the sum; mismatched parts are refused with the reason.
#include <sysid/core/assemble.hpp>
#include <sysid/core/frequency_response.hpp>

#include <gtest/gtest.h>

#include "random_systems.hpp"

namespace test_unit_core_assemble {

using namespace sysid;

namespace {
StateSpace named(StateSpace s, std::vector<std::string> inputs, std::vector<std::string> outputs) {
  s.input_names = std::move(inputs);
  s.output_names = std::move(outputs);
  return s;
}
}  // namespace

TEST(Assemble, FrequencyResponseEqualsTheStackedParts) {
  const StateSpace p1 = named(test::random_modal_system(3, 1, 3, 11), {"u1"}, {"y1", "y2", "y3"});
  const StateSpace p2 = named(test::random_modal_system(2, 2, 3, 12), {"u2", "u3"}, {"y1", "y2", "y3"});
  const StateSpace p3 = named(test::random_modal_system(2, 1, 3, 13), {"u4"}, {"y1", "y2", "y3"});
  const StateSpace all = assemble_inputs({p1, p2, p3});
  EXPECT_EQ(all.order(), 14);
  EXPECT_EQ(all.inputs(), 4);
  EXPECT_EQ(all.outputs(), 3);
  EXPECT_EQ(all.input_names, std::vector<std::string>({"u1", "u2", "u3", "u4"}));
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(40, 0.0, 0.49 / p1.Ts);
  const auto g = frequency_response(all, f), g1 = frequency_response(p1, f), g2 = frequency_response(p2, f), g3 = frequency_response(p3, f);
  for (std::size_t k = 0; k < g.size(); ++k) {
    Eigen::MatrixXcd stacked(3, 4);
    stacked << g1[k], g2[k], g3[k];
    EXPECT_LE((g[k] - stacked).norm(), 1e-12 * (1.0 + stacked.norm())) << "frequency " << f(static_cast<Eigen::Index>(k));
  }
}

TEST(Assemble, MismatchedPartsAreRefused) {
  const StateSpace a = named(test::random_modal_system(1, 1, 2, 1), {"u1"}, {"y1", "y2"});
  StateSpace other_ts = named(test::random_modal_system(1, 1, 2, 2), {"u2"}, {"y1", "y2"});
  other_ts.Ts = 2.0;
  EXPECT_THROW(assemble_inputs({a, other_ts}), std::invalid_argument);
  const StateSpace swapped = named(test::random_modal_system(1, 1, 2, 3), {"u2"}, {"y2", "y1"});
  try {
    assemble_inputs({a, swapped});
    FAIL() << "swapped outputs accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("same sensors"), std::string::npos) << e.what();
  }
  const StateSpace same_input = named(test::random_modal_system(1, 1, 2, 4), {"u1"}, {"y1", "y2"});
  EXPECT_THROW(assemble_inputs({a, same_input}), std::invalid_argument);
  const StateSpace three_outputs = named(test::random_modal_system(1, 1, 3, 5), {"u3"}, {"y1", "y2", "y3"});
  EXPECT_THROW(assemble_inputs({a, three_outputs}), std::invalid_argument);
  EXPECT_THROW(assemble_inputs({}), std::invalid_argument);
}

}  // namespace test_unit_core_assemble

namespace test_unit_core_assemble_disturbance {

using namespace sysid;

// The disturbance input model is the innovation model scaled to unit white
// noise: its spectrum H L L' H^* equals the innovation model's H Lambda H^*, and
// beside a plant it adds one input per output (named w_<output>).
TEST(DisturbanceInputModel, UnitNoiseGivesTheInnovationSpectrum) {
  Eigen::MatrixXd A(2, 2), C(2, 2), K(2, 2), Lambda(2, 2);
  A << 0.9, 0.2, -0.2, 0.8;
  C << 1.0, 0.0, 0.5, 1.0;
  K << 0.3, 0.1, -0.1, 0.4;
  Lambda << 2.0, 0.3, 0.3, 0.5;
  StateSpace noise(A, Eigen::MatrixXd::Zero(2, 0), C, Eigen::MatrixXd::Zero(2, 0), 0.01);
  noise.output_names = {"y1", "y2"};
  const StateSpace w = disturbance_input_model(noise, K, Lambda);
  ASSERT_EQ(w.inputs(), 2);
  EXPECT_EQ(w.input_names, (std::vector<std::string>{"w_y1", "w_y2"}));
  const std::complex<double> z = std::exp(std::complex<double>(0.0, 0.7));
  const Eigen::MatrixXcd I = Eigen::MatrixXcd::Identity(2, 2);
  const Eigen::MatrixXcd H = C.cast<std::complex<double>>() * (z * I - A.cast<std::complex<double>>()).inverse() *
                                 K.cast<std::complex<double>>() + I;
  const Eigen::MatrixXcd G = w.C.cast<std::complex<double>>() * (z * I - w.A.cast<std::complex<double>>()).inverse() *
                                 w.B.cast<std::complex<double>>() + w.D.cast<std::complex<double>>();
  EXPECT_LT((G * G.adjoint() - H * Lambda.cast<std::complex<double>>() * H.adjoint()).norm(), 1e-12);

  StateSpace plant(Eigen::MatrixXd::Constant(1, 1, 0.5), Eigen::MatrixXd::Ones(1, 1), Eigen::MatrixXd::Ones(2, 1),
                   Eigen::MatrixXd::Zero(2, 1), 0.01);
  plant.input_names = {"u"};
  plant.output_names = {"y1", "y2"};
  const StateSpace gp = assemble_inputs({plant, w});
  EXPECT_EQ(gp.inputs(), 3);
  EXPECT_EQ(gp.order(), 3);
  EXPECT_EQ(gp.input_names, (std::vector<std::string>{"u", "w_y1", "w_y2"}));
}

TEST(DisturbanceInputModel, RefusesAModelWithoutItsNoiseDescription) {
  const StateSpace noise(Eigen::MatrixXd::Constant(1, 1, 0.5), Eigen::MatrixXd::Zero(1, 0), Eigen::MatrixXd::Ones(1, 1),
                         Eigen::MatrixXd::Zero(1, 0), 0.01);
  EXPECT_THROW(disturbance_input_model(noise, Eigen::MatrixXd(), Eigen::MatrixXd::Ones(1, 1)), std::invalid_argument);
  EXPECT_THROW(disturbance_input_model(noise, Eigen::MatrixXd::Ones(1, 1), -Eigen::MatrixXd::Ones(1, 1)), std::invalid_argument);
}

}  // namespace test_unit_core_assemble_disturbance
