#pragma once
/// @file
/// Purpose: one way to print a number in a message or a report line — with a
/// few significant digits ("97.17 Hz", "cond 4.23e+15") instead of
/// std::to_string's fixed six decimals ("4228148214493445.000000").
#include <cstdio>
#include <string>

namespace sysid {

/// `value` with `digits` significant digits (printf "%.*g"); a negative zero
/// prints as "0". NaN and Inf print as "nan" and "inf".
inline std::string format_number(double value, int digits = 4) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, value);
  std::string s = buf;
  if (s == "-0") s = "0";
  return s;
}

}  // namespace sysid
