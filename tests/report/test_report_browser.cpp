// report.html in headless Chromium, opened from disk with networking disabled: no JavaScript error,
// every chart drawn, and a screenshot that shows them. Skipped when chromium is not installed
// (scripts/setup.sh installs it).
#include <gtest/gtest.h>

#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "crowdslam/report/report.h"
#include "report_test_helpers.h"

using namespace crowdslam;
namespace fs = std::filesystem;

namespace {

// 2 trajectory views, error, frame time, mapping (steps' median/p95 and each keyframe), people, features,
// tracking.
constexpr int kChartsWithGroundTruth = 9;

#define REQUIRE_CHROMIUM()                                                            \
  do {                                                                                \
    if (test::chromium_binary().empty()) GTEST_SKIP() << "chromium is not installed"; \
  } while (0)

// Pixels within `tolerance` of a colour (BGR) in the screenshot.
int pixels_near(const cv::Mat& image, const cv::Vec3b& bgr, int tolerance) {
  int count = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const auto& p = image.at<cv::Vec3b>(y, x);
      if (std::abs(p[0] - bgr[0]) <= tolerance && std::abs(p[1] - bgr[1]) <= tolerance &&
          std::abs(p[2] - bgr[2]) <= tolerance) {
        ++count;
      }
    }
  }
  return count;
}

const cv::Vec3b kFirstRunColour(180, 119, 31);  // #1f77b4, the page's first run colour
const cv::Vec3b kSecondRunColour(40, 39, 214);  // #d62728

}  // namespace

TEST(ReportBrowser, PageDrawsEveryChartWithoutErrorsOffline) {
  REQUIRE_CHROMIUM();
  test::TempDir tmp;
  const auto dataset = test::make_crowd_room(tmp, 4);
  test::run_room(dataset, tmp / "out", true, 10);
  const auto html = tmp / "out" / "report.html";
  ASSERT_TRUE(fs::is_regular_file(html));

  const std::string dom = test::dump_dom(tmp.path(), html);
  ASSERT_NE(dom.find("<body"), std::string::npos) << dom.substr(0, 2000);
  const std::string errors = test::body_attribute(dom, "data-errors");
  EXPECT_TRUE(errors.empty() || errors == "0") << "JavaScript errors: " << errors;
  EXPECT_EQ(test::body_attribute(dom, "data-charts"), std::to_string(kChartsWithGroundTruth));
  EXPECT_EQ(test::body_attribute(dom, "data-charts-expected"), std::to_string(kChartsWithGroundTruth));
  EXPECT_NE(dom.find("<td>completed</td>"), std::string::npos);                 // summary table filled in
  EXPECT_NE(dom.find("<figcaption>frame 30</figcaption>"), std::string::npos);  // the saved-frame strip

  // Screenshots of the page, and of the same page with a Chart.js that draws nothing: the charts must
  // make a large visible difference (blank canvases would not).
  const auto png = tmp / "report.png";
  ASSERT_EQ(
      test::run_chromium(
          tmp.path(), "--hide-scrollbars --window-size=1280,2400 --screenshot='" + png.string() + "'", html),
      0)
      << test::read_text(tmp / "chromium.log");
  const cv::Mat image = cv::imread(png.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(image.cols, 1280);
  cv::Scalar mean, stddev;
  cv::meanStdDev(image, mean, stddev);
  EXPECT_GT(stddev[0], 15.0) << "a near-blank screenshot";

  const auto stub = tmp / "stub_chart.js";
  test::write_text(stub,
                   "window.Chart = function () {};\n"
                   "window.Chart.defaults = { font: {}, plugins: { legend: { labels: {} } } };\n");
  report::ReportOptions no_charts;
  no_charts.chartjs = stub;
  const auto blank_html = tmp / "blank.html";
  report::write_report(tmp / "out", {}, blank_html, no_charts);
  const auto blank_png = tmp / "blank.png";
  ASSERT_EQ(
      test::run_chromium(
          tmp.path(), "--hide-scrollbars --window-size=1280,2400 --screenshot='" + blank_png.string() + "'",
          blank_html),
      0);
  const cv::Mat blank = cv::imread(blank_png.string(), cv::IMREAD_COLOR);
  ASSERT_EQ(blank.size(), image.size());
  cv::Mat difference, changed;
  cv::absdiff(image, blank, difference);
  cv::cvtColor(difference, difference, cv::COLOR_BGR2GRAY);
  cv::threshold(difference, changed, 40, 255, cv::THRESH_BINARY);
  const int changed_pixels = cv::countNonZero(changed);
  EXPECT_GT(changed_pixels, 50000) << "the charts drew (almost) nothing";
  std::printf("[ measured ] screenshot stddev %.1f, %d pixels drawn by the charts\n", stddev[0],
              changed_pixels);
}

TEST(ReportBrowser, CompareOverlaysTwoRuns) {
  REQUIRE_CHROMIUM();
  test::TempDir tmp;
  const auto dataset = test::make_crowd_room(tmp, 4);
  test::run_room(dataset, tmp / "filter_on", true);
  test::run_room(dataset, tmp / "filter_off", false);
  const auto html = tmp / "compare.html";
  const auto result = report::write_report(tmp / "filter_on", {tmp / "filter_off"}, html);
  EXPECT_EQ(result.runs, 2u);

  const std::string dom = test::dump_dom(tmp.path(), html);
  const std::string errors = test::body_attribute(dom, "data-errors");
  EXPECT_TRUE(errors.empty() || errors == "0") << "JavaScript errors: " << errors;
  EXPECT_EQ(test::body_attribute(dom, "data-charts"), std::to_string(kChartsWithGroundTruth));
  // One summary column per run, the filter shown on for one and off for the other.
  EXPECT_NE(dom.find("</span>filter_on</th>"), std::string::npos);
  EXPECT_NE(dom.find("</span>filter_off</th>"), std::string::npos);
  EXPECT_NE(dom.find("<td>off</td>"), std::string::npos);
  EXPECT_NE(dom.find("<td>mot-file"), std::string::npos) << "people filter row of the filtered run";

  const auto png = tmp / "compare.png";
  ASSERT_EQ(
      test::run_chromium(
          tmp.path(), "--hide-scrollbars --window-size=1280,2400 --screenshot='" + png.string() + "'", html),
      0);
  const cv::Mat image = cv::imread(png.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  EXPECT_GT(pixels_near(image, kFirstRunColour, 30), 2000);
  EXPECT_GT(pixels_near(image, kSecondRunColour, 30), 2000);
}
