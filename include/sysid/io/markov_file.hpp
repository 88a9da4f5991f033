#pragma once
/// @file
/// Purpose: Markov-parameter files (impulse responses / FIR taps), the hand-over
/// between `sysid lms` / `sysid okid` and `sysid era`:
///
///   {"type": "markov", "Ts": 0.0009765625, "inputs": ["u5"], "outputs": ["y1", ...],
///    "markov": [ h0, h1, ... ],   // each an l x m row-major nested list; h0 = D
///    "provenance": {...}}
///
/// Numbers are written with 17 significant digits (exact round trip), the file
/// atomically (io/atomic_file.hpp). Reading errors are sysid::DataError naming
/// the file and what was expected.
#include <sysid/realization/markov_parameters.hpp>

#include <nlohmann/json.hpp>
#include <string>

namespace sysid {

struct MarkovFile {
  MarkovParameters markov;
  nlohmann::json provenance = nlohmann::json::object();
};

void write_markov_file(const std::string& path, const MarkovFile& file);
MarkovFile read_markov_file(const std::string& path);

}  // namespace sysid
