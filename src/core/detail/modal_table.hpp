#pragma once
/// @file
/// Internals of core/modal_table.hpp shared by several compiled parts
/// (src/core/modal_table.cpp, src/reduce/modal_truncation.cpp); defined in src/core/modal_table.cpp.
#include <sysid/core/modal_table.hpp>

#include <complex>

namespace sysid::detail {

/// The Mode of pole p (one of a conjugate pair when `pair`) of a model with sample
/// time Ts (0: continuous), by the map of the core/modal_table.hpp file comment.
Mode make_mode(std::complex<double> p, double Ts, bool pair);

}  // namespace sysid::detail
