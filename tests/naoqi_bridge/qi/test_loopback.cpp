// QiBridge / QiSession against MockNaoqiServer over loopback (ephemeral ports): frames, moves,
// watchdog, disconnects, login, TLS, malformed replies. Every byte crosses the real wire format.
#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>
#include <chrono>
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
  auto log = robot.command_log();
  ASSERT_FALSE(log.empty());
  EXPECT_FLOAT_EQ(static_cast<float>(log.back().velocity.v_x_m_s), 0.2f);
  EXPECT_FLOAT_EQ(static_cast<float>(log.back().velocity.omega_rad_s), -0.15f);
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
  server.disconnect_all();
  ASSERT_TRUE(wait_until([&] { return bridge.state() == nb::ConnectionState::kLost; }, 3000ms));
  // Server side: the mock stops the base when the commanding connection drops.
  ASSERT_TRUE(wait_until([&] { return server.stats().base_stops_on_disconnect > 0; }, 2000ms));
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
  EXPECT_FLOAT_EQ(static_cast<float>(robot.command_log().back().velocity.v_x_m_s), 0.1f);
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
  EXPECT_FLOAT_EQ(static_cast<float>(robot.command_log().back().velocity.v_x_m_s), 0.1f);

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
