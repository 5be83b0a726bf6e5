// The plots of `skyloc eval` and `skyloc experiment`: points land where the axis mapping
// puts them, matches are coloured by their correctness, and the documents are whole.
#include "tools/svg_plot.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace skyloc::tools {
namespace {

std::size_t CountOf(std::string_view text, std::string_view what) {
  std::size_t count = 0;
  for (std::size_t at = text.find(what); at != std::string_view::npos;
       at = text.find(what, at + what.size()))
    ++count;
  return count;
}

// The first element (from '<' to '>') that contains `attribute`; empty when none does.
std::string ElementWith(const std::string& svg, std::string_view attribute) {
  const std::size_t at = svg.find(attribute);
  if (at == std::string::npos)
    return "";
  const std::size_t start = svg.rfind('<', at);
  return svg.substr(start, svg.find('>', at) - start + 1);
}

void ExpectWholeDocument(const std::string& svg) {
  EXPECT_EQ(svg.rfind("<svg xmlns=\"http://www.w3.org/2000/svg\"", 0), 0u) << svg;
  ASSERT_GE(svg.size(), 7u);
  EXPECT_EQ(svg.substr(svg.size() - 7), "</svg>\n");
  EXPECT_EQ(CountOf(svg, "<svg"), 1u);
}

dsp::PrPoint Point(double recall, double precision) {
  dsp::PrPoint p;
  p.recall = recall;
  p.precision = precision;
  return p;
}

TEST(SvgPlot, PrPointLandsWhereTheAxesPutIt) {
  // The plot area is x 70..530 (recall 0..1) and y 40..440 (precision 1..0): recall 0.5,
  // precision 0.25 is at x = 70 + 0.5 * 460 = 300, y = 40 + 0.75 * 400 = 340. The step
  // to it runs from recall 0 at that precision.
  const std::vector<PrCurve> curves = {{"one point", {Point(0.5, 0.25)}, LineDash::kSolid}};
  const std::string svg = PrPlotSvg("title", curves);
  ExpectWholeDocument(svg);
  EXPECT_NE(svg.find("points=\"70.0,340.0 300.0,340.0 \""), std::string::npos) << svg;
}

TEST(SvgPlot, PrCurveIsAStepPerPoint) {
  // (0.25, 1) then (0.75, 0.5): up at precision 1 from recall 0 to 0.25, then at 0.5 from
  // 0.25 to 0.75 (x 185.0 and 415.0; y 40.0 and 240.0).
  const std::vector<PrCurve> curves = {
      {"two points", {Point(0.25, 1.0), Point(0.75, 0.5)}, LineDash::kSolid}};
  const std::string svg = PrPlotSvg("title", curves);
  EXPECT_NE(svg.find("points=\"70.0,40.0 185.0,40.0 185.0,240.0 415.0,240.0 \""), std::string::npos)
      << svg;
}

TEST(SvgPlot, PrPlotHasOnePolylineAndLegendEntryPerCurve) {
  const std::vector<PrCurve> curves = {{"sky ds=1", {Point(1, 0.5)}, LineDash::kDashed},
                                       {"sky ds=10", {Point(1, 0.8)}, LineDash::kSolid},
                                       {"vanilla ds=20", {Point(1, 0.9)}, LineDash::kDotted}};
  const std::string svg = PrPlotSvg("Precision & recall", curves);
  ExpectWholeDocument(svg);
  EXPECT_EQ(CountOf(svg, "<polyline"), 3u);
  EXPECT_NE(svg.find(">Precision &amp; recall</text>"), std::string::npos) << "escaped title";
  EXPECT_NE(svg.find(">Recall</text>"), std::string::npos);
  EXPECT_NE(svg.find(">Precision</text>"), std::string::npos);
  for (const PrCurve& c : curves)
    EXPECT_NE(svg.find(">" + c.name + "</text>"), std::string::npos) << c.name;
  // Curve and legend sample share the palette colour and the dash.
  EXPECT_EQ(CountOf(svg, "stroke=\"#1f77b4\" stroke-width=\"2\" stroke-dasharray=\"6 3\""), 2u);
  EXPECT_EQ(CountOf(svg, "stroke=\"#ff7f0e\" stroke-width=\"2\" points"), 1u);
  EXPECT_EQ(CountOf(svg, "stroke=\"#2ca02c\" stroke-width=\"2\" stroke-dasharray=\"2 2\""), 2u);
}

TEST(SvgPlot, CorrespondenceColoursCorrectGreenAndWrongRed) {
  // Five query and five reference frames: the plot area is x 60..390 for queries 0..4 and
  // y 40..340 for references 4..0. Query 2 matched to 2 (correct) is at (225, 190); query
  // 4 matched to 0 (wrong) is at (390, 340).
  CorrespondencePanel panel{"sky ds=1", {0, 1, 2, 3, 4}, 5, {}};
  panel.matches = {{2, 2, true}, {4, 0, false}};
  const std::string svg = CorrespondenceSvg({&panel, 1}, 3);
  ExpectWholeDocument(svg);
  const std::string green = ElementWith(svg, "stroke=\"#1a9e1a\"");
  const std::string red = ElementWith(svg, "stroke=\"#d62020\"");
  EXPECT_NE(green.find("d=\"M225.0 190.0h0\""), std::string::npos) << green;
  EXPECT_NE(red.find("d=\"M390.0 340.0h0\""), std::string::npos) << red;
  EXPECT_NE(svg.find(">sky ds=1 (1 of 2 correct)</text>"), std::string::npos) << svg;
  EXPECT_NE(svg.find("black: ground truth; green: correct match; red: wrong match"),
            std::string::npos);
}

TEST(SvgPlot, GroundTruthBreaksWhereTheQueryIsOffTheRoute) {
  CorrespondencePanel panel{"run", {0, 1, -1, 3, 4}, 5, {}};
  const std::string svg = CorrespondenceSvg({&panel, 1}, 3);
  ExpectWholeDocument(svg);
  EXPECT_EQ(CountOf(svg, "<polyline"), 2u);
  EXPECT_NE(svg.find("points=\"60.0,340.0 142.5,265.0 \""), std::string::npos) << svg;
  EXPECT_NE(svg.find("points=\"307.5,115.0 390.0,40.0 \""), std::string::npos) << svg;
  EXPECT_EQ(CountOf(svg, "<path"), 0u) << "no matches, no dots";
}

TEST(SvgPlot, CorrespondencePanelsFillRowsOfTheGivenColumns) {
  // A panel cell is 410 x 390 px; 30 px below the last row hold the key.
  const std::vector<CorrespondencePanel> panels(5, CorrespondencePanel{"run", {0, 1}, 2, {}});
  const std::string svg = CorrespondenceSvg(panels, 2);
  ExpectWholeDocument(svg);
  EXPECT_NE(svg.find("width=\"820\" height=\"1200\""), std::string::npos) << svg;
  EXPECT_EQ(CountOf(svg, ">run (0 of 0 correct)</text>"), 5u);
}

}  // namespace
}  // namespace skyloc::tools
