// QiBridge / QiSession against MockNaoqiServer over loopback (ephemeral ports): frames, moves,
// watchdog, disconnects, login, TLS, malformed replies. Every byte crosses the real wire format.
#include <gtest/gtest.h>
#include <unistd.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <thread>

#include "naoqi_bridge/qi/mock_server.hpp"
#include "naoqi_bridge/qi/qi_bridge.hpp"
#include "naoqi_bridge/qi/session.hpp"
#include "sim/synthetic_pattern_robot.hpp"

namespace qi = pepper::naoqi_bridge::qi;
namespace nb = pepper::naoqi_bridge;
namespace sim = pepper::sim;
using sim::SyntheticPatternOptions;
using sim::SyntheticPatternRobot;
using namespace std::chrono_literals;

namespace {

qi::QiBridgeOptions bridge_options(const qi::MockNaoqiServer& server) {
  qi::QiBridgeOptions o;
  o.url = server.url();
  o.connect_timeout = 3000ms;
  o.call_timeout = 3000ms;
  o.head_settle_timeout = 0ms;
  return o;
}

template <class Pred>
bool wait_until(Pred pred, std::chrono::milliseconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (pred()) return true;
    std::this_thread::sleep_for(5ms);
  }
  return pred();
}

/// Waits until the robot's last command is a forward speed of `v_x_m_s` (a velocity command
/// goes out as a moveTo whose answer the bridge does not await).
bool wait_last_forward(const SyntheticPatternRobot& robot, double v_x_m_s) {
  return wait_until(
      [&] {
        const auto log = robot.command_log();
        return !log.empty() && !log.back().stop_move &&
               std::fabs(log.back().velocity.v_x_m_s - v_x_m_s) < 1e-5;
      },
      2000ms);
}

bool is_stop(const sim::CommandRecord& r) {
  return r.stop_move ||
         (r.velocity.v_x_m_s == 0.0 && r.velocity.v_y_m_s == 0.0 && r.velocity.omega_rad_s == 0.0);
}

}  // namespace

TEST(QiLoopback, SessionFindsServicesAndResolvesOverloads) {
  SyntheticPatternRobot robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  qi::QiSession session;
  session.connect(server.url());
  EXPECT_TRUE(session.is_connected());
  EXPECT_TRUE(session.server_capabilities().at("MessageFlags").as_bool());

  const auto motion = session.service("ALMotion");
  EXPECT_EQ(motion.meta.find("move", "(fff)")->uid, 135u);
  EXPECT_EQ(motion.meta.find("move", "(fffm)")->uid, 136u);
  const auto video = session.service("ALVideoDevice");
  EXPECT_EQ(video.meta.find("getImageRemote", "(s)")->uid, 162u);
  EXPECT_EQ(video.meta.find("getImageRemote", "(s)")->return_signature, "m");

  const qi::Value angles = session.call(
      motion, "getAngles", "(mb)", {qi::Value::strings({"HeadYaw"}), qi::Value::boolean(true)});
  ASSERT_EQ(angles.elements().size(), 1u);

  try {
    (void)session.service("ALNope");
    FAIL();
  } catch (const qi::ServiceNotFound& e) {
    EXPECT_NE(std::string(e.what()).find("Cannot find service 'ALNope'"), std::string::npos)
        << e.what();
  }
  try {
    (void)session.call(motion, "move", "(ff)", {});
    FAIL();
  } catch (const qi::MethodNotFound& e) {
    EXPECT_NE(std::string(e.what()).find("move(fffm)"), std::string::npos) << e.what();
  }
  const auto life = session.service("ALAutonomousLife");
  try {
    session.call(life, "setState", "(s)", {qi::Value::string("bogus")});
    FAIL();
  } catch (const qi::RemoteCallError& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("ALAutonomousLife.setState"), std::string::npos) << text;
    EXPECT_NE(text.find("invalid state 'bogus'"), std::string::npos) << text;
  }
  // Joints the simulated robot does not have (sim::SimError) are Error replies carrying the
  // method and the robot's text.
  const auto expect_refused = [&](const char* method, const char* signature,
                                  std::vector<qi::Value> args, const std::string& text) {
    try {
      (void)session.call(motion, method, signature, std::move(args));
      FAIL() << method;
    } catch (const qi::RemoteCallError& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  expect_refused(
      "setAngles", "(mmf)",
      {qi::Value::strings({"LElbowRoll"}), qi::Value::floats({0.0f}), qi::Value::float32(0.1f)},
      "ALMotion::setAngles: set_joint_angles: unknown joint 'LElbowRoll'");
  expect_refused("getAngles", "(mb)", {qi::Value::strings({"Nope"}), qi::Value::boolean(true)},
                 "ALMotion::getAngles: joint_angles: unknown joint 'Nope'");
  // The connection survives remote errors.
  EXPECT_EQ(session.call(life, "getState", "()", {}).as_string(), "solitary");
}

TEST(QiLoopback, LegacySixFieldServiceInfoAccepted) {
  SyntheticPatternRobot robot;
  qi::MockServerOptions so;
  so.legacy_service_info = true;
  qi::MockNaoqiServer server(robot, so);
  server.start();
  qi::QiSession session;
  session.connect(server.url());
  EXPECT_EQ(session.service("ALMotion").id, 2u);
}

TEST(QiLoopback, CameraFramesArriveIntactAndInOrder) {
  SyntheticPatternRobot robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  qi::QiBridge bridge(bridge_options(server));
  bridge.connect();
  EXPECT_EQ(bridge.state(), nb::ConnectionState::kConnected);
  const auto intr = bridge.start_camera({});
  EXPECT_EQ(intr, pepper::core::CameraIntrinsics::pepper_top_vga().scaled_to(640, 480));
  std::int64_t last_index = -1;
  std::int64_t last_t = -1;
  for (int i = 0; i < 12; ++i) {
    const auto f = bridge.next_frame(3000ms);
    ASSERT_TRUE(f.has_value()) << i;
    ASSERT_EQ(f->gray.cols, 640);
    ASSERT_EQ(f->gray.rows, 480);
    const auto index = SyntheticPatternRobot::verify_frame(f->gray);
    ASSERT_TRUE(index.has_value()) << "frame " << i << " corrupted";
    EXPECT_EQ(*index, last_index + 1);  // every capture delivered, in order
    EXPECT_GT(f->t_ns, last_t);
    // Robot timestamp (s + us) -> t_ns: lockstep at 30 Hz gives multiples of 33.333 ms.
    EXPECT_EQ(f->t_ns % 1000, 0);
    last_index = *index;
    last_t = f->t_ns;
  }
  EXPECT_EQ(bridge.counters().frames, 12u);
  bridge.release();
  EXPECT_TRUE(server.video_subscribers().empty());
}

TEST(QiLoopback, QvgaAndFrameDropsSkipStaleImages) {
  SyntheticPatternRobot robot;
  qi::MockServerOptions so;
  so.drop_every_nth_frame = 3;
  qi::MockNaoqiServer server(robot, so);
  server.start();
  qi::QiBridge bridge(bridge_options(server));
  bridge.connect();
  nb::CameraRequest req;
  req.width_px = 320;
  req.height_px = 240;
  bridge.start_camera(req);
  std::int64_t last_t = -1;
  for (int i = 0; i < 9; ++i) {
    const auto f = bridge.next_frame(3000ms);
    ASSERT_TRUE(f.has_value());
    EXPECT_EQ(f->gray.cols, 320);
    EXPECT_TRUE(SyntheticPatternRobot::verify_frame(f->gray).has_value());
    EXPECT_GT(f->t_ns, last_t);  // a repeated image is never returned twice
    last_t = f->t_ns;
  }
  EXPECT_GT(bridge.counters().stale_replies, 0u);
}

TEST(QiLoopback, CommandedMovesArriveAndStopSendsZeroThenStopMove) {
  SyntheticPatternRobot robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  qi::QiBridge bridge(bridge_options(server));
  bridge.connect();
  bridge.move({0.2, 0.0, -0.15});
  ASSERT_TRUE(wait_last_forward(robot, 0.2));
  auto log = robot.command_log();
  EXPECT_NEAR(log.back().velocity.omega_rad_s, -0.15, 1e-5);
  EXPECT_NEAR(log.back().velocity.v_y_m_s, 0.0, 1e-5);
  EXPECT_FALSE(log.back().stop_move);
  bridge.stop();
  log = robot.command_log();
  ASSERT_GE(log.size(), 3u);
  EXPECT_FALSE(log[log.size() - 2].stop_move);
  EXPECT_EQ(log[log.size() - 2].velocity.v_x_m_s, 0.0);
  EXPECT_TRUE(log.back().stop_move);
}

TEST(QiLoopback, WatchdogStopsBaseWhenAppStalls) {
  SyntheticPatternOptions ro;
  ro.clock = SyntheticPatternOptions::Clock::kWallClock;  // log stamps measure real delays
  SyntheticPatternRobot robot(ro);
  qi::MockNaoqiServer server(robot);
  server.start();
  auto o = bridge_options(server);
  o.watchdog_timeout = 300ms;
  o.deadman_horizon = 0ms;  // the laptop-side watchdog alone (the robot-side stop is tested below)
  qi::QiBridge bridge(o);
  bridge.connect();
  bridge.move({0.1, 0.0, 0.0});
  // The app stalls: no further move. The watchdog must stop the base on its own.
  ASSERT_TRUE(wait_until([&] { return bridge.counters().watchdog_stops > 0; }, 3000ms));
  ASSERT_TRUE(wait_until([&] { return robot.command_log().back().stop_move; }, 1000ms));
  const auto log = robot.command_log();
  std::int64_t t_move = -1;
  std::int64_t t_stop = -1;
  for (const auto& r : log) {
    if (!is_stop(r)) t_move = r.t_ns;
    if (is_stop(r) && t_move >= 0 && t_stop < 0) t_stop = r.t_ns;
  }
  ASSERT_GE(t_move, 0);
  ASSERT_GE(t_stop, 0);
  const double delay_ms = static_cast<double>(t_stop - t_move) * 1e-6;
  // Watchdog limit 300 ms, checked every 20 ms: generous bounds, no tight timing.
  EXPECT_GE(delay_ms, 250.0);
  EXPECT_LE(delay_ms, 1500.0);
  EXPECT_TRUE(log.back().stop_move);
  EXPECT_NE(bridge.last_stop_reason().find("watchdog: no move command"), std::string::npos);
  // Not latched: the app may resume.
  EXPECT_FALSE(bridge.needs_operator());
  EXPECT_NO_THROW(bridge.move({0.05, 0.0, 0.0}));
}

TEST(QiLoopback, StalledFramesStopTheBase) {
  SyntheticPatternRobot robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  auto o = bridge_options(server);
  o.frame_stall_timeout = 300ms;
  o.deadman_horizon = 0ms;  // the laptop-side stop alone
  o.watchdog_timeout = 1000ms;
  qi::QiBridge bridge(o);
  bridge.connect();
  bridge.start_camera({});
  ASSERT_TRUE(bridge.next_frame(3000ms).has_value());
  server.set_stall_frames(true);
  (void)bridge.next_frame(50ms);  // the request in flight is never answered
  bridge.move({0.1, 0.0, 0.0});
  ASSERT_TRUE(wait_until([&] { return bridge.counters().watchdog_stops > 0; }, 3000ms));
  EXPECT_NE(bridge.last_stop_reason().find("frames stalled"), std::string::npos)
      << bridge.last_stop_reason();
  ASSERT_TRUE(wait_until([&] { return robot.command_log().back().stop_move; }, 1000ms));
}

TEST(QiLoopback, DisconnectLeavesBaseStoppedAndLatchesNeedsOperator) {
  SyntheticPatternRobot robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  auto o = bridge_options(server);
  o.reconnect_initial_backoff = 10ms;
  qi::QiBridge bridge(o);
  bridge.connect();
  bridge.start_camera({});
  ASSERT_TRUE(bridge.next_frame(3000ms).has_value());
  bridge.move({0.2, 0.0, 0.3});
  ASSERT_TRUE(wait_last_forward(robot, 0.2));  // arrived (its answer is not awaited)
  server.disconnect_all();
  ASSERT_TRUE(wait_until([&] { return bridge.state() == nb::ConnectionState::kLost; }, 3000ms));
  // Server side: like a real NAOqi the mock does not stop on disconnect; the last command was a
  // time-constrained moveTo, which ends by itself within the bridge's horizon.
  ASSERT_TRUE(wait_until([&] { return server.stats().bounded_moves_ended > 0; }, 2000ms));
  EXPECT_EQ(server.stats().base_stops_on_disconnect, 0u);
  EXPECT_TRUE(robot.command_log().back().stop_move);
  // Client side: latched, move refused, frames report the loss.
  EXPECT_TRUE(bridge.needs_operator());
  try {
    bridge.move({0.1, 0.0, 0.0});
    FAIL();
  } catch (const nb::BridgeError& e) {
    EXPECT_NE(std::string(e.what()).find("operator"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)bridge.next_frame(100ms), nb::BridgeError);
  const auto records_before = robot.command_log().size();
  // Operator action 1: reconnect. Still latched: the base does not restart by itself.
  bridge.reconnect();
  EXPECT_EQ(bridge.state(), nb::ConnectionState::kConnected);
  EXPECT_TRUE(bridge.needs_operator());
  EXPECT_THROW(bridge.move({0.1, 0.0, 0.0}), nb::BridgeError);
  const auto since_loss = robot.command_log();
  for (std::size_t i = records_before; i < since_loss.size(); ++i) {
    EXPECT_TRUE(is_stop(since_loss[i]));  // nothing but stops since the loss
  }
  ASSERT_TRUE(bridge.next_frame(3000ms).has_value());  // camera re-subscribed
  // Operator action 2: clear the fault; moving works again.
  bridge.clear_fault();
  EXPECT_NO_THROW(bridge.move({0.1, 0.0, 0.0}));
  EXPECT_TRUE(wait_last_forward(robot, 0.1));
}

TEST(QiLoopback, WrongPasswordIsReportedAsSuch) {
  SyntheticPatternRobot robot;
  qi::MockServerOptions so;
  so.user = "nao";
  so.password = "s3cret";
  qi::MockNaoqiServer server(robot, so);
  server.start();
  auto o = bridge_options(server);
  o.user = "nao";
  o.password = "wrong";
  qi::QiBridge bad(o);
  try {
    bad.connect();
    FAIL();
  } catch (const qi::AuthenticationError& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("wrong user or password"), std::string::npos) << text;
    EXPECT_NE(text.find("Authentication failed"), std::string::npos) << text;
    EXPECT_EQ(text.find("wrong\""), std::string::npos);
    EXPECT_EQ(text.find("s3cret"), std::string::npos);
  }
  EXPECT_EQ(server.stats().auth_failures, 1u);
  auto anon = bridge_options(server);
  qi::QiBridge none(anon);
  try {
    none.connect();
    FAIL();
  } catch (const qi::AuthenticationError& e) {
    EXPECT_NE(std::string(e.what()).find("login required"), std::string::npos) << e.what();
  }
  o.password = "s3cret";
  qi::QiBridge good(o);
  EXPECT_NO_THROW(good.connect());
  EXPECT_EQ(good.describe().find("s3cret"), std::string::npos);
}

TEST(QiLoopback, TlsWithLoginWorks) {
  SyntheticPatternRobot robot;
  qi::MockServerOptions so;
  so.listen_url = "tcps://127.0.0.1:0";
  so.user = "nao";
  so.password = "pepper";
  qi::MockNaoqiServer server(robot, so);
  server.start();
  ASSERT_EQ(server.url().rfind("tcps://", 0), 0u);
  auto o = bridge_options(server);
  o.user = "nao";
  o.password = "pepper";
  o.tls_pin_sha256 = server.certificate_sha256();
  qi::QiBridge bridge(o);
  bridge.connect();
  EXPECT_EQ(bridge.tls_fingerprint(), server.certificate_sha256());
  EXPECT_EQ(bridge.tls_fingerprint().size(), 95u);  // 32 bytes "AB:" x 32 - 1
  bridge.start_camera({});
  const auto f = bridge.next_frame(3000ms);
  ASSERT_TRUE(f.has_value());
  EXPECT_TRUE(SyntheticPatternRobot::verify_frame(f->gray).has_value());
  bridge.move({0.1, 0.0, 0.0});
  EXPECT_TRUE(wait_last_forward(robot, 0.1));

  // A wrong pin is refused before any login.
  auto pinned = o;
  pinned.tls_pin_sha256 = std::string(64, 'A');
  qi::QiBridge wrong_pin(pinned);
  try {
    wrong_pin.connect();
    FAIL();
  } catch (const qi::TlsError& e) {
    EXPECT_NE(std::string(e.what()).find("does not match the pinned"), std::string::npos);
  }
}

TEST(QiLoopback, HeadLockHoldsAndReleaseRestoresAutonomy) {
  SyntheticPatternRobot robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  qi::QiBridge bridge(bridge_options(server));
  bridge.connect();
  nb::HeadLockRequest req;
  req.head_yaw_rad = 0.0;
  req.head_pitch_rad = -0.1;
  const auto status = bridge.lock_head(req);
  EXPECT_TRUE(status.holding);
  EXPECT_NEAR(status.head_pitch_rad, -0.1, 1e-6);
  EXPECT_EQ(server.autonomous_life_state(), "disabled");
  EXPECT_FALSE(server.basic_awareness_enabled());
  EXPECT_EQ(server.stiffness("HeadPitch"), 1.0);
  EXPECT_EQ(server.stiffness("KneePitch"), 1.0);
  EXPECT_TRUE(server.external_collision_protection());  // left on
  EXPECT_NEAR(robot.joint_angles({"HeadPitch"})[0], -0.1, 1e-6);
  bridge.release();
  EXPECT_EQ(server.autonomous_life_state(), "solitary");
  EXPECT_TRUE(server.basic_awareness_enabled());
}

TEST(QiLoopback, StaleSubscriptionsOfOursAreCleanedUp) {
  SyntheticPatternRobot robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  {
    // A crashed earlier run left three instances behind.
    qi::QiSession s;
    s.connect(server.url());
    const auto video = s.service("ALVideoDevice");
    for (int i = 0; i < 3; ++i) {
      s.call(video, "subscribeCamera", "(siiii)",
             {qi::Value::string("pepper_nav"), qi::Value::int32(0), qi::Value::int32(2),
              qi::Value::int32(0), qi::Value::int32(15)});
    }
    s.call(video, "subscribeCamera", "(siiii)",
           {qi::Value::string("other_app"), qi::Value::int32(0), qi::Value::int32(1),
            qi::Value::int32(0), qi::Value::int32(15)});
  }
  ASSERT_EQ(server.video_subscribers().size(), 4u);
  qi::QiBridge bridge(bridge_options(server));
  bridge.connect();
  bridge.start_camera({});
  const auto subs = server.video_subscribers();
  EXPECT_EQ(subs, (std::vector<std::string>{"other_app_0", "pepper_nav_0"}));
}

TEST(QiLoopback, MalformedReplyClosesTheConnectionWithATypedError) {
  SyntheticPatternRobot robot;
  qi::MockServerOptions so;
  so.malformed_reply_every_nth = 1;  // every non-empty reply after authentication
  qi::MockNaoqiServer server(robot, so);
  server.start();
  qi::QiSession session;
  session.connect(server.url());
  try {
    (void)session.service("ALMotion");
    FAIL();
  } catch (const qi::ProtocolViolation& e) {
    EXPECT_NE(std::string(e.what()).find("malformed"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(session.is_connected());
}

TEST(QiLoopback, ServerSurvivesGarbageAndKeepsServingOthers) {
  SyntheticPatternRobot robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  boost::asio::io_context io;
  boost::asio::ip::tcp::socket sock(io);
  sock.connect({boost::asio::ip::make_address("127.0.0.1"), server.port()});
  const std::uint8_t garbage[28] = {0x13, 0x37};
  boost::asio::write(sock, boost::asio::buffer(garbage));
  std::uint8_t buf[16];
  boost::system::error_code ec;
  boost::asio::read(sock, boost::asio::buffer(buf), ec);
  EXPECT_EQ(ec, boost::asio::error::eof);  // dropped at once, as libqi does on a bad magic
  qi::QiSession session;
  session.connect(server.url());
  EXPECT_EQ(session.service("ALRobotPosture").meta.find("goToPosture", "(sf)")->uid, 114u);
}

TEST(QiLoopback, ConnectErrorsNameTheCause) {
  // A port with nothing listening: bind one, close it, connect there.
  boost::asio::io_context io;
  boost::asio::ip::tcp::acceptor a(io, {boost::asio::ip::make_address("127.0.0.1"), 0});
  const auto port = a.local_endpoint().port();
  a.close();
  qi::QiSession session;
  try {
    session.connect("tcp://127.0.0.1:" + std::to_string(port));
    FAIL();
  } catch (const qi::ConnectError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot reach tcp://127.0.0.1:" + std::to_string(port)),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(qi::parse_url("http://x"), nb::BridgeError);
  EXPECT_EQ(qi::parse_url("tcps://pepper.local").port, 9503);
  EXPECT_EQ(qi::parse_url("tcp://[::1]:1234").host, "::1");
}

TEST(QiLoopback, Regression_ImageRequestForAnUnsubscribedHandleIsAnErrorNotAHang) {
  // An image request in flight while the subscriber is removed (release() does this) once
  // deadlocked the server's I/O thread; with paced frames the request is answered later.
  SyntheticPatternRobot robot;
  qi::MockServerOptions so;
  so.pace_frames = true;
  qi::MockNaoqiServer server(robot, so);
  server.start();
  qi::QiSession s;
  s.connect(server.url());
  const auto video = s.service("ALVideoDevice");
  const std::string handle = s.call(video, "subscribeCamera", "(siiii)",
                                    {qi::Value::string("t"), qi::Value::int32(0),
                                     qi::Value::int32(1), qi::Value::int32(0), qi::Value::int32(5)})
                                 .as_string();
  (void)s.call_async(video, "getImageRemote", "(s)", {qi::Value::string(handle)}).get();
  // The next one is paced 200 ms later (5 fps); unsubscribe meanwhile.
  auto pending = s.call_async(video, "getImageRemote", "(s)", {qi::Value::string(handle)});
  s.call(video, "unsubscribe", "(s)", {qi::Value::string(handle)});
  try {
    (void)pending.get(std::chrono::milliseconds(3000));
    FAIL();
  } catch (const qi::RemoteCallError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown subscriber"), std::string::npos) << e.what();
  }
  EXPECT_EQ(s.call(video, "unsubscribe", "(s)", {qi::Value::string(handle)}).as_bool(), false);
  EXPECT_EQ(server.stats().connections_open, 1u);
}

TEST(QiLoopback, UnsolicitedCapabilityMessageIsMerged) {
  SyntheticPatternRobot robot;
  qi::MockServerOptions so;
  so.announce_capabilities = true;
  qi::MockNaoqiServer server(robot, so);
  server.start();
  qi::QiSession session;
  session.connect(server.url());
  (void)session.service("ALMotion");  // a round trip after the Capability message
  const auto caps = session.server_capabilities();
  ASSERT_TRUE(caps.count("MockAnnounced"));
  EXPECT_TRUE(caps.at("MockAnnounced").as_bool());
  EXPECT_TRUE(caps.count("MetaObjectCache"));  // from the authenticate reply
}

TEST(QiLoopback, RepliesWithDynamicPayloadFlagAreAccepted) {
  SyntheticPatternRobot robot;
  qi::MockServerOptions so;
  so.dynamic_replies = true;  // every method reply is one `m` with flag 0x01
  qi::MockNaoqiServer server(robot, so);
  server.start();
  qi::QiSession session;
  session.connect(server.url());
  const auto life = session.service("ALAutonomousLife");  // metaObject came as a dynamic too
  EXPECT_EQ(session.call(life, "getState", "()", {}).as_string(), "solitary");
  const auto motion = session.service("ALMotion");
  const qi::Value a =
      session.call(motion, "getAngles", "(mb)",
                   {qi::Value::strings({"HeadYaw", "KneePitch"}), qi::Value::boolean(true)});
  EXPECT_EQ(a.signature(), "[f]");
  EXPECT_EQ(a.elements().size(), 2u);
  EXPECT_NO_THROW(session.call(motion, "stopMove", "()", {}));
}

// ---- Robot-side deadman (issue 23) ------------------------------------------------------------

namespace {

/// A second client, as an observer of the robot: what ALMotion reports as the base velocity.
std::vector<double> robot_velocity(qi::QiSession& s, const qi::ServiceHandle& motion) {
  std::vector<double> out;
  const qi::Value v = s.call(motion, "getRobotVelocity", "()", {});
  for (const auto& e : v.elements()) out.push_back(e.as_double());
  return out;
}

bool velocity_is_zero(const std::vector<double>& v) {
  return v.size() == 3 && v[0] == 0.0 && v[1] == 0.0 && v[2] == 0.0;
}

}  // namespace

TEST(QiLoopback, EachMoveEndsByItselfOnTheRobotAfterTheHorizon) {
  SyntheticPatternRobot robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  auto o = bridge_options(server);
  // A horizon well above the 50 ms command period, so a loaded machine's late wake-ups do not
  // open gaps; the app's own default is 250 ms at 66 ms per frame.
  o.deadman_horizon = 500ms;
  o.watchdog_timeout = 5000ms;  // keep the laptop-side watchdog out of the way
  qi::QiBridge bridge(o);
  bridge.connect();
  ASSERT_TRUE(bridge.robot_side_deadman()) << bridge.robot_side_deadman_summary();
  qi::QiSession observer;
  observer.connect(server.url());
  const auto motion = observer.service("ALMotion");

  // Commands closer together than the horizon: the base drives without a gap.
  for (int i = 0; i < 8; ++i) {
    bridge.move({0.15, 0.0, 0.3});
    std::this_thread::sleep_for(50ms);
    const auto v = robot_velocity(observer, motion);
    ASSERT_EQ(v.size(), 3u);
    EXPECT_NEAR(v[0], 0.15, 1e-4);
    EXPECT_NEAR(v[1], 0.0, 1e-4);
    EXPECT_NEAR(v[2], 0.3, 1e-4);
    EXPECT_TRUE(observer.call(motion, "moveIsActive", "()", {}).as_bool());
  }
  EXPECT_EQ(server.stats().bounded_moves_ended, 0u);
  for (const auto& r : robot.command_log()) EXPECT_FALSE(r.stop_move);

  // Then silence after one last command: the robot stops by itself at the horizon.
  bridge.move({0.15, 0.0, 0.3});
  const auto last = std::chrono::steady_clock::now();
  ASSERT_TRUE(wait_until([&] { return velocity_is_zero(robot_velocity(observer, motion)); },
                         3000ms));
  const auto stopped_after = std::chrono::steady_clock::now() - last;
  EXPECT_GE(stopped_after, 480ms);  // not before the horizon (it starts when the robot gets it)
  EXPECT_LT(stopped_after, 2000ms);
  EXPECT_EQ(server.stats().bounded_moves_ended, 1u);
  EXPECT_TRUE(robot.command_log().back().stop_move);
  EXPECT_FALSE(observer.call(motion, "moveIsActive", "()", {}).as_bool());
  EXPECT_EQ(bridge.counters().bounded_move_errors, 0u) << bridge.last_move_error();
}

TEST(QiLoopback, PlainMoveKeepsDrivingAfterTheClientLeavesAsOnARealNaoqi) {
  SyntheticPatternRobot robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  {
    auto o = bridge_options(server);
    o.deadman_horizon = 0ms;  // plain ALMotion.move
    o.watchdog_timeout = 5000ms;
    qi::QiBridge bridge(o);
    bridge.connect();
    EXPECT_FALSE(bridge.robot_side_deadman());
    EXPECT_NE(bridge.robot_side_deadman_summary().find("leaves the base driving"),
              std::string::npos);
    bridge.move({0.15, 0.0, 0.0});
    server.disconnect_all();
    ASSERT_TRUE(wait_until([&] { return bridge.state() == nb::ConnectionState::kLost; }, 3000ms));
  }
  std::this_thread::sleep_for(300ms);
  qi::QiSession observer;
  observer.connect(server.url());
  const auto motion = observer.service("ALMotion");
  const auto v = robot_velocity(observer, motion);
  ASSERT_EQ(v.size(), 3u);
  EXPECT_NEAR(v[0], 0.15, 1e-6);  // the hazard the deadman exists for
  EXPECT_EQ(server.stats().base_stops_on_disconnect, 0u);
  observer.call(motion, "stopMove", "()", {});
  EXPECT_TRUE(velocity_is_zero(robot_velocity(observer, motion)));
}

TEST(QiLoopback, NonFiniteVelocitiesAreRefusedByTheRobot) {
  SyntheticPatternRobot robot;
  qi::MockNaoqiServer server(robot);
  server.start();
  qi::QiSession s;
  s.connect(server.url());
  const auto motion = s.service("ALMotion");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_THROW(s.call(motion, "move", "(fff)",
                      {qi::Value::float32(nan), qi::Value::float32(0.f), qi::Value::float32(0.f)}),
               qi::RemoteCallError);
  EXPECT_THROW(s.call(motion, "moveTo", "(ffff)",
                      {qi::Value::float32(0.f), qi::Value::float32(inf), qi::Value::float32(0.f),
                       qi::Value::float32(0.25f)}),
               qi::RemoteCallError);
  EXPECT_THROW(s.call(motion, "moveTo", "(ffff)",
                      {qi::Value::float32(0.f), qi::Value::float32(0.f), qi::Value::float32(0.f),
                       qi::Value::float32(0.f)}),
               qi::RemoteCallError);
  EXPECT_TRUE(robot.command_log().empty());
  EXPECT_TRUE(velocity_is_zero(robot_velocity(s, motion)));
}

TEST(QiLoopback, CallLogHasOneJsonLinePerCallAndNeverTheToken) {
  SyntheticPatternRobot robot;
  const std::string log = ::testing::TempDir() + "/qi_call_log_" + std::to_string(getpid()) + ".jsonl";
  std::remove(log.c_str());
  qi::MockServerOptions so;
  so.user = "nao";
  so.password = "s3cret-token";
  so.call_log_file = log;
  qi::MockNaoqiServer server(robot, so);
  server.start();
  qi::SessionOptions sopt;
  sopt.user = "nao";
  sopt.password = "s3cret-token";
  qi::QiSession s(sopt);
  s.connect(server.url());
  const auto motion = s.service("ALMotion");
  s.call(motion, "move", "(fff)",
         {qi::Value::float32(0.1f), qi::Value::float32(0.f), qi::Value::float32(0.5f)});
  s.call(motion, "moveTo", "(ffff)",
         {qi::Value::float32(0.f), qi::Value::float32(0.f), qi::Value::float32(0.f),
          qi::Value::float32(0.05f)});
  s.close();
  server.stop();
  std::ifstream in(log);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::string all;
  for (const auto& l : lines) all += l + "\n";
  EXPECT_EQ(all.find("s3cret-token"), std::string::npos) << all;
  ASSERT_GE(lines.size(), 6u) << all;  // authenticate, 2 lookups, 2 metaObjects... and the moves
  EXPECT_NE(lines.front().find("\"method\":\"authenticate\""), std::string::npos) << all;
  EXPECT_NE(lines.front().find("\"auth_user\":\"nao\""), std::string::npos) << all;
  EXPECT_NE(lines.front().find("<12 characters>"), std::string::npos) << all;
  EXPECT_NE(all.find("\"service\":\"ALMotion\",\"method\":\"move\",\"args\":[0.100000001,0,0.5]"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("moveTo reached its pose"), std::string::npos) << all;
  for (const auto& l : lines) EXPECT_EQ(l.rfind("{\"t_unix_s\":", 0), 0u) << l;
}

// ---- A mock that survives many and hostile connections (issue 23) -----------------------------

namespace {

std::size_t rss_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages_total = 0, pages_resident = 0;
  statm >> pages_total >> pages_resident;
  return pages_resident * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}

}  // namespace

TEST(QiLoopback, ManyConnectionsAndSlowClientsNeitherGrowMemoryNorStarveAGoodClient) {
  namespace asio = boost::asio;
  using tcp = asio::ip::tcp;
  SyntheticPatternRobot robot;
  qi::MockServerOptions so;
  so.handshake_timeout = 1500ms;
  so.max_connections = 64;
  qi::MockNaoqiServer server(robot, so);
  server.start();
  asio::io_context io;
  const tcp::endpoint ep(asio::ip::make_address("127.0.0.1"), server.port());
  // Connect and close; every 100th announces a 64 MiB message, sends 256 KiB of it and leaves
  // (the server used to keep such a buffer). Half close with RST to spare the port range.
  auto cycles = [&](int n) {
    std::vector<std::uint8_t> chunk(256 * 1024, 0x5a);
    for (int i = 0; i < n; ++i) {
      tcp::socket s(io);
      s.connect(ep);
      if (i % 100 == 0) {
        qi::MessageHeader h;
        h.id = 1;
        h.type = qi::MessageType::kCall;
        h.service = 1;
        h.object = 1;
        h.action = 100;
        h.size = 64u << 20;
        const auto bytes = qi::encode_header(h);
        asio::write(s, asio::buffer(bytes));
        asio::write(s, asio::buffer(chunk));
      }
      if (i % 2 == 0) s.set_option(asio::socket_base::linger(true, 0));
      s.close();
    }
    ASSERT_TRUE(wait_until([&] { return server.stats().connections_open == 0; }, 10000ms));
  };
  cycles(500);  // warm-up: allocator pools, first big buffers
  const std::size_t before = rss_bytes();
  cycles(10000);
  const std::size_t after = rss_bytes();
  std::cout << "[measured] RSS growth over 10000 connect/close cycles: "
            << (static_cast<double>(after) - static_cast<double>(before)) / 1e6 << " MB\n";
  EXPECT_LT(static_cast<double>(after) - static_cast<double>(before), 5e6);
  // Connections reset before accept() took them are never accepted: at least the graceful half.
  EXPECT_GE(server.stats().connections_accepted, 5250u);

  // 50 slow clients: half a header each, then nothing.
  std::vector<tcp::socket> slow;
  for (int i = 0; i < 50; ++i) {
    slow.emplace_back(io);
    slow.back().connect(ep);
    const std::uint8_t partial[10] = {0x42, 0xde, 0xad, 0x42, 1, 0, 0, 0, 0, 0};
    asio::write(slow.back(), asio::buffer(partial));
  }
  ASSERT_TRUE(wait_until([&] { return server.stats().connections_open >= 50; }, 3000ms));
  // A well-behaved client is served at once, beside them.
  qi::QiSession good;
  good.connect(server.url());
  const auto motion = good.service("ALMotion");
  EXPECT_TRUE(velocity_is_zero(robot_velocity(good, motion)));
  // Beyond the limit, connections are refused on accept (the accept loop keeps going).
  std::vector<tcp::socket> extra;
  for (int i = 0; i < 20; ++i) {
    extra.emplace_back(io);
    extra.back().connect(ep);
  }
  ASSERT_TRUE(wait_until([&] { return server.stats().connections_refused >= 7; }, 3000ms))
      << server.stats().connections_refused;
  // The silent ones are closed by the handshake timeout; the good client keeps being served.
  ASSERT_TRUE(wait_until([&] { return server.stats().connections_timed_out >= 63; }, 8000ms))
      << server.stats().connections_timed_out;
  for (auto& s : slow) {
    std::uint8_t b = 0;
    boost::system::error_code ec;
    s.read_some(asio::buffer(&b, 1), ec);
    EXPECT_TRUE(ec == asio::error::eof || ec == asio::error::connection_reset) << ec.message();
  }
  good.call(motion, "stopMove", "()", {});
  EXPECT_TRUE(velocity_is_zero(robot_velocity(good, motion)));
}
