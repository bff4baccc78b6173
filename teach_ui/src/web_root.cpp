#include "teach_ui/web_root.hpp"

namespace pepper::teach_ui {

std::string default_web_root() { return PEPPER_UI_WEB_ROOT; }

}  // namespace pepper::teach_ui
