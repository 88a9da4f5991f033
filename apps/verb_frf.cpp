// sysid frf: non-parametric frequency response (H1/H2) with coherence and
// confidence bounds, written as the DESIGN.md frequency-response CSV.
#include <sysid/io/atomic_file.hpp>
#include <sysid/fem/sparse_frf.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/io/fem_model_file.hpp>
#include <sysid/spectral/frf.hpp>

#include <cmath>
#include <iostream>
#include <memory>
#include <numbers>

#include "cli_common.hpp"
#include "plot.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

/// Pairs drawn in one plot at most (an 8 x 8 FRF has 64; the CSV has them all).
constexpr Eigen::Index kFrfPlotPairs = 8;

struct FrfArgs {
  std::string log_path;
  LogArgs log;
  WelchArgs welch;
  std::string estimator = "h1";
  double confidence = 0.95;
  std::string out, plot;
  // --fem: the response of a finite-element model instead of an estimate from a log.
  std::string fem_path;
  std::string band;  ///< LO:HI Hz of the FE frequency grid
  Eigen::Index points = 500;
  std::string spacing = "linear";
  std::string solver = "automatic";  ///< sparse_frf's method
};

double db(double a) { return 20.0 * std::log10(a); }  // 0 -> -inf, inf -> inf: written as such

/// The FE model's response by sparse solves (fem/sparse_frf.hpp) on a grid over
/// --band, written with the columns of DESIGN.md (no coherence: nothing is estimated).
void run_fem_frf(const FrfArgs& a) {
  const std::string verb = "frf";
  if (a.band.empty()) throw CLI::ValidationError("--band", "--fem needs the frequency band LO:HI in Hz");
  claim_outputs({a.out, a.plot}, {a.fem_path});
  const auto [lo, hi] = parse_range(a.band, "--band");
  if (lo < 0.0 || (a.spacing == "log" && lo <= 0.0))
    throw CLI::ValidationError("--band", "need LO >= 0 (LO > 0 with --spacing log), found '" + a.band + "'");
  const fem::SecondOrderModel model = read_fem_model(a.fem_path);
  Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(a.points, lo, hi);
  if (a.spacing == "log") f = Eigen::VectorXd::LinSpaced(a.points, std::log10(lo), std::log10(hi)).unaryExpr([](double e) {
    return std::pow(10.0, e);
  });
  fem::SparseFrfOptions options;
  options.method = fem::sparse_frf_method_from_name(a.solver);
  const fem::SparseFrfResult r = fem::sparse_frf(model, f, options);
  std::cout << "frequency response of " << a.fem_path << " (" << model.dofs() << " DOFs, " << model.inputs.size()
            << " input(s), " << model.outputs.size() << " output(s)) at " << f.size() << " frequencies, " << fmt(lo)
            << ".." << fmt(hi) << " Hz, " << fem::sparse_frf_method_name(r.method) << ": "
            << r.symbolic_factorisations << " symbolic analysis, " << r.numeric_factorisations
            << " numeric factorisations";
  if (r.krylov_frequencies > 0)
    std::cout << "; " << r.krylov_frequencies << " frequencies from a Krylov basis of " << r.krylov_basis_size
              << " columns (largest estimated error " << fmt(r.krylov_max_estimated_error, 3) << ")";
  if (r.direct_frequencies > 0)
    std::cout << "; " << r.direct_frequencies << " solved directly, smallest reciprocal condition "
              << fmt(r.min_rcond, 3) << " at " << fmt(r.min_rcond_freq_hz) << " Hz";
  std::cout << "\n";
  for (const auto& w : r.warnings) warn(verb, w);
  const auto l = static_cast<Eigen::Index>(r.output_names.size()), m = static_cast<Eigen::Index>(r.input_names.size());
  const double to_deg = 180.0 / std::numbers::pi;
  if (!a.out.empty()) {
    std::vector<std::string> names{"f_hz"};
    for (Eigen::Index i = 0; i < l; ++i)
      for (Eigen::Index j = 0; j < m; ++j) {
        const std::string s = "_" + r.output_names[static_cast<std::size_t>(i)] + "_" + r.input_names[static_cast<std::size_t>(j)];
        for (const char* p : {"re", "im", "mag_db", "phase_deg"}) names.push_back(p + s);
      }
    Eigen::MatrixXd table(f.size(), 1 + 4 * l * m);
    for (Eigen::Index k = 0; k < f.size(); ++k) {
      table(k, 0) = f(k);
      Eigen::Index c = 1;
      for (Eigen::Index i = 0; i < l; ++i)
        for (Eigen::Index j = 0; j < m; ++j, c += 4) {
          const std::complex<double> h = r.H[static_cast<std::size_t>(k)](i, j);
          table.row(k).segment(c, 4) << h.real(), h.imag(), db(std::abs(h)), std::arg(h) * to_deg;
        }
    }
    write_csv(a.out, names, table);
    note(verb, "wrote " + std::to_string(f.size()) + " frequencies x " + std::to_string(l * m) + " pair(s) to " + a.out);
  }
  if (!a.plot.empty()) {
    std::vector<BodeCurve> curves;
    for (Eigen::Index i = 0; i < l && static_cast<Eigen::Index>(curves.size()) < kFrfPlotPairs; ++i)
      for (Eigen::Index j = 0; j < m && static_cast<Eigen::Index>(curves.size()) < kFrfPlotPairs; ++j) {
        BodeCurve b;
        b.title = r.output_names[static_cast<std::size_t>(i)] + " <- " + r.input_names[static_cast<std::size_t>(j)];
        b.f = f;
        b.h.resize(f.size());
        for (Eigen::Index k = 0; k < f.size(); ++k) b.h(k) = r.H[static_cast<std::size_t>(k)](i, j);
        curves.push_back(std::move(b));
      }
    PlotFigure fig;
    fig.title = "FE model " + a.fem_path + " (" + std::to_string(model.dofs()) + " DOFs, sparse solves)";
    fig.panels = bode_panels(curves, "");
    write_plot(fig, a.plot, verb);
  }
}

void run_frf(const FrfArgs& a) {
  const std::string verb = "frf";
  if (a.out.empty() && a.plot.empty()) throw CLI::ValidationError("--out/--plot", "give --out FILE.csv and/or --plot FILE.svg");
  if (!a.fem_path.empty()) {
    if (!a.log_path.empty()) throw CLI::ValidationError("--fem", "give either a log or --fem MODEL.json, not both");
    run_fem_frf(a);
    return;
  }
  if (a.log_path.empty()) throw CLI::ValidationError("log", "give the CSV log (or --fem MODEL.json)");
  if (a.log.inputs.empty() || a.log.outputs.empty())
    throw CLI::ValidationError("--inputs/--outputs", "an estimate from a log needs --inputs and --outputs");
  claim_outputs({a.out, a.plot}, {a.log_path});
  const std::vector<std::string> inputs = split_names(a.log.inputs, "--inputs");
  const std::vector<std::string> outputs = split_names(a.log.outputs, "--outputs");
  const LoadedLog log = load_log(a.log_path, make_log_options(a.log, inputs, outputs));

  FrfOptions o;
  o.welch = welch_options(a.welch);
  o.estimator = a.estimator == "h2" ? FrfEstimator::h2 : FrfEstimator::h1;
  o.confidence = a.confidence;
  const FrfResult r = frf(log.data, o);
  if (r.nfft != a.welch.nfft)
    note(verb, "--nfft " + std::to_string(a.welch.nfft) + " is longer than the log (" + std::to_string(log.data.total_samples()) +
                   " samples): using " + std::to_string(r.nfft));
  std::cout << r.brief_report() << "\n";
  for (const auto& w : r.warnings) warn(verb, w);

  const Eigen::Index l = r.outputs(), m = r.inputs(), nf = r.freq_hz.size();
  const double to_deg = 180.0 / std::numbers::pi;
  if (!a.out.empty()) {
    // DESIGN.md "Frequency-response files": f_hz, then per output-input pair
    // re, im, mag_db, phase_deg, coh; then the confidence bounds of the pair.
    std::vector<std::string> names{"f_hz"};
    for (Eigen::Index i = 0; i < l; ++i)
      for (Eigen::Index j = 0; j < m; ++j) {
        const std::string s = "_" + outputs[static_cast<std::size_t>(i)] + "_" + inputs[static_cast<std::size_t>(j)];
        for (const char* p : {"re", "im", "mag_db", "phase_deg", "coh", "mag_db_lo", "mag_db_hi", "phase_deg_lo", "phase_deg_hi"})
          names.push_back(p + s);
      }
    constexpr Eigen::Index kPerPair = 9;
    Eigen::MatrixXd table(nf, 1 + kPerPair * l * m);
    for (Eigen::Index k = 0; k < nf; ++k) {
      const auto b = static_cast<std::size_t>(k);
      table(k, 0) = r.freq_hz(k);
      Eigen::Index c = 1;
      for (Eigen::Index i = 0; i < l; ++i)
        for (Eigen::Index j = 0; j < m; ++j) {
          const std::complex<double> h = r.H[b](i, j);
          const double phase = std::arg(h) * to_deg, hw = r.phase_halfwidth_rad[b](i, j) * to_deg;
          table.row(k).segment(c, kPerPair) << h.real(), h.imag(), db(std::abs(h)), phase, r.coherence[b](i, j),
              db(r.magnitude_lower[b](i, j)), db(r.magnitude_upper[b](i, j)), phase - hw, phase + hw;
          c += kPerPair;
        }
    }
    write_csv(a.out, names, table);
    note(verb, "wrote " + std::to_string(nf) + " frequencies x " + std::to_string(l * m) + " pair(s) to " + a.out);
  }

  if (!a.plot.empty()) {
    std::vector<BodeCurve> curves;
    PlotPanel coh;
    coh.title = "coherence";
    coh.xlabel = "frequency [Hz]";
    coh.ylabel = "gamma^2";
    coh.logx = true;
    coh.yrange = std::make_pair(0.0, 1.05);
    Eigen::Index drawn = 0;
    for (Eigen::Index i = 0; i < l && drawn < kFrfPlotPairs; ++i)
      for (Eigen::Index j = 0; j < m && drawn < kFrfPlotPairs; ++j, ++drawn) {
        BodeCurve b;
        b.title = outputs[static_cast<std::size_t>(i)] + " <- " + inputs[static_cast<std::size_t>(j)];
        b.f = r.freq_hz;
        b.h.resize(nf);
        b.mag_lo.resize(nf);
        b.mag_hi.resize(nf);
        b.phase_halfwidth_deg.resize(nf);
        PlotCurve c;
        c.title = b.title;
        c.x.resize(nf - 1);
        c.y.resize(nf - 1);
        for (Eigen::Index k = 0; k < nf; ++k) {
          const auto bk = static_cast<std::size_t>(k);
          b.h(k) = r.H[bk](i, j);
          b.mag_lo(k) = r.magnitude_lower[bk](i, j);
          b.mag_hi(k) = r.magnitude_upper[bk](i, j);
          b.phase_halfwidth_deg(k) = r.phase_halfwidth_rad[bk](i, j) * to_deg;
          if (k > 0) {
            c.x(k - 1) = r.freq_hz(k);
            c.y(k - 1) = r.coherence[bk](i, j);
          }
        }
        curves.push_back(std::move(b));
        coh.curves.push_back(std::move(c));
      }
    if (l * m > kFrfPlotPairs)
      note(verb, "the plot shows the first " + std::to_string(kFrfPlotPairs) + " of " + std::to_string(l * m) +
                     " pairs (the CSV has all)");
    PlotFigure fig;
    fig.title = std::string(r.estimator == FrfEstimator::h1 ? "H1" : "H2") + " estimate of " + a.log_path + " (" +
                fmt(100.0 * r.confidence, 3) + " % confidence band, nfft " + std::to_string(r.nfft) + ")";
    fig.panels = bode_panels(curves, "");
    fig.panels.push_back(std::move(coh));
    write_plot(fig, a.plot, verb);
  }
}

}  // namespace

Verb register_frf(CLI::App& app) {
  auto args = std::make_shared<FrfArgs>();
  CLI::App* cmd = app.add_subcommand(
      "frf", "Non-parametric frequency response (H1/H2) with coherence and confidence bounds, as CSV (and a Bode plot)");
  cmd->add_option("log", args->log_path, "CSV log with the input and output columns (not with --fem)");
  LogOptionSpec spec;
  spec.inputs_required = false;
  spec.outputs_required = false;
  add_log_options(*cmd, args->log, spec);
  add_welch_options(*cmd, args->welch);
  cmd->add_option("--estimator", args->estimator, "h1 (noise on the outputs) or h2 (noise on the inputs)")
      ->capture_default_str()
      ->check(CLI::IsMember({"h1", "h2"}));
  cmd->add_option("--confidence", args->confidence, "level of the magnitude and phase bounds, 0 < level < 1")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 0.9999));
  cmd->add_option("--out", args->out, "frequency-response CSV file (one row per frequency)");
  cmd->add_option("--plot", args->plot, "Bode magnitude and phase with the confidence band, and coherence (.svg or .png; needs gnuplot)")
      ->check(plot_path_validator());
  cmd->add_option("--fem", args->fem_path,
                  "finite-element model (JSON naming Matrix Market M, K, C and the force/output DOFs): its response "
                  "by sparse solves instead of an estimate from a log");
  cmd->add_option("--band", args->band, "with --fem: frequency band LO:HI in Hz")->check(range_validator());
  cmd->add_option("--points", args->points, "with --fem: number of frequencies in the band")
      ->capture_default_str()
      ->check(CLI::Range(Eigen::Index{1}, Eigen::Index{10000000}));
  cmd->add_option("--spacing", args->spacing, "with --fem: linear or log frequency grid")
      ->capture_default_str()
      ->check(CLI::IsMember({"linear", "log"}));
  cmd->add_option("--solver", args->solver,
                  "with --fem: direct (a sparse LU per frequency), krylov (one factorisation for the sweep, every "
                  "frequency certified by its residual) or automatic (krylov for >= 50 frequencies and >= 2000 DOFs)")
      ->capture_default_str()
      ->check(CLI::IsMember({"automatic", "direct", "krylov"}));
  cmd->footer(
      "Columns: f_hz, then for each output y and input u: re_<y>_<u>, im_<y>_<u>, mag_db_<y>_<u>,\n"
      "phase_deg_<y>_<u> (wrapped to +-180), coh_<y>_<u> (ordinary coherence), and the confidence\n"
      "bounds mag_db_lo_<y>_<u>, mag_db_hi_<y>_<u>, phase_deg_lo_<y>_<u>, phase_deg_hi_<y>_<u>\n"
      "(Bendat & Piersol random error; -inf/inf where no bound can be given).\n"
      "With several inputs all must be excited independently in the log (H = G_yu G_uu^-1).\n"
      "Example:\n"
      "With --fem the columns are re, im, mag_db, phase_deg per pair (exact response, no coherence or bounds);\n"
      "one symbolic factorisation serves every frequency.\n"
      "Examples:\n"
      "  sysid frf par2_gu.csv --inputs u --outputs y --nfft 4096 --out frf.csv --plot frf.svg\n"
      "  sysid frf --fem beam.json --band 1:500 --points 2000 --out beam_frf.csv");
  return {cmd, [args] { run_frf(*args); }};
}

}  // namespace sysid::cli
