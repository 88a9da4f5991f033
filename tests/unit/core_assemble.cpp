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
