// RenderPlot: real gnuplot output in both formats, and the one-line errors of bad requests.
#include "cli/gnuplot.h"

#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>

#include "common/error.h"
#include "tests/support/cli.h"

namespace ident::testing {
namespace {

using cli::PlotPanel;
using cli::RenderPlot;

PlotPanel SinePanel() {
  PlotPanel panel{"sine", "t", "y", {}};
  cli::PlotSeries s{"sin", {}, {}};
  for (int i = 0; i < 200; ++i) {
    s.x.push_back(0.05 * i);
    s.y.push_back(i == 100 ? NAN : std::sin(0.05 * i));  // a gap must not break the plot
  }
  panel.series.push_back(s);
  return panel;
}

TEST(RenderPlot, WritesSvgWithTheSeriesTitles) {
  const std::string path = TempDir() + "/sine.svg";
  RenderPlot(path, {SinePanel(), SinePanel()});
  const std::string svg = ReadFile(path);
  EXPECT_GT(svg.size(), 1000u);
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("sine"), std::string::npos);
}

TEST(RenderPlot, WritesPng) {
  const std::string path = TempDir() + "/sine.png";
  RenderPlot(path, {SinePanel()});
  const std::string png = ReadFile(path);
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
}

TEST(RenderPlot, RejectsUnknownFormatAndEmptyRequests) {
  EXPECT_THROW(RenderPlot(TempDir() + "/x.pdf", {SinePanel()}), InvalidArgument);
  EXPECT_THROW(RenderPlot(TempDir() + "/x.svg", {}), InvalidArgument);
  EXPECT_THROW(RenderPlot(TempDir() + "/x.svg", {PlotPanel{"empty", "", "", {}}}), InvalidArgument);
  PlotPanel ragged{"ragged", "", "", {{"r", {1, 2, 3}, {1, 2}}}};
  EXPECT_THROW(RenderPlot(TempDir() + "/x.svg", {ragged}), InvalidArgument);
}

TEST(RenderPlot, UnwritableFileIsAnError) {
  try {
    RenderPlot("/nonexistent-dir/x.svg", {SinePanel()});
    FAIL() << "expected an error";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.svg"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ident::testing
