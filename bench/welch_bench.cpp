/// @file
/// Purpose: the performance target of issue 3: Welch H1 of an 8-input 8-output log
/// of 10^6 samples with nfft 4096, timed (minimum of 3 runs), to be compared with
/// scipy.signal.csd on the same data in the same run (bench/welch_scipy.py drives
/// both).
///
/// Usage:
///   sysid_bench_welch [--samples 1000000] [--nfft 4096] [--repeats 3] [--seed 1]
///                     [--write-data PATH] [--write-h PATH]
///
/// Method: 8 independent white Gaussian inputs (std::mt19937_64, seed), outputs
/// y = u M^T + 0.1 e with M an 8 x 8 standard normal matrix and e white (the
/// timing does not depend on the system; a static one makes the check exact:
/// H1 -> M at every frequency). sysid::frf with Hann window, 50 % overlap, mean
/// detrend per segment (scipy's defaults), timed around the call (spectra, H1
/// solve, coherences and bounds). Prints `welch_h1_seconds <min>` and the worst
/// |H1 - M| as a check.
/// --write-data: the 10^6 x 16 matrix [u y] as raw little-endian float64,
/// column-major (column k is samples k*N .. k*N+N-1), for the Python side.
/// --write-h: H1 at every frequency as raw complex128, bins x 8 x 8 (output-major,
/// H[k][i][j] at (k*64 + i*8 + j)), so Python can compare its result.
#include <sysid/spectral/frf.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <string>

namespace {

void write_raw(const std::string& path, const void* data, std::size_t bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  if (!f) {
    std::fprintf(stderr, "cannot write %s\n", path.c_str());
    std::exit(2);
  }
}

}  // namespace

int main(int argc, char** argv) {
  Eigen::Index samples = 1000000, nfft = 4096;
  int repeats = 3;
  std::uint64_t seed = 1;
  std::string data_path, h_path;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--samples") samples = std::stol(v);
    else if (k == "--nfft") nfft = std::stol(v);
    else if (k == "--repeats") repeats = std::stoi(v);
    else if (k == "--seed") seed = std::stoull(v);
    else if (k == "--write-data") data_path = v;
    else if (k == "--write-h") h_path = v;
    else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 1;
    }
  }
  const Eigen::Index m = 8, l = 8;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd M(l, m);
  for (Eigen::Index i = 0; i < M.size(); ++i) M.data()[i] = g(rng);
  Eigen::MatrixXd uy(samples, m + l);
  for (Eigen::Index c = 0; c < m; ++c)
    for (Eigen::Index r = 0; r < samples; ++r) uy(r, c) = g(rng);
  uy.rightCols(l) = uy.leftCols(m) * M.transpose();
  for (Eigen::Index c = m; c < m + l; ++c)
    for (Eigen::Index r = 0; r < samples; ++r) uy(r, c) += 0.1 * g(rng);
  if (!data_path.empty()) write_raw(data_path, uy.data(), static_cast<std::size_t>(uy.size()) * sizeof(double));

  const double fs = 1000.0;
  sysid::IoData data(uy.leftCols(m), uy.rightCols(l), 1.0 / fs);
  uy.resize(0, 0);
  sysid::FrfOptions o;
  o.welch.nfft = nfft;
  o.welch.overlap = 0.5;
  o.welch.window = sysid::WindowType::hann;
  o.welch.detrend = sysid::Detrend::mean;
  double best = std::numeric_limits<double>::infinity();
  sysid::FrfResult r;
  for (int k = 0; k < repeats; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    r = sysid::frf(data, o);
    const auto t1 = std::chrono::steady_clock::now();
    best = std::min(best, std::chrono::duration<double>(t1 - t0).count());
  }
  double worst = 0.0;
  for (std::size_t b = 1; b < r.H.size(); ++b) worst = std::max(worst, (r.H[b] - M.cast<std::complex<double>>()).cwiseAbs().maxCoeff());
  std::printf("samples %ld inputs %ld outputs %ld nfft %ld segments %ld\n", static_cast<long>(samples), static_cast<long>(m),
              static_cast<long>(l), static_cast<long>(r.nfft), static_cast<long>(r.segments.front()));
  std::printf("welch_h1_seconds %.4f (min of %d)\n", best, repeats);
  std::printf("max |H1 - M| over f > 0: %.3g\n", worst);
  if (!h_path.empty()) {
    std::vector<std::complex<double>> h(r.H.size() * static_cast<std::size_t>(l * m));
    for (std::size_t b = 0; b < r.H.size(); ++b)
      for (Eigen::Index i = 0; i < l; ++i)
        for (Eigen::Index j = 0; j < m; ++j) h[b * static_cast<std::size_t>(l * m) + static_cast<std::size_t>(i * m + j)] = r.H[b](i, j);
    write_raw(h_path, h.data(), h.size() * sizeof(std::complex<double>));
  }
  return 0;
}
