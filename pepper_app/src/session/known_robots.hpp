#pragma once
// Trust on first use for tcps:// robots (NAOqi 2.9): a robot's self-signed TLS certificate is
// remembered by its SHA-256 fingerprint in a known-robots file, and every later connection
// checks it before any credential is sent (naoqi_bridge SessionOptions::verify_certificate runs
// between the TLS handshake and the login).
//
//   first contact   the fingerprint is shown; it is trusted (and saved) only with
//                   --trust-new-robot or a "yes" typed at the terminal; otherwise the connection
//                   is refused with the fingerprint and the two ways to accept it
//   known robot     the same fingerprint passes; a different one is refused with a message that
//                   says what to check and which line of which file to remove
//   --tls-pin F     an explicit pin replaces the file (the session checks it; nothing is saved)
//
// File: one robot per line, "HOST:PORT SHA256" (fingerprint as AB:CD:..., any case), '#'
// comments. Location: $PEPPER_KNOWN_ROBOTS, else $XDG_CONFIG_HOME/pepper_nav/known_robots, else
// ~/.config/pepper_nav/known_robots. Written by appending one line (the folder is created).
// Errors: naoqi_bridge::qi::TlsError (refusals, with the fix), naoqi_bridge::BridgeError (the file
// cannot be read or written).

#include <filesystem>
#include <functional>
#include <string>

namespace pepper::app {

struct TrustOptions {
  std::filesystem::path file;   ///< empty: default_known_robots_file()
  bool trust_new_robot = false; ///< first contact: trust and save without asking
  bool allow_prompt = true;     ///< first contact: ask at the terminal (when stdin is one)
};

/// $PEPPER_KNOWN_ROBOTS, else $XDG_CONFIG_HOME/pepper_nav/known_robots, else
/// ~/.config/pepper_nav/known_robots.
std::filesystem::path default_known_robots_file();

/// The check for SessionOptions::verify_certificate / QiBridgeOptions::verify_certificate.
/// Messages for the operator (a new robot trusted) go to stderr.
std::function<void(const std::string& url, const std::string& sha256)> known_robots_verifier(
    TrustOptions options);

}  // namespace pepper::app
