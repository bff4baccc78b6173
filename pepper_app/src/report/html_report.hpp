#pragma once
// A self-contained HTML report (images embedded as base64 PNG, no external files or network), for
// the main job's replay report and the evaluation. Written atomically (temp file + rename).

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace pepper::app::report {

struct Table {
  std::string caption;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

class HtmlReport {
 public:
  explicit HtmlReport(std::string title) : title_(std::move(title)) {}

  void heading(const std::string& text);
  void paragraph(const std::string& text);        ///< escaped
  void preformatted(const std::string& text);     ///< escaped, monospace
  void table(const Table& table);
  void image(const cv::Mat& bgr_or_gray, const std::string& caption);
  /// Markup added as it is (the caller escapes its text with html_escape).
  void raw_html(const std::string& html) { body_ += html; }

  std::string html() const;
  /// Writes the page; throws std::runtime_error naming the path on failure.
  void write(const std::filesystem::path& path) const;

 private:
  std::string title_;
  std::string body_;
};

std::string html_escape(const std::string& text);
std::string base64_encode(const std::vector<unsigned char>& bytes);

}  // namespace pepper::app::report
