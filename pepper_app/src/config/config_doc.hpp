#pragma once
// The Markdown reference of the configuration (docs/configuration.md), generated from the
// parameter table (parameters.hpp) and the defaults of a default-constructed AppConfig:
// `pepper_app config doc > docs/configuration.md`. A test compares the committed file with this
// text, so the reference cannot drift from the code.
#include <string>

namespace pepper::app {

std::string configuration_markdown();

}  // namespace pepper::app
