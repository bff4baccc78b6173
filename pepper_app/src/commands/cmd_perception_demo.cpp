// pepper_app perception-demo: features and verified matches between 2 or 3 images, drawn side by
// side, with the counts printed (the README's first demo until the navigation lands).
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "commands/commands.hpp"
#include "commands/error_advice.hpp"
#include "core/camera/intrinsics_io.hpp"
#include "core/features/image_features.hpp"
#include "core/features/matching.hpp"

namespace pepper::app {
namespace {

namespace feat = core::features;

struct PerceptionDemoOptions {
  std::vector<std::string> images;
  std::string camera;
  std::string out = "matches.png";
};

std::vector<std::string> default_images() {
  const std::string dir = "/usr/share/visp-images-data/ViSP-images/mbt/cube/";
  return {dir + "image0000.pgm", dir + "image0005.pgm", dir + "image0010.pgm"};
}

cv::Scalar colour(size_t i) {
  static const cv::Scalar kColours[] = {{255, 80, 0},  {0, 200, 0},   {0, 80, 255},  {255, 0, 200},
                                        {0, 220, 220}, {220, 220, 0}, {128, 0, 255}, {0, 128, 255}};
  return kColours[i % (sizeof(kColours) / sizeof(kColours[0]))];
}

int run(const PerceptionDemoOptions& o) {
  std::vector<std::string> paths = o.images.empty() ? default_images() : o.images;
  if (paths.size() < 2 || paths.size() > 3) {
    std::cerr << "pepper_app: error: --images takes 2 or 3 files, got " << paths.size()
              << ": give two or three image files of one scene\n";
    return 2;
  }
  std::vector<cv::Mat> colour_images, grey;
  for (const auto& p : paths) {
    const cv::Mat img = cv::imread(p, cv::IMREAD_UNCHANGED);
    if (img.empty()) {
      std::cerr << "pepper_app: error: cannot read image " << p
                << ": check the path (a PNG or JPEG file)\n";
      return 1;
    }
    grey.push_back(feat::to_gray(img));
    cv::Mat c;
    cv::cvtColor(grey.back(), c, cv::COLOR_GRAY2BGR);
    colour_images.push_back(c);
  }
  core::CameraIntrinsics camera = core::CameraIntrinsics::pepper_top_vga();
  if (!o.camera.empty()) camera = core::camera::load_intrinsics(o.camera);
  const feat::FeatureExtractor extractor(camera);
  std::vector<feat::ImageFeatures> f;
  for (const auto& g : grey) f.push_back(extractor.extract(g));
  for (size_t i = 0; i < f.size(); ++i) {
    std::cout << "image " << i << ": " << paths[i] << " (" << f[i].image_size.width << "x"
              << f[i].image_size.height << "): " << f[i].lines.size() << " lines, "
              << f[i].corners_px.size() << " FAST corners, " << f[i].keypoints.size() << " ORB keypoints\n";
  }

  // Hub: the last image (the "current" one); the others are key images tracked into it.
  const size_t hub = f.size() - 1;
  feat::FrameMatcher fm(f[hub]);
  std::vector<const feat::TwoViewMatches*> pair(f.size(), nullptr);
  for (size_t i = 0; i < hub; ++i) {
    pair[i] = &fm.two_view(static_cast<int64_t>(i), f[i]);
    const auto& w = fm.wide_baseline(static_cast<int64_t>(i), f[i]);
    std::cout << "n(" << i << ", " << hub << "): " << pair[i]->n_lines() << " lines (of "
              << pair[i]->line_candidates << " descriptor matches) + " << pair[i]->n_points()
              << " points (of " << pair[i]->point_candidates << " KLT tracks) = " << pair[i]->total()
              << "; wide baseline (ORB): " << w.n_points() << " points of " << w.point_candidates << "\n";
  }
  const feat::ThreeViewMatches* three = nullptr;
  if (f.size() == 3) {
    three = &fm.three_view(0, f[0], 1, f[1]);
    std::cout << "three views (0 -> 2 <- 1): nL = " << three->n_lines() << " (of "
              << three->line_candidates << " chained, RANSAC " << three->trifocal.iterations
              << " samples), nP = " << three->n_points() << "\n";
  }

  // Side by side, scaled to a common height.
  const int h = colour_images[0].rows;
  std::vector<cv::Mat> panels;
  std::vector<double> scale;
  std::vector<int> x0;
  int width = 0;
  for (auto& c : colour_images) {
    const double s = static_cast<double>(h) / c.rows;
    cv::Mat r;
    cv::resize(c, r, cv::Size(static_cast<int>(c.cols * s), h));
    panels.push_back(r);
    scale.push_back(s);
    x0.push_back(width);
    width += r.cols;
  }
  cv::Mat canvas(h, width, CV_8UC3);
  for (size_t i = 0; i < panels.size(); ++i) panels[i].copyTo(canvas(cv::Rect(x0[i], 0, panels[i].cols, h)));
  auto at = [&](size_t view, const cv::Point2f& p) {
    return cv::Point2f(static_cast<float>(p.x * scale[view] + x0[view]), static_cast<float>(p.y * scale[view]));
  };
  // Unmatched lines in grey.
  for (size_t v = 0; v < f.size(); ++v)
    for (const auto& l : f[v].lines) cv::line(canvas, at(v, l.p0_px), at(v, l.p1_px), {150, 150, 150}, 1, cv::LINE_AA);
  size_t k = 0;
  if (three) {
    // Three-view verified lines: same colour in all three panels.
    for (const auto& t : three->lines) {
      const cv::Scalar c = colour(k++);
      const auto& lx = f[0].lines[static_cast<size_t>(t.idx_x)];
      const auto& lh = f[hub].lines[static_cast<size_t>(t.idx_hub)];
      const auto& ly = f[1].lines[static_cast<size_t>(t.idx_y)];
      cv::line(canvas, at(0, lx.p0_px), at(0, lx.p1_px), c, 2, cv::LINE_AA);
      cv::line(canvas, at(1, ly.p0_px), at(1, ly.p1_px), c, 2, cv::LINE_AA);
      cv::line(canvas, at(hub, lh.p0_px), at(hub, lh.p1_px), c, 2, cv::LINE_AA);
    }
  } else {
    for (const auto& m : pair[0]->lines) {
      const cv::Scalar c = colour(k++);
      const auto& la = f[0].lines[static_cast<size_t>(m.idx_a)];
      const auto& lb = f[hub].lines[static_cast<size_t>(m.idx_b)];
      cv::line(canvas, at(0, la.p0_px), at(0, la.p1_px), c, 2, cv::LINE_AA);
      cv::line(canvas, at(hub, lb.p0_px), at(hub, lb.p1_px), c, 2, cv::LINE_AA);
    }
  }
  // Verified KLT points: a circle in the key image, a joining line to the current image.
  for (size_t i = 0; i < hub; ++i) {
    for (const auto& p : pair[i]->points) {
      cv::circle(canvas, at(i, p.a_px), 3, {0, 255, 255}, 1, cv::LINE_AA);
      cv::circle(canvas, at(hub, p.b_px), 3, {0, 255, 255}, 1, cv::LINE_AA);
    }
  }
  if (!pair[0]->points.empty()) {
    for (size_t q = 0; q < pair[0]->points.size(); q += 4) {
      const auto& p = pair[0]->points[q];
      cv::line(canvas, at(0, p.a_px), at(hub, p.b_px), {0, 200, 255}, 1, cv::LINE_AA);
    }
  }
  std::string label = "n(0," + std::to_string(hub) + ")=" + std::to_string(pair[0]->total());
  if (three) label += "  nL3=" + std::to_string(three->n_lines()) + " nP3=" + std::to_string(three->n_points());
  cv::putText(canvas, label, {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.7, {0, 0, 255}, 2, cv::LINE_AA);
  if (!cv::imwrite(o.out, canvas)) {
    std::cerr << "pepper_app: error: cannot write " << o.out
              << ": check that its folder exists and is writable\n";
    return 1;
  }
  std::cout << "wrote " << o.out << "\n";
  return 0;
}

}  // namespace

void register_perception_demo_command(CLI::App& app) {
  auto opts = std::make_shared<PerceptionDemoOptions>();
  auto* cmd = app.add_subcommand(
      "perception-demo",
      "Extract lines (EDLines + band descriptors), FAST corners and ORB keypoints from 2-3 images\n"
      "(any size; colour is converted to grey), verify matches against the last image (KLT +\n"
      "five-point RANSAC, LBD-style line matching, planar three-view line RANSAC), print the\n"
      "counts and draw them side by side. Without --images: three frames of visp-images-data.");
  cmd->add_option("--images", opts->images, "2 or 3 image files; the last one is the 'current' image");
  cmd->add_option("--camera", opts->camera, "intrinsics file (.xml ViSP, .yaml/.json); default Pepper top VGA");
  cmd->add_option("--out", opts->out, "annotated output image")->capture_default_str();
  cmd->footer(
      "Example:\n  pepper_app perception-demo --images a.png b.png c.png --out matches.png\n"
      "  pepper_app perception-demo   # mbt/cube frames 0, 5, 10 of visp-images-data");
  cmd->callback([opts] {
    try {
      exit_code() = run(*opts);
    } catch (const std::exception& e) {
      std::cerr << "pepper_app: error: " << message_with_next_step(e) << "\n";
      exit_code() = 1;
    }
  });
}

}  // namespace pepper::app
