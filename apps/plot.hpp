#pragma once
// Plots for the verbs' --plot option, drawn by gnuplot (an external, well-kept
// plotting program; Debian package gnuplot-nox). The verbs describe a figure as
// panels of curves; write_plot() turns it into a gnuplot script plus one data file
// per curve in a private temporary directory, runs gnuplot, and moves the picture
// into place atomically (io/atomic_file.hpp), so a failed run leaves no file.
//
// Why here (apps/) and not in include/sysid/io: it spawns a program and depends on
// one being installed at run time; the library must stay usable without either
// (DESIGN.md: the algorithm families work without files, and the installed package
// promises no run-time tools). Only the CLI offers pictures.
//
// Without gnuplot, write_plot() writes nothing, says on stderr how to get plots,
// and returns false: the verb still succeeds (exit 0).
#include <CLI/CLI.hpp>
#include <Eigen/Dense>
#include <complex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sysid::cli {

/// One curve: y over x, optionally with a shaded band [lo, hi] underneath.
struct PlotCurve {
  std::string title;  ///< legend entry (empty: none)
  Eigen::VectorXd x, y;
  Eigen::VectorXd lo, hi;      ///< both empty, or the size of x: confidence band drawn shaded
  std::string style = "lines";  ///< gnuplot style: lines, points, linespoints, impulses
  int color = -1;               ///< index into the palette; -1 = the curve's position in the panel
  bool dashed = false;
  int point_type = 7;  ///< gnuplot point type for point styles (7 filled circle, 2 cross, 6 open circle)
  double point_size = 0.9;
};

/// One panel (one pair of axes).
struct PlotPanel {
  std::string title, xlabel, ylabel;
  bool logx = false, logy = false;
  std::optional<std::pair<double, double>> xrange, yrange;
  bool square = false;        ///< equal scales on x and y (pole-zero map)
  bool unit_circle = false;   ///< draw the unit circle (discrete-time pole-zero map)
  std::vector<PlotCurve> curves;
};

struct PlotFigure {
  std::string title;
  std::vector<PlotPanel> panels;  ///< stacked in `columns` columns, row by row
  int columns = 1;
  int width = 900;           ///< pixels
  int height_per_row = 280;  ///< pixels per row of panels
};

/// CLI11 check for --plot: a file name ending in .svg or .png.
CLI::Validator plot_path_validator();

/// The gnuplot program: $SYSID_GNUPLOT when set, else `gnuplot` on PATH; empty when not found.
std::string find_gnuplot();

/// Draws `figure` into `path` (.svg: svg terminal; .png: pngcairo, or gd's png when
/// cairo is missing, with a note). Returns false, with a note on stderr naming the
/// package to install, when gnuplot is not found. Throws std::runtime_error when
/// gnuplot fails (its messages included) and sysid::DataError when `path` cannot be
/// written.
bool write_plot(const PlotFigure& figure, const std::string& path, const std::string& verb);

/// One frequency response for bode_panels(): h over f (Hz), optionally with bounds
/// on |h| (absolute values, not dB) and a phase half-width in degrees.
struct BodeCurve {
  std::string title;
  Eigen::VectorXd f;
  Eigen::VectorXcd h;
  Eigen::VectorXd mag_lo, mag_hi;  ///< empty or size of f
  Eigen::VectorXd phase_halfwidth_deg;  ///< empty or size of f
  int color = -1;
  bool dashed = false;
};

/// Magnitude (dB) and phase (degrees, unwrapped) panels over a logarithmic
/// frequency axis; bins at f <= 0 are left out (a log axis has no DC).
std::vector<PlotPanel> bode_panels(const std::vector<BodeCurve>& curves, const std::string& title);

/// Keeps at most `max_points` rows (every k-th): time series of 10^6 samples
/// would give SVG files of tens of MB. Returns the stride used.
Eigen::Index plot_stride(Eigen::Index rows, Eigen::Index max_points = 20000);

/// Bode helpers: 20 log10 |h| (NaN for 0 or non-finite), phase in degrees unwrapped
/// along the vector (continuous through +-180 degree jumps).
Eigen::VectorXd magnitude_db(const Eigen::VectorXcd& h);
Eigen::VectorXd unwrapped_phase_deg(const Eigen::VectorXcd& h);

}  // namespace sysid::cli
