#pragma once
// Small helpers shared by the command files: progress lines, camera files, error reporting.

#include <chrono>
#include <cstddef>
#include <optional>
#include <string>

#include "core/camera/intrinsics.hpp"

namespace pepper::app {

/// Prints "label: done/total (pct%)" on stderr at most every 0.5 s, and a final line.
class ProgressLine {
 public:
  explicit ProgressLine(std::string label) : label_(std::move(label)) {}
  void update(std::size_t done, std::size_t total, const std::string& extra = "");
  void finish(const std::string& extra = "");

 private:
  std::string label_;
  std::chrono::steady_clock::time_point last_{};
  std::size_t done_ = 0, total_ = 0;
};

/// Loads --camera FILE (.xml ViSP, .yaml/.yml/.json plain) when non-empty.
std::optional<core::CameraIntrinsics> load_camera_option(const std::string& path);

/// Prints "pepper_app: error: <what>" to stderr and returns exit code 1.
int report_error(const std::string& what);

}  // namespace pepper::app
