// Trust on first use for tcps:// robots (issue 23): the known-robots file decides before any
// credential is sent. The impostor test runs a TLS server (our mock NAOqi with a fresh
// self-signed certificate) on 127.0.0.1 that records every message it receives: a robot whose
// certificate changed must be refused with nothing, no password, sent.
#include "session/known_robots.hpp"

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "naoqi_bridge/qi/errors.hpp"
#include "naoqi_bridge/qi/mock_server.hpp"
#include "session/robot_connection.hpp"
#include "sim/synthetic_pattern_robot.hpp"
#include "support/temp_dir.hpp"

namespace pepper::app {
namespace {

namespace qi = naoqi_bridge::qi;

const std::string kFingerprint =
    "AA:BB:CC:DD:EE:FF:00:11:22:33:44:55:66:77:88:99:AA:BB:CC:DD:EE:FF:00:11:22:33:44:55:66:77:"
    "88:99";
const std::string kOther =
    "01:BB:CC:DD:EE:FF:00:11:22:33:44:55:66:77:88:99:AA:BB:CC:DD:EE:FF:00:11:22:33:44:55:66:77:"
    "88:99";

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string refusal(const std::function<void(const std::string&, const std::string&)>& verify,
                    const std::string& url, const std::string& fingerprint) {
  try {
    verify(url, fingerprint);
  } catch (const qi::TlsError& e) {
    return e.what();
  }
  return "";
}

TEST(KnownRobots, FirstContactIsRefusedUnlessTrustedThenTheSameCertificatePasses) {
  test::TempDir tmp;
  TrustOptions trust;
  trust.file = tmp.path() / "cfg" / "known_robots";
  trust.allow_prompt = false;
  const std::string first = refusal(known_robots_verifier(trust), "tcps://10.0.0.5:9503",
                                    kFingerprint);
  EXPECT_NE(first.find(kFingerprint), std::string::npos) << first;
  EXPECT_NE(first.find("--trust-new-robot"), std::string::npos) << first;
  EXPECT_NE(first.find("--tls-pin"), std::string::npos) << first;
  EXPECT_FALSE(std::filesystem::exists(trust.file));

  trust.trust_new_robot = true;
  EXPECT_EQ(refusal(known_robots_verifier(trust), "tcps://10.0.0.5:9503", kFingerprint), "");
  EXPECT_EQ(slurp(trust.file), "10.0.0.5:9503 " + kFingerprint + "\n");

  // Known now: passes without the flag, in any spelling of the same fingerprint.
  trust.trust_new_robot = false;
  std::string plain;
  for (char c : kFingerprint)
    if (c != ':') plain += static_cast<char>(std::tolower(c));
  EXPECT_EQ(refusal(known_robots_verifier(trust), "tcps://10.0.0.5:9503", plain), "");
  // Another port of the same host is another robot.
  EXPECT_NE(refusal(known_robots_verifier(trust), "tcps://10.0.0.5:9504", kFingerprint), "");
}

TEST(KnownRobots, ChangedCertificateIsRefusedWithWhatToDoEvenWithTrustNewRobot) {
  test::TempDir tmp;
  TrustOptions trust;
  trust.file = tmp.path() / "known_robots";
  trust.allow_prompt = false;
  trust.trust_new_robot = true;
  {
    std::ofstream f(trust.file);
    f << "# robots seen\n10.0.0.5:9503 " << kFingerprint << "\n";
  }
  const std::string why = refusal(known_robots_verifier(trust), "tcps://10.0.0.5:9503", kOther);
  EXPECT_NE(why.find("changed"), std::string::npos) << why;
  EXPECT_NE(why.find(trust.file.string() + " line 2"), std::string::npos) << why;
  EXPECT_NE(why.find(kOther), std::string::npos) << why;
  EXPECT_NE(why.find("remove that line"), std::string::npos) << why;
  EXPECT_NE(why.find("no password"), std::string::npos) << why;
  EXPECT_EQ(slurp(trust.file).find(kOther), std::string::npos);  // nothing learnt
}

TEST(KnownRobots, ImpostorWithAChangedCertificateReceivesNoCredential) {
  test::TempDir tmp;
  const auto known = tmp.path() / "known_robots";
  const auto calls = tmp.path() / "impostor_calls.jsonl";
  const auto password_file = tmp.path() / "pw";
  std::ofstream(password_file) << "robot-password\n";

  sim::SyntheticPatternRobot robot;
  qi::MockServerOptions so;
  so.listen_url = "tcps://127.0.0.1:0";  // a fresh self-signed certificate: not the robot's
  so.user = "nao";
  so.password = "robot-password";
  so.call_log_file = calls.string();
  qi::MockNaoqiServer impostor(robot, so);
  impostor.start();
  const std::string url = impostor.url();
  const std::string host_port = url.substr(std::string("tcps://").size());
  std::ofstream(known) << host_port << " " << kFingerprint << "\n";  // the real robot's

  RobotConnectOptions o;
  o.password_file = password_file.string();  // user defaults to nao on tcps
  o.allow_prompt = false;
  o.trust_new_robot = true;  // must not matter for a known robot
  o.known_robots_file = known;
  RobotConnection c = open_robot(url, o);
  try {
    c.bridge->connect();
    FAIL() << "connected to an impostor";
  } catch (const qi::TlsError& e) {
    EXPECT_NE(std::string(e.what()).find("changed"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(impostor.certificate_sha256()), std::string::npos)
        << e.what();
  }
  c.bridge.reset();
  // The server counts the connection on its own thread: on a loaded machine that can come after
  // the client has already given up (seen once in a full suite run), so wait for it.
  for (int i = 0; i < 200 && impostor.stats().connections_accepted == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  impostor.stop();
  EXPECT_EQ(impostor.stats().connections_accepted, 1u);  // it did get a TLS connection
  EXPECT_EQ(impostor.stats().messages_received, 0u);     // and not a single message
  EXPECT_EQ(slurp(calls), "");                           // its own record: nothing
}

TEST(KnownRobots, TrustedRobotLogsInAndAPinReplacesTheFile) {
  test::TempDir tmp;
  const auto known = tmp.path() / "known_robots";
  const auto password_file = tmp.path() / "pw";
  std::ofstream(password_file) << "robot-password\n";
  sim::SyntheticPatternRobot robot;
  qi::MockServerOptions so;
  so.listen_url = "tcps://127.0.0.1:0";
  so.user = "nao";
  so.password = "robot-password";
  qi::MockNaoqiServer server(robot, so);
  server.start();

  RobotConnectOptions o;
  o.password_file = password_file.string();
  o.allow_prompt = false;
  o.known_robots_file = known;
  // First contact without --trust-new-robot: refused, nothing received.
  EXPECT_THROW(open_robot(server.url(), o).bridge->connect(), qi::TlsError);
  EXPECT_EQ(server.stats().messages_received, 0u);
  // With it: trusted, saved, logged in; later connections need no flag.
  o.trust_new_robot = true;
  EXPECT_NO_THROW(open_robot(server.url(), o).bridge->connect());
  EXPECT_NE(slurp(known).find(server.certificate_sha256()), std::string::npos);
  o.trust_new_robot = false;
  EXPECT_NO_THROW(open_robot(server.url(), o).bridge->connect());
  // An explicit pin wins over the file: a wrong one is refused, the right one passes.
  o.tls_pin = kFingerprint;
  EXPECT_THROW(open_robot(server.url(), o).bridge->connect(), qi::TlsError);
  o.tls_pin = server.certificate_sha256();
  EXPECT_NO_THROW(open_robot(server.url(), o).bridge->connect());
  EXPECT_EQ(server.stats().auth_failures, 0u);
}

}  // namespace
}  // namespace pepper::app
