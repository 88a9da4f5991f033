#pragma once
// Whether this test binary is built with AddressSanitizer (the asan-ubsan preset).
// The longest acceptance runs use it to run a representative part of their cases
// under the sanitizers (the same code paths and assertions, fewer repetitions or
// shorter records), where they cost 10-20 times their optimised time; the
// optimised build runs every case.
//
// Compiling the tests with -DSYSID_TEST_SANITIZER_SIZES=1 gives the optimised
// build the sanitizer sizes too: that is how the reduced cases are checked to
// hold their assertions without waiting for a sanitized build
// (cmake --preset ci -DCMAKE_CXX_FLAGS=-DSYSID_TEST_SANITIZER_SIZES=1).
namespace sysid::test {

#if defined(SYSID_TEST_SANITIZER_SIZES) && SYSID_TEST_SANITIZER_SIZES
inline constexpr bool kSanitized = true;
#elif defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

}  // namespace sysid::test
