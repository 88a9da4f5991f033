// Acceptance of the LMS/ERA/reduction issue, items 6 and 7: the isolator
// reproduction on the experiments of data/isolator/generate_isolator.cpp.
//  - Eight single-actuator chirp experiments: LMS FIR (2048 taps, K = 3) -> ERA
//    order 14 each -> assembled order 112 -> balanced truncation to the orders
//    where the paper's HSV ratio is 0.4 % and 2 %; in-band (10-400 Hz) FRF error
//    of every model against the non-parametric H1 FRF of the experiments and
//    against the true model.
//  - Three hammer-tap records: OKID Markov parameters -> ERA order 8 each ->
//    assembled 24 -> reduced to 10 with a ratio below 3 %.
// The bound on the FRF errors: the same pipeline run on the exact Markov
// parameters of the true model (the "floor") shows what the fixed orders 14 / 8
// and the reductions cost by themselves; identification from the noisy logs may
// add at most kFloorMargin to the relative in-band error. Measured (data/README.md,
// "Reproductions (LMS/ERA/reduction issue)"): +0.2 points at most, so the margin
// of 1 point is five times what the data cost.
#include <sysid/core/frequency_response.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/markov_file.hpp>
#include <sysid/io/model_json.hpp>
#include <sysid/realization/markov_parameters.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "run_cli.hpp"
#include "sanitizers.hpp"

namespace test_acceptance_realization_isolator {

using namespace sysid;
using namespace sysid::test;

namespace {

const std::string kData = std::string(SYSID_TEST_DATA_DIR) + "/isolator";
const std::string kOutputs = "y1,y2,y3,y4,y5,y6,y7,y8";

// The FIR must span the decay of the slowest mode (18 Hz, damping 1 %: time
// constant 0.88 s = 905 samples at 1024 Hz). 2048 taps leave 0.7 % of the
// impulse response's energy in the unmodelled tail; the 256 taps of the issue's
// example leave 41 %, and the realised models miss the true FRF by 60 %
// (data/README.md).
constexpr int kTaps = 2048;
// ERA Hankel of 64 block rows (512 x 1983): every lag is used on the column side,
// and the SVD takes 0.4 s instead of the 4.6 s of the near-square default.
const std::string kEraRowBlocks = "64";
constexpr double kBandLoHz = 10.0, kBandHiHz = 400.0;  // all eight modes, 18-330 Hz
constexpr double kFloorMargin = 0.01;
// Under the sanitizers (tests/support/sanitizers.hpp) the LMS runs on the first
// two of the eight experiments and the other six take the exact Markov parameters:
// the same verbs and assertions, while the eight 2048-tap LMS runs were about 70 %
// of this test's 133 s under ASan + UBSan (2026-11-29). The optimised build runs
// the LMS on all eight.
constexpr int kSanitizedLmsExperiments = 2;

/// Column `j` of `sys` (one input), as one experiment sees it.
StateSpace column(const StateSpace& sys, Eigen::Index j) {
  StateSpace g(sys.A, sys.B.col(j), sys.C, sys.D.col(j), sys.Ts);
  g.input_names = {sys.input_names.at(static_cast<std::size_t>(j))};
  g.output_names = sys.output_names;
  return g;
}

/// The exact Markov parameters h[0..count] of input j of `truth`, as a file.
void write_exact_markov(const StateSpace& truth, Eigen::Index j, int count, const std::string& out) {
  write_markov_file(out, {markov_parameters(column(truth, j), count), {{"method", "exact"}}});
}

void run_ok(const std::vector<std::string>& args) {
  const CliResult r = run_cli(args);
  ASSERT_EQ(r.exit_code, 0) << describe(r);
}

/// The multi-step NLMS FIR of one experiment as Markov parameters (the paper's
/// K = 3 with gamma 0.5, 0.3, 0.2).
void lms_markov(const std::string& log, const std::string& input, int taps, const std::string& out) {
  run_ok({"lms", log, "--inputs", input, "--outputs", kOutputs, "--taps", std::to_string(taps), "--steps", "3", "--gamma",
          "0.5,0.3,0.2", "--mu", "0.5", "--out", out});
}

/// ERA of one experiment at `order`: of its estimated Markov parameters (the model
/// `name`, appended to `parts`) and of the exact ones of input j of `truth` (the
/// floor, appended to `floor_parts`).
void realise_with_floor(const TempDir& dir, const std::string& estimate, const StateSpace& truth, Eigen::Index j, int count,
                        int order, const std::string& name, std::vector<std::string>& parts,
                        std::vector<std::string>& floor_parts) {
  const std::string o = std::to_string(order), exact = dir / ("exact_" + name + ".json");
  run_ok({"era", estimate, "--order", o, "--row-blocks", kEraRowBlocks, "--out", dir / (name + ".json")});
  write_exact_markov(truth, j, count, exact);
  run_ok({"era", exact, "--order", o, "--row-blocks", kEraRowBlocks, "--out", dir / ("floor_" + name + ".json")});
  parts.push_back(dir / (name + ".json"));
  floor_parts.push_back(dir / ("floor_" + name + ".json"));
}


/// Sums for a relative in-band error sqrt(sum |G - H|^2 / sum |H|^2).
struct BandError {
  double num = 0.0, den = 0.0;
  double relative() const { return std::sqrt(num / den); }
};

/// Model input j (all outputs) against the H1 estimate of `frf_csv` (input `u`)
/// at its frequency lines in the band.
void add_h1_error(BandError& e, const StateSpace& model, Eigen::Index j, const std::string& frf_csv, const std::string& u) {
  const CsvTable t = read_csv(frf_csv);
  const Eigen::VectorXd f_all = t.values.col(t.column("f_hz"));
  std::vector<Eigen::Index> rows;
  for (Eigen::Index k = 0; k < f_all.size(); ++k)
    if (f_all(k) >= kBandLoHz && f_all(k) <= kBandHiHz) rows.push_back(k);
  Eigen::VectorXd f(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t k = 0; k < rows.size(); ++k) f(static_cast<Eigen::Index>(k)) = f_all(rows[k]);
  const auto g = frequency_response(model, f);
  for (std::size_t k = 0; k < rows.size(); ++k)
    for (Eigen::Index i = 0; i < model.outputs(); ++i) {
      const std::string pair = "_y" + std::to_string(i + 1) + "_" + u;
      const std::complex<double> h(t.values(rows[k], t.column("re" + pair)), t.values(rows[k], t.column("im" + pair)));
      e.num += std::norm(g[k](i, j) - h);
      e.den += std::norm(h);
    }
}

/// Relative in-band error of `model` against `truth` (all inputs and outputs) on
/// a 0.05 Hz grid, fine enough for the narrowest resonance (18 Hz, half-power
/// bandwidth 0.36 Hz).
double truth_error(const StateSpace& model, const StateSpace& truth) {
  const auto n = static_cast<Eigen::Index>(std::lround((kBandHiHz - kBandLoHz) / 0.05)) + 1;
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(n, kBandLoHz, kBandHiHz);
  const auto g = frequency_response(model, f), g0 = frequency_response(truth, f);
  BandError e;
  for (std::size_t k = 0; k < g.size(); ++k) {
    e.num += (g[k] - g0[k]).squaredNorm();
    e.den += g0[k].squaredNorm();
  }
  return e.relative();
}

/// What `sysid reduce` printed.
struct Reduction {
  int order = 0;
  double ratio = 0, bound = 0, hinf_error = 0;
  std::string out;
};

Reduction reduce(const std::string& model, const std::string& option, const std::string& value, const std::string& out) {
  const CliResult r = run_cli({"reduce", model, option, value, "--out", out});
  EXPECT_EQ(r.exit_code, 0) << describe(r);
  Reduction red;
  red.out = r.out;
  red.order = static_cast<int>(number_after(r.out, "-> "));
  red.ratio = number_after(r.out, "discarded HSV ratio ");
  red.bound = number_after(r.out, "2*sum(discarded HSV) = ");
  red.hinf_error = number_after(r.out, "points) ");
  return red;
}

StateSpace model_of(const std::string& path) { return read_model_json(path).model; }

}  // namespace

TEST(IsolatorReproduction, ChirpExperimentsLmsEraAssembleReduce) {
  TempDir dir;
  const StateSpace truth = model_of(kData + "/avi8x8_true.json");
  std::vector<std::string> parts{"assemble"}, floor_parts{"assemble"};
  for (int j = 1; j <= 8; ++j) {
    const std::string n = std::to_string(j), log = kData + "/exp" + n + ".csv";
    if (kSanitized && j > kSanitizedLmsExperiments)
      write_exact_markov(truth, j - 1, kTaps - 1, dir / ("fir" + n + ".json"));
    else
      lms_markov(log, "u" + n, kTaps, dir / ("fir" + n + ".json"));
    realise_with_floor(dir, dir / ("fir" + n + ".json"), truth, j - 1, kTaps - 1, 14, "m" + n, parts, floor_parts);
    // The chirp repeats every 4096 samples: a rectangular window of one period
    // has no leakage once the start-up transient has decayed.
    run_ok({"frf", log, "--inputs", "u" + n, "--outputs", kOutputs, "--nfft", "4096", "--window", "rectangular", "--overlap", "0",
            "--out", dir / ("frf" + n + ".csv")});
  }
  if (HasFatalFailure()) return;
  const std::string assembled = dir / "avi112.json", floor_assembled = dir / "floor112.json";
  parts.insert(parts.end(), {"--out", assembled});
  floor_parts.insert(floor_parts.end(), {"--out", floor_assembled});
  const CliResult a = run_cli(parts);
  ASSERT_EQ(a.exit_code, 0) << describe(a);
  EXPECT_NE(a.out.find("order 112"), std::string::npos) << a.out;
  const StateSpace big = model_of(assembled);
  EXPECT_EQ(big.order(), 112);
  EXPECT_EQ(big.inputs(), 8);
  EXPECT_EQ(big.outputs(), 8);
  run_ok(floor_parts);

  // In-band error against the H1 FRFs of the eight experiments and against the truth.
  const auto h1_error_of = [&](const StateSpace& m) {
    BandError h1;
    for (int j = 1; j <= 8; ++j) add_h1_error(h1, m, j - 1, dir / ("frf" + std::to_string(j) + ".csv"), "u" + std::to_string(j));
    return h1.relative();
  };
  const auto errors = [&](const StateSpace& m) { return std::pair{h1_error_of(m), truth_error(m, truth)}; };
  // The reference itself: how far the H1 estimates are from the truth (1 % output noise, 8 periods).
  std::printf("H1 FRF of the experiments against the true model: %.4f (10-400 Hz)\n", h1_error_of(truth));
  std::printf("%-22s %6s %10s %10s %10s %10s %10s %10s\n", "model", "order", "ratio", "Hinf err", "Hinf bound", "vs H1", "vs truth",
              "floor");
  const StateSpace floor_big = model_of(floor_assembled);
  const auto [h1_error, true_error] = errors(big);
  const auto [floor_h1, floor_true] = errors(floor_big);
  std::printf("%-22s %6d %10s %10s %10s %10.4f %10.4f %10.4f\n", "assembled", 112, "-", "-", "-", h1_error, true_error, floor_true);
  EXPECT_LE(h1_error, floor_h1 + kFloorMargin);
  EXPECT_LE(true_error, floor_true + kFloorMargin);

  int previous_order = 112;
  for (const auto& [level, ratio_max] : {std::pair<std::string, double>{"0.4%", 0.004}, {"2%", 0.02}}) {
    SCOPED_TRACE("--max-error " + level);
    const std::string out = dir / ("r" + level + ".json"), floor_out = dir / ("floor_r" + level + ".json");
    const Reduction r = reduce(assembled, "--max-error", level, out);
    EXPECT_LE(r.ratio, ratio_max) << r.out;
    EXPECT_LE(r.hinf_error, r.bound * (1.0 + 1e-6)) << r.out;
    EXPECT_LT(r.order, previous_order) << r.out;
    previous_order = r.order;
    // The floor reduced to the same order: what this order costs with exact data.
    reduce(floor_assembled, "--order", std::to_string(r.order), floor_out);
    const StateSpace small = model_of(out);
    EXPECT_EQ(small.order(), r.order);
    const auto [e_h1, e_true] = errors(small);
    const auto [f_h1, f_true] = errors(model_of(floor_out));
    std::printf("%-22s %6d %10.5f %10.4g %10.4g %10.4f %10.4f %10.4f\n", ("reduced, " + level).c_str(), r.order, r.ratio, r.hinf_error,
                r.bound, e_h1, e_true, f_true);
    EXPECT_LE(e_h1, f_h1 + kFloorMargin);
    EXPECT_LE(e_true, f_true + kFloorMargin);
  }
  std::cout << std::flush;
}

TEST(IsolatorReproduction, HammerTapsOkidEraAssembleReduce) {
  // The CLI has no verb for the hammer-tap deconvolution of
  // realization/markov_parameters.hpp; OKID (observer order 20, 2048 system
  // Markov parameters: the 18 Hz mode's decay, as for the LMS) takes its place.
  // The ratio below 3 % holds for the tap points the generator uses, chosen among
  // the few that allow it on this structure (data/isolator/README.md).
  TempDir dir;
  const StateSpace truth = model_of(kData + "/taps_true.json");
  std::vector<std::string> parts{"assemble"}, floor_parts{"assemble"};
  for (int k = 1; k <= 3; ++k) {
    const std::string n = std::to_string(k);
    run_ok({"okid", kData + "/tap" + n + ".csv", "--inputs", "f" + n, "--outputs", kOutputs, "--observer-order", "20", "--count", "2048",
            "--out", dir / ("okid" + n + ".json")});
    realise_with_floor(dir, dir / ("okid" + n + ".json"), truth, k - 1, 2048, 8, "t" + n, parts, floor_parts);
  }
  if (HasFatalFailure()) return;
  const std::string assembled = dir / "taps24.json", floor_assembled = dir / "floor24.json";
  parts.insert(parts.end(), {"--out", assembled});
  floor_parts.insert(floor_parts.end(), {"--out", floor_assembled});
  run_ok(parts);
  run_ok(floor_parts);
  const StateSpace big = model_of(assembled);
  EXPECT_EQ(big.order(), 24);
  EXPECT_EQ(big.inputs(), 3);

  const Reduction r = reduce(assembled, "--order", "10", dir / "taps10.json");
  EXPECT_EQ(r.order, 10) << r.out;
  EXPECT_LT(r.ratio, 0.03) << r.out;
  EXPECT_LE(r.hinf_error, r.bound * (1.0 + 1e-6)) << r.out;
  reduce(floor_assembled, "--order", "10", dir / "floor10.json");

  const double e24 = truth_error(big, truth), f24 = truth_error(model_of(floor_assembled), truth);
  const double e10 = truth_error(model_of(dir / "taps10.json"), truth), f10 = truth_error(model_of(dir / "floor10.json"), truth);
  std::printf("taps: assembled 24 vs truth %.4f (floor %.4f); reduced to 10: ratio %.5f, Hinf error %.4g (bound %.4g), "
              "vs truth %.4f (floor %.4f)\n",
              e24, f24, r.ratio, r.hinf_error, r.bound, e10, f10);
  std::cout << std::flush;
  EXPECT_LE(e24, f24 + kFloorMargin);
  EXPECT_LE(e10, f10 + kFloorMargin);
}

}  // namespace test_acceptance_realization_isolator
