#include "plot.hpp"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <sysid/core/errors.hpp>
#include <sysid/io/atomic_file.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "cli_common.hpp"

namespace sysid::cli {

namespace {

/// Colour-blind-safe palette (Okabe & Ito 2008), then greys.
const char* const kPalette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00",
                                "#56B4E9", "#000000", "#F0E442", "#777777", "#AAAAAA"};
constexpr int kPaletteSize = sizeof kPalette / sizeof kPalette[0];

std::string extension_of(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

/// A gnuplot double-quoted string literal.
std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    if (c == '\n') {
      q += "\\n";
      continue;
    }
    q += c;
  }
  return q + "\"";
}

/// Single-quoted for /bin/sh.
std::string shell_quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

bool executable(const std::string& path) {
  struct stat st {};
  return !path.empty() && ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

/// Runs a shell command; returns its exit status (-1 if it could not run).
int run_command(const std::string& command) {
  const int status = std::system(command.c_str());
  if (status == -1 || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

/// A private temporary directory, removed with its contents on destruction.
class ScratchDir {
 public:
  ScratchDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "sysid_plot_XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) throw std::runtime_error("cannot create a temporary directory for the plot");
    m_path = tmpl;
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(m_path, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  std::string file(const std::string& name) const { return (m_path / name).string(); }

 private:
  std::filesystem::path m_path;
};

void write_number(std::ostream& out, double v) {
  if (std::isfinite(v))
    out << v;
  else
    out << "NaN";  // gnuplot: undefined point, the line is broken there
}

/// Data file of one curve: x y [lo hi] per line.
void write_curve_data(const std::string& path, const PlotCurve& c) {
  std::ofstream out(path);
  out.precision(10);
  const bool band = c.lo.size() == c.x.size() && c.hi.size() == c.x.size() && c.x.size() > 0;
  for (Eigen::Index k = 0; k < c.x.size(); ++k) {
    write_number(out, c.x(k));
    out << ' ';
    write_number(out, k < c.y.size() ? c.y(k) : NAN);
    if (band) {
      out << ' ';
      write_number(out, c.lo(k));
      out << ' ';
      write_number(out, c.hi(k));
    }
    out << '\n';
  }
  if (!out) throw std::runtime_error("cannot write the plot data file " + path);
}

std::string terminal_for(const std::string& ext, const std::string& gnuplot, int width, int height, const std::string& verb) {
  std::ostringstream t;
  if (ext == ".svg") {
    t << "set terminal svg size " << width << "," << height << " dynamic noenhanced font \"sans,11\" background rgb \"white\"";
  } else {
    static int cairo = -1;  // probed once per process
    if (cairo < 0) cairo = run_command(shell_quoted(gnuplot) + " -e 'set terminal pngcairo' >/dev/null 2>&1") == 0 ? 1 : 0;
    if (cairo == 1) {
      t << "set terminal pngcairo size " << width << "," << height << " noenhanced font \"sans,10\" background rgb \"white\"";
    } else {
      note(verb, "gnuplot has no cairo terminal: the PNG is drawn with the plainer gd 'png' terminal");
      t << "set terminal png size " << width << "," << height << " noenhanced background rgb \"white\"";
    }
  }
  return t.str();
}

}  // namespace

CLI::Validator plot_path_validator() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        const std::string ext = extension_of(s);
        if (ext != ".svg" && ext != ".png") return "the plot file must end in .svg or .png, found '" + s + "'";
        return {};
      },
      "FILE.svg|FILE.png");
}

std::string find_gnuplot() {
  if (const char* env = std::getenv("SYSID_GNUPLOT")) return executable(env) ? std::string(env) : std::string();
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  std::size_t start = 0;
  for (;;) {
    const std::size_t colon = dirs.find(':', start);
    const std::string dir = dirs.substr(start, colon == std::string::npos ? std::string::npos : colon - start);
    const std::string candidate = (dir.empty() ? std::string(".") : dir) + "/gnuplot";
    if (executable(candidate)) return candidate;
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  return {};
}

bool write_plot(const PlotFigure& figure, const std::string& path, const std::string& verb) {
  const std::string ext = extension_of(path);
  if (ext != ".svg" && ext != ".png") throw std::invalid_argument("--plot: the plot file must end in .svg or .png");
  const std::string gnuplot = find_gnuplot();
  if (gnuplot.empty()) {
    note(verb, "gnuplot was not found, so no plot was written to " + path +
                   ". To get plots, install gnuplot (Debian/Ubuntu: sudo apt-get install gnuplot-nox; "
                   "macOS: brew install gnuplot) or set SYSID_GNUPLOT to the gnuplot program.");
    return false;
  }
  if (figure.panels.empty()) throw std::invalid_argument("plot: nothing to draw");

  ScratchDir dir;
  const int columns = std::max(1, figure.columns);
  const int rows = static_cast<int>((figure.panels.size() + static_cast<std::size_t>(columns) - 1) / static_cast<std::size_t>(columns));
  const int height = figure.height_per_row * rows + (figure.title.empty() ? 0 : 30);
  const std::string picture = dir.file("plot" + ext);

  std::ostringstream gp;
  gp << terminal_for(ext, gnuplot, figure.width, height, verb) << "\n";
  gp << "set output " << quoted(picture) << "\n";
  gp << "set multiplot layout " << rows << "," << columns;
  if (!figure.title.empty()) gp << " title " << quoted(figure.title);
  gp << "\n";
  int file_no = 0;
  for (const PlotPanel& p : figure.panels) {
    gp << "reset\nset grid lc rgb \"#dddddd\"\nset key top right opaque box lc rgb \"#cccccc\" samplen 2\n";
    gp << "set title " << quoted(p.title) << "\nset xlabel " << quoted(p.xlabel) << "\nset ylabel " << quoted(p.ylabel) << "\n";
    if (p.logx) gp << "set logscale x\nset format x \"%g\"\n";
    if (p.logy) gp << "set logscale y\nset format y \"%g\"\n";
    if (p.xrange) gp << "set xrange [" << p.xrange->first << ":" << p.xrange->second << "]\n";
    if (p.yrange) gp << "set yrange [" << p.yrange->first << ":" << p.yrange->second << "]\n";
    if (p.square) gp << "set size ratio -1\n";
    if (p.unit_circle) gp << "set object 1 circle at 0,0 size 1 fs empty border lc rgb \"#888888\" dt 2\n";
    std::vector<std::string> items;
    for (std::size_t c = 0; c < p.curves.size(); ++c) {
      const PlotCurve& curve = p.curves[c];
      const std::string data = dir.file("d" + std::to_string(file_no++) + ".dat");
      write_curve_data(data, curve);
      const int ci = curve.color >= 0 ? curve.color : static_cast<int>(c);
      const std::string color = std::string("rgb \"") + kPalette[ci % kPaletteSize] + "\"";
      if (curve.lo.size() == curve.x.size() && curve.hi.size() == curve.x.size() && curve.x.size() > 0)
        items.push_back(quoted(data) + " using 1:3:4 with filledcurves fc " + color +
                        " fs transparent solid 0.18 noborder notitle");
      std::string item = quoted(data) + " using 1:2 with " + curve.style + " lc " + color;
      if (curve.style == "lines" || curve.style == "linespoints" || curve.style == "impulses")
        item += curve.dashed ? " lw 1.5 dt 2" : " lw 1.5";
      if (curve.style == "points" || curve.style == "linespoints")
        item += " pt " + std::to_string(curve.point_type) + " ps " + std::to_string(curve.point_size);
      item += curve.title.empty() ? " notitle" : " title " + quoted(curve.title);
      items.push_back(item);
    }
    if (items.empty()) {
      gp << "set key off\nplot NaN notitle\n";  // an empty panel keeps the layout
      continue;
    }
    gp << "plot ";
    for (std::size_t k = 0; k < items.size(); ++k) gp << (k ? ", \\\n     " : "") << items[k];
    gp << "\n";
  }
  gp << "unset multiplot\nset output\n";
  const std::string script = dir.file("plot.gp");
  {
    std::ofstream s(script);
    s << gp.str();
    if (!s) throw std::runtime_error("cannot write the gnuplot script " + script);
  }
  const std::string log = dir.file("gnuplot.log");
  const int rc = run_command(shell_quoted(gnuplot) + " " + shell_quoted(script) + " > " + shell_quoted(log) + " 2>&1");
  std::error_code ec;
  if (rc != 0 || !std::filesystem::exists(picture, ec) || std::filesystem::file_size(picture, ec) == 0) {
    std::ifstream l(log);
    std::ostringstream msg;
    msg << l.rdbuf();
    std::string text = msg.str();
    if (text.size() > 2000) text = text.substr(0, 2000) + "...";
    throw std::runtime_error("gnuplot (" + gnuplot + ") failed with status " + std::to_string(rc) + ": " + text);
  }
  write_file_atomically(path, read_whole_file(picture));
  note(verb, "wrote plot " + path);
  return true;
}

Eigen::VectorXd magnitude_db(const Eigen::VectorXcd& h) {
  Eigen::VectorXd m(h.size());
  for (Eigen::Index k = 0; k < h.size(); ++k) {
    const double a = std::abs(h(k));
    m(k) = a > 0.0 && std::isfinite(a) ? 20.0 * std::log10(a) : NAN;
  }
  return m;
}

Eigen::VectorXd unwrapped_phase_deg(const Eigen::VectorXcd& h) {
  Eigen::VectorXd p(h.size());
  double offset = 0.0, previous = NAN;
  for (Eigen::Index k = 0; k < h.size(); ++k) {
    const double raw = std::arg(h(k)) * 180.0 / std::numbers::pi;
    if (!std::isfinite(std::abs(h(k)))) {
      p(k) = NAN;
      continue;
    }
    if (std::isfinite(previous)) {
      while (raw + offset - previous > 180.0) offset -= 360.0;
      while (raw + offset - previous < -180.0) offset += 360.0;
    }
    p(k) = raw + offset;
    previous = p(k);
  }
  return p;
}

std::vector<PlotPanel> bode_panels(const std::vector<BodeCurve>& curves, const std::string& title) {
  PlotPanel mag, phase;
  mag.title = title.empty() ? std::string("magnitude") : title + ": magnitude";
  phase.title = title.empty() ? std::string("phase") : title + ": phase";
  mag.xlabel = phase.xlabel = "frequency [Hz]";
  mag.ylabel = "|H| [dB]";
  phase.ylabel = "phase [deg]";
  mag.logx = phase.logx = true;
  for (std::size_t c = 0; c < curves.size(); ++c) {
    const BodeCurve& b = curves[c];
    Eigen::Index first = 0;
    while (first < b.f.size() && !(b.f(first) > 0.0)) ++first;
    const Eigen::Index n = b.f.size() - first;
    const Eigen::VectorXcd h = b.h.segment(first, n);
    PlotCurve m, p;
    m.title = p.title = b.title;
    m.x = p.x = b.f.segment(first, n);
    m.y = magnitude_db(h);
    p.y = unwrapped_phase_deg(h);
    m.color = p.color = b.color >= 0 ? b.color : static_cast<int>(c);
    m.dashed = p.dashed = b.dashed;
    if (b.mag_lo.size() == b.f.size() && b.mag_hi.size() == b.f.size()) {
      m.lo = magnitude_db(b.mag_lo.segment(first, n).cast<std::complex<double>>());
      m.hi = magnitude_db(b.mag_hi.segment(first, n).cast<std::complex<double>>());
      // An infinite upper or zero lower bound: shade to the curve itself (no band there).
      for (Eigen::Index k = 0; k < n; ++k) {
        if (!std::isfinite(m.lo(k))) m.lo(k) = m.y(k);
        if (!std::isfinite(m.hi(k))) m.hi(k) = m.y(k);
      }
    }
    if (b.phase_halfwidth_deg.size() == b.f.size()) {
      p.lo = p.y - b.phase_halfwidth_deg.segment(first, n);
      p.hi = p.y + b.phase_halfwidth_deg.segment(first, n);
    }
    mag.curves.push_back(std::move(m));
    phase.curves.push_back(std::move(p));
  }
  return {mag, phase};
}

Eigen::Index plot_stride(Eigen::Index rows, Eigen::Index max_points) {
  return rows <= max_points ? 1 : (rows + max_points - 1) / max_points;
}

}  // namespace sysid::cli
