#include "rff_ceres/plot/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"

namespace rff {
namespace {

// Matplotlib's "tab10": distinct, print-friendly colours.
constexpr const char* kPalette[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                    "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                                    "#bcbd22", "#17becf"};
constexpr int kPaletteSize = sizeof(kPalette) / sizeof(kPalette[0]);

// Relative slack when comparing ticks with a range: tick values are
// computed as integer multiples of a step and carry rounding.
constexpr double kTickSlack = 1e-9;

std::string Px(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.2f", value);
  return buffer;
}

bool HasLegend(const Plot& plot) {
  for (const PlotSeries& s : plot.series) {
    if (!s.label.empty()) return true;
  }
  return false;
}

std::string SeriesColor(const PlotSeries& series, int index) {
  return series.color.empty() ? kPalette[index % kPaletteSize] : series.color;
}

// Grows [*low, *high] about its centre to `span`.
void GrowTo(double span, double* low, double* high) {
  const double centre = 0.5 * (*low + *high);
  *low = centre - 0.5 * span;
  *high = centre + 0.5 * span;
}

// The multiples of `step` inside [low, high].
std::vector<double> MultiplesInside(double low, double high, double step) {
  std::vector<double> ticks;
  const double first = std::ceil(low / step - kTickSlack);
  const double last = std::floor(high / step + kTickSlack);
  for (double k = first; k <= last + 0.5; k += 1.0) {
    const double value = k * step;
    ticks.push_back(value == 0.0 ? 0.0 : value);
  }
  return ticks;
}

}  // namespace

std::vector<double> NiceTicks(double low, double high, int target) {
  if (high < low) std::swap(low, high);
  if (high == low) {
    low -= 0.5;
    high += 0.5;
  }
  target = std::max(1, target);
  const double raw = (high - low) / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double normalized = raw / magnitude;
  const double nice = normalized <= 1.0   ? 1.0
                      : normalized <= 2.0 ? 2.0
                      : normalized <= 5.0 ? 5.0
                                          : 10.0;
  const double step = nice * magnitude;
  const double first = std::floor(low / step + kTickSlack);
  const double last = std::ceil(high / step - kTickSlack);
  std::vector<double> ticks;
  for (double k = first; k <= last + 0.5; k += 1.0) {
    const double value = k * step;
    ticks.push_back(value == 0.0 ? 0.0 : value);  // No -0.
  }
  return ticks;
}

std::vector<double> LogTicks(double low, double high) {
  if (high < low) std::swap(low, high);
  const int first = static_cast<int>(std::floor(std::log10(low)));
  const int last = static_cast<int>(std::ceil(std::log10(high)));
  auto collect = [&](const std::vector<double>& mantissas) {
    std::vector<double> ticks;
    for (int d = first; d <= last; ++d) {
      for (double m : mantissas) {
        const double value = m * std::pow(10.0, d);
        if (value >= low * (1.0 - kTickSlack) &&
            value <= high * (1.0 + kTickSlack)) {
          ticks.push_back(value);
        }
      }
    }
    return ticks;
  };
  std::vector<double> ticks = collect({1.0});
  if (ticks.size() < 3) {
    ticks = collect({1.0, 2.0, 5.0});
    // Doublings of the noise scale (x0.5 .. x4) end on a 4: label it.
    if (!ticks.empty() && 2.0 * ticks.back() <= high * (1.0 + kTickSlack)) {
      ticks.push_back(2.0 * ticks.back());
    }
  }
  return ticks;
}

std::string TickLabel(double value, double step) {
  char buffer[64];
  if (step > 0.0) {
    const int decimals = std::max(
        0, static_cast<int>(-std::floor(std::log10(step) + kTickSlack)));
    std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  } else {
    std::snprintf(buffer, sizeof(buffer), "%g", value);
  }
  std::string text = buffer;
  // "-0", "-0.0" and the like from rounding: print without the sign.
  if (text[0] == '-' && text.find_first_not_of("-0.") == std::string::npos) {
    text.erase(0, 1);
  }
  return text;
}

std::string XmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

double AxisMap::ToPixel(double value) const {
  double fraction;
  if (log) {
    fraction = (std::log10(value) - std::log10(data_low)) /
               (std::log10(data_high) - std::log10(data_low));
  } else {
    fraction = (value - data_low) / (data_high - data_low);
  }
  return pixel_low + fraction * (pixel_high - pixel_low);
}

bool ComputeLayout(const Plot& plot, PlotLayout* layout, std::string* error) {
  double x_min = std::numeric_limits<double>::infinity();
  double x_max = -x_min, y_min = x_min, y_max = -x_min;
  for (const PlotSeries& s : plot.series) {
    if (s.x.size() != s.y.size()) {
      *error = "series '" + s.label + "' has " + std::to_string(s.x.size()) +
               " x values but " + std::to_string(s.y.size()) + " y values";
      return false;
    }
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      if (plot.log_x && s.x[i] <= 0.0) {
        *error = "series '" + s.label + "': x = " + FormatNumber(s.x[i]) +
                 " on a log axis (must be > 0)";
        return false;
      }
      x_min = std::min(x_min, s.x[i]);
      x_max = std::max(x_max, s.x[i]);
      y_min = std::min(y_min, s.y[i]);
      y_max = std::max(y_max, s.y[i]);
    }
  }
  if (!(x_min <= x_max)) {
    // Nothing to show (e.g. every run failed): empty axes, legend kept.
    x_min = plot.log_x ? 1.0 : 0.0;
    x_max = plot.log_x ? 10.0 : 1.0;
    y_min = 0.0;
    y_max = 1.0;
  }
  if (plot.y_from_zero) {
    y_min = std::min(y_min, 0.0);
    y_max = std::max(y_max, 0.0);
  }

  PlotLayout& l = *layout;
  l = PlotLayout();
  l.left = kPlotMarginLeft;
  l.top = kPlotMarginTop;
  l.right = plot.width -
            (HasLegend(plot) ? kPlotLegendWidth : kPlotMarginRightNoLegend);
  l.bottom = plot.height - kPlotMarginBottom;
  if (l.right - l.left < 10.0 || l.bottom - l.top < 10.0) {
    *error = "plot '" + plot.title + "' is too small (" +
             std::to_string(plot.width) + " x " + std::to_string(plot.height) +
             " pixels)";
    return false;
  }

  double x_low, x_high;
  if (plot.log_x) {
    // A little room in log space so the end points are not on the frame.
    const double pad = x_min == x_max ? 2.0 : 1.15;
    x_low = x_min / pad;
    x_high = x_max * pad;
    l.x_ticks = LogTicks(x_low, x_high);
    l.x_step = 0.0;
  } else {
    l.x_ticks = NiceTicks(x_min, x_max);
    x_low = l.x_ticks.front();
    x_high = l.x_ticks.back();
    l.x_step = l.x_ticks[1] - l.x_ticks[0];
  }
  l.y_ticks = NiceTicks(y_min, y_max);
  double y_low = l.y_ticks.front(), y_high = l.y_ticks.back();
  l.y_step = l.y_ticks[1] - l.y_ticks[0];

  if (plot.equal_scale && !plot.log_x) {
    // The axis with fewer units per pixel grows to match the other.
    const double width = l.right - l.left, height = l.bottom - l.top;
    const double per_pixel =
        std::max((x_high - x_low) / width, (y_high - y_low) / height);
    GrowTo(per_pixel * width, &x_low, &x_high);
    GrowTo(per_pixel * height, &y_low, &y_high);
    // One tick spacing for both axes, so the grid is made of squares.
    const double step = std::max(l.x_step, l.y_step);
    l.x_ticks = MultiplesInside(x_low, x_high, step);
    l.y_ticks = MultiplesInside(y_low, y_high, step);
    l.x_step = l.y_step = step;
  }

  l.x = AxisMap{x_low, x_high, l.left, l.right, plot.log_x};
  l.y = AxisMap{y_low, y_high, l.bottom, l.top, false};
  return true;
}

bool RenderSvg(const Plot& plot, std::string* svg, std::string* error) {
  PlotLayout l;
  if (!ComputeLayout(plot, &l, error)) return false;
  std::ostringstream out;
  out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << plot.width
      << "\" height=\"" << plot.height << "\" viewBox=\"0 0 " << plot.width
      << " " << plot.height
      << "\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\">\n";
  out << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  out << "<text class=\"title\" x=\"" << Px(0.5 * (l.left + l.right))
      << "\" y=\"24\" text-anchor=\"middle\" font-size=\"15\">"
      << XmlEscape(plot.title) << "</text>\n";

  // Grid lines and tick labels.
  out << "<g class=\"grid\" stroke=\"#dddddd\" stroke-width=\"1\">\n";
  for (double t : l.x_ticks) {
    const std::string x = Px(l.x.ToPixel(t));
    out << "<line x1=\"" << x << "\" y1=\"" << Px(l.top) << "\" x2=\"" << x
        << "\" y2=\"" << Px(l.bottom) << "\"/>\n";
  }
  for (double t : l.y_ticks) {
    const std::string y = Px(l.y.ToPixel(t));
    out << "<line x1=\"" << Px(l.left) << "\" y1=\"" << y << "\" x2=\""
        << Px(l.right) << "\" y2=\"" << y << "\"/>\n";
  }
  out << "</g>\n";
  out << "<g class=\"ticks\">\n";
  for (double t : l.x_ticks) {
    out << "<text class=\"x-tick\" x=\"" << Px(l.x.ToPixel(t)) << "\" y=\""
        << Px(l.bottom + 16) << "\" text-anchor=\"middle\">"
        << XmlEscape(TickLabel(t, l.x_step)) << "</text>\n";
  }
  for (double t : l.y_ticks) {
    out << "<text class=\"y-tick\" x=\"" << Px(l.left - 6) << "\" y=\""
        << Px(l.y.ToPixel(t) + 4) << "\" text-anchor=\"end\">"
        << XmlEscape(TickLabel(t, l.y_step)) << "</text>\n";
  }
  out << "</g>\n";
  out << "<rect class=\"frame\" x=\"" << Px(l.left) << "\" y=\"" << Px(l.top)
      << "\" width=\"" << Px(l.right - l.left) << "\" height=\""
      << Px(l.bottom - l.top)
      << "\" fill=\"none\" stroke=\"black\" stroke-width=\"1\"/>\n";
  out << "<text class=\"x-label\" x=\"" << Px(0.5 * (l.left + l.right))
      << "\" y=\"" << Px(plot.height - 12) << "\" text-anchor=\"middle\">"
      << XmlEscape(plot.x_label) << "</text>\n";
  const std::string y_centre = Px(0.5 * (l.top + l.bottom));
  out << "<text class=\"y-label\" x=\"16\" y=\"" << y_centre
      << "\" text-anchor=\"middle\" transform=\"rotate(-90 16 " << y_centre
      << ")\">" << XmlEscape(plot.y_label) << "</text>\n";

  // Series, clipped to the plot area.
  out << "<clipPath id=\"plot-area\"><rect x=\"" << Px(l.left) << "\" y=\""
      << Px(l.top) << "\" width=\"" << Px(l.right - l.left) << "\" height=\""
      << Px(l.bottom - l.top) << "\"/></clipPath>\n";
  out << "<g clip-path=\"url(#plot-area)\">\n";
  for (std::size_t s = 0; s < plot.series.size(); ++s) {
    const PlotSeries& series = plot.series[s];
    const std::string color = XmlEscape(SeriesColor(series, s));
    out << "<g class=\"series\">\n";
    if (series.line) {
      std::string points;
      int count = 0;
      auto flush = [&]() {
        if (count >= 2) {
          out << "<polyline fill=\"none\" stroke=\"" << color
              << "\" stroke-width=\"" << Px(series.line_width)
              << "\" stroke-linejoin=\"round\" points=\"" << points << "\"/>\n";
        }
        points.clear();
        count = 0;
      };
      for (std::size_t i = 0; i < series.x.size(); ++i) {
        if (!std::isfinite(series.x[i]) || !std::isfinite(series.y[i])) {
          flush();
          continue;
        }
        if (count > 0) points += ' ';
        points +=
            Px(l.x.ToPixel(series.x[i])) + "," + Px(l.y.ToPixel(series.y[i]));
        ++count;
      }
      flush();
    }
    if (series.markers) {
      for (std::size_t i = 0; i < series.x.size(); ++i) {
        if (!std::isfinite(series.x[i]) || !std::isfinite(series.y[i])) {
          continue;
        }
        out << "<circle cx=\"" << Px(l.x.ToPixel(series.x[i])) << "\" cy=\""
            << Px(l.y.ToPixel(series.y[i])) << "\" r=\""
            << Px(series.marker_radius) << "\" fill=\"" << color << "\"/>\n";
      }
    }
    out << "</g>\n";
  }
  out << "</g>\n";

  // Legend to the right of the plot area.
  double legend_y = l.top + 12;
  const double legend_x = l.right + 12;
  for (std::size_t s = 0; s < plot.series.size(); ++s) {
    const PlotSeries& series = plot.series[s];
    if (series.label.empty()) continue;
    const std::string color = XmlEscape(SeriesColor(series, s));
    out << "<g class=\"legend-entry\">";
    if (series.line) {
      out << "<line x1=\"" << Px(legend_x) << "\" y1=\"" << Px(legend_y)
          << "\" x2=\"" << Px(legend_x + 24) << "\" y2=\"" << Px(legend_y)
          << "\" stroke=\"" << color << "\" stroke-width=\""
          << Px(series.line_width) << "\"/>";
    }
    if (series.markers) {
      out << "<circle cx=\"" << Px(legend_x + 12) << "\" cy=\"" << Px(legend_y)
          << "\" r=\"" << Px(series.marker_radius) << "\" fill=\"" << color
          << "\"/>";
    }
    out << "<text x=\"" << Px(legend_x + 30) << "\" y=\"" << Px(legend_y + 4)
        << "\">" << XmlEscape(series.label) << "</text></g>\n";
    legend_y += 18;
  }
  out << "</svg>\n";
  *svg = out.str();
  return true;
}

bool WriteSvg(const Plot& plot, const std::string& path, std::string* error) {
  std::string svg;
  if (!RenderSvg(plot, &svg, error)) {
    *error = path + ": " + *error;
    return false;
  }
  return WriteOutputFile(
      path, [&](std::ostream* out) { *out << svg; }, error);
}

}  // namespace rff
