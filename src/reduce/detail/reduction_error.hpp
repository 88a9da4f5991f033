#pragma once
/// @file
/// Internals of reduce/reduction_error.hpp shared by several compiled parts
/// (src/reduce/reduction_error.cpp, src/reduce/modal_truncation.cpp); defined in
/// src/reduce/reduction_error.cpp.
#include <Eigen/Dense>

namespace sysid::detail {

/// sigma_max of a small complex matrix from its smaller Gram matrix (Inf if an
/// entry is not finite, 0 for an empty matrix).
double max_singular_value(const Eigen::MatrixXcd& G);

}  // namespace sysid::detail
