// Line, point and box plots rendered by gnuplot (Debian package gnuplot-nox) into an SVG or PNG file.
//
// ident does not draw pictures itself: a figure is a list of panels stacked vertically, each a list of
// (x, y) series; RenderPlot writes the data and a gnuplot script to a private temporary directory, runs
// gnuplot, and checks that the image was written. The format follows the file extension. gnuplot writes
// the image into an OutputFile's temporary file (cli/output_file.h), renamed onto the target on success.
//
//   PlotPanel panel{.title = "validation", .xlabel = "t", .ylabel = "y"};
//   panel.series.push_back({"measured", t, y});
//   panel.series.push_back({"one-step", t, y_hat});
//   RenderPlot("fit.svg", {panel});
//
// Text is printed as written (gnuplot's enhanced mode is off: `a_1` is not a subscript).
//
// Errors (unknown extension, gnuplot missing or failing, unwritable file) throw ident::InvalidArgument
// with one line naming the file, so the CLI exits 1.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace ident::cli {

class OutputFile;

struct PlotSeries {
  std::string title;
  std::vector<double> x;
  std::vector<double> y;  // same length as x; non-finite values leave a gap
  // gnuplot's `with` clause, e.g. "points pt 7 ps 0.5 lc rgb 'red'" or "boxplot"; empty: "lines lw 1.5".
  // A boxplot series has one x value (its position) and its y values are the sample.
  std::string style = {};
};

struct PlotRange {
  double low = 0, high = 0;
};

struct PlotPanel {
  std::string title;
  std::string xlabel;
  std::string ylabel;
  std::vector<PlotSeries> series;
  std::optional<PlotRange> xrange = {}, yrange = {};       // empty: gnuplot's autoscale
  std::vector<std::pair<double, std::string>> xtics = {};  // labelled x positions (categories); empty: numbers
};

struct PlotSize {
  int width = 1000;            // pixels
  int height_per_panel = 320;  // pixels
  // The plot areas span these fractions of the width in every panel (aligned); the keys go to the right.
  double left = 0.08, right = 0.72;
};

// Renders `panels` (at least one, each with at least one non-empty series) into `path` (*.svg or *.png),
// through an OutputFile: `path` gets the complete image or keeps its old content.
void RenderPlot(const std::string& path, const std::vector<PlotPanel>& panels, PlotSize size = {});

// The same into `out`'s temporary file (the format follows out.path()); the caller commits `out`, so a
// command with several outputs replaces them all only when every one is complete.
void RenderPlot(OutputFile& out, const std::vector<PlotPanel>& panels, PlotSize size = {});

// Throws InvalidArgument unless `path` ends in .svg or .png (checked before a command's work).
void CheckPlotFileName(const std::string& path);

// True when a gnuplot executable is on PATH.
bool GnuplotAvailable();

}  // namespace ident::cli
