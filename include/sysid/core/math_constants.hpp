#pragma once
/// @file
/// Purpose: constants the library's sources share (one definition, so no two
/// translation units carry their own copy).
#include <numbers>

namespace sysid {

/// 2 pi: radians per cycle, for Hz <-> rad/s.
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

}  // namespace sysid
