// Implementation of core/flush_subnormals.hpp (why and how there).
#include <sysid/core/flush_subnormals.hpp>

#if defined(__x86_64__) || defined(_M_X64)
#include <xmmintrin.h>
#endif

namespace sysid {

namespace {

#if defined(__x86_64__) || defined(_M_X64)
// MXCSR bit 15 (FTZ: subnormal results become zero) and bit 6 (DAZ: subnormal
// operands read as zero); Intel SDM vol. 1, 10.2.3. Both are needed: FTZ alone
// leaves the assists on subnormal inputs.
constexpr unsigned kFlushBits = 0x8040u;
unsigned long long read_mode() { return _mm_getcsr(); }
void write_mode(unsigned long long mode) { _mm_setcsr(static_cast<unsigned>(mode)); }
unsigned long long flushing(unsigned long long mode) { return mode | kFlushBits; }
constexpr bool kSupported = true;
#elif defined(__aarch64__)
// FPCR bit 24 (FZ): subnormal operands and results are flushed to zero (Arm ARM, C5.2.8).
constexpr unsigned long long kFlushBits = 1ull << 24;
unsigned long long read_mode() {
  unsigned long long fpcr;
  __asm__ __volatile__("mrs %0, fpcr" : "=r"(fpcr));
  return fpcr;
}
void write_mode(unsigned long long mode) { __asm__ __volatile__("msr fpcr, %0" : : "r"(mode)); }
unsigned long long flushing(unsigned long long mode) { return mode | kFlushBits; }
constexpr bool kSupported = true;
#else
unsigned long long read_mode() { return 0; }
void write_mode(unsigned long long) {}
unsigned long long flushing(unsigned long long mode) { return mode; }
constexpr bool kSupported = false;
#endif

}  // namespace

ScopedFlushSubnormals::ScopedFlushSubnormals() : m_saved_mode(read_mode()) { write_mode(flushing(m_saved_mode)); }

ScopedFlushSubnormals::~ScopedFlushSubnormals() { write_mode(m_saved_mode); }

bool ScopedFlushSubnormals::supported() { return kSupported; }

}  // namespace sysid
