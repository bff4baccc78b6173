#include "report/plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <opencv2/imgproc.hpp>

namespace pepper::app::report {
namespace {

std::string format_tick(double value, double step) {
  char buf[32];
  const int decimals = step >= 1.0 ? 0 : std::min(6, static_cast<int>(std::ceil(-std::log10(step))));
  std::snprintf(buf, sizeof buf, "%.*f", decimals, std::abs(value) < step * 1e-9 ? 0.0 : value);
  return buf;
}

}  // namespace

cv::Scalar palette(std::size_t i) {
  static const cv::Scalar kColours[] = {{180, 119, 31}, {14, 127, 255}, {44, 160, 44},
                                        {40, 39, 214},  {189, 103, 148}, {75, 86, 140},
                                        {194, 119, 227}, {127, 127, 127}};
  return kColours[i % (sizeof kColours / sizeof kColours[0])];
}

std::vector<double> nice_ticks(double lo, double hi, int target_count) {
  std::vector<double> ticks;
  if (!(std::isfinite(lo) && std::isfinite(hi)) || hi <= lo || target_count < 1) return ticks;
  const double raw = (hi - lo) / target_count;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (raw <= m * mag) {
      step = m * mag;
      break;
    }
  }
  for (double t = std::ceil(lo / step) * step; t <= hi + step * 1e-9; t += step) ticks.push_back(t);
  return ticks;
}

cv::Mat render_plot(const PlotSpec& spec, const std::vector<Series>& series) {
  cv::Mat img(spec.height_px, spec.width_px, CV_8UC3, cv::Scalar(255, 255, 255));
  const int left = 70, right = 20, top = 36, bottom = 50;
  cv::Rect area(left, top, std::max(10, spec.width_px - left - right),
                std::max(10, spec.height_px - top - bottom));

  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo;
  double y_lo = x_lo, y_hi = -x_lo;
  for (const auto& s : series) {
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x_lo = std::min(x_lo, s.x[i]);
      x_hi = std::max(x_hi, s.x[i]);
      y_lo = std::min(y_lo, s.y[i]);
      y_hi = std::max(y_hi, s.y[i]);
    }
  }
  if (!std::isfinite(x_lo)) x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;
  if (x_hi - x_lo < 1e-9) x_lo -= 0.5, x_hi += 0.5;
  if (y_hi - y_lo < 1e-9) y_lo -= 0.5, y_hi += 0.5;
  const double x_pad = 0.03 * (x_hi - x_lo), y_pad = 0.06 * (y_hi - y_lo);
  x_lo -= x_pad, x_hi += x_pad, y_lo -= y_pad, y_hi += y_pad;
  if (spec.equal_aspect) {
    const double sx = (x_hi - x_lo) / area.width, sy = (y_hi - y_lo) / area.height;
    const double s = std::max(sx, sy);
    const double cx = 0.5 * (x_lo + x_hi), cy = 0.5 * (y_lo + y_hi);
    x_lo = cx - 0.5 * s * area.width, x_hi = cx + 0.5 * s * area.width;
    y_lo = cy - 0.5 * s * area.height, y_hi = cy + 0.5 * s * area.height;
  }
  auto to_px = [&](double x, double y) {
    return cv::Point(static_cast<int>(std::lround(area.x + (x - x_lo) / (x_hi - x_lo) * area.width)),
                     static_cast<int>(std::lround(area.y + area.height -
                                                  (y - y_lo) / (y_hi - y_lo) * area.height)));
  };

  const cv::Scalar grid(230, 230, 230), axis(60, 60, 60), text(30, 30, 30);
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  const auto xt = nice_ticks(x_lo, x_hi, 8), yt = nice_ticks(y_lo, y_hi, 6);
  const double xs = xt.size() > 1 ? xt[1] - xt[0] : 1.0, ys = yt.size() > 1 ? yt[1] - yt[0] : 1.0;
  for (double t : xt) {
    const cv::Point p = to_px(t, y_lo);
    cv::line(img, {p.x, area.y}, {p.x, area.y + area.height}, grid, 1);
    const std::string s = format_tick(t, xs);
    cv::putText(img, s, {p.x - 4 * static_cast<int>(s.size()), area.y + area.height + 18}, font, 0.42,
                text, 1, cv::LINE_AA);
  }
  for (double t : yt) {
    const cv::Point p = to_px(x_lo, t);
    cv::line(img, {area.x, p.y}, {area.x + area.width, p.y}, grid, 1);
    const std::string s = format_tick(t, ys);
    cv::putText(img, s, {area.x - 8 - 8 * static_cast<int>(s.size()), p.y + 4}, font, 0.42, text, 1,
                cv::LINE_AA);
  }
  cv::rectangle(img, area, axis, 1);
  cv::putText(img, spec.title, {left, 24}, font, 0.6, text, 1, cv::LINE_AA);
  cv::putText(img, spec.x_label, {area.x + area.width / 2 - 40, spec.height_px - 10}, font, 0.48,
              text, 1, cv::LINE_AA);
  cv::putText(img, spec.y_label, {4, top - 8}, font, 0.42, text, 1, cv::LINE_AA);

  int legend_y = top + 18;
  for (const auto& s : series) {
    std::vector<cv::Point> pts;
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        if (pts.size() > 1 && !s.markers) cv::polylines(img, pts, false, s.bgr, s.thickness_px, cv::LINE_AA);
        pts.clear();
        continue;
      }
      pts.push_back(to_px(s.x[i], s.y[i]));
    }
    if (s.markers) {
      for (const auto& p : pts) cv::circle(img, p, 3, s.bgr, cv::FILLED, cv::LINE_AA);
    } else if (pts.size() > 1) {
      cv::polylines(img, pts, false, s.bgr, s.thickness_px, cv::LINE_AA);
    }
    for (std::size_t i = 0; i < std::min({s.x.size(), s.y.size(), s.point_labels.size()}); ++i) {
      if (s.point_labels[i].empty() || !std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      const cv::Point p = to_px(s.x[i], s.y[i]);
      cv::putText(img, s.point_labels[i], {p.x + 5, p.y - 5}, font, 0.38, s.bgr, 1, cv::LINE_AA);
    }
    if (!s.label.empty()) {
      const int lx = area.x + area.width - 190;
      cv::line(img, {lx, legend_y - 4}, {lx + 24, legend_y - 4}, s.bgr, 3, cv::LINE_AA);
      cv::putText(img, s.label, {lx + 30, legend_y}, font, 0.42, text, 1, cv::LINE_AA);
      legend_y += 18;
    }
  }
  return img;
}

}  // namespace pepper::app::report
