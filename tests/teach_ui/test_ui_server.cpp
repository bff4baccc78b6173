// UiServer over real loopback sockets with Beast clients: static files, WebSocket publishing,
// intents, dead-man on disconnect, malformed and oversized messages, slow clients, origins.
#include <gtest/gtest.h>

#include <fstream>
#include <mutex>

#include "teach_ui/ui_server.hpp"
#include "teach_ui/ui_test_client.hpp"
#include "teach_ui/wire.hpp"

namespace pepper::teach_ui {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using testing::http_request;
using testing::WsClient;
using testing::WsMessage;

// Generous: these bound how long a test waits for something that must happen, they are not
// timing assertions (a broken server fails by timing out, a working one answers in milliseconds).
constexpr auto kWait = 5s;
// Used only where nothing must arrive.
constexpr auto kQuiet = 300ms;

nlohmann::json text_json(const WsMessage& m) { return nlohmann::json::parse(m.data); }

bool is_type(const WsMessage& m, const char* type) {
  return !m.binary && text_json(m).value("type", "") == type;
}

class UiServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = fs::temp_directory_path() /
            ("pepper_ui_server_" +
             std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(base_);
    fs::create_directories(base_ / "web");
    std::ofstream(base_ / "web" / "index.html") << "<!doctype html><title>teach</title>";
    std::ofstream(base_ / "web" / "app.js") << "console.log(1);";
    std::ofstream(base_ / "secret.txt") << "TOP-SECRET";
    options_.web_root = (base_ / "web").string();
    options_.log = [this](UiLogLevel, std::string_view text) {
      std::lock_guard<std::mutex> lock(log_mutex_);
      log_.emplace_back(text);
    };
  }
  void TearDown() override {
    server_.reset();
    fs::remove_all(base_);
  }

  UiServer& start() {
    server_ = std::make_unique<UiServer>(options_);
    server_->start();
    return *server_;
  }

  bool logged(const std::string& needle) {
    std::lock_guard<std::mutex> lock(log_mutex_);
    for (const auto& l : log_) {
      if (l.find(needle) != std::string::npos) return true;
    }
    return false;
  }

  /// Connects and consumes the greeting so later reads see only what the test causes.
  std::unique_ptr<WsClient> connect() {
    auto c = std::make_unique<WsClient>(server_->port());
    auto hello = c->read(kWait);
    EXPECT_TRUE(hello && is_type(*hello, "hello"));
    return c;
  }

  std::optional<Intent> wait_intent() {
    return server_->next_intent(std::chrono::duration_cast<std::chrono::milliseconds>(kWait));
  }

  fs::path base_;
  UiOptions options_;
  std::unique_ptr<UiServer> server_;
  std::mutex log_mutex_;
  std::vector<std::string> log_;
};

TEST_F(UiServerTest, StartReportsEphemeralPortAndLoopbackUrl) {
  UiServer& s = start();
  EXPECT_TRUE(s.running());
  EXPECT_NE(s.port(), 0);
  EXPECT_EQ(s.url(), "http://127.0.0.1:" + std::to_string(s.port()) + "/");
  s.stop();
  EXPECT_FALSE(s.running());
  s.stop();  // idempotent
}

TEST_F(UiServerTest, ServesStaticPageWithContentType) {
  start();
  const auto index = http_request(server_->port(), "/");
  EXPECT_EQ(index.status, 200);
  EXPECT_EQ(index.content_type, "text/html; charset=utf-8");
  EXPECT_NE(index.body.find("<title>teach</title>"), std::string::npos);
  const auto js = http_request(server_->port(), "/app.js");
  EXPECT_EQ(js.status, 200);
  EXPECT_EQ(js.content_type, "text/javascript; charset=utf-8");
  const auto head = http_request(server_->port(), "/app.js", testing::http::verb::head);
  EXPECT_EQ(head.status, 200);
  EXPECT_TRUE(head.body.empty());
}

TEST_F(UiServerTest, MissingFileIs404AndOtherMethodsAre405) {
  start();
  EXPECT_EQ(http_request(server_->port(), "/nope.html").status, 404);
  EXPECT_EQ(http_request(server_->port(), "/index.html", testing::http::verb::post).status, 405);
  EXPECT_EQ(http_request(server_->port(), "/index.html", testing::http::verb::delete_).status, 405);
}

TEST_F(UiServerTest, PathTraversalIsRefused) {
  start();
  for (const char* target : {"/../secret.txt", "/%2e%2e/secret.txt", "/..%2fsecret.txt",
                             "/x/../../secret.txt", "/..%5csecret.txt"}) {
    SCOPED_TRACE(target);
    const auto r = http_request(server_->port(), target);
    EXPECT_EQ(r.status, 400);
    EXPECT_EQ(r.body.find("TOP-SECRET"), std::string::npos);
  }
  EXPECT_TRUE(logged("refused request target"));
}

TEST_F(UiServerTest, DefaultWebRootServesTheShippedPage) {
  options_.web_root.clear();
  start();
  const auto index = http_request(server_->port(), "/");
  EXPECT_EQ(index.status, 200);
  EXPECT_NE(index.body.find("Pepper"), std::string::npos);
}

TEST_F(UiServerTest, WebSocketReceivesPublishedStateFrameAndImage) {
  options_.limits.max_v_m_s = 0.25;
  start();
  WsClient client(server_->port());
  const auto hello = client.read(kWait);
  ASSERT_TRUE(hello);
  ASSERT_TRUE(is_type(*hello, "hello"));
  EXPECT_DOUBLE_EQ(text_json(*hello)["limits"]["max_v_m_s"].get<double>(), 0.25);

  server_->publish_state({{"mode", "teach"}, {"recording", true}});
  const auto state = client.read_until([](const WsMessage& m) { return is_type(m, "state"); });
  ASSERT_TRUE(state);
  EXPECT_EQ(text_json(*state)["state"]["mode"], "teach");
  EXPECT_EQ(text_json(*state)["state"]["recording"], true);

  const std::string jpeg(
      "\xff\xd8\xff\xe0"
      "fake-jpeg"
      "\xff\xd9",
      15);
  server_->publish_frame(jpeg, {{"width_px", 320}, {"height_px", 240}});
  const auto frame = client.read_until([](const WsMessage& m) { return m.binary; });
  ASSERT_TRUE(frame);
  const auto view = decode_binary_message(frame->data);
  ASSERT_TRUE(view);
  EXPECT_EQ(view->kind, kBinaryFrame);
  EXPECT_EQ(view->payload, jpeg);
  const auto header = nlohmann::json::parse(view->header_json);
  EXPECT_EQ(header["seq"], 1);
  EXPECT_EQ(header["overlay"]["width_px"], 320);

  server_->publish_image("key/0", std::vector<std::uint8_t>{'P', 'N', 'G', 'D', 'A', 'T', 'A'});
  const auto image = client.read_until([](const WsMessage& m) { return m.binary; });
  ASSERT_TRUE(image);
  const auto iview = decode_binary_message(image->data);
  ASSERT_TRUE(iview);
  EXPECT_EQ(iview->kind, kBinaryImage);
  EXPECT_EQ(nlohmann::json::parse(iview->header_json)["name"], "key/0");
  EXPECT_EQ(iview->payload, "PNGDATA");

  server_->publish_samples({{"t_s", 0.1}, {"v_m_s", 0.2}});
  const auto samples = client.read_until([](const WsMessage& m) { return is_type(m, "samples"); });
  ASSERT_TRUE(samples);
  ASSERT_EQ(text_json(*samples)["samples"].size(), 1u);
  EXPECT_DOUBLE_EQ(text_json(*samples)["samples"][0]["v_m_s"].get<double>(), 0.2);
}

TEST_F(UiServerTest, LateClientGetsSnapshotOfStateImagesSamplesAndLatestFrame) {
  start();
  server_->publish_state({{"mode", "teach"}, {"recording", false}});
  server_->publish_state({{"recording", true}});  // replaces only this key
  server_->publish_image("key/0", "K0");
  server_->publish_image("key/1", "K1");
  server_->publish_image("key/1", "");  // removed
  server_->publish_samples(nlohmann::json::array({{{"t_s", 0.0}}, {{"t_s", 0.1}}}));
  server_->publish_frame("F1", nlohmann::json::object());
  server_->publish_frame("F2", nlohmann::json::object());
  // Wait until the I/O thread has applied them: a first client sees the latest frame.
  {
    WsClient first(server_->port());
    ASSERT_TRUE(first.read_until([](const WsMessage& m) {
      const auto v = decode_binary_message(m.data);
      return m.binary && v && v->payload == "F2";
    }));
  }
  WsClient late(server_->port());
  nlohmann::json state;
  std::vector<std::string> images;
  std::size_t n_samples = 0;
  std::string frame;
  while (frame.empty()) {
    const auto m = late.read(kWait);
    ASSERT_TRUE(m) << "snapshot incomplete";
    if (m->binary) {
      const auto v = decode_binary_message(m->data);
      ASSERT_TRUE(v);
      if (v->kind == kBinaryFrame) frame = std::string(v->payload);
      if (v->kind == kBinaryImage) images.emplace_back(v->payload);
    } else if (is_type(*m, "state")) {
      state = text_json(*m)["state"];
    } else if (is_type(*m, "samples")) {
      n_samples += text_json(*m)["samples"].size();
    }
  }
  EXPECT_EQ(state["mode"], "teach");
  EXPECT_EQ(state["recording"], true);
  EXPECT_EQ(images, std::vector<std::string>{"K0"});
  EXPECT_EQ(n_samples, 2u);
  EXPECT_EQ(frame, "F2");
}

TEST_F(UiServerTest, IntentsArriveInOrderAndDrivesAreClamped) {
  options_.limits = {0.3, 0.9};
  start();
  auto client = connect();
  client->send_text(R"({"type":"start_recording"})");
  for (int i = 1; i <= 10; ++i) {
    client->send_text(
        nlohmann::json{{"type", "drive"}, {"v_m_s", 0.01 * i}, {"omega_rad_s", 0}}.dump());
  }
  client->send_text(R"({"type":"drive","v_m_s":2.0,"omega_rad_s":-2.0})");
  client->send_text(R"({"type":"drive_released","reason":"key_released"})");
  client->send_text(R"({"type":"stop_recording"})");
  client->send_text(R"({"type":"finish_teach"})");
  client->send_text(R"({"type":"start_replay"})");
  client->send_text(R"({"type":"estop","reason":"button"})");

  auto next = [&] {
    auto i = wait_intent();
    EXPECT_TRUE(i);
    return i.value_or(Intent{});
  };
  EXPECT_EQ(next().kind, IntentKind::kStartRecording);
  for (int i = 1; i <= 10; ++i) {
    const Intent d = next();
    EXPECT_EQ(d.kind, IntentKind::kDrive);
    EXPECT_DOUBLE_EQ(d.v_m_s, 0.01 * i);
  }
  const Intent clamped = next();
  EXPECT_DOUBLE_EQ(clamped.v_m_s, 0.3);
  EXPECT_DOUBLE_EQ(clamped.omega_rad_s, -0.9);
  const Intent released = next();
  EXPECT_EQ(released.kind, IntentKind::kDriveReleased);
  EXPECT_EQ(released.reason, "key_released");
  EXPECT_EQ(released.source, IntentSource::kClient);
  EXPECT_EQ(next().kind, IntentKind::kStopRecording);
  EXPECT_EQ(next().kind, IntentKind::kFinishTeach);
  EXPECT_EQ(next().kind, IntentKind::kStartReplay);
  const Intent estop = next();
  EXPECT_EQ(estop.kind, IntentKind::kEmergencyStop);
  EXPECT_EQ(estop.reason, "button");
  EXPECT_FALSE(server_->next_intent(kQuiet));
  EXPECT_EQ(server_->stats().intents_received, 17u);
}

TEST_F(UiServerTest, DisconnectWhileDrivingQueuesServerStop) {
  start();
  auto client = connect();
  client->send_text(R"({"type":"drive","v_m_s":0.2,"omega_rad_s":0.1})");
  const auto drive = wait_intent();
  ASSERT_TRUE(drive);
  EXPECT_EQ(drive->kind, IntentKind::kDrive);
  client->drop();  // tab killed: no close frame, no release message
  const auto stop = wait_intent();
  ASSERT_TRUE(stop);
  EXPECT_EQ(stop->kind, IntentKind::kDriveReleased);
  EXPECT_EQ(stop->source, IntentSource::kServer);
  EXPECT_EQ(stop->reason, "client_disconnected");
  EXPECT_EQ(stop->client_id, drive->client_id);
}

TEST_F(UiServerTest, PoliteCloseWhileDrivingAlsoQueuesServerStop) {
  start();
  auto client = connect();
  client->send_text(R"({"type":"drive","v_m_s":0.0,"omega_rad_s":0.4})");
  ASSERT_TRUE(wait_intent());
  client->close();
  const auto stop = wait_intent();
  ASSERT_TRUE(stop);
  EXPECT_EQ(stop->kind, IntentKind::kDriveReleased);
  EXPECT_EQ(stop->reason, "client_disconnected");
}

TEST_F(UiServerTest, DisconnectAfterReleaseQueuesNothing) {
  start();
  auto client = connect();
  client->send_text(R"({"type":"drive","v_m_s":0.2,"omega_rad_s":0})");
  client->send_text(R"({"type":"drive_released"})");
  ASSERT_TRUE(wait_intent());
  ASSERT_TRUE(wait_intent());
  client->drop();
  EXPECT_FALSE(server_->next_intent(kQuiet));
}

TEST_F(UiServerTest, DriveNotRefreshedTimesOutIntoServerStop) {
  options_.drive_timeout_s = 0.25;  // the smallest allowed
  start();
  auto client = connect();
  client->send_text(R"({"type":"drive","v_m_s":0.1,"omega_rad_s":0})");
  ASSERT_TRUE(wait_intent());
  const auto stop = wait_intent();  // the client stays connected but silent
  ASSERT_TRUE(stop);
  EXPECT_EQ(stop->kind, IntentKind::kDriveReleased);
  EXPECT_EQ(stop->source, IntentSource::kServer);
  EXPECT_EQ(stop->reason, "drive_timeout");
}

TEST_F(UiServerTest, MalformedMessagesAreIgnoredAndLogged) {
  start();
  auto client = connect();
  client->send_text("not json");
  client->send_text(R"({"type":"fly"})");
  client->send_text(R"({"type":"drive","v_m_s":"fast","omega_rad_s":0})");
  client->send_binary(std::string("\x00\x01\x02", 3));
  client->send_text(R"({"type":"estop"})");
  const auto intent = wait_intent();
  ASSERT_TRUE(intent);
  EXPECT_EQ(intent->kind, IntentKind::kEmergencyStop);  // the only valid one, connection alive
  EXPECT_EQ(server_->stats().malformed_messages, 4u);
  EXPECT_TRUE(logged("ignored malformed message"));
  // Still served: a ping is answered.
  client->send_text(R"({"type":"ping","t_ms":12.5})");
  const auto pong = client->read_until([](const WsMessage& m) { return is_type(m, "pong"); });
  ASSERT_TRUE(pong);
  EXPECT_DOUBLE_EQ(text_json(*pong)["t_ms"].get<double>(), 12.5);
}

TEST_F(UiServerTest, OversizedMessageClosesThatClientOnly) {
  options_.max_message_bytes = 1024;
  start();
  auto other = connect();
  auto client = connect();
  // The write itself may fail when the server closes before the whole message went out.
  (void)client->try_send_text(R"({"type":"drive","v_m_s":0.1,"omega_rad_s":0,"pad":")" +
                              std::string(4096, 'x') + "\"}");
  // The server closes the connection: the read ends without a message.
  EXPECT_FALSE(client->read_until([](const WsMessage&) { return false; }, kWait));
  EXPECT_TRUE(client->closed());
  EXPECT_FALSE(server_->next_intent(kQuiet));  // the oversized drive never became an intent
  other->send_text(R"({"type":"estop"})");
  const auto intent = wait_intent();
  ASSERT_TRUE(intent);
  EXPECT_EQ(intent->kind, IntentKind::kEmergencyStop);
}

TEST_F(UiServerTest, SlowClientDoesNotBlockPublishOrOtherClients) {
  start();
  // A client that never reads, with a tiny receive buffer: its connection fills up at once.
  WsClient slow(server_->port(), "", 4096);
  auto fast = connect();
  constexpr int kFrames = 60;
  const std::string big(256 * 1024, '\x55');  // 60 x 256 KiB = 15 MiB, far above socket buffers
  for (int i = 0; i < kFrames; ++i) server_->publish_frame(big, {{"i", i}});
  // publish_frame returned for every frame (never blocked); the reading client still gets the
  // newest one, and frames were dropped rather than queued for the slow one.
  const auto last = fast->read_until([&](const WsMessage& m) {
    const auto v = decode_binary_message(m.data);
    return m.binary && v && nlohmann::json::parse(v->header_json)["seq"] == kFrames;
  });
  ASSERT_TRUE(last);
  EXPECT_EQ(server_->stats().frames_published, static_cast<std::uint64_t>(kFrames));
  EXPECT_GT(server_->stats().frames_dropped, 0u);
  server_->publish_state({{"after", true}});
  EXPECT_TRUE(fast->read_until([](const WsMessage& m) { return is_type(m, "state"); }));
}

TEST_F(UiServerTest, ForeignOriginIsRefusedOwnOriginAccepted) {
  start();
  EXPECT_THROW(WsClient(server_->port(), "http://evil.example"), boost::system::system_error);
  WsClient own(server_->port(), "http://127.0.0.1:" + std::to_string(server_->port()));
  const auto hello = own.read(kWait);
  ASSERT_TRUE(hello);
  EXPECT_TRUE(is_type(*hello, "hello"));
}

TEST_F(UiServerTest, IntentHandlerReceivesIntentsInsteadOfQueue) {
  std::mutex m;
  std::condition_variable cv;
  std::vector<IntentKind> seen;
  start();  // handler must be set before start: check that it is refused after
  EXPECT_THROW(server_->set_intent_handler([](const Intent&) {}), std::logic_error);
  server_.reset();
  server_ = std::make_unique<UiServer>(options_);
  server_->set_intent_handler([&](const Intent& i) {
    std::lock_guard<std::mutex> lock(m);
    seen.push_back(i.kind);
    cv.notify_one();
  });
  server_->start();
  auto client = connect();
  client->send_text(R"({"type":"start_recording"})");
  client->send_text(R"({"type":"finish_teach"})");
  std::unique_lock<std::mutex> lock(m);
  ASSERT_TRUE(cv.wait_for(lock, kWait, [&] { return seen.size() == 2; }));
  EXPECT_EQ(seen[0], IntentKind::kStartRecording);
  EXPECT_EQ(seen[1], IntentKind::kFinishTeach);
  EXPECT_FALSE(server_->next_intent(1ms));
}

TEST_F(UiServerTest, StopWithDrivingClientQueuesStop) {
  start();
  auto client = connect();
  client->send_text(R"({"type":"drive","v_m_s":0.1,"omega_rad_s":0})");
  ASSERT_TRUE(wait_intent());
  server_->stop();
  const auto stop = server_->next_intent(1ms);  // queued before stop() returned
  ASSERT_TRUE(stop);
  EXPECT_EQ(stop->kind, IntentKind::kDriveReleased);
  EXPECT_EQ(server_->stats().clients, 0u);
}

TEST(UiOptionsTest, ValidateNamesBadFields) {
  UiOptions o;
  EXPECT_TRUE(o.validate().empty());
  o.bind_address = "localhost";  // a name, not a literal
  o.limits.max_v_m_s = -1;
  o.max_message_bytes = 10;
  o.drive_timeout_s = 99;
  const auto errors = o.validate();
  ASSERT_EQ(errors.size(), 4u);
  EXPECT_NE(errors[0].find("bind_address"), std::string::npos);
  EXPECT_NE(errors[1].find("limits.max_v_m_s"), std::string::npos);
  EXPECT_NE(errors[2].find("max_message_bytes"), std::string::npos);
  EXPECT_NE(errors[3].find("drive_timeout_s"), std::string::npos);
  UiServer server(o);
  EXPECT_THROW(server.start(), UiServerError);
}

TEST(UiOptionsTest, MissingWebRootThrowsAtStart) {
  UiOptions o;
  o.web_root = "/nonexistent/pepper/web";
  UiServer server(o);
  EXPECT_THROW(server.start(), UiServerError);
  EXPECT_FALSE(server.running());
}

TEST(UiOptionsTest, PublishStateRejectsNonObjects) {
  UiServer server(UiOptions{});
  EXPECT_THROW(server.publish_state(nlohmann::json::array()), std::invalid_argument);
  EXPECT_THROW(server.publish_samples(42), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::teach_ui
