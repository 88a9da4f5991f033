#pragma once
/// @file
/// Purpose: run the long linear recursions of the library (the B/D/x0
/// regressors, simulation, IIR filtering) without the cost of subnormal
/// numbers.
///
/// Why: the impulse response of a stable system decays geometrically, and a
/// recursion that runs over a long record carries it down through the
/// subnormal range (|x| < 2.2e-308) on its way to zero. On Intel cores every
/// floating-point operation with a subnormal operand or result takes a
/// microcode assist of ~100 cycles instead of 4. On the Par2 log (40 000
/// samples, order 10) the x0 regressors (C A^t), in their recursion and in the
/// Gram updates of their rows, made n4sid 2.1x slower: 15.6 ms against 7.3 ms
/// on the 2-core Xeon CI machine. A 10th-order model
/// simulated over 200 000 samples with the input zero after the first 1 000 took
/// 115 ms against 6.6 ms. (AMD's Zen cores handle most subnormal operations
/// without an assist; the EPYC machine of bench/README.md measured the Par2
/// n4sid at 5.2 ms before the flush.) Values that small are ~1e-300 of the
/// scale of anything a fit or a simulation reports: flushing them changes no
/// result the data can determine (the Par2 model files are byte-identical with
/// and without).
///
/// Method: the guard sets the floating-point unit's flush-to-zero mode for the
/// calling thread (x86-64: MXCSR's FTZ and DAZ bits; AArch64: FPCR's FZ bit)
/// and restores the previous mode when it goes out of scope, so it nests and
/// leaves the caller's mode as it found it, also when an exception passes.
/// The mode is per thread: a parallel_for body that runs a recursion sets its
/// own guard. A thread started inside the scope inherits the mode (Linux copies
/// the floating-point environment): start none there (parallel_for's helpers
/// would keep flushing for the life of the process). On other targets the guard does nothing
/// and the recursions are only slower (`supported()` is false).
///
/// Where: around the recursions (core/simulate.hpp, signal/sos_filter.hpp,
/// signal/polynomial_filter.hpp, the B/D/x0 and x0 regressors, diagnose's
/// augmented simulation), whose operands are a decaying state and measured data;
/// no instrument resolves 1e-308, so a subnormal data value is zero too.

namespace sysid {

class ScopedFlushSubnormals {
 public:
  ScopedFlushSubnormals();
  ~ScopedFlushSubnormals();
  ScopedFlushSubnormals(const ScopedFlushSubnormals&) = delete;
  ScopedFlushSubnormals& operator=(const ScopedFlushSubnormals&) = delete;

  /// Whether this target has a flush-to-zero mode the guard sets.
  static bool supported();

 private:
  unsigned long long m_saved_mode = 0;
};

}  // namespace sysid
