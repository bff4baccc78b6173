#pragma once
// LBD-style line band descriptor (after Zhang & Koch, "An efficient and robust line segment
// matching approach based on LBD descriptor and pairwise geometric consistency", JVCIR 2013),
// our own implementation: OpenCV's BinaryDescriptor::compute is measured ~3x slower per line
// (docs/perception.md).
//
// For a segment with unit direction d (p0 -> p1) and left normal n = (d_y, -d_x), the line
// support region is 9 bands of `band_width_px` rows parallel to the segment, centred on it. At up
// to `samples_along` points along the segment and every row, the image gradient g (central
// differences, nearest pixel, replicated border) is split into g.n and g.d; per row the weighted
// sums of the positive and negative parts of both give 4 values (global Gaussian weight over the
// row offset, sigma = half the region width). Per band: mean and standard deviation of the 4
// values over its rows -> 8 numbers; 9 bands -> 72. The 36 means and the 36 deviations are each
// scaled to unit norm, concatenated, clipped at 0.4 and the whole rescaled to unit norm
// (L2 distance in [0, 2]).
//
// Orientation: orient_segment() swaps the endpoints so that the mean gradient points along +n
// (brighter side on the left of p0 -> p1), which makes the descriptor independent of the
// detector's endpoint order.

#include <vector>

#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>

namespace pepper::core::features {

/// Swaps p0/p1 if needed so that the mean gradient across the segment points to the left normal.
void orient_segment(const cv::Mat& gray, cv::Point2f& p0_px, cv::Point2f& p1_px);

/// Descriptors of the given segments (rows of a CV_32F matrix, 72 columns). `gray` CV_8UC1.
/// Segments shorter than 1 px give a zero row. `threads` > 1 splits the segments into that
/// many contiguous ranges, the first computed on the calling thread and each other one on a
/// thread started and joined by this call: the same matrix, bit for bit (each row depends on
/// its own segment only).
cv::Mat compute_band_descriptors(const cv::Mat& gray,
                                 const std::vector<std::pair<cv::Point2f, cv::Point2f>>& segments,
                                 int band_width_px = 5, int samples_along = 32, int threads = 1);

}  // namespace pepper::core::features
