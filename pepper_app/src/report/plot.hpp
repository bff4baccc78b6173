#pragma once
// Small PNG plots drawn with OpenCV: line plots with labelled axes and ticks, and equal-aspect
// top views of trajectories. Used by the evaluation and the replay report; no extra dependency.

#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace pepper::app::report {

struct Series {
  std::string label;
  std::vector<double> x;
  std::vector<double> y;
  cv::Scalar bgr{200, 80, 30};
  int thickness_px = 2;
  bool markers = false;  ///< draw a small circle at every sample instead of joining them
  /// Text drawn beside sample i (an empty string, or an index past the end: none), e.g. the
  /// numbers of the key images on a top view.
  std::vector<std::string> point_labels{};
};

struct PlotSpec {
  std::string title;
  std::string x_label;
  std::string y_label;
  int width_px = 900;
  int height_px = 360;
  bool equal_aspect = false;  ///< one metre is the same length on both axes (top views)
};

/// Renders the series (non-finite samples are skipped; empty series are listed in the legend only).
cv::Mat render_plot(const PlotSpec& spec, const std::vector<Series>& series);

/// "Nice" tick positions covering [lo, hi] with about `target_count` ticks (1, 2, 5 x 10^k steps).
std::vector<double> nice_ticks(double lo, double hi, int target_count);

/// A categorical colour, stable per index.
cv::Scalar palette(std::size_t i);

}  // namespace pepper::app::report
