#include "commands/doctor_report.hpp"

#include <iomanip>
#include <iostream>
#include <sstream>

#include "naoqi_bridge/qi/errors.hpp"

namespace pepper::app::doctor {

namespace qi = pepper::naoqi_bridge::qi;

void Report::line(const char* tag, const std::string& check, const std::string& msg,
                  const std::string& todo) {
  std::cout << tag << "  " << std::left << std::setw(24) << check << " " << msg
            << (todo.empty() ? "" : " -> " + todo) << "\n"
            << std::flush;
}

std::string classify(const std::exception& e) {
  if (dynamic_cast<const qi::AuthenticationError*>(&e)) return std::string("login: ") + e.what();
  if (dynamic_cast<const qi::TlsError*>(&e)) return std::string("TLS: ") + e.what();
  if (dynamic_cast<const qi::ConnectError*>(&e)) {
    return std::string("host unreachable: ") + e.what();
  }
  if (dynamic_cast<const qi::ServiceNotFound*>(&e))
    return std::string("missing service: ") + e.what();
  if (dynamic_cast<const qi::CallTimeout*>(&e)) return std::string("timeout: ") + e.what();
  if (dynamic_cast<const qi::ConnectionLost*>(&e))
    return std::string("connection lost: ") + e.what();
  return e.what();
}

std::string fmt(double v, int decimals) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(decimals) << v;
  return os.str();
}

int summarize(const Report& report) {
  const std::string warned = report.warnings() == 0 ? ""
                                                    : std::to_string(report.warnings()) +
                                                          " warning(s): see the WARN lines";
  if (report.failures() == 0) {
    std::cout << "all checks passed" << (warned.empty() ? "" : ", " + warned) << "\n";
  } else {
    std::cout << report.failures() << " check(s) failed: fix the FAIL lines before driving"
              << (warned.empty() ? "" : "; " + warned) << "\n";
  }
  return report.failures() == 0 ? 0 : 1;
}

}  // namespace pepper::app::doctor
