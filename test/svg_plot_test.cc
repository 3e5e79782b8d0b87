#include "rff_ceres/plot/svg_plot.h"

#include <cmath>
#include <limits>
#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "test/test_files.h"

namespace rff {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;

TEST(NiceTicksTest, RangeZeroToSevenPointThreeStepsByTwo) {
  // (7.3 - 0) / 5 = 1.46 -> the next nice step is 2; the last tick covers 7.3.
  EXPECT_THAT(NiceTicks(0.0, 7.3), ElementsAre(0, 2, 4, 6, 8));
  // Ten intervals wanted: 0.73 -> 1.
  EXPECT_THAT(NiceTicks(0.0, 7.3, 10), ElementsAre(0, 1, 2, 3, 4, 5, 6, 7, 8));
}

TEST(NiceTicksTest, FractionalNegativeAndDegenerateRanges) {
  // 0.17 / 5 = 0.034 -> 0.05.
  const std::vector<double> ticks = NiceTicks(0.03, 0.2);
  ASSERT_EQ(ticks.size(), 5u);
  EXPECT_NEAR(ticks.front(), 0.0, 1e-15);
  EXPECT_NEAR(ticks.back(), 0.2, 1e-15);
  EXPECT_THAT(NiceTicks(-12.0, 33.0), ElementsAre(-20, -10, 0, 10, 20, 30, 40));
  // A single value gets a unit-wide range: [2.5, 3.5] / 5 = 0.2.
  const std::vector<double> single = NiceTicks(3.0, 3.0);
  EXPECT_NEAR(single.front(), 2.4, 1e-12);
  EXPECT_NEAR(single.back(), 3.6, 1e-12);
  // No "-0" tick from floor(-0.x).
  EXPECT_THAT(NiceTicks(-0.3, 0.9), ElementsAre(-0.5, 0, 0.5, 1));
  EXPECT_FALSE(std::signbit(NiceTicks(-0.3, 0.9)[1]));
}

TEST(LogTicksTest, PowersOfTenOrOneTwoFive) {
  EXPECT_THAT(LogTicks(0.5, 2000.0), ElementsAre(1, 10, 100, 1000));
  // Fewer than three powers inside: 1, 2, 5 per decade.
  EXPECT_THAT(LogTicks(4.0, 120.0), ElementsAre(5, 10, 20, 50, 100));
  EXPECT_THAT(LogTicks(0.4, 4.6), ElementsAre(0.5, 1, 2, 4));
  EXPECT_THAT(LogTicks(0.5, 4.0), ElementsAre(0.5, 1, 2, 4));
}

TEST(TickLabelTest, DecimalsFollowTheStep) {
  EXPECT_EQ(TickLabel(4.0, 2.0), "4");
  EXPECT_EQ(TickLabel(0.15000000000000002, 0.05), "0.15");
  EXPECT_EQ(TickLabel(-1e-17, 0.5), "0.0");
  EXPECT_EQ(TickLabel(0.5, 0.0), "0.5");  // Log axis: %g.
  EXPECT_EQ(TickLabel(1000.0, 0.0), "1000");
}

TEST(XmlEscapeTest, EscapesMarkupCharacters) {
  EXPECT_EQ(XmlEscape("a<b & \"c\" 'd'>"),
            "a&lt;b &amp; &quot;c&quot; &apos;d&apos;&gt;");
  EXPECT_EQ(XmlEscape("plain [m]"), "plain [m]");
}

Plot TwoSeriesPlot() {
  Plot plot;
  plot.title = "errors <&>";
  plot.x_label = "time [s]";
  plot.y_label = "error [m]";
  plot.width = 720;
  plot.height = 480;
  PlotSeries a;
  a.label = "rff & co";
  a.x = {0.0, 4.0, 7.3};
  a.y = {0.0, 1.0, 2.0};
  PlotSeries b;
  b.label = "wnoa";
  b.x = {1.0, 2.0};
  b.y = {0.5, 1.5};
  b.markers = true;
  b.line = false;
  plot.series = {a, b};
  return plot;
}

TEST(ComputeLayoutTest, MapsDataOntoThePlotArea) {
  PlotLayout layout;
  std::string error;
  ASSERT_TRUE(ComputeLayout(TwoSeriesPlot(), &layout, &error)) << error;
  // Area: left 70, right 720 - 170 (legend) = 550, top 40, bottom 430.
  EXPECT_DOUBLE_EQ(layout.left, 70.0);
  EXPECT_DOUBLE_EQ(layout.right, 550.0);
  EXPECT_DOUBLE_EQ(layout.top, 40.0);
  EXPECT_DOUBLE_EQ(layout.bottom, 430.0);
  EXPECT_THAT(layout.x_ticks, ElementsAre(0, 2, 4, 6, 8));
  // y data [0, 2]: 2 / 5 = 0.4 -> step 0.5.
  ASSERT_EQ(layout.y_ticks.size(), 5u);
  EXPECT_DOUBLE_EQ(layout.y_step, 0.5);
  // x = 2 is a quarter of [0, 8]: 70 + 0.25 * 480 = 190; y = 1.5 is three
  // quarters up [0, 2]: 430 - 0.75 * 390 = 137.5.
  EXPECT_DOUBLE_EQ(layout.x.ToPixel(2.0), 190.0);
  EXPECT_DOUBLE_EQ(layout.y.ToPixel(1.5), 137.5);
}

TEST(ComputeLayoutTest, LogAxisMapsDecadesEvenly) {
  Plot plot;
  PlotSeries s;
  s.x = {1.0, 100.0};
  s.y = {1.0, 2.0};
  plot.series = {s};  // No label: no legend, right margin 20.
  PlotLayout layout;
  std::string error;
  plot.log_x = true;
  ASSERT_TRUE(ComputeLayout(plot, &layout, &error)) << error;
  EXPECT_DOUBLE_EQ(layout.right, 700.0);
  // Padded by 1.15 both ways: 10 is the centre of [1 / 1.15, 115].
  EXPECT_NEAR(layout.x.ToPixel(10.0), 0.5 * (70.0 + 700.0), 1e-9);
  EXPECT_THAT(layout.x_ticks, ElementsAre(1, 10, 100));
  EXPECT_DOUBLE_EQ(layout.x_step, 0.0);

  plot.series[0].x[0] = 0.0;
  EXPECT_FALSE(ComputeLayout(plot, &layout, &error));
  EXPECT_EQ(error, "series '': x = 0 on a log axis (must be > 0)");
}

TEST(ComputeLayoutTest, EqualScaleGivesTheSameMetresPerPixel) {
  Plot plot;
  plot.equal_scale = true;
  PlotSeries s;
  s.x = {0.0, 100.0};
  s.y = {0.0, 10.0};
  plot.series = {s};
  PlotLayout layout;
  std::string error;
  ASSERT_TRUE(ComputeLayout(plot, &layout, &error)) << error;
  const double x_scale =
      (layout.x.data_high - layout.x.data_low) / (layout.right - layout.left);
  const double y_scale =
      (layout.y.data_high - layout.y.data_low) / (layout.bottom - layout.top);
  EXPECT_NEAR(x_scale, y_scale, 1e-12);
  EXPECT_DOUBLE_EQ(layout.x_step, layout.y_step);
  // y's range grew about its centre (5) to keep the scale.
  EXPECT_NEAR(0.5 * (layout.y.data_low + layout.y.data_high), 5.0, 1e-9);
}

TEST(ComputeLayoutTest, MismatchedSeriesIsAnError) {
  Plot plot;
  PlotSeries s;
  s.label = "bad";
  s.x = {1.0, 2.0};
  s.y = {1.0};
  plot.series = {s};
  PlotLayout layout;
  std::string error;
  EXPECT_FALSE(ComputeLayout(plot, &layout, &error));
  EXPECT_EQ(error, "series 'bad' has 2 x values but 1 y values");
}

TEST(RenderSvgTest, WellFormedWithEscapedTextAndOneLegendEntryPerLabel) {
  std::string svg, error;
  ASSERT_TRUE(RenderSvg(TwoSeriesPlot(), &svg, &error)) << error;
  EXPECT_THAT(svg, StartsWith("<svg xmlns=\"http://www.w3.org/2000/svg\""));
  EXPECT_THAT(svg, HasSubstr("</svg>\n"));
  EXPECT_THAT(svg, HasSubstr(">errors &lt;&amp;&gt;</text>"));
  EXPECT_THAT(svg, HasSubstr(">rff &amp; co</text>"));
  EXPECT_THAT(svg, Not(HasSubstr("errors <&>")));
  EXPECT_THAT(svg, HasSubstr(">time [s]</text>"));
  EXPECT_THAT(svg, HasSubstr(">error [m]</text>"));
  EXPECT_EQ(testing::CountOccurrences(svg, "class=\"legend-entry\""), 2);
  // The first series is one polyline of three points, the second two dots.
  EXPECT_EQ(testing::CountOccurrences(svg, "<polyline"), 1);
  EXPECT_THAT(svg, HasSubstr("points=\"70.00,430.00 310.00,235.00 "
                             "508.00,40.00\""));
  EXPECT_EQ(testing::CountOccurrences(svg, "<circle"),
            2 + 1);  // Two points + legend marker.
  EXPECT_EQ(testing::CountOccurrences(svg, "class=\"x-tick\""), 5);
  EXPECT_THAT(svg, HasSubstr(">8</text>"));
  EXPECT_EQ(testing::CountOccurrences(svg, "<g"),
            testing::CountOccurrences(svg, "</g>"));
}

TEST(RenderSvgTest, NonFiniteValuesBreakTheLine) {
  Plot plot;
  PlotSeries s;
  s.label = "gappy";
  const double nan = std::numeric_limits<double>::quiet_NaN();
  s.x = {0, 1, 2, 3, 4, 5};
  s.y = {0, 1, nan, 3, 4, 5};
  plot.series = {s};
  std::string svg, error;
  ASSERT_TRUE(RenderSvg(plot, &svg, &error)) << error;
  EXPECT_EQ(testing::CountOccurrences(svg, "<polyline"), 2);
  EXPECT_THAT(svg, Not(HasSubstr("nan")));
}

TEST(RenderSvgTest, NoFinitePointDrawsEmptyAxesWithTheLegend) {
  Plot plot;
  PlotSeries s;
  s.label = "all failed";
  s.x = {1.0};
  s.y = {std::numeric_limits<double>::quiet_NaN()};
  plot.series = {s};
  std::string svg, error;
  ASSERT_TRUE(RenderSvg(plot, &svg, &error)) << error;
  EXPECT_EQ(testing::CountOccurrences(svg, "class=\"legend-entry\""), 1);
  EXPECT_EQ(testing::CountOccurrences(svg, "<polyline"), 0);
}

}  // namespace
}  // namespace rff
