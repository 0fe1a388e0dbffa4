#include "cli/gnuplot.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string_view>

#include <fmt/format.h>

#include "cli/output_file.h"
#include "common/error.h"

namespace ident::cli {
namespace {

namespace fs = std::filesystem;

// A private directory under the system temp dir, removed on destruction.
class ScratchDirectory {
 public:
  ScratchDirectory() {
    std::string pattern = (fs::temp_directory_path() / "ident-plot-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw InvalidArgument("cannot create a temporary directory for the plot");
    path_ = pattern;
  }
  ~ScratchDirectory() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  ScratchDirectory(const ScratchDirectory&) = delete;
  ScratchDirectory& operator=(const ScratchDirectory&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// gnuplot string literal in single quotes: a quote is doubled.
std::string Quoted(std::string_view text) {
  std::string out = "'";
  for (char c : text) {
    if (c == '\'')
      out += "''";
    else
      out += c;
  }
  return out + "'";
}

std::string ShellQuoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) {
    if (c == '\'')
      out += "'\\''";
    else
      out += c;
  }
  return out + "'";
}

std::string Terminal(const std::string& path, int width, int height) {
  const std::string ext = fs::path(path).extension().string();
  if (ext == ".svg") return fmt::format("svg size {},{} dynamic background rgb 'white'", width, height);
  if (ext == ".png") return fmt::format("pngcairo size {},{} background rgb 'white'", width, height);
  throw InvalidArgument(fmt::format("plot file '{}': unknown format; use a name ending in .svg or .png", path));
}

void WriteSeries(const fs::path& file, const PlotSeries& s) {
  std::ofstream out(file);
  out.precision(17);
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    if (std::isfinite(s.x[i]) && std::isfinite(s.y[i]))
      out << s.x[i] << ' ' << s.y[i] << '\n';
    else
      out << '\n';  // a blank line is a gap in gnuplot
  }
  if (!out) throw InvalidArgument(fmt::format("cannot write plot data to '{}'", file.string()));
}

}  // namespace

bool GnuplotAvailable() { return std::system("command -v gnuplot > /dev/null 2>&1") == 0; }

void CheckPlotFileName(const std::string& path) { Terminal(path, 1, 1); }

void RenderPlot(const std::string& path, const std::vector<PlotPanel>& panels, PlotSize size) {
  CheckPlotFileName(path);
  OutputFile out(path, "plot");
  RenderPlot(out, panels, size);
  out.Commit();
}

void RenderPlot(OutputFile& out, const std::vector<PlotPanel>& panels, PlotSize size) {
  const std::string& path = out.path();
  IDENT_REQUIRE(!panels.empty(), "plot '{}': nothing to draw", path);
  const int height = size.height_per_panel * static_cast<int>(panels.size());
  const std::string terminal = Terminal(path, size.width, height);
  if (!GnuplotAvailable()) {
    throw InvalidArgument(
        fmt::format("cannot write plot '{}': gnuplot is not installed (Debian: apt-get install gnuplot-nox)", path));
  }

  ScratchDirectory scratch;
  std::string script = fmt::format("set terminal {}\nset output {}\nset multiplot layout {},1\n", terminal,
                                   Quoted(fs::absolute(out.temp_path()).string()), panels.size());
  script += "set termoption noenhanced\nset grid\nset style data lines\n";
  script += fmt::format("set lmargin at screen {}\nset rmargin at screen {}\n", size.left, size.right);
  script += fmt::format("set key at screen {}, graph 1 left top Left reverse\n", size.right + 0.02);
  script += "set style boxplot nooutliers\nset style fill empty\nset boxwidth 0.4\n";
  for (std::size_t p = 0; p < panels.size(); ++p) {
    const PlotPanel& panel = panels[p];
    IDENT_REQUIRE(!panel.series.empty(), "plot '{}': panel {} has no series", path, p + 1);
    script += fmt::format("set title {}\nset xlabel {}\nset ylabel {}\n", Quoted(panel.title), Quoted(panel.xlabel),
                          Quoted(panel.ylabel));
    script += panel.xrange ? fmt::format("set xrange [{:.17g}:{:.17g}]\n", panel.xrange->low, panel.xrange->high)
                           : "set xrange [*:*]\n";
    script += panel.yrange ? fmt::format("set yrange [{:.17g}:{:.17g}]\n", panel.yrange->low, panel.yrange->high)
                           : "set yrange [*:*]\n";
    if (panel.xtics.empty()) {
      script += "set xtics autofreq\n";
    } else {
      script += "set xtics (";
      for (std::size_t i = 0; i < panel.xtics.size(); ++i)
        script += fmt::format("{}{} {:.17g}", i ? ", " : "", Quoted(panel.xtics[i].second), panel.xtics[i].first);
      script += ")\n";
    }
    script += "plot ";
    for (std::size_t k = 0; k < panel.series.size(); ++k) {
      const PlotSeries& s = panel.series[k];
      IDENT_REQUIRE(s.x.size() == s.y.size() && !s.x.empty(), "plot '{}': series '{}' has {} x and {} y values", path,
                    s.title, s.x.size(), s.y.size());
      const fs::path data = scratch.path() / fmt::format("p{}s{}.dat", p, k);
      WriteSeries(data, s);
      script += fmt::format("{}{} using 1:2 {} with {}", k == 0 ? "" : ", ", Quoted(data.string()),
                            s.title.empty() ? "notitle" : "title " + Quoted(s.title),
                            s.style.empty() ? "lines lw 1.5" : s.style);
    }
    script += "\n";
  }
  script += "unset multiplot\nset output\n";

  const fs::path script_file = scratch.path() / "plot.gp";
  const fs::path log_file = scratch.path() / "gnuplot.log";
  {
    std::ofstream script_out(script_file);
    script_out << script;
    if (!script_out.flush()) throw InvalidArgument(fmt::format("cannot write the gnuplot script for plot '{}'", path));
  }
  const std::string command =
      fmt::format("gnuplot {} > {} 2>&1", ShellQuoted(script_file.string()), ShellQuoted(log_file.string()));
  const int status = std::system(command.c_str());
  std::error_code ec;
  const auto written = fs::file_size(out.temp_path(), ec);
  if (status != 0 || ec || written == 0) {
    std::ifstream log(log_file);
    std::string first_line;
    std::getline(log, first_line);
    while (first_line.empty() && std::getline(log, first_line)) {}
    throw InvalidArgument(
        fmt::format("cannot write plot '{}': gnuplot failed{}{}", path, first_line.empty() ? "" : ": ", first_line));
  }
}

}  // namespace ident::cli
