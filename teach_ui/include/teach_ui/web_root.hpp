#pragma once
// Where the teach UI's static page is served from.
#include <string>

namespace pepper::teach_ui {

/// The page folder of the source tree this binary was built from (teach_ui/web).
std::string default_web_root();

}  // namespace pepper::teach_ui
