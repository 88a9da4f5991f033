// libFuzzer target for the augmented-model reader: what `sysid simulate` and
// `sysid diagnose` do with a model file, model_from_json_string then
// augmented_model_from_file (include/sysid/io/augmented_model_file.hpp), then a
// short simulation of what was read.
//
// Error contract checked: a bad file or a bad block -> sysid::DataError (caught).
// Anything else escaping is a bug and aborts; in particular a block the reader
// accepted must simulate (the reader validates the parameters so that the
// simulation's std::invalid_argument preconditions hold). Properties checked on
// success:
//  - augmented_model_to_file -> text -> read again gives the same blocks (kind,
//    channels, parameters bit for bit), substeps and nominal;
//  - a discrete nominal with its blocks simulates 16 samples without throwing.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_check.hpp"
#include "sysid/core/errors.hpp"
#include "sysid/diagnose/augmented_model.hpp"
#include "sysid/io/augmented_model_file.hpp"
#include "sysid/io/model_json.hpp"

namespace {

using sysid::fuzz::check;
using sysid::fuzz::same_bits;

void check_same_model(const sysid::AugmentedModel& a, const sysid::AugmentedModel& b) {
  check(same_bits(a.nominal.Ts, b.nominal.Ts) && same_bits(a.nominal.A, b.nominal.A) &&
            same_bits(a.nominal.B, b.nominal.B) && same_bits(a.nominal.C, b.nominal.C) &&
            same_bits(a.nominal.D, b.nominal.D),
        "round trip: nominal bit for bit");
  check(same_bits(a.x0, b.x0) && same_bits(a.input_offset, b.input_offset) &&
            same_bits(a.output_offset, b.output_offset),
        "round trip: x0 and offsets");
  check(a.blocks.size() == b.blocks.size(), "round trip: number of blocks");
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    const auto& x = a.blocks[k];
    const auto& y = b.blocks[k];
    check(x.kind == y.kind && x.input == y.input && x.output == y.output, "round trip: block kind and channels");
    check(x.params.size() == y.params.size(), "round trip: block parameter count");
    for (const auto& [name, value] : x.params)
      check(y.params.count(name) && same_bits(value, y.params.at(name)), "round trip: block parameter " + name);
  }
  // A file without blocks is written as a plain state-space file: no substeps.
  if (!a.blocks.empty()) check(a.substeps == b.substeps, "round trip: substeps");
}

/// The simulation verbs run a discrete nominal as read; keep the cost bounded for
/// the fuzzer's sake (the file size already bounds the order to a few dozen).
void check_simulates(const sysid::AugmentedModel& model) {
  if (!model.nominal.is_discrete()) return;  // the CLI discretises first, at the log's rate
  constexpr Eigen::Index samples = 16;
  const Eigen::Index m = model.nominal.inputs();
  Eigen::MatrixXd u(samples, m);
  for (Eigen::Index k = 0; k < samples; ++k)
    for (Eigen::Index j = 0; j < m; ++j) u(k, j) = std::sin(0.7 * static_cast<double>(k) + static_cast<double>(j));
  const Eigen::MatrixXd y = sysid::simulate_augmented(model, u);
  check(y.rows() == samples && y.cols() == model.nominal.outputs(), "simulation: samples x outputs");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(bytes), size);
  sysid::AugmentedModel model;
  try {
    model = sysid::augmented_model_from_file(sysid::model_from_json_string(text, "fuzz.json"), "fuzz.json");
  } catch (const sysid::DataError&) {
    return 0;
  }
  // From here on nothing may throw.
  const std::string written = sysid::model_to_json_string(sysid::augmented_model_to_file(model));
  sysid::AugmentedModel back;
  try {
    back = sysid::augmented_model_from_file(sysid::model_from_json_string(written, "round-trip.json"), "round-trip.json");
  } catch (const sysid::DataError& e) {
    sysid::fuzz::property_violated(std::string("an augmented model written by the library is refused: ") + e.what());
  }
  check_same_model(model, back);
  check_simulates(model);
  return 0;
}
