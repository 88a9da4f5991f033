// sysid psd: Welch power spectral density of any columns of a log, with
// chi-square confidence bounds, as CSV (and a log-log plot).
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/spectral/confidence.hpp>
#include <sysid/spectral/welch.hpp>

#include <iostream>
#include <memory>

#include "cli_common.hpp"
#include "plot.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

struct PsdArgs {
  std::string log_path;
  std::string columns;
  std::optional<double> ts;
  std::string time_column = "t";
  std::string nan_policy = "error";
  WelchArgs welch;
  std::string scaling = "density";
  double confidence = 0.95;
  std::string out, plot;
};

void run_psd(const PsdArgs& a) {
  const std::string verb = "psd";
  if (a.out.empty() && a.plot.empty()) throw CLI::ValidationError("--out/--plot", "give --out FILE.csv and/or --plot FILE.svg");
  claim_outputs({a.out, a.plot}, {a.log_path});
  const std::vector<std::string> columns = split_names(a.columns, "--columns");
  if (columns.empty()) throw CLI::ValidationError("--columns", "name at least one column");
  LogArgs la;
  la.ts = a.ts;
  la.time_column = a.time_column;
  la.nan_policy = a.nan_policy;
  const LoadedLog log = load_log(a.log_path, make_log_options(la, {}, columns));
  const Eigen::MatrixXd& x = log.data.experiments.front().y;

  WelchOptions o = welch_options(a.welch);
  o.scaling = a.scaling == "spectrum" ? SpectralScaling::spectrum : SpectralScaling::density;
  const PowerSpectrum ps = welch_psd(x, 1.0 / log.data.Ts, o);
  const auto [lo_factor, hi_factor] = psd_confidence_factors(ps.dof, a.confidence);
  std::cout << "Welch " << (o.scaling == SpectralScaling::density ? "PSD [units^2/Hz]" : "power spectrum [units^2]") << " of "
            << columns.size() << " column(s), nfft " << ps.nfft << ", " << window_name(o.window) << " window, "
            << ps.segments << " segments (nu = " << fmt(ps.dof, 4) << "), " << fmt(100.0 * a.confidence, 3)
            << " % bounds x[" << fmt(lo_factor, 4) << ", " << fmt(hi_factor, 4) << "]\n";
  for (std::size_t c = 0; c < columns.size(); ++c) {
    // Parseval: the density integrates to the (window-weighted) variance.
    const double df = ps.freq_hz.size() > 1 ? ps.freq_hz(1) - ps.freq_hz(0) : 0.0;
    if (o.scaling == SpectralScaling::density)
      std::cout << "  " << columns[c] << ": RMS from the PSD " << fmt(std::sqrt(ps.psd.col(static_cast<Eigen::Index>(c)).sum() * df), 5)
                << "\n";
  }
  if (ps.segments < 4)
    warn(verb, "only " + std::to_string(ps.segments) + " segment(s) averaged: the estimate is very noisy (use a smaller --nfft)");

  const Eigen::Index nf = ps.freq_hz.size(), nc = static_cast<Eigen::Index>(columns.size());
  if (!a.out.empty()) {
    std::vector<std::string> names{"f_hz"};
    for (const auto& c : columns)
      for (const char* p : {"psd_", "psd_lo_", "psd_hi_"}) names.push_back(p + c);
    Eigen::MatrixXd table(nf, 1 + 3 * nc);
    table.col(0) = ps.freq_hz;
    // DC and Nyquist bins are real-valued: half the degrees of freedom there.
    const auto [lo_edge, hi_edge] = psd_confidence_factors(0.5 * ps.dof, a.confidence);
    for (Eigen::Index c = 0; c < nc; ++c) {
      table.col(1 + 3 * c) = ps.psd.col(c);
      for (Eigen::Index k = 0; k < nf; ++k) {
        const bool edge = k == 0 || (ps.nfft % 2 == 0 && k == nf - 1);
        table(k, 2 + 3 * c) = ps.psd(k, c) * (edge ? lo_edge : lo_factor);
        table(k, 3 + 3 * c) = ps.psd(k, c) * (edge ? hi_edge : hi_factor);
      }
    }
    write_csv(a.out, names, table);
    note(verb, "wrote " + std::to_string(nf) + " frequencies x " + std::to_string(nc) + " column(s) to " + a.out);
  }
  if (!a.plot.empty()) {
    PlotPanel p;
    p.title = o.scaling == SpectralScaling::density ? "power spectral density" : "power spectrum";
    p.xlabel = "frequency [Hz]";
    p.ylabel = o.scaling == SpectralScaling::density ? "PSD [units^2/Hz]" : "power [units^2]";
    p.logx = p.logy = true;
    for (Eigen::Index c = 0; c < nc; ++c) {
      PlotCurve cv;
      cv.title = columns[static_cast<std::size_t>(c)];
      cv.x = ps.freq_hz.tail(nf - 1);
      cv.y = ps.psd.col(c).tail(nf - 1);
      cv.lo = cv.y * lo_factor;
      cv.hi = cv.y * hi_factor;
      p.curves.push_back(std::move(cv));
    }
    PlotFigure fig;
    fig.title = "Welch estimate of " + a.log_path + " (nfft " + std::to_string(ps.nfft) + ", " +
                fmt(100.0 * a.confidence, 3) + " % band)";
    fig.panels.push_back(std::move(p));
    fig.height_per_row = 420;
    write_plot(fig, a.plot, verb);
  }
}

}  // namespace

Verb register_psd(CLI::App& app) {
  auto args = std::make_shared<PsdArgs>();
  CLI::App* cmd = app.add_subcommand("psd", "Welch power spectral density of columns of a log, with confidence bounds, as CSV");
  cmd->add_option("log", args->log_path, "CSV log")->required();
  cmd->add_option("--columns,--outputs", args->columns, "columns to analyse, comma-separated (e.g. y1,y2)")->required();
  cmd->add_option("--ts", args->ts, "sample time in seconds; required when the log has no time column")->check(CLI::PositiveNumber);
  cmd->add_option("--time-column", args->time_column, "name of the time column ('none': ignore any time column)")
      ->capture_default_str();
  cmd->add_option("--nan-policy", args->nan_policy, "NaN/Inf/empty cells: error, drop (leading/trailing rows), interpolate")
      ->check(CLI::IsMember({"error", "drop", "interpolate"}))
      ->capture_default_str();
  add_welch_options(*cmd, args->welch);
  cmd->add_option("--scaling", args->scaling, "density (units^2/Hz) or spectrum (units^2: reads sine powers, best with flattop)")
      ->capture_default_str()
      ->check(CLI::IsMember({"density", "spectrum"}));
  cmd->add_option("--confidence", args->confidence, "level of the chi-square bounds, 0 < level < 1")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 0.9999));
  cmd->add_option("--out", args->out, "CSV file: f_hz, then psd_<c>, psd_lo_<c>, psd_hi_<c> per column");
  cmd->add_option("--plot", args->plot, "log-log plot with the confidence band (.svg or .png; needs gnuplot)")
      ->check(plot_path_validator());
  cmd->footer(
      "One-sided Welch estimate (Welch 1967); the bounds are chi-square with Welch's equivalent\n"
      "degrees of freedom nu (half of it at DC and Nyquist).\n"
      "Example:\n"
      "  sysid psd par2_gu.csv --columns u,y --nfft 4096 --out psd.csv");
  return {cmd, [args] { run_psd(*args); }};
}

}  // namespace sysid::cli
