// sysid excite: write an excitation signal (chirp, log chirp, multisine, PRBS) as CSV.
#include <sysid/io/csv.hpp>
#include <sysid/signal/excitation.hpp>

#include <cmath>
#include <memory>
#include <optional>

#include "cli_common.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct ExciteArgs {
  std::string signal;
  double fs = 0;
  std::string band;
  double amplitude = 1.0;
  std::optional<double> duration;
  std::optional<Eigen::Index> samples;
  Eigen::Index inputs = 1;
  std::uint64_t seed = 1;
  int prbs_bits = 10;
  std::optional<int> clock_divider;
  std::string names;
  std::string out;
};

void run_excite(const ExciteArgs& a) {
  const std::string verb = "excite";
  claim_outputs({a.out}, {});
  // Length: exactly one of --duration / --samples (enforced by CLI11 excludes + this check).
  Eigen::Index n = 0;
  if (a.samples) {
    n = *a.samples;
  } else if (a.duration) {
    n = static_cast<Eigen::Index>(std::llround(*a.duration * a.fs));
  } else {
    throw CLI::ValidationError("--duration/--samples", "give the length with --duration S or --samples N");
  }
  if (n < 2) throw CLI::ValidationError("--duration/--samples", "the signal needs at least 2 samples, got " + std::to_string(n));
  if (a.signal != "multisine" && a.inputs != 1)
    throw CLI::ValidationError("--inputs", "only multisine makes several independent columns (" + a.signal + " gives one)");
  std::vector<std::string> names = split_names(a.names, "--names");
  if (names.empty()) {
    if (a.inputs == 1)
      names = {"u"};
    else
      for (Eigen::Index c = 0; c < a.inputs; ++c) names.push_back("u" + std::to_string(c + 1));
  }
  if (static_cast<Eigen::Index>(names.size()) != a.inputs)
    throw CLI::ValidationError("--names", std::to_string(names.size()) + " names for " + std::to_string(a.inputs) + " column(s)");

  std::optional<std::pair<double, double>> band;
  if (!a.band.empty()) band = parse_range(a.band, "--band");

  Eigen::MatrixXd x;
  if (a.signal == "chirp" || a.signal == "logchirp") {
    if (!band) throw CLI::ValidationError("--band", a.signal + " needs --band LO:HI");
    ChirpOptions o;
    o.fs_hz = a.fs;
    o.f0_hz = band->first;
    o.f1_hz = band->second;
    o.duration_s = static_cast<double>(n) / a.fs;  // round(duration fs) = n exactly
    o.amplitude = a.amplitude;
    o.sweep = a.signal == "chirp" ? ChirpSweep::linear : ChirpSweep::logarithmic;
    x = chirp(o);
  } else if (a.signal == "multisine") {
    if (!band) throw CLI::ValidationError("--band", "multisine needs --band LO:HI");
    MultisineOptions o;
    o.fs_hz = a.fs;
    o.f_min_hz = band->first;
    o.f_max_hz = band->second;
    o.samples = n;
    o.inputs = a.inputs;
    o.seed = a.seed;
    x = multisine(o);
    // --amplitude is the peak of every column (what an actuator limit constrains);
    // the generator makes unit RMS, so scale each column to its peak.
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
      const double peak = x.col(c).cwiseAbs().maxCoeff();
      if (peak > 0) x.col(c) *= a.amplitude / peak;
    }
  } else {  // prbs
    PrbsOptions o;
    o.register_bits = a.prbs_bits;
    o.samples = n;
    o.amplitude = a.amplitude;
    o.seed = a.seed;
    if (a.clock_divider) {
      o.clock_divider = *a.clock_divider;
    } else if (band) {
      // The PRBS spectrum falls as sinc^2(pi f D / fs): 3 dB down at about 0.443 fs / D.
      // Choose the largest divider that keeps HI within that band.
      o.clock_divider = std::max(1, static_cast<int>(std::floor(0.443 * a.fs / band->second)));
      note(verb, "prbs: --clock-divider " + std::to_string(o.clock_divider) + " keeps " + fmt(band->second) +
                     " Hz within the 3 dB band (about " + fmt(0.443 * a.fs / o.clock_divider, 4) + " Hz)");
    }
    x = prbs(o);
  }

  Eigen::MatrixXd table(n, x.cols() + 1);
  table.col(0) = Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) / a.fs;
  table.rightCols(x.cols()) = x;
  std::vector<std::string> columns{"t"};
  columns.insert(columns.end(), names.begin(), names.end());
  write_csv(a.out, columns, table);
  note(verb, "wrote " + std::to_string(n) + " samples of " + a.signal + " to " + a.out);
}

}  // namespace

Verb register_excite(CLI::App& app) {
  auto args = std::make_shared<ExciteArgs>();
  CLI::App* cmd = app.add_subcommand("excite", "Write an excitation signal (chirp, log chirp, multisine, PRBS) to a CSV file");
  cmd->add_option("--signal", args->signal, "chirp (linear sweep), logchirp (log sweep), multisine (random phase), prbs")
      ->required()
      ->check(CLI::IsMember({"chirp", "logchirp", "multisine", "prbs"}));
  cmd->add_option("--fs", args->fs, "sampling frequency in Hz")->required()->check(CLI::PositiveNumber);
  cmd->add_option("--band", args->band,
                  "LO:HI in Hz: sweep range (chirp), excited band (multisine); prbs: sets the clock divider so HI is "
                  "within the 3 dB band")
      ->check(range_validator());
  cmd->add_option("--amplitude", args->amplitude, "peak amplitude of every column")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  CLI::Option* dur = cmd->add_option("--duration", args->duration, "length in seconds")->check(CLI::PositiveNumber);
  CLI::Option* smp = cmd->add_option("--samples", args->samples, "length in samples")->check(CLI::PositiveNumber);
  dur->excludes(smp);
  cmd->add_option("--inputs", args->inputs, "number of columns (multisine only: independent random phases)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--seed", args->seed, "random seed (multisine phases; prbs initial register state, 0 < seed < 2^bits)")
      ->capture_default_str();
  cmd->add_option("--prbs-bits", args->prbs_bits, "prbs shift-register length (period 2^bits - 1)")
      ->capture_default_str()
      ->check(CLI::Range(2, 30));
  cmd->add_option("--clock-divider", args->clock_divider, "prbs: hold each bit this many samples")->check(CLI::Range(1, 1000000));
  cmd->add_option("--names", args->names, "column names, comma-separated (default u, or u1..uM)");
  cmd->add_option("--out", args->out, "output CSV file (columns t and the signal)")->required();
  cmd->footer(
      "Writes the time column t = k/fs and one column per input. The file is written\n"
      "atomically at the end; an error leaves no file.\n"
      "Example:\n"
      "  sysid excite --signal multisine --fs 1000 --band 1:200 --samples 20000 --amplitude 2 --out u.csv\n"
      "  sysid excite --signal prbs --fs 1000 --prbs-bits 12 --clock-divider 2 --duration 30 --out u.csv");
  return {cmd, [args] { run_excite(*args); }};
}

}  // namespace sysid::cli
