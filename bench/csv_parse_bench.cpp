/// @file
/// Purpose: throughput of sysid::read_csv (MB/s) on a generated numeric log of
/// about 100 MB with 17 columns (t, u1..u8, y1..y8), the size and shape of a long
/// multi-channel rig recording. Target: >= 200 MB/s in Release.
///
/// Plain std::chrono program (not wired into CMake). Build against a Release build
/// of the library, e.g.
///
///   cmake --build build/release --target sysid
///   g++ -std=c++20 -O2 -DNDEBUG -I include $(pkg-config --cflags eigen3)
///       bench/csv_parse_bench.cpp build/release/libsysid.a -o csv_parse_bench     (one line)
///   ./csv_parse_bench [megabytes=100] [file=/tmp/sysid_csv_bench.csv]
///
/// Method: the file is written once (time stamps with 6 decimals, signals with 9
/// significant digits, as a logger would print them), then each measurement is the
/// best of 5 runs (the page cache is warm after the first; best-of filters out
/// other processes on a shared machine). Three figures: read_csv (read + parse),
/// read_csv_string (parse only), read_log (parse + column selection + Ts check).
#include <algorithm>
#include <charconv>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <random>
#include <string>

#include "sysid/io/atomic_file.hpp"
#include "sysid/io/csv.hpp"

namespace {

std::string generate(double megabytes) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> normal;
  std::string s = "t,u1,u2,u3,u4,u5,u6,u7,u8,y1,y2,y3,y4,y5,y6,y7,y8\n";
  const auto target = static_cast<std::size_t>(megabytes * 1e6);
  s.reserve(target + 512);
  char buf[64];
  for (long k = 0; s.size() < target; ++k) {
    auto r = std::to_chars(buf, buf + sizeof buf, static_cast<double>(k) * 1e-4, std::chars_format::fixed, 6);
    s.append(buf, r.ptr);
    for (int c = 0; c < 16; ++c) {
      s += ',';
      r = std::to_chars(buf, buf + sizeof buf, normal(rng), std::chars_format::general, 9);
      s.append(buf, r.ptr);
    }
    s += '\n';
  }
  return s;
}

double cpu_now() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// Best of `runs`: wall-clock seconds and process CPU seconds (the latter is what
/// to quote on a machine shared with other jobs: it does not count time the
/// process spent waiting for a core).
struct Timing {
  double wall = 1e300, cpu = 1e300;
};

template <class F>
Timing best_of(int runs, F&& f) {
  Timing best;
  for (int i = 0; i < runs; ++i) {
    const double c0 = cpu_now();
    const auto t0 = std::chrono::steady_clock::now();
    f();
    const auto t1 = std::chrono::steady_clock::now();
    const double c1 = cpu_now();
    best.wall = std::min(best.wall, std::chrono::duration<double>(t1 - t0).count());
    best.cpu = std::min(best.cpu, c1 - c0);
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  const double megabytes = argc > 1 ? std::atof(argv[1]) : 100.0;
  const std::string path = argc > 2 ? argv[2] : "/tmp/sysid_csv_bench.csv";

  const std::string text = generate(megabytes);
  sysid::write_file_atomically(path, text);
  const double mb = static_cast<double>(text.size()) / 1e6;

  Eigen::Index rows = 0;
  const Timing t_file = best_of(5, [&] { rows = sysid::read_csv(path).values.rows(); });
  const Timing t_mem = best_of(5, [&] { rows = sysid::read_csv_string(text, "mem").values.rows(); });
  sysid::LogOptions o;
  o.inputs = {"u1", "u2", "u3", "u4", "u5", "u6", "u7", "u8"};
  o.outputs = {"y1", "y2", "y3", "y4", "y5", "y6", "y7", "y8"};
  double ts = 0.0;
  const Timing t_log = best_of(5, [&] { ts = sysid::read_log(path, o).Ts; });

  std::printf("file: %s, %.1f MB, %ld rows x 17 columns, Ts = %g s\n", path.c_str(), mb, static_cast<long>(rows), ts);
  std::printf("%-34s %10s %10s\n", "", "MB/s wall", "MB/s CPU");
  std::printf("%-34s %10.1f %10.1f\n", "read_csv (read + parse)", mb / t_file.wall, mb / t_file.cpu);
  std::printf("%-34s %10.1f %10.1f\n", "read_csv_string (parse only)", mb / t_mem.wall, mb / t_mem.cpu);
  std::printf("%-34s %10.1f %10.1f\n", "read_log (parse + select + Ts)", mb / t_log.wall, mb / t_log.cpu);
  std::remove(path.c_str());
  return 0;
}
