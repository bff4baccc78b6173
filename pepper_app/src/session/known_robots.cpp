// Trust on first use for tcps:// robots (see the header).
#include "session/known_robots.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

#include "naoqi_bridge/qi/errors.hpp"
#include "naoqi_bridge/qi/url.hpp"

namespace pepper::app {

namespace fs = std::filesystem;
namespace qi = naoqi_bridge::qi;

namespace {

/// "ab:cd:..." and "ABCD..." compare equal.
std::string canonical(const std::string& fingerprint) {
  std::string hex;
  for (const char c : fingerprint) {
    if (std::isxdigit(static_cast<unsigned char>(c))) {
      hex += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
  }
  return hex;
}

/// The robot's identity in the file: host and port of its URL.
std::string robot_key(const std::string& url) {
  const qi::Url u = qi::parse_url(url);
  return u.host + ":" + std::to_string(u.port);
}

struct KnownEntry {
  std::string fingerprint;
  int line = 0;
};

std::optional<KnownEntry> lookup(const fs::path& file, const std::string& key) {
  std::ifstream in(file);
  if (!in) return std::nullopt;  // no file yet: every robot is new
  std::string text;
  for (int n = 1; std::getline(in, text); ++n) {
    std::istringstream fields(text);
    std::string host_port, fingerprint;
    if (!(fields >> host_port) || host_port[0] == '#') continue;
    if (host_port == key && (fields >> fingerprint)) return KnownEntry{fingerprint, n};
  }
  return std::nullopt;
}

void remember(const fs::path& file, const std::string& key, const std::string& fingerprint) {
  std::error_code ec;
  if (file.has_parent_path()) fs::create_directories(file.parent_path(), ec);
  std::ofstream out(file, std::ios::app);
  out << key << " " << fingerprint << "\n";
  out.flush();
  if (!out) {
    throw naoqi_bridge::BridgeError("cannot write the known-robots file '" + file.string() +
                                    "' (set PEPPER_KNOWN_ROBOTS to a writable file)");
  }
}

bool ask_yes(const std::string& question) {
  std::cerr << question << std::flush;
  std::string answer;
  if (!std::getline(std::cin, answer)) return false;
  std::transform(answer.begin(), answer.end(), answer.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return answer == "yes" || answer == "y";
}

}  // namespace

fs::path default_known_robots_file() {
  if (const char* f = std::getenv("PEPPER_KNOWN_ROBOTS"); f && *f) return f;
  if (const char* x = std::getenv("XDG_CONFIG_HOME"); x && *x) {
    return fs::path(x) / "pepper_nav" / "known_robots";
  }
  if (const char* h = std::getenv("HOME"); h && *h) {
    return fs::path(h) / ".config" / "pepper_nav" / "known_robots";
  }
  return fs::path("known_robots");
}

std::function<void(const std::string&, const std::string&)> known_robots_verifier(
    TrustOptions options) {
  if (options.file.empty()) options.file = default_known_robots_file();
  return [options](const std::string& url, const std::string& sha256) {
    const std::string key = robot_key(url);
    const std::string file = options.file.string();
    if (const auto known = lookup(options.file, key)) {
      if (canonical(known->fingerprint) == canonical(sha256)) return;
      throw qi::TlsError(
          "the TLS certificate of " + url + " changed: " + file + " line " +
          std::to_string(known->line) + " expects SHA-256 " + known->fingerprint +
          ", the robot now shows " + sha256 +
          ". Nothing was sent (no password). If the robot was reinstalled or its certificate "
          "renewed, check the new fingerprint on the robot itself, then remove that line and "
          "connect again with --trust-new-robot (or pass --tls-pin " + sha256 +
          "); otherwise another machine may be answering for the robot: do not connect.");
    }
    const std::string intro = "first contact with " + url +
                              ": its TLS certificate has SHA-256 fingerprint " + sha256;
    if (options.trust_new_robot) {
      remember(options.file, key, sha256);
      std::cerr << intro << "; trusted (--trust-new-robot) and saved to " << file << "\n";
      return;
    }
    if (options.allow_prompt && ::isatty(STDIN_FILENO) != 0) {
      if (ask_yes(intro + ".\nCompare it with the robot's own certificate. Trust this robot "
                          "and save it to " + file + "? (yes/no) ")) {
        remember(options.file, key, sha256);
        return;
      }
      throw qi::TlsError("not trusted: " + intro + " (answer was not yes; nothing was sent)");
    }
    throw qi::TlsError(intro + ", not in " + file +
                       ". Nothing was sent (no password). Check the fingerprint on the robot, "
                       "then connect again with --trust-new-robot (saves it) or --tls-pin " +
                       sha256 + ".");
  };
}

}  // namespace pepper::app
