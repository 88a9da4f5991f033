// libFuzzer target for the model JSON reader (include/sysid/io/model_json.hpp):
// model_from_json_string on the whole input.
//
// Error contract checked: invalid JSON or an invalid model -> sysid::DataError
// (caught). Anything else escaping the reader, or any exception from writing a
// model the reader accepted, is a bug and aborts. Properties checked on success
// (the round trip model_json.hpp promises: every number bit-exact, every unknown
// key kept):
//  - model_to_json_string accepts what model_from_json_string returned;
//  - reading that text back gives the same model, offsets, names, provenance and
//    extra keys;
//  - writing it again gives the same text (the layout is a fixed point).
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_check.hpp"
#include "sysid/core/errors.hpp"
#include "sysid/io/model_json.hpp"

namespace {

using sysid::fuzz::check;
using sysid::fuzz::same_bits;

void check_same_file(const sysid::ModelFile& a, const sysid::ModelFile& b) {
  check(a.type == b.type, "round trip: type");
  check(same_bits(a.model.Ts, b.model.Ts), "round trip: Ts");
  check(same_bits(a.model.A, b.model.A) && same_bits(a.model.B, b.model.B) && same_bits(a.model.C, b.model.C) &&
            same_bits(a.model.D, b.model.D),
        "round trip: A, B, C, D bit for bit");
  check(same_bits(a.K, b.K) && same_bits(a.noise_covariance, b.noise_covariance) && same_bits(a.x0, b.x0),
        "round trip: K, noise_covariance, x0 bit for bit");
  check(same_bits(a.input_offset, b.input_offset) && same_bits(a.output_offset, b.output_offset),
        "round trip: offsets bit for bit");
  check(a.model.input_names == b.model.input_names && a.model.output_names == b.model.output_names,
        "round trip: channel names");
  check(a.provenance == b.provenance, "round trip: provenance");
  check(a.extra == b.extra, "round trip: unknown keys kept");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(bytes), size);
  sysid::ModelFile file;
  try {
    file = sysid::model_from_json_string(text, "fuzz.json");
  } catch (const sysid::DataError&) {
    return 0;
  }
  // From here on nothing may throw: an accepted model must be writable and read back.
  const std::string written = sysid::model_to_json_string(file);
  sysid::ModelFile back;
  try {
    back = sysid::model_from_json_string(written, "round-trip.json");
  } catch (const sysid::DataError& e) {
    sysid::fuzz::property_violated(std::string("model_to_json_string wrote text the reader refuses: ") + e.what());
  }
  check_same_file(file, back);
  check(sysid::model_to_json_string(back) == written, "writing the re-read model gives the same text");
  return 0;
}
