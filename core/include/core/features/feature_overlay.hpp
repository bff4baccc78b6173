#pragma once
// Pixel positions of features in one image, for display only (the teach UI draws them over the
// live camera image). Nothing in the method reads them. The counts are capped so a frame's
// overlay stays a few KB on the wire; the caps equal the extractor's defaults (max_lines 150,
// max_corners 300), so they only cut when those options are raised.
//
// Units: pixels of the image the features were extracted from (pixel centres at integers,
// docs/conventions.md).

#include <cstddef>
#include <opencv2/core/types.hpp>
#include <vector>

#include "core/features/image_features.hpp"
#include "core/features/matching.hpp"

namespace pepper::core::features {

struct FeatureOverlay {
  static constexpr std::size_t kMaxLines = 150;
  static constexpr std::size_t kMaxPoints = 300;
  struct Segment {
    cv::Point2f p0_px, p1_px;
  };
  std::vector<Segment> lines;
  std::vector<cv::Point2f> points_px;
  int key_index = -1;  ///< the key image the features were matched with (-1: none, detections)
};

/// The image's own detections: its lines and its KLT corners (first ones kept when capped).
inline FeatureOverlay detected_overlay(const ImageFeatures& image) {
  FeatureOverlay o;
  for (std::size_t i = 0; i < image.lines.size() && i < FeatureOverlay::kMaxLines; ++i) {
    o.lines.push_back({image.lines[i].p0_px, image.lines[i].p1_px});
  }
  for (std::size_t i = 0; i < image.corners_px.size() && i < FeatureOverlay::kMaxPoints; ++i) {
    o.points_px.push_back(image.corners_px[i]);
  }
  return o;
}

/// The verified matches of a two-view result (a = key image `key_index`, b = `current`), at
/// their positions in the current image.
inline FeatureOverlay matched_overlay(const TwoViewMatches& matches, const ImageFeatures& current,
                                      int key_index) {
  FeatureOverlay o;
  o.key_index = key_index;
  for (const LineMatch& m : matches.lines) {
    if (o.lines.size() >= FeatureOverlay::kMaxLines) break;
    const LineSegment& s = current.lines[static_cast<std::size_t>(m.idx_b)];
    o.lines.push_back({s.p0_px, s.p1_px});
  }
  for (const PointMatch& m : matches.points) {
    if (o.points_px.size() >= FeatureOverlay::kMaxPoints) break;
    o.points_px.push_back(m.b_px);
  }
  return o;
}

}  // namespace pepper::core::features
