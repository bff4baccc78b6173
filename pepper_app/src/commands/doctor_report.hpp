#pragma once
// `pepper_app doctor`'s report: one line per check, OK, WARN (works; something to know, with
// what to do) or FAIL (fix before driving, with what to do), and the closing verdict with the
// exit code (0 when nothing failed, warnings allowed; 1 when a check failed).

#include <exception>
#include <string>

namespace pepper::app::doctor {

class Report {
 public:
  void ok(const std::string& check, const std::string& msg) { line("OK  ", check, msg, ""); }
  /// Works, with a limit the operator must know about (not counted as a failure); `todo` says
  /// what to do about it.
  void warn(const std::string& check, const std::string& msg, const std::string& todo = "") {
    line("WARN", check, msg, todo);
    ++warnings_;
  }
  void fail(const std::string& check, const std::string& msg, const std::string& todo = "") {
    line("FAIL", check, msg, todo);
    ++failures_;
  }
  int failures() const { return failures_; }
  int warnings() const { return warnings_; }

 private:
  /// `TAG  check  message -> todo` on stdout, flushed (the operator follows it live).
  void line(const char* tag, const std::string& check, const std::string& msg,
            const std::string& todo);
  int failures_ = 0;
  int warnings_ = 0;
};

/// An exception as one short operator-facing phrase (login, TLS, unreachable, missing service,
/// timeout, connection lost, or its text).
std::string classify(const std::exception& e);

/// `v` with `decimals` digits after the point.
std::string fmt(double v, int decimals);

/// Prints the closing line and returns the exit code.
int summarize(const Report& report);

}  // namespace pepper::app::doctor
