#pragma once
// Mapping of an HTTP request target to a file under the web root, refusing any escape.
//
// Used by UiServer for every GET/HEAD; public so that the traversal rules can be tested on their
// own. Rules: the target must start with '/'; the query ("?...") and fragment are dropped; %XX
// escapes are decoded once (a bad escape is refused); after decoding, NUL, backslash, a ".."
// segment or a segment starting with '.' (hidden files) is refused; a target ending in '/' means
// its index.html; finally the real path (symbolic links resolved) must lie inside the real web
// root and be a regular file. Pure function of the file system; never throws.
#include <filesystem>
#include <string>
#include <string_view>

namespace pepper::teach_ui {

enum class WebPathStatus {
  kOk,         ///< `path` is a regular file inside the root
  kBadTarget,  ///< refused (traversal, bad escape, NUL...): answer 400
  kNotFound,   ///< well-formed but no such regular file inside the root: answer 404
};

struct WebPath {
  WebPathStatus status = WebPathStatus::kNotFound;
  std::filesystem::path path;  ///< canonical file path when kOk
};

/// `root_canonical` must be std::filesystem::canonical() of an existing folder.
WebPath resolve_web_path(const std::filesystem::path& root_canonical, std::string_view target);

/// Content-Type for a file name by extension ("text/html; charset=utf-8", "image/png"...);
/// "application/octet-stream" when unknown.
std::string_view mime_type_for(const std::filesystem::path& file);

}  // namespace pepper::teach_ui
