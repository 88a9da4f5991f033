// A project outside sysid links the installed package and uses it.
#include <sysid/config.hpp>
#include <sysid/core/state_space.hpp>
#include <sysid/io/model_json.hpp>

#include <iostream>

int main() {
  sysid::ModelFile file;
  file.model = sysid::StateSpace(Eigen::MatrixXd::Constant(1, 1, 0.5), Eigen::MatrixXd::Ones(1, 1),
                                 Eigen::MatrixXd::Ones(1, 1), Eigen::MatrixXd::Zero(1, 1), 0.01);
  const sysid::ModelFile back = sysid::model_from_json_string(sysid::model_to_json_string(file), "consumer");
  if (back.model.A(0, 0) != 0.5) return 1;
  std::cout << "sysid " << SYSID_VERSION_STRING << " consumer ok\n";
  return 0;
}
