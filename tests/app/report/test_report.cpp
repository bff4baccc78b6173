#include <cmath>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "report/html_report.hpp"
#include "report/plot.hpp"
#include "support/temp_dir.hpp"

namespace pepper::app::report {
namespace {

TEST(Base64, MatchesRfc4648Vectors) {
  auto enc = [](const std::string& s) {
    return base64_encode(std::vector<unsigned char>(s.begin(), s.end()));
  };
  EXPECT_EQ(enc(""), "");
  EXPECT_EQ(enc("f"), "Zg==");
  EXPECT_EQ(enc("fo"), "Zm8=");
  EXPECT_EQ(enc("foo"), "Zm9v");
  EXPECT_EQ(enc("foob"), "Zm9vYg==");
  EXPECT_EQ(enc("fooba"), "Zm9vYmE=");
  EXPECT_EQ(enc("foobar"), "Zm9vYmFy");
}

TEST(NiceTicks, UseOneTwoFiveSteps) {
  const auto t = nice_ticks(0.0, 1.0, 5);
  ASSERT_EQ(t.size(), 6u);  // step 0.2: 0, 0.2, ..., 1.0
  EXPECT_NEAR(t[1], 0.2, 1e-12);
  const auto u = nice_ticks(-3.0, 17.0, 4);  // raw 5 -> step 5: -0, 5, 10, 15
  ASSERT_EQ(u.size(), 4u);
  EXPECT_NEAR(u[0], 0.0, 1e-12);
  EXPECT_TRUE(nice_ticks(1.0, 1.0, 5).empty());
}

TEST(Plot, DrawsSeriesInsideTheAxesAndSurvivesNaN) {
  Series s{"omega", {0, 1, 2, 3}, {0.0, 0.5, std::nan(""), -0.5}, palette(0), 2, false};
  const cv::Mat img = render_plot({"t", "x", "y", 400, 200, false}, {s});
  ASSERT_EQ(img.rows, 200);
  ASSERT_EQ(img.cols, 400);
  // The series colour appears somewhere (it was drawn).
  cv::Mat mask;
  cv::inRange(img, palette(0) - cv::Scalar(10, 10, 10), palette(0) + cv::Scalar(10, 10, 10), mask);
  EXPECT_GT(cv::countNonZero(mask), 20);
}

// Labels (the key images' numbers on a top view) are drawn beside their own samples only.
TEST(Plot, PointLabelsAreDrawnBesideTheirSamples) {
  Series plain{"keys", {1.0, 5.0, 9.0}, {1.0, 5.0, 9.0}, palette(4), 1, true};
  Series labelled = plain;
  labelled.point_labels = {"10", "", "30"};
  const PlotSpec spec{"t", "x", "y", 400, 400, true};
  const cv::Mat a = render_plot(spec, {plain}), b = render_plot(spec, {labelled});
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  cv::cvtColor(diff, diff, cv::COLOR_BGR2GRAY);
  std::vector<cv::Point> changed;
  cv::findNonZero(diff, changed);
  ASSERT_GT(changed.size(), 10u) << "the labels were drawn";
  // Every changed pixel is up and to the right of the first or the third sample, none near the
  // unlabelled middle one (the middle of the plot).
  const cv::Point mid(a.cols / 2, a.rows / 2);
  for (const cv::Point& p : changed) {
    EXPECT_GT(std::hypot(p.x - mid.x, p.y - mid.y), 40.0) << p;
  }
}

TEST(HtmlReport, EscapesTextAndEmbedsImages) {
  HtmlReport r("Replay <report>");
  r.paragraph("a & b");
  r.table({"summary", {"run", "ok"}, {{"1", "yes"}}});
  r.image(cv::Mat(4, 4, CV_8UC3, cv::Scalar(1, 2, 3)), "plot");
  const std::string html = r.html();
  EXPECT_NE(html.find("Replay &lt;report&gt;"), std::string::npos);
  EXPECT_NE(html.find("a &amp; b"), std::string::npos);
  EXPECT_NE(html.find("data:image/png;base64,iVBORw0KGgo"), std::string::npos);  // PNG magic
  test::TempDir tmp;
  r.write(tmp.path() / "r.html");
  std::ifstream in(tmp.path() / "r.html");
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), html);
}

}  // namespace
}  // namespace pepper::app::report
