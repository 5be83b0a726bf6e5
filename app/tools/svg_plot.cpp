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

std::string PrPlotSvg(std::string_view title, std::span<const PrCurve> curves) {
  // The plot area; the legend lines go below it.
  constexpr double kLeft = 70, kTop = 40, kWidth = 460, kHeight = 400, kLegendLine = 22;
  auto sx = [](double recall) { return kLeft + recall * kWidth; };
  auto sy = [](double precision) { return kTop + (1.0 - precision) * kHeight; };
  std::string svg;
  // 260 px to the right of the plot: room for a legend line's text.
  AppendSvgStart(&svg, kLeft + kWidth + 260,
                 kTop + kHeight + 60 + kLegendLine * static_cast<double>(curves.size()));
  Append(&svg, "<text x=\"%.1f\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">%s</text>\n",
         kLeft + kWidth / 2, XmlEscape(title).c_str());
  for (int i = 0; i <= 5; ++i) {
    const double v = i / 5.0;
    Append(&svg,
           "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n"
           "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n",
           sx(v), sy(0), sx(v), sy(1), sx(0), sy(v), sx(1), sy(v));
    Append(&svg,
           "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%.1f</text>\n"
           "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%.1f</text>\n",
           sx(v), sy(0) + 16, v, sx(0) - 6, sy(v) + 4, v);
  }
  Append(&svg,
         "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
         "stroke=\"black\"/>\n",
         kLeft, kTop, kWidth, kHeight);
  Append(&svg, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">Recall</text>\n",
         kLeft + kWidth / 2, kTop + kHeight + 36);
  Append(&svg,
         "<text x=\"18\" y=\"%.1f\" text-anchor=\"middle\" transform=\"rotate(-90 18 "
         "%.1f)\">Precision</text>\n",
         kTop + kHeight / 2, kTop + kHeight / 2);
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const PrCurve& curve = curves[i];
    const char* colour = kPalette[i % kPaletteSize];
    const char* dash = DashAttribute(curve.dash);
    Append(&svg, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"2\"%s points=\"", colour,
           dash);
    // Steps: along the previous recall at the new precision, then along the new precision,
    // as the area under the curve sums them (docs/SEQSLAM.md).
    double previous_recall = 0.0;
    for (const dsp::PrPoint& p : curve.points) {
      Append(&svg, "%.1f,%.1f %.1f,%.1f ", sx(previous_recall), sy(p.precision), sx(p.recall),
             sy(p.precision));
      previous_recall = p.recall;
    }
    svg += "\"/>\n";
    const double legend_y = kTop + kHeight + 56 + kLegendLine * static_cast<double>(i);
    Append(&svg,
           "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" "
           "stroke-width=\"2\"%s/>\n",
           kLeft, legend_y - 4, kLeft + 30, legend_y - 4, colour, dash);
    Append(&svg, "<text x=\"%.1f\" y=\"%.1f\">%s</text>\n", kLeft + 38, legend_y,
           XmlEscape(curve.name).c_str());
  }
  return svg + "</svg>\n";
}

std::string RocPlotSvg(std::string_view title, std::span<const RocCurveLine> curves) {
  constexpr double kLeft = 70, kTop = 40, kSize = 400, kLegendLine = 22;
  auto sx = [](double fpr) { return kLeft + fpr * kSize; };
  auto sy = [](double tpr) { return kTop + (1.0 - tpr) * kSize; };
  std::string svg;
  AppendSvgStart(&svg, kLeft + kSize + 320,
                 kTop + kSize + 60 + kLegendLine * static_cast<double>(curves.size()));
  Append(&svg, "<text x=\"%.1f\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">%s</text>\n",
         kLeft + kSize / 2, XmlEscape(title).c_str());
  for (int i = 0; i <= 5; ++i) {
    const double v = i / 5.0;
    Append(&svg,
           "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n"
           "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n"
           "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%.1f</text>\n"
           "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%.1f</text>\n",
           sx(v), sy(0), sx(v), sy(1), sx(0), sy(v), sx(1), sy(v), sx(v), sy(0) + 16, v, sx(0) - 6,
           sy(v) + 4, v);
  }
  Append(&svg,
         "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#999\" "
         "stroke-dasharray=\"4 4\"/>\n"
         "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
         "stroke=\"black\"/>\n",
         sx(0), sy(0), sx(1), sy(1), kLeft, kTop, kSize, kSize);
  Append(&svg, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">False positive rate</text>\n",
         kLeft + kSize / 2, kTop + kSize + 36);
  Append(&svg,
         "<text x=\"18\" y=\"%.1f\" text-anchor=\"middle\" transform=\"rotate(-90 18 "
         "%.1f)\">True positive rate</text>\n",
         kTop + kSize / 2, kTop + kSize / 2);
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const char* colour = kPalette[i % kPaletteSize];
    const char* dash = DashAttribute(curves[i].dash);
    Append(&svg, "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"2\"%s points=\"", colour,
           dash);
    for (const dsp::RocPoint& p : curves[i].points)
      Append(&svg, "%.1f,%.1f ", sx(p.false_positive_rate), sy(p.true_positive_rate));
    svg += "\"/>\n";
    const double legend_y = kTop + kSize + 56 + kLegendLine * static_cast<double>(i);
    Append(&svg,
           "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" "
           "stroke-width=\"2\"%s/>\n",
           kLeft, legend_y - 4, kLeft + 30, legend_y - 4, colour, dash);
    Append(&svg, "<text x=\"%.1f\" y=\"%.1f\">%s</text>\n", kLeft + 38, legend_y,
           XmlEscape(curves[i].name).c_str());
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
