#pragma once
/// @file
/// Purpose: name the inputs of a MIMO record that carry the same signal (up to
/// scale and offset), so an identification verb can say "u1 and u2 are
/// collinear: only their combined effect is identifiable" instead of a bare
/// condition number.
///
/// Method: the sample correlation of every pair of mean-removed inputs over all
/// experiments; a pair with |r| >= threshold is collinear. (Collinearity of three
/// or more inputs without a collinear pair shows as an ill-conditioned regression,
/// which the verbs report separately.)
#include <cmath>
#include <string>
#include <vector>

#include "sysid/core/io_data.hpp"

namespace sysid {

/// One warning per collinear input pair (empty when none). `who` prefixes the
/// message ("n4sid", "arx", ...; empty: no prefix).
inline std::vector<std::string> collinear_input_warnings(const IoData& data, const std::string& who,
                                                         double threshold = 1.0 - 1e-6) {
  std::vector<std::string> out;
  const Eigen::Index m = data.inputs();
  if (m < 2) return out;
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(m);
  double count = 0.0;
  for (const auto& e : data.experiments) {
    mean += e.u.colwise().sum().transpose();
    count += static_cast<double>(e.samples());
  }
  mean /= count;
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(m, m);
  for (const auto& e : data.experiments) {
    const Eigen::MatrixXd centred = e.u.rowwise() - mean.transpose();
    gram.noalias() += centred.transpose() * centred;
  }
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = i + 1; j < m; ++j) {
      const double scale = std::sqrt(gram(i, i) * gram(j, j));
      if (!(scale > 0.0)) continue;  // a constant input is reported elsewhere
      const double r = gram(i, j) / scale;
      if (std::abs(r) >= threshold)
        out.push_back((who.empty() ? std::string() : who + ": ") + "inputs " + data.input_name(i) + " and " + data.input_name(j) +
                      " are collinear (correlation " + std::to_string(r) +
                      "): only their combined effect can be identified, not each one's; excite them independently");
    }
  return out;
}

}  // namespace sysid
