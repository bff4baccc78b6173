// Request target -> file under the web root (see teach_ui/static_files.hpp).
#include "teach_ui/static_files.hpp"

#include <array>
#include <optional>
#include <system_error>
#include <utility>

namespace pepper::teach_ui {
namespace {

std::optional<int> hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return std::nullopt;
}

std::optional<std::string> percent_decode(std::string_view in) {
  std::string out;
  out.reserve(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (in[i] != '%') {
      out.push_back(in[i]);
      continue;
    }
    if (i + 2 >= in.size()) return std::nullopt;
    const auto hi = hex_value(in[i + 1]);
    const auto lo = hex_value(in[i + 2]);
    if (!hi || !lo) return std::nullopt;
    out.push_back(static_cast<char>(*hi * 16 + *lo));
    i += 2;
  }
  return out;
}

bool inside(const std::filesystem::path& root, const std::filesystem::path& p) {
  auto r = root.begin();
  auto q = p.begin();
  for (; r != root.end(); ++r, ++q) {
    if (r->empty()) continue;  // trailing separator of the root
    if (q == p.end() || *q != *r) return false;
  }
  return true;
}

}  // namespace

WebPath resolve_web_path(const std::filesystem::path& root_canonical, std::string_view target) {
  WebPath result;
  result.status = WebPathStatus::kBadTarget;
  if (target.empty() || target.front() != '/') return result;
  if (const auto cut = target.find_first_of("?#"); cut != std::string_view::npos) {
    target = target.substr(0, cut);
  }
  const auto decoded = percent_decode(target);
  if (!decoded) return result;
  std::string rel = *decoded;
  if (rel.find('\0') != std::string::npos || rel.find('\\') != std::string::npos) return result;
  if (rel.back() == '/') rel += "index.html";
  // Check every segment; empty segments ("//") and "." are harmless.
  std::size_t start = 1;
  while (start <= rel.size()) {
    const std::size_t end = std::min(rel.find('/', start), rel.size());
    const std::string_view seg(rel.data() + start, end - start);
    if (seg == "..") return result;
    if (!seg.empty() && seg != "." && seg.front() == '.') {
      result.status = WebPathStatus::kNotFound;  // hidden file: pretend it does not exist
      return result;
    }
    start = end + 1;
  }
  result.status = WebPathStatus::kNotFound;
  std::error_code ec;
  const std::filesystem::path real =
      std::filesystem::weakly_canonical(root_canonical / std::filesystem::path(rel.substr(1)), ec);
  if (ec || !inside(root_canonical, real)) return result;
  if (!std::filesystem::is_regular_file(real, ec) || ec) return result;
  result.status = WebPathStatus::kOk;
  result.path = real;
  return result;
}

std::string_view mime_type_for(const std::filesystem::path& file) {
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 12> kTypes{{
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},
      {".png", "image/png"},
      {".jpg", "image/jpeg"},
      {".jpeg", "image/jpeg"},
      {".svg", "image/svg+xml"},
      {".ico", "image/x-icon"},
      {".txt", "text/plain; charset=utf-8"},
      {".woff2", "font/woff2"},
  }};
  const std::string ext = file.extension().string();
  for (const auto& [e, type] : kTypes) {
    if (e == ext) return type;
  }
  return "application/octet-stream";
}

}  // namespace pepper::teach_ui
