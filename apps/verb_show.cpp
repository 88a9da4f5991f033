// sysid show: human-readable summary of a model file.
#include <sysid/core/modal_table.hpp>
#include <sysid/core/poles_zeros.hpp>
#include <sysid/core/frequency_response.hpp>
#include <sysid/core/transfer_function.hpp>
#include <sysid/io/atomic_file.hpp>

#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <numbers>
#include <sstream>

#include "cli_common.hpp"
#include "plot.hpp"
#include "verbs.hpp"

namespace sysid::cli {

namespace {

/// Transfer functions printed at most (a 10 x 10 model would give 100 lines).
constexpr Eigen::Index kMaxChannels = 16;
/// Elements of a provenance list printed before "...".
constexpr std::size_t kMaxListItems = 8;

struct ShowArgs {
  std::string model_path;
  int digits = 4;
  std::string plot;
};

/// Bode plot of the model (the first kMaxPairs input-output pairs)
/// and its pole-zero map.
void plot_model(const ShowArgs& a, const StateSpace& sys, const Eigen::VectorXcd& p) {
  constexpr Eigen::Index kMaxPairs = 8;
  // Frequency grid: discrete, 1e-3 of Nyquist up to Nyquist; continuous, a decade
  // either side of the poles' natural frequencies.
  double f_lo = 0.0, f_hi = 0.0;
  if (sys.is_discrete()) {
    f_hi = 0.5 / sys.Ts;
    f_lo = 1e-3 * f_hi;
  } else {
    double wmin = std::numeric_limits<double>::infinity(), wmax = 0.0;
    for (Eigen::Index i = 0; i < p.size(); ++i)
      if (std::abs(p[i]) > 0.0) {
        wmin = std::min(wmin, std::abs(p[i]));
        wmax = std::max(wmax, std::abs(p[i]));
      }
    if (!(wmax > 0.0)) wmin = wmax = 2.0 * std::numbers::pi;
    f_lo = 0.1 * wmin / (2.0 * std::numbers::pi);
    f_hi = 10.0 * wmax / (2.0 * std::numbers::pi);
  }
  const Eigen::Index nf = 800;
  Eigen::VectorXd f(nf);
  for (Eigen::Index k = 0; k < nf; ++k)
    f(k) = f_lo * std::pow(f_hi / f_lo, static_cast<double>(k) / static_cast<double>(nf - 1));
  const std::vector<Eigen::MatrixXcd> g = frequency_response(sys, f);
  std::vector<BodeCurve> curves;
  for (Eigen::Index i = 0; i < sys.outputs(); ++i)
    for (Eigen::Index j = 0; j < sys.inputs(); ++j) {
      if (static_cast<Eigen::Index>(curves.size()) == kMaxPairs) continue;
      BodeCurve b;
      b.title = sys.output_name(i) + " <- " + sys.input_name(j);
      b.f = f;
      b.h.resize(nf);
      for (Eigen::Index k = 0; k < nf; ++k) b.h(k) = g[static_cast<std::size_t>(k)](i, j);
      curves.push_back(std::move(b));
    }
  PlotFigure fig;
  fig.title = a.model_path + " (order " + std::to_string(sys.order()) + ")";
  fig.panels = bode_panels(curves, "");
  PlotPanel pz;
  pz.title = sys.is_discrete() ? "poles (x) and transmission zeros (o), z-plane" : "poles (x) and transmission zeros (o), s-plane";
  pz.xlabel = "real";
  pz.ylabel = "imaginary";
  pz.square = true;
  pz.unit_circle = sys.is_discrete();
  PlotCurve pc, zc;
  pc.title = "poles";
  pc.style = zc.style = "points";
  pc.point_type = 2;
  zc.point_type = 6;
  pc.x = p.real();
  pc.y = p.imag();
  Eigen::VectorXcd z;
  try {
    z = transmission_zeros(sys);
  } catch (const std::exception&) {
    z.resize(0);  // a failed zero computation leaves the map with poles only
  }
  zc.title = "zeros";
  zc.x = z.real();
  zc.y = z.imag();
  zc.color = 1;
  pz.curves.push_back(std::move(pc));
  if (z.size() > 0) pz.curves.push_back(std::move(zc));
  if (sys.is_discrete()) {
    double r = 1.1;
    for (Eigen::Index i = 0; i < z.size(); ++i)
      if (std::isfinite(std::abs(z[i]))) r = std::max(r, 1.1 * std::abs(z[i]));
    for (Eigen::Index i = 0; i < p.size(); ++i) r = std::max(r, 1.1 * std::abs(p[i]));
    r = std::min(r, 5.0);  // far zeros are clipped rather than shrinking the unit circle to a dot
    pz.xrange = pz.yrange = std::make_pair(-r, r);
  }
  fig.panels.push_back(std::move(pz));
  fig.height_per_row = 300;
  write_plot(fig, a.plot, "show");
}

std::string format_complex(std::complex<double> z, int digits) {
  if (z.imag() == 0.0) return fmt(z.real(), digits);
  return fmt(z.real(), digits) + (z.imag() < 0 ? " - " : " + ") + fmt(std::abs(z.imag()), digits) + "j";
}

/// One provenance value on one line; long lists shortened (singular values).
std::string format_json_value(const nlohmann::json& v, int digits) {
  if (v.is_array() && v.size() > kMaxListItems) {
    nlohmann::json head = nlohmann::json::array();
    for (std::size_t k = 0; k < kMaxListItems; ++k) head.push_back(v[k]);
    std::string s = format_json_value(head, digits);
    s.pop_back();  // ']'
    return s + ", ... (" + std::to_string(v.size()) + " values)]";
  }
  if (v.is_array()) {
    std::string s = "[";
    for (std::size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + format_json_value(v[k], digits);
    return s + "]";
  }
  if (v.is_number_float()) return fmt(v.get<double>(), digits + 2);
  if (v.is_string()) return v.get<std::string>();
  return v.dump();
}

void run_show(const ShowArgs& a) {
  claim_outputs({a.plot}, {a.model_path});
  const ModelFile file = load_model(a.model_path, /*allow_augmented=*/true);
  const StateSpace& sys = file.model;
  const int d = a.digits;
  std::ostringstream out;
  out << "model: " << a.model_path << "\n";
  out << "type: " << file.type << (file.type == "augmented" ? " (nominal state-space part shown)" : "") << "\n";
  if (sys.is_discrete())
    out << "Ts: " << fmt(sys.Ts, 9) << " s (" << fmt(1.0 / sys.Ts, 9) << " Hz)\n";
  else
    out << "Ts: 0 (continuous time)\n";
  out << "order: " << sys.order() << "\n";
  out << "inputs (" << sys.inputs() << "): " << join(model_input_names(file)) << "\n";
  out << "outputs (" << sys.outputs() << "): " << join(model_output_names(file)) << "\n";
  if (file.input_offset.size())
    out << "input offset: " << format_json_value(json_list_or_null(file.input_offset), d) << "\n";
  if (file.output_offset.size())
    out << "output offset: " << format_json_value(json_list_or_null(file.output_offset), d) << "\n";
  out << "Kalman gain K: " << (file.K.size() ? "present (k-step prediction possible)" : "absent") << "\n";

  const Eigen::VectorXcd p = poles(sys);
  if (sys.is_discrete()) {
    const double radius = p.size() ? p.cwiseAbs().maxCoeff() : 0.0;
    out << "stability: " << (radius < 1.0 ? "stable" : "UNSTABLE") << " (spectral radius " << fmt(radius, d + 2) << ")\n";
  } else {
    double abscissa = -std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < p.size(); ++i) abscissa = std::max(abscissa, p[i].real());
    out << "stability: " << (p.size() == 0 || abscissa < 0.0 ? "stable" : "UNSTABLE") << " (largest real part of a pole "
        << fmt(p.size() ? abscissa : 0.0, d + 2) << ")\n";
  }
  out << "poles (" << (sys.is_discrete() ? "z" : "s") << "):\n";
  for (Eigen::Index i = 0; i < p.size(); ++i)
    out << "  " << format_complex(p[i], d + 2) << (sys.is_discrete() ? "   |z| = " + fmt(std::abs(p[i]), d + 2) : "") << "\n";
  out << "modes:\n" << format_modal_table(modal_table(sys));

  out << "transfer functions (factored):\n";
  Eigen::Index shown = 0;
  for (Eigen::Index i = 0; i < sys.outputs(); ++i)
    for (Eigen::Index j = 0; j < sys.inputs(); ++j) {
      if (shown == kMaxChannels) continue;
      out << "  " << sys.output_name(i) << " <- " << sys.input_name(j) << ": " << format_factored(zero_pole_gain(sys, i, j), d)
          << "\n";
      ++shown;
    }
  if (sys.outputs() * sys.inputs() > kMaxChannels)
    out << "  (" << sys.outputs() * sys.inputs() - kMaxChannels << " more channels not shown; first " << kMaxChannels
        << " listed)\n";

  if (!file.provenance.empty()) {
    out << "provenance:\n";
    for (auto it = file.provenance.begin(); it != file.provenance.end(); ++it)
      out << "  " << it.key() << ": " << format_json_value(it.value(), d) << "\n";
  }
  std::cout << out.str();
  if (!a.plot.empty()) plot_model(a, sys, p);
}

}  // namespace

Verb register_show(CLI::App& app) {
  auto args = std::make_shared<ShowArgs>();
  CLI::App* cmd =
      app.add_subcommand("show", "Summarise a model file: order, stability, poles, modes, transfer functions, provenance");
  cmd->add_option("model", args->model_path, "model file (JSON)")->required();
  cmd->add_option("--digits", args->digits, "significant digits of poles and transfer-function coefficients")
      ->capture_default_str()
      ->check(CLI::Range(1, 17));
  cmd->add_option("--plot", args->plot, "Bode plot of the model and its pole-zero map (.svg or .png; needs gnuplot)")
      ->check(plot_path_validator());
  cmd->footer(
      "Example:\n"
      "  sysid show model.json --digits 6\n"
      "  sysid show model.json --plot model.svg");
  return {cmd, [args] { run_show(*args); }};
}

}  // namespace sysid::cli
