#include "tools/svg_plot.h"

#include <algorithm>
#include <cstdarg>
#include <cstddef>
#include <cstdio>
#include <utility>

namespace skyloc::tools {
namespace {

// printf onto the end of `out`.
void Append(std::string* out, const char* format, ...) __attribute__((format(printf, 2, 3)));
void Append(std::string* out, const char* format, ...) {
  std::va_list args;
  va_start(args, format);
  std::va_list args_again;
  va_copy(args_again, args);
  const int length = std::vsnprintf(nullptr, 0, format, args);
  va_end(args);
  if (length > 0) {
    const std::size_t at = out->size();
    const std::size_t size = static_cast<std::size_t>(length);
    out->resize(at + size + 1);  // vsnprintf writes the terminating '\0' too
    std::vsnprintf(out->data() + at, size + 1, format, args_again);
    out->resize(at + size);
  }
  va_end(args_again);
}

std::string XmlEscape(std::string_view s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

void AppendSvgStart(std::string* svg, double width, double height) {
  Append(svg,
         "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
         "font-family=\"sans-serif\" font-size=\"12\">\n"
         "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
         width, height);
}

constexpr const char* kPalette[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
constexpr std::size_t kPaletteSize = sizeof kPalette / sizeof kPalette[0];

const char* DashAttribute(LineDash dash) {
  switch (dash) {
    case LineDash::kDashed:
      return " stroke-dasharray=\"6 3\"";
    case LineDash::kDotted:
      return " stroke-dasharray=\"2 2\"";
    case LineDash::kSolid:
      break;
  }
  return "";
}

}  // namespace

namespace {

// A plot of the unit square (both axes 0 to 1) with its title above, ticks every 0.2, the
// axis names and a legend line per curve below it.
struct UnitSquarePlot {
  double left = 70, top = 40, width = 400, height = 400;
  static constexpr double kLegendLine = 22;
  double X(double v) const { return left + v * width; }
  double Y(double v) const { return top + (1.0 - v) * height; }
};

// The plot's frame; `diagonal` draws the chance line y = x (a ROC plot's).
void AppendUnitSquareFrame(std::string* svg, const UnitSquarePlot& p, std::string_view title,
                           const char* x_name, const char* y_name, bool diagonal) {
  Append(svg, "<text x=\"%.1f\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">%s</text>\n",
         p.left + p.width / 2, XmlEscape(title).c_str());
  for (int i = 0; i <= 5; ++i) {
    const double v = i / 5.0;
    Append(svg,
           "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n"
           "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n"
           "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%.1f</text>\n"
           "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%.1f</text>\n",
           p.X(v), p.Y(0), p.X(v), p.Y(1), p.X(0), p.Y(v), p.X(1), p.Y(v), p.X(v), p.Y(0) + 16, v,
           p.X(0) - 6, p.Y(v) + 4, v);
  }
  if (diagonal) {
    Append(svg,
           "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#999\" "
           "stroke-dasharray=\"4 4\"/>\n",
           p.X(0), p.Y(0), p.X(1), p.Y(1));
  }
  Append(svg,
         "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
         "stroke=\"black\"/>\n",
         p.left, p.top, p.width, p.height);
  Append(svg, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%s</text>\n",
         p.left + p.width / 2, p.top + p.height + 36, x_name);
  Append(svg,
         "<text x=\"18\" y=\"%.1f\" text-anchor=\"middle\" transform=\"rotate(-90 18 "
         "%.1f)\">%s</text>\n",
         p.top + p.height / 2, p.top + p.height / 2, y_name);
}

// Curve I's polyline opening (its colour and dash); the caller appends the points and
// closes it with AppendCurveEnd.
void AppendCurveStart(std::string* svg, std::size_t i, LineDash dash) {
  Append(svg, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"2\"%s points=\"",
         kPalette[i % kPaletteSize], DashAttribute(dash));
}

// Closes curve I's polyline and writes its legend line below the plot.
void AppendCurveEnd(std::string* svg, const UnitSquarePlot& p, std::size_t i, LineDash dash,
                    std::string_view name) {
  *svg += "\"/>\n";
  const double legend_y =
      p.top + p.height + 56 + UnitSquarePlot::kLegendLine * static_cast<double>(i);
  Append(svg,
         "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" "
         "stroke-width=\"2\"%s/>\n",
         p.left, legend_y - 4, p.left + 30, legend_y - 4, kPalette[i % kPaletteSize],
         DashAttribute(dash));
  Append(svg, "<text x=\"%.1f\" y=\"%.1f\">%s</text>\n", p.left + 38, legend_y,
         XmlEscape(name).c_str());
}

// The height of a plot with N legend lines below it.
double PlotHeight(const UnitSquarePlot& p, std::size_t n) {
  return p.top + p.height + 60 + UnitSquarePlot::kLegendLine * static_cast<double>(n);
}

}  // namespace

std::string PrPlotSvg(std::string_view title, std::span<const PrCurve> curves) {
  UnitSquarePlot plot;
  plot.width = 460;
  std::string svg;
  // 260 px to the right of the plot: room for a legend line's text.
  AppendSvgStart(&svg, plot.left + plot.width + 260, PlotHeight(plot, curves.size()));
  AppendUnitSquareFrame(&svg, plot, title, "Recall", "Precision", false);
  for (std::size_t i = 0; i < curves.size(); ++i) {
    AppendCurveStart(&svg, i, curves[i].dash);
    // Steps: along the previous recall at the new precision, then along the new precision,
    // as the area under the curve sums them (docs/SEQSLAM.md).
    double previous_recall = 0.0;
    for (const dsp::PrPoint& p : curves[i].points) {
      Append(&svg, "%.1f,%.1f %.1f,%.1f ", plot.X(previous_recall), plot.Y(p.precision),
             plot.X(p.recall), plot.Y(p.precision));
      previous_recall = p.recall;
    }
    AppendCurveEnd(&svg, plot, i, curves[i].dash, curves[i].name);
  }
  return svg + "</svg>\n";
}

std::string RocPlotSvg(std::string_view title, std::span<const RocCurveLine> curves) {
  const UnitSquarePlot plot;
  std::string svg;
  AppendSvgStart(&svg, plot.left + plot.width + 320, PlotHeight(plot, curves.size()));
  AppendUnitSquareFrame(&svg, plot, title, "False positive rate", "True positive rate", true);
  for (std::size_t i = 0; i < curves.size(); ++i) {
    AppendCurveStart(&svg, i, curves[i].dash);
    for (const dsp::RocPoint& p : curves[i].points)
      Append(&svg, "%.1f,%.1f ", plot.X(p.false_positive_rate), plot.Y(p.true_positive_rate));
    AppendCurveEnd(&svg, plot, i, curves[i].dash, curves[i].name);
  }
  return svg + "</svg>\n";
}

std::string CorrespondenceSvg(std::span<const CorrespondencePanel> panels, int columns) {
  // A panel's plot area and its margins for the title, the ticks and the axis names.
  constexpr double kPlotWidth = 330, kPlotHeight = 300;
  constexpr double kMarginLeft = 60, kMarginTop = 40, kMarginBottom = 50, kMarginRight = 20;
  constexpr double kCellWidth = kMarginLeft + kPlotWidth + kMarginRight;
  constexpr double kCellHeight = kMarginTop + kPlotHeight + kMarginBottom;
  const std::size_t per_row = std::max<std::size_t>(
      1, std::min(panels.size(), static_cast<std::size_t>(std::max(columns, 1))));
  const std::size_t rows = (panels.size() + per_row - 1) / per_row;
  std::string svg;
  // 30 px below the panels for the key.
  AppendSvgStart(&svg, kCellWidth * static_cast<double>(per_row),
                 kCellHeight * static_cast<double>(rows) + 30);
  Append(&svg,
         "<text x=\"10\" y=\"%.1f\">black: ground truth; green: correct match; red: wrong "
         "match</text>\n",
         kCellHeight * static_cast<double>(rows) + 20);
  for (std::size_t i = 0; i < panels.size(); ++i) {
    const CorrespondencePanel& panel = panels[i];
    const double origin_x = kCellWidth * static_cast<double>(i % per_row);
    const double left = origin_x + kMarginLeft;
    const double top = kCellHeight * static_cast<double>(i / per_row) + kMarginTop;
    const int query_frames = static_cast<int>(panel.ground_truth.size());
    const double last_query = std::max(1, query_frames - 1);
    const double last_reference = std::max(1, panel.reference_frames - 1);
    auto sx = [&](double query) { return left + query / last_query * kPlotWidth; };
    auto sy = [&](double reference) {
      return top + (1.0 - reference / last_reference) * kPlotHeight;
    };
    const auto correct = std::count_if(panel.matches.begin(), panel.matches.end(),
                                       [](const CorrespondenceMatch& m) { return m.correct; });
    Append(&svg,
           "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" font-size=\"14\">%s "
           "(%td of %zu correct)</text>\n",
           left + kPlotWidth / 2, top - 14, XmlEscape(panel.name).c_str(), correct,
           panel.matches.size());
    Append(&svg,
           "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
           "stroke=\"black\"/>\n",
           left, top, kPlotWidth, kPlotHeight);
    for (int k = 0; k <= 4; ++k) {
      const double query = last_query * k / 4.0, reference = last_reference * k / 4.0;
      Append(&svg,
             "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%.0f</text>\n"
             "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%.0f</text>\n",
             sx(query), top + kPlotHeight + 16, query, left - 6, sy(reference) + 4, reference);
    }
    Append(&svg, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">query frame</text>\n",
           left + kPlotWidth / 2, top + kPlotHeight + 36);
    Append(&svg,
           "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" transform=\"rotate(-90 %.1f "
           "%.1f)\">reference frame</text>\n",
           origin_x + 16, top + kPlotHeight / 2, origin_x + 16, top + kPlotHeight / 2);
    // The ground truth: one polyline per stretch of the query on the route.
    bool line_open = false;
    for (int q = 0; q < query_frames; ++q) {
      const int truth = panel.ground_truth[static_cast<std::size_t>(q)];
      if (truth < 0) {
        if (line_open)
          svg += "\"/>\n";
        line_open = false;
        continue;
      }
      if (!line_open)
        svg += "<polyline fill=\"none\" stroke=\"black\" stroke-width=\"1.5\" points=\"";
      line_open = true;
      Append(&svg, "%.1f,%.1f ", sx(q), sy(truth));
    }
    if (line_open)
      svg += "\"/>\n";
    // One path per colour, each match a zero-length segment whose round cap is the dot: a
    // few bytes a match, so the plot of a whole experiment stays small.
    std::string correct_dots, wrong_dots;
    for (const CorrespondenceMatch& m : panel.matches) {
      Append(m.correct ? &correct_dots : &wrong_dots, "M%.1f %.1fh0", sx(m.query), sy(m.reference));
    }
    for (const auto& [dots, colour] :
         {std::pair{&correct_dots, "#1a9e1a"}, std::pair{&wrong_dots, "#d62020"}}) {
      if (!dots->empty()) {
        Append(&svg,
               "<path stroke=\"%s\" stroke-width=\"4.4\" stroke-linecap=\"round\" "
               "d=\"%s\"/>\n",
               colour, dots->c_str());
      }
    }
  }
  return svg + "</svg>\n";
}

}  // namespace skyloc::tools
