// A small standalone SVG line and scatter plot writer for the experiment
// figures: axes with "nice" ticks and labelled units, a title, a legend and
// any number of series, optionally a logarithmic x axis or equal axis scales.
// No dependencies beyond the standard library; the output opens in a browser.
#ifndef RFF_CERES_PLOT_SVG_PLOT_H_
#define RFF_CERES_PLOT_SVG_PLOT_H_

#include <string>
#include <vector>

namespace rff {

// One curve or point set. Points with a non-finite coordinate are skipped
// (and break the line there).
struct PlotSeries {
  std::string label;  // Legend entry; series with an empty label get none.
  std::vector<double> x;
  std::vector<double> y;
  bool line = true;      // Connect the points in order.
  bool markers = false;  // Draw a circle at each point.
  std::string color;     // Any SVG colour; empty picks from the palette.
  double line_width = 1.5;
  double marker_radius = 3.0;
};

struct Plot {
  std::string title;
  std::string x_label;  // With the unit, e.g. "time [s]".
  std::string y_label;
  bool log_x = false;  // Every finite x must then be > 0.
  // Same metres per pixel on both axes (the data ranges grow to fit).
  bool equal_scale = false;
  // Show y = 0 on the axis (errors and other non-negative quantities).
  bool y_from_zero = false;
  int width = 720;  // Pixels of the whole image.
  int height = 480;
  std::vector<PlotSeries> series;
};

// Linear ticks at 1, 2 or 5 times a power of ten covering [low, high]: the
// first tick is <= low and the last >= high, with about `target` intervals.
// low == high gets a unit-wide range around the value.
std::vector<double> NiceTicks(double low, double high, int target = 5);

// Ticks of a log axis inside [low, high] (both > 0): the powers of ten, or,
// when that gives fewer than three, 1, 2 and 5 times the powers of ten.
std::vector<double> LogTicks(double low, double high);

// Tick text: the fewest decimals that tell the ticks apart (step is the tick
// spacing; 0 for log ticks, which use %g).
std::string TickLabel(double value, double step);

// `text` with &, <, >, " and ' replaced by their XML entities.
std::string XmlEscape(const std::string& text);

// Maps data values onto pixels, linearly or in log10.
struct AxisMap {
  double data_low = 0.0;
  double data_high = 1.0;
  double pixel_low = 0.0;  // Pixel of data_low (for y: the bottom).
  double pixel_high = 1.0;
  bool log = false;
  double ToPixel(double value) const;
};

// Where the plot area lies and how data maps onto it, with the ticks.
struct PlotLayout {
  double left = 0.0, right = 0.0, top = 0.0, bottom = 0.0;  // Plot area.
  AxisMap x;
  AxisMap y;
  std::vector<double> x_ticks;
  std::vector<double> y_ticks;
  double x_step = 0.0;  // Tick spacing (0 on a log axis).
  double y_step = 0.0;
};

// Margins (pixels) around the plot area: room for tick labels, the axis
// labels, the title and the legend on the right.
inline constexpr double kPlotMarginLeft = 70.0;
inline constexpr double kPlotMarginBottom = 50.0;
inline constexpr double kPlotMarginTop = 40.0;
inline constexpr double kPlotMarginRightNoLegend = 20.0;
inline constexpr double kPlotLegendWidth = 170.0;

// The layout of `plot`. Without any finite point the axes span [0, 1] (log:
// [1, 10]). Fails when log_x is set and a finite x is <= 0, or when x and y
// of a series differ in length.
bool ComputeLayout(const Plot& plot, PlotLayout* layout, std::string* error);

// The whole SVG document.
bool RenderSvg(const Plot& plot, std::string* svg, std::string* error);

// RenderSvg into `path`.
bool WriteSvg(const Plot& plot, const std::string& path, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_PLOT_SVG_PLOT_H_
