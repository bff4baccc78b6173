#pragma once
// The next step for an error that reaches the user. The libraries' messages name the offending
// value (the map folder, the world file, the robot URL, the setting); the app knows what the user
// can do about it, so the advice is added here, once, by the error's type. docs/errors.md lists
// every error exit of the CLI with its message, cause, next step and exit code; a test
// (tests/app/e2e/test_errors_e2e.cpp) triggers each one it can offline and checks the table.

#include <exception>
#include <string>

namespace pepper::app {

/// What to do about `e` ("" when its message already says, or nothing better is known).
std::string next_step_for(const std::exception& e);

/// The same for a stored exception ("" for none or a non-std one).
std::string next_step_for(const std::exception_ptr& e);

/// `e.what()` followed by its next step, as one line for stderr.
std::string message_with_next_step(const std::exception& e);

/// Prints "pepper_app: error: MESSAGE: NEXT STEP" to stderr. Returns the exit code of the
/// error's kind: 2 for a refused configuration (nothing was started), else `code`.
int report_exception(const std::exception& e, int code = 1);

}  // namespace pepper::app
