#pragma once
// Whether this test binary is built with AddressSanitizer (the asan-ubsan preset).
// The longest acceptance runs use it to run a representative part of their cases
// under the sanitizers (the same code paths and assertions, fewer repetitions),
// where they cost 10-20 times their optimised time; the optimised build runs
// every case.
namespace sysid::test {

#if defined(__SANITIZE_ADDRESS__)
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
