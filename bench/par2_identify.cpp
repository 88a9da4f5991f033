/// @file
/// Purpose: the sysid side of the Par2 GU peer comparison (bench/run_peers.sh):
/// identify a model of the given order and horizon from the estimation log with
/// sysid::n4sid, time the identification call, and write the model JSON that the
/// common evaluator (par2_eval.cpp) scores like every peer's model.
///
/// Usage:
///   sysid_bench_par2_identify EST.csv --out MODEL.json [--order 10] [--horizon 20]
///       [--repeats 5] [--decimation 0] [--weighting n4sid|moesp|cva] [--rank-tolerance 1e-10]
///       [--tag sysid]
///
/// Method: the log is read once (not timed: the peers' drivers do not time their
/// CSV loading either); then n4sid runs `repeats` times on a fresh copy of the
/// data and the minimum wall time is reported (on a shared machine the minimum is
/// the least disturbed run). The data are given as they are: n4sid removes the
/// means itself, and they are the same estimation means that the peers' drivers
/// remove before calling their tools.
///
/// Output (one line, parsed by run_peers.sh):
///   RESULT tag=sysid status=ok fit_time_s=0.0123 cpu_s=0.0121 repeats=5 maxrss_mb=12.3 decimation=5 ...
/// or, when n4sid throws (exit code 3):
///   RESULT tag=sysid status=failed maxrss_mb=9.3 reason=<the exception's message>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <string>

#include "sysid/io/csv.hpp"
#include "sysid/io/model_json.hpp"
#include "sysid/subspace/n4sid.hpp"

namespace {

double cpu_now() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double max_rss_mb() {
  rusage r{};
  getrusage(RUSAGE_SELF, &r);
  return static_cast<double>(r.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

[[noreturn]] void usage(const std::string& why) {
  std::cerr << "sysid_bench_par2_identify: " << why
            << "\nusage: sysid_bench_par2_identify EST.csv --out MODEL.json [--order 10] [--horizon 20] [--repeats 5]"
               " [--decimation 0] [--weighting n4sid|moesp|cva] [--rank-tolerance 1e-10] [--tag sysid]\n";
  std::exit(1);
}

}  // namespace

int main(int argc, char** argv) {
  std::string est, out, tag = "sysid";
  sysid::N4sidOptions options;
  options.order = 10;
  options.horizon = 20;
  int repeats = 5;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    auto value = [&]() -> std::string {
      if (a + 1 >= argc) usage(arg + " needs a value");
      return argv[++a];
    };
    if (arg == "--out") out = value();
    else if (arg == "--order") options.order = std::stoi(value());
    else if (arg == "--horizon") options.horizon = std::stoi(value());
    else if (arg == "--repeats") repeats = std::stoi(value());
    else if (arg == "--decimation") options.decimation = std::stoi(value());
    else if (arg == "--rank-tolerance") options.rank_tolerance = std::stod(value());
    else if (arg == "--tag") tag = value();
    else if (arg == "--weighting") {
      const std::string w = value();
      if (w == "n4sid") options.weighting = sysid::SubspaceWeighting::n4sid;
      else if (w == "moesp") options.weighting = sysid::SubspaceWeighting::moesp;
      else if (w == "cva") options.weighting = sysid::SubspaceWeighting::cva;
      else usage("unknown weighting '" + w + "'");
    } else if (!arg.empty() && arg[0] == '-') usage("unknown option " + arg);
    else if (est.empty()) est = arg;
    else usage("more than one log given");
  }
  if (est.empty() || out.empty()) usage("need EST.csv and --out");
  if (repeats < 1) usage("need --repeats >= 1");

  try {
    sysid::LogOptions lo;
    lo.inputs = {"u"};
    lo.outputs = {"y"};
    const sysid::IoData data = sysid::read_log(est, lo);

    sysid::N4sidResult result;
    double best_wall = 1e300, best_cpu = 1e300;
    for (int r = 0; r < repeats; ++r) {
      sysid::IoData copy = data;  // n4sid scales its argument in place; the copy is outside the timed region
      const double c0 = cpu_now();
      const auto t0 = std::chrono::steady_clock::now();
      result = sysid::n4sid(std::move(copy), options);
      const auto t1 = std::chrono::steady_clock::now();
      best_cpu = std::min(best_cpu, cpu_now() - c0);
      best_wall = std::min(best_wall, std::chrono::duration<double>(t1 - t0).count());
    }

    sysid::ModelFile file;
    file.model = result.model;
    file.input_offset = result.input_offset;
    file.output_offset = result.output_offset;
    if (result.K.size() > 0) file.K = result.K;
    file.provenance = {{"method", sysid::to_string(options.weighting)}, {"order", result.order},
                       {"horizon", result.horizon}, {"data", est}, {"decimation", result.decimation}};
    sysid::write_model_json(out, file);

    for (const auto& w : result.warnings) std::cerr << "sysid warning: " << w << "\n";
    std::printf("RESULT tag=%s status=ok fit_time_s=%.6f cpu_s=%.6f repeats=%d maxrss_mb=%.1f decimation=%d horizon=%d est_fit=%.3f\n",
                tag.c_str(), best_wall, best_cpu, repeats, max_rss_mb(), result.decimation, result.horizon,
                result.fit_percent(0));
    return 0;
  } catch (const std::exception& e) {
    // A failure is a result too: the table reports it with its reason.
    std::cerr << "sysid_bench_par2_identify: " << e.what() << "\n";
    std::printf("RESULT tag=%s status=failed maxrss_mb=%.1f reason=%s\n", tag.c_str(), max_rss_mb(), e.what());
    return 3;
  }
}
