// sysid psd: Welch power spectral density of any columns of a log, with
// chi-square confidence bounds, as CSV (and a log-log plot); with --model, the
// output spectrum each model predicts beside it and how well the two agree.
#include <sysid/io/atomic_file.hpp>
#include <sysid/io/csv.hpp>
#include <sysid/spectral/confidence.hpp>
#include <sysid/spectral/model_spectrum.hpp>
#include <sysid/spectral/welch.hpp>

#include <algorithm>

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
  std::vector<std::string> models;
  std::string band;
  std::string out, plot;
};

/// One model's predicted spectrum of each analysed column it has as an output.
struct ModelCurves {
  std::string path;
  std::vector<Eigen::Index> column;  ///< index into the analysed columns
  std::vector<Eigen::VectorXd> psd;  ///< the model's output PSD for that column
};

std::vector<std::string> with_unique(std::vector<std::string> names, const std::vector<std::string>& more) {
  for (const auto& n : more)
    if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
  return names;
}

Eigen::Index position(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<Eigen::Index>(it - names.begin());
}

/// The spectrum `file` predicts on the Welch grid of `ps`: its disturbance part from
/// K and the noise covariance, its input part from the Welch cross-spectra of the
/// log's columns named as its inputs (the same segments and window as the estimate).
ModelCurves model_curves(const ModelFile& file, const std::string& path, const std::vector<std::string>& columns,
                         const std::vector<std::string>& signals, const Eigen::MatrixXd& x, double ts, const WelchOptions& o,
                         const PowerSpectrum& ps) {
  const std::string verb = "psd";
  const StateSpace model = model_for_sample_time(file, ts, path, verb);
  const bool discrete_noise_model = file.model.Ts > 0.0 && file.K.size() > 0 && file.noise_covariance.size() > 0;
  ModelCurves mc;
  mc.path = path;
  const std::vector<std::string> outputs = model_output_names(file), inputs = model_input_names(file);
  std::vector<Eigen::Index> model_output;  // the model output of each analysed column
  for (std::size_t r = 0; r < outputs.size(); ++r)
    if (const Eigen::Index c = position(columns, outputs[r]); c >= 0) {
      mc.column.push_back(c);
      model_output.push_back(static_cast<Eigen::Index>(r));
    }
  if (mc.column.empty())
    throw DataError(path + ": none of the model's outputs (" + join(outputs) + ") is among --columns (" + join(columns) + ")");
  std::vector<Eigen::MatrixXcd> input_csd;
  if (!inputs.empty()) {
    Eigen::MatrixXd u(x.rows(), static_cast<Eigen::Index>(inputs.size()));
    for (std::size_t i = 0; i < inputs.size(); ++i) u.col(static_cast<Eigen::Index>(i)) = x.col(position(signals, inputs[i]));
    input_csd = welch_csd(u, u, 1.0 / ts, o).csd;
  }
  if (!discrete_noise_model) {
    if (inputs.empty())
      throw DataError(path + ": a model without inputs needs a disturbance model (K and noise_covariance of a discrete model) for a spectrum");
    warn(verb, path + " has no discrete disturbance model (K, noise_covariance): its curve is the input part G Phi_u G^H alone");
  }
  const ModelSpectrum spectrum =
      model_output_spectrum(model, discrete_noise_model ? file.K : Eigen::MatrixXd(),
                            discrete_noise_model ? file.noise_covariance : Eigen::MatrixXd(), ps.freq_hz, input_csd);
  for (const auto& w : spectrum.warnings) warn(verb, path + ": " + w);
  for (const Eigen::Index r : model_output) mc.psd.push_back(spectrum.output_psd.col(r));
  return mc;
}

void run_psd(const PsdArgs& a) {
  const std::string verb = "psd";
  if (a.out.empty() && a.plot.empty()) throw CLI::ValidationError("--out/--plot", "give --out FILE.csv and/or --plot FILE.svg");
  std::vector<std::string> inputs{a.log_path};
  inputs.insert(inputs.end(), a.models.begin(), a.models.end());
  claim_outputs({a.out, a.plot}, inputs);
  const std::vector<std::string> columns = split_names(a.columns, "--columns");
  if (columns.empty()) throw CLI::ValidationError("--columns", "name at least one column");
  LogArgs la;
  la.ts = a.ts;
  la.time_column = a.time_column;
  la.nan_policy = a.nan_policy;
  // The models' inputs are read with the analysed columns (each column once).
  std::vector<std::string> signals = columns;
  std::vector<ModelFile> files;
  for (const auto& path : a.models) {
    files.push_back(load_model(path));
    signals = with_unique(signals, model_input_names(files.back()));
  }
  const LoadedLog log = load_log(a.log_path, make_log_options(la, {}, signals));
  const Eigen::MatrixXd& all = log.data.experiments.front().y;
  const Eigen::MatrixXd x = all.leftCols(static_cast<Eigen::Index>(columns.size()));

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

  std::vector<ModelCurves> models;
  if (!a.models.empty()) {
    if (o.scaling != SpectralScaling::density)
      throw CLI::ValidationError("--model", "a model's spectrum is compared as a density: use --scaling density");
    const double nyquist = 0.5 / log.data.Ts;
    const auto [f_lo, f_hi] = a.band.empty() ? std::pair{ps.freq_hz(1), nyquist} : parse_range(a.band, "--band");
    for (std::size_t k = 0; k < files.size(); ++k)
      models.push_back(model_curves(files[k], a.models[k], columns, signals, all, log.data.Ts, o, ps));
    std::cout << "model spectra against the estimate, " << fmt(f_lo, 4) << "-" << fmt(f_hi, 4)
              << " Hz (level = median of 10 log10(model/estimate), shape = mean of its absolute value):\n";
    for (std::size_t k = 0; k < models.size(); ++k)
      for (std::size_t r = 0; r < models[k].column.size(); ++r) {
        const Eigen::Index c = models[k].column[r];
        const SpectrumAgreement ag =
            spectrum_agreement(ps.psd.col(c), models[k].psd[r], ps.freq_hz, f_lo, f_hi, lo_factor, hi_factor);
        std::cout << "  model" << k + 1 << " (" << models[k].path << "), " << columns[static_cast<std::size_t>(c)] << ": level "
                  << (ag.median_db >= 0 ? "+" : "") << fmt(ag.median_db, 3) << " dB, shape " << fmt(ag.mean_abs_db, 3) << " dB, "
                  << fmt(100.0 * ag.fraction_inside, 3) << " % of " << ag.bins << " bins inside the "
                  << fmt(100.0 * a.confidence, 3) << " % band\n";
      }
  }

  const Eigen::Index nf = ps.freq_hz.size(), nc = static_cast<Eigen::Index>(columns.size());
  if (!a.out.empty()) {
    std::vector<std::string> names{"f_hz"};
    for (const auto& c : columns)
      for (const char* p : {"psd_", "psd_lo_", "psd_hi_"}) names.push_back(p + c);
    std::vector<Eigen::VectorXd> model_columns;
    for (std::size_t k = 0; k < models.size(); ++k)
      for (std::size_t r = 0; r < models[k].column.size(); ++r) {
        names.push_back("psd_model" + std::to_string(k + 1) + "_" + columns[static_cast<std::size_t>(models[k].column[r])]);
        model_columns.push_back(models[k].psd[r]);
      }
    Eigen::MatrixXd table(nf, 1 + 3 * nc + static_cast<Eigen::Index>(model_columns.size()));
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
    for (std::size_t j = 0; j < model_columns.size(); ++j) table.col(1 + 3 * nc + static_cast<Eigen::Index>(j)) = model_columns[j];
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
    for (std::size_t k = 0; k < models.size(); ++k)
      for (std::size_t r = 0; r < models[k].column.size(); ++r) {
        PlotCurve cv;
        cv.title = columns[static_cast<std::size_t>(models[k].column[r])] + ", " + models[k].path;
        cv.x = ps.freq_hz.tail(nf - 1);
        cv.y = models[k].psd[r].tail(nf - 1);
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
  add_csv_layout_options(*cmd);
  add_welch_options(*cmd, args->welch);
  cmd->add_option("--scaling", args->scaling, "density (units^2/Hz) or spectrum (units^2: reads sine powers, best with flattop)")
      ->capture_default_str()
      ->check(CLI::IsMember({"density", "spectrum"}));
  cmd->add_option("--confidence", args->confidence, "level of the chi-square bounds, 0 < level < 1")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 0.9999));
  cmd->add_option("--model", args->models,
                  "model file(s) whose predicted output spectrum is compared with the estimate (AR, ARMA, any model with K and "
                  "noise_covariance; a model's inputs are read from the log); repeat for several");
  cmd->add_option("--band", args->band, "lo:hi in Hz where the model spectra are scored (default: every bin but DC)")
      ->check(range_validator());
  cmd->add_option("--out", args->out,
                  "CSV file: f_hz, then psd_<c>, psd_lo_<c>, psd_hi_<c> per column, then psd_model<k>_<c> per model and column");
  cmd->add_option("--plot", args->plot, "log-log plot with the confidence band (.svg or .png; needs gnuplot)")
      ->check(plot_path_validator());
  cmd->footer(
      "One-sided Welch estimate (Welch 1967); the bounds are chi-square with Welch's equivalent\n"
      "degrees of freedom nu (half of it at DC and Nyquist).\n"
      "With --model, each model's output spectrum G Phi_u G^H + 2 Ts H Lambda H^H (Ljung 1999, eq. 2.68;\n"
      "the innovation form's K and noise covariance, Phi_u from the log's inputs) is scored against the\n"
      "estimate: level (median dB offset), shape (mean absolute dB error) and the share of bins inside\n"
      "the confidence band.\n"
      "Examples:\n"
      "  sysid psd par2_gu.csv --columns u,y --nfft 4096 --out psd.csv\n"
      "  sysid psd par2_gw.csv --columns y --nfft 4096 --model ar16.json --model arma16.json --plot gw.svg");
  add_hold_option(*cmd);
  return {cmd, [args] { run_psd(*args); }};
}

}  // namespace sysid::cli
