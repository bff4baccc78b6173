#include "report/map_page.hpp"

#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "report/plot.hpp"

namespace pepper::app::report {

namespace mem = core::memory;

namespace {

// Wide enough to recognise a place, small enough for a 50-image tour to stay a light page.
constexpr int kThumbWidthPx = 200;

std::string fixed(double v, int decimals) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string jpeg_data_uri(const cv::Mat& gray) {
  cv::Mat small = gray;
  if (gray.cols > kThumbWidthPx) {
    cv::resize(gray, small, cv::Size(kThumbWidthPx, gray.rows * kThumbWidthPx / gray.cols), 0, 0,
               cv::INTER_AREA);
  }
  std::vector<unsigned char> jpeg;
  if (small.empty() || !cv::imencode(".jpg", small, jpeg, {cv::IMWRITE_JPEG_QUALITY, 85})) {
    return "";
  }
  return "data:image/jpeg;base64," + base64_encode(jpeg);
}

/// The top view: ground truth when the map carries it, else the key images' odometry.
std::optional<cv::Mat> path_plot(const mem::VisualMemory& map,
                                 const std::optional<TaughtPath>& taught, std::string& caption) {
  std::vector<double> px, py, kx, ky;
  if (taught && !taught->path_m.empty()) {
    for (const auto& p : taught->path_m) {
      px.push_back(p.x());
      py.push_back(p.y());
    }
    for (const auto& p : taught->key_images_m) {
      kx.push_back(p.x());
      ky.push_back(p.y());
    }
    caption =
        "Taught path in the mock world '" + taught->world + "' (ground truth); circles: key images";
  } else {
    for (const auto& k : map.key_images) {
      if (!k.odom) continue;
      kx.push_back(k.odom->x_m);
      ky.push_back(k.odom->y_m);
    }
    if (kx.size() < 2) return std::nullopt;
    px = kx;
    py = ky;
    caption =
        "Key images by the robot's odometry during teach (odometry frame; joined in tour "
        "order)";
  }
  PlotSpec spec{"Taught path", "x (m)", "y (m)", 900, 600, true};
  return render_plot(spec,
                     {{"taught", px, py, palette(0)}, {"key images", kx, ky, palette(1), 2, true}});
}

}  // namespace

std::string key_image_thumbnails(const mem::VisualMemory& map, const std::set<int>& flagged) {
  const mem::MapSummary summary = mem::summarize(map);
  std::string grid =
      "<style>.thumbs{display:flex;flex-wrap:wrap;gap:10px}.thumbs figure{margin:0;width:" +
      std::to_string(kThumbWidthPx + 6) +
      "px}.thumbs img{width:100%}.thumbs .weak img{border:3px solid #d22}"
      ".thumbs .weak figcaption{color:#b00}.warnings li{color:#b00}</style>\n"
      "<div class=\"thumbs\">\n";
  for (std::size_t i = 0; i < map.key_images.size(); ++i) {
    const auto& k = map.key_images[i];
    const auto& s = summary.key_images[i];
    std::string text = "#" + std::to_string(i) + ": " + std::to_string(s.lines) + " lines, " +
                       std::to_string(s.corners) + " points";
    if (std::isfinite(s.travelled_m)) text += ", at " + fixed(s.travelled_m, 2) + " m";
    const bool weak = flagged.count(static_cast<int>(i)) > 0;
    // Appended piece by piece: one long concatenation trips GCC 12's -Wrestrict (a false alarm).
    grid += weak ? "<figure class=\"key weak\"" : "<figure class=\"key\"";
    grid += " id=\"key-" + std::to_string(i) + "\"><img alt=\"key image " + std::to_string(i);
    grid += "\" src=\"" + jpeg_data_uri(k.features.gray) + "\"><figcaption>";
    grid += html_escape(text) + "</figcaption></figure>\n";
  }
  return grid + "</div>\n";
}

HtmlReport map_page(const std::string& name, const mem::VisualMemory& map,
                    const std::vector<TourWarning>& warnings,
                    const std::optional<TaughtPath>& taught_path) {
  const mem::MapSummary summary = mem::summarize(map);
  HtmlReport page("Map " + name);
  Table table;
  table.header = {"quantity", "value"};
  const double length_m = summary.key_images.empty() ? NAN
                                                     : summary.key_images.back().travelled_m -
                                                           summary.key_images.front().travelled_m;
  table.rows = {
      {"key images", std::to_string(summary.key_image_count)},
      {"taught length", std::isfinite(length_m) ? fixed(length_m, 2) + " m" : "unknown"},
      {"taught duration", fixed(summary.taught_duration_s, 1) + " s"},
      {"camera",
       std::to_string(summary.camera.width_px) + "x" + std::to_string(summary.camera.height_px)},
      {"taught path", taught_path ? "mock world '" + taught_path->world + "'"
                                  : std::string("none (a real robot's map)")},
      {"warnings", std::to_string(warnings.size())},
  };
  page.table(table);

  page.heading("Warnings");
  if (warnings.empty()) {
    page.paragraph(
        "None: every key image has enough lines and points, and no gap between key "
        "images is unusually long.");
  } else {
    std::string list = "<ul class=\"warnings\">\n";
    for (const auto& w : warnings) list += "<li>" + html_escape(w.text) + "</li>\n";
    page.raw_html(list + "</ul>\n");
  }

  std::string caption;
  if (auto plot = path_plot(map, taught_path, caption)) {
    page.heading("Taught path");
    page.image(*plot, caption);
  }

  page.heading("Key images");
  std::set<int> flagged;
  for (const auto& w : warnings) flagged.insert(w.key_index);
  page.raw_html(key_image_thumbnails(map, flagged));
  return page;
}

}  // namespace pepper::app::report
