#include <sysid/core/detail/lagged_sums.hpp>

#include <algorithm>
#include <vector>

namespace sysid::detail {

namespace {

constexpr Eigen::Index kCorrelateBlock = 256;  // terms per restarted Dot2 (header: error ~ block * u^2)

/// Sums of a[t] * b[t + q0 + q] for t in [t0, t1), q < Lags, by restarted Dot2
/// (header): the running sum in h[q] and the error terms in e[q], written at
/// the end. The Lags partial sums live in registers over the whole t loop:
/// an array of them read and written in memory at every t made the kernel
/// bound by loads and stores (2.3 ns per term for 33 lags on one AVX2 core
/// against 1.1 ns in registers, bench/README.md).
template <bool Fma, int Lags>
[[gnu::always_inline]] inline void correlate_tile(const double* a, const double* b, Eigen::Index t0, Eigen::Index t1,
                                                  Eigen::Index q0, double* h, double* e) {
  double hi[Lags] = {}, lo[Lags] = {};
  for (Eigen::Index t = t0; t < t1; ++t) {
    const double at = a[t];
    const double* __restrict bt = b + t + q0;
    for (int q = 0; q < Lags; ++q) {
      const DoubleDouble p = Fma ? two_prod_fma(at, bt[q]) : two_prod_dekker(at, bt[q]);
      const DoubleDouble s = two_sum(hi[q], p.hi);
      hi[q] = s.hi;
      lo[q] += p.lo + s.lo;
    }
  }
  for (int q = 0; q < Lags; ++q) {
    h[q] = hi[q];
    e[q] = lo[q];
  }
}

/// The kernel of correlate_double_double: tiles of 16 lags, then 8, 4 and the
/// rest. Every (t, q) sees the same operations in the same order whatever the
/// tile, and the product is exact either way (one fma, or Dekker's splitting),
/// so every instance returns the same bits.
template <bool Fma>
[[gnu::always_inline]] inline void correlate_kernel(const double* a, const double* b, Eigen::Index count,
                                                    Eigen::Index lags, DoubleDouble* out) {
  std::vector<double> hi(static_cast<std::size_t>(lags)), lo(static_cast<std::size_t>(lags));
  double* h = hi.data();
  double* e = lo.data();
  for (Eigen::Index t0 = 0; t0 < count; t0 += kCorrelateBlock) {
    const Eigen::Index t1 = std::min(count, t0 + kCorrelateBlock);
    Eigen::Index q = 0;
    for (; q + 16 <= lags; q += 16) correlate_tile<Fma, 16>(a, b, t0, t1, q, h + q, e + q);
    if (q + 8 <= lags) {
      correlate_tile<Fma, 8>(a, b, t0, t1, q, h + q, e + q);
      q += 8;
    }
    if (q + 4 <= lags) {
      correlate_tile<Fma, 4>(a, b, t0, t1, q, h + q, e + q);
      q += 4;
    }
    switch (lags - q) {
      case 3:
        correlate_tile<Fma, 3>(a, b, t0, t1, q, h + q, e + q);
        break;
      case 2:
        correlate_tile<Fma, 2>(a, b, t0, t1, q, h + q, e + q);
        break;
      case 1:
        correlate_tile<Fma, 1>(a, b, t0, t1, q, h + q, e + q);
        break;
      default:
        break;
    }
    for (Eigen::Index r = 0; r < lags; ++r) out[r] += two_sum(h[r], e[r]);
  }
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(FP_FAST_FMA)
#define SYSID_CORRELATE_DISPATCH 1
// The portable build (x86-64 baseline: SSE2, no FMA) splits every product by
// Dekker's 17 flops, two lanes at a time. The same kernel compiled for AVX2 +
// FMA and for AVX-512 ran 3.5x and 4.7x faster (40 000 terms, 33 lags, one
// core, before the register tiles; with them AVX2 + FMA 1.1 ns per term against
// 2.2 for the portable kernel); the processor's features choose at run time. `flatten` inlines the
// helpers so that they are compiled for the target too (std::fma left as a
// call would be the slow library function).
[[gnu::target("avx2,fma"), gnu::flatten]] void correlate_avx2(const double* a, const double* b, Eigen::Index count,
                                                              Eigen::Index lags, DoubleDouble* out) {
  correlate_kernel<true>(a, b, count, lags, out);
}

[[gnu::target("avx512f,avx2,fma"), gnu::flatten]] void correlate_avx512(const double* a, const double* b,
                                                                        Eigen::Index count, Eigen::Index lags,
                                                                        DoubleDouble* out) {
  correlate_kernel<true>(a, b, count, lags, out);
}

enum class CorrelateKernel { portable, avx2, avx512 };

CorrelateKernel fastest_correlate_kernel() {
  static const CorrelateKernel kernel = [] {
    if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) return CorrelateKernel::portable;
    return __builtin_cpu_supports("avx512f") ? CorrelateKernel::avx512 : CorrelateKernel::avx2;
  }();
  return kernel;
}
#endif

}  // namespace

void correlate_double_double(const double* a, const double* b, Eigen::Index count, Eigen::Index lags,
                             DoubleDouble* out) {
#if defined(FP_FAST_FMA)
  correlate_kernel<true>(a, b, count, lags, out);
#else
#ifdef SYSID_CORRELATE_DISPATCH
  switch (fastest_correlate_kernel()) {
    case CorrelateKernel::avx512:
      return correlate_avx512(a, b, count, lags, out);
    case CorrelateKernel::avx2:
      return correlate_avx2(a, b, count, lags, out);
    case CorrelateKernel::portable:
      break;
  }
#endif
  correlate_kernel<false>(a, b, count, lags, out);
#endif
}

void correlate_double_double_without_fma(const double* a, const double* b, Eigen::Index count, Eigen::Index lags,
                                         DoubleDouble* out) {
  correlate_kernel<false>(a, b, count, lags, out);
}

}  // namespace sysid::detail
