// ui_fake_session: runs a UiServer with a synthetic session, for the browser test and for
// working on the page without a robot. Not part of the app.
//
// It publishes a moving synthetic camera image (grayscale PNG encoded here, no OpenCV) with an
// overlay of lines and points, the state a teach or replay session would publish, key image
// thumbnails and plot samples, and reacts to intents the way the app would (recording, finish,
// replay, emergency stop; drive intents turn and move the synthetic view).
//
// Standard output, one JSON object per line (flushed):
//   {"event":"listening","url":"http://127.0.0.1:PORT/","port":PORT}
//   {"event":"intent","kind":"drive","v_m_s":0.15,"omega_rad_s":0,"source":"client",...}
//   {"event":"log","level":"warning","text":"..."}
//   {"event":"stopped"}
// Options: --port N (0), --web-root DIR (the source tree's teach_ui/web), --fps HZ (15),
//   --scenario teach|replay|offline (teach: empty teach session; replay/offline: a finished
//   tour with progress, plots and trajectories), --exit-on-stdin-eof (stop when stdin closes,
//   so a test harness that dies takes this process with it), --duration-s S (0 = until SIGINT,
//   SIGTERM or stdin EOF).
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "teach_ui/ui_server.hpp"
#include "teach_ui/web_root.hpp"

namespace {

using pepper::teach_ui::Intent;
using pepper::teach_ui::IntentKind;
using pepper::teach_ui::UiLogLevel;
using pepper::teach_ui::UiOptions;
using pepper::teach_ui::UiServer;
using json = nlohmann::json;

std::atomic<bool> g_quit{false};
void on_signal(int) { g_quit = true; }

std::mutex g_out_mutex;
void emit(const json& line) {
  std::lock_guard<std::mutex> lock(g_out_mutex);
  std::cout << line.dump(-1, ' ', false, json::error_handler_t::replace) << '\n' << std::flush;
}

// ------------------------------------------------------------------ minimal PNG (stored deflate)
std::uint32_t crc32(const std::uint8_t* data, std::size_t n, std::uint32_t crc = 0) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (std::size_t i = 0; i < n; ++i) crc = table[(crc ^ data[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

void put_u32_be(std::string& out, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<char>((v >> s) & 0xFFu));
}

void put_chunk(std::string& out, const char* type, const std::string& data) {
  put_u32_be(out, static_cast<std::uint32_t>(data.size()));
  std::string body(type, 4);
  body += data;
  out += body;
  put_u32_be(out, crc32(reinterpret_cast<const std::uint8_t*>(body.data()), body.size()));
}

/// 8-bit grayscale PNG, uncompressed deflate blocks: simple, valid, and fast to produce.
std::string encode_png_gray(const std::vector<std::uint8_t>& pixels, int width, int height) {
  std::string raw;
  raw.reserve(static_cast<std::size_t>(height) * (width + 1));
  for (int y = 0; y < height; ++y) {
    raw.push_back(0);  // filter: none
    raw.append(reinterpret_cast<const char*>(&pixels[static_cast<std::size_t>(y) * width]),
               static_cast<std::size_t>(width));
  }
  std::string z = {'\x78', '\x01'};
  std::size_t pos = 0;
  do {
    const std::size_t n = std::min<std::size_t>(65535, raw.size() - pos);
    const bool last = pos + n == raw.size();
    z.push_back(last ? 1 : 0);
    z.push_back(static_cast<char>(n & 0xFF));
    z.push_back(static_cast<char>(n >> 8));
    z.push_back(static_cast<char>(~n & 0xFF));
    z.push_back(static_cast<char>((~n >> 8) & 0xFF));
    z.append(raw, pos, n);
    pos += n;
  } while (pos < raw.size());
  std::uint32_t a = 1, b = 0;
  for (unsigned char c : raw) {
    a = (a + c) % 65521u;
    b = (b + a) % 65521u;
  }
  put_u32_be(z, (b << 16) | a);
  std::string ihdr;
  put_u32_be(ihdr, static_cast<std::uint32_t>(width));
  put_u32_be(ihdr, static_cast<std::uint32_t>(height));
  ihdr += std::string{'\x08', '\x00', '\x00', '\x00', '\x00'};  // 8 bit, gray, deflate, none, none
  std::string png = "\x89PNG\r\n\x1a\n";
  put_chunk(png, "IHDR", ihdr);
  put_chunk(png, "IDAT", z);
  put_chunk(png, "IEND", "");
  return png;
}

// ------------------------------------------------------------------ synthetic scene
struct Scene {
  static constexpr int kW = 320;
  static constexpr int kH = 240;
  static constexpr double kFocalPx = 150.0;  // about Pepper's QVGA focal length / 2

  /// Renders a corridor of vertical posts seen from heading `yaw_rad` and forward position
  /// `x_m`; returns pixels and fills the overlay (post edges as lines, post tops as points).
  std::vector<std::uint8_t> render(double yaw_rad, double x_m, json& overlay) const {
    std::vector<std::uint8_t> px(static_cast<std::size_t>(kW) * kH);
    for (int v = 0; v < kH; ++v) {
      const std::uint8_t base = v < kH / 2 ? 190 : 90;  // wall above, floor below
      for (int u = 0; u < kW; ++u) {
        const bool tile = v >= kH / 2 && ((static_cast<int>(u / 20 + x_m * 8) + v / 12) % 2 == 0);
        px[static_cast<std::size_t>(v) * kW + u] =
            static_cast<std::uint8_t>(base + (tile ? 25 : 0));
      }
    }
    json segments = json::array();
    json corners = json::array();
    for (int k = 0; k < 24; ++k) {
      const double bearing = k * (2 * M_PI / 24) - yaw_rad;  // posts all around the robot
      const double b = std::remainder(bearing, 2 * M_PI);
      if (std::abs(b) > 0.9) continue;
      const double dist_m = 2.0 + 0.8 * std::sin(k * 1.7) - 0.3 * std::fmod(x_m, 1.0);
      const int uc = static_cast<int>(kW / 2 - kFocalPx * std::tan(b));
      const int half_w = static_cast<int>(60.0 / dist_m);
      const int top = static_cast<int>(kH / 2 - 200.0 / dist_m);
      const int bottom = static_cast<int>(kH / 2 + 90.0 / dist_m);
      for (int v = std::max(0, top); v < std::min(kH, bottom); ++v) {
        for (int u = std::max(0, uc - half_w); u < std::min(kW, uc + half_w); ++u) {
          px[static_cast<std::size_t>(v) * kW + u] = static_cast<std::uint8_t>(30 + 7 * (k % 5));
        }
      }
      for (const int u : {uc - half_w, uc + half_w}) {
        if (u >= 0 && u < kW)
          segments.push_back({u, std::max(0, top), u, std::min(kH - 1, bottom)});
      }
      if (top >= 0) {
        corners.push_back({uc - half_w, top});
        corners.push_back({uc + half_w, top});
      }
    }
    overlay = {
        {"width_px", kW},
        {"height_px", kH},
        {"lines", json::array({{{"color", "#22c55e"},
                                {"label", "lines"},
                                {"width_px", 2},
                                {"segments", segments}}})},
        {"points",
         json::array(
             {{{"color", "#ef4444"}, {"label", "points"}, {"radius_px", 3}, {"uv", corners}}})}};
    return px;
  }
};

/// 80x60 thumbnail by 4x4 box averaging.
std::string thumbnail(const std::vector<std::uint8_t>& px) {
  constexpr int kS = 4;
  const int w = Scene::kW / kS, h = Scene::kH / kS;
  std::vector<std::uint8_t> t(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      int sum = 0;
      for (int dy = 0; dy < kS; ++dy) {
        for (int dx = 0; dx < kS; ++dx) {
          sum += px[static_cast<std::size_t>(y * kS + dy) * Scene::kW + x * kS + dx];
        }
      }
      t[static_cast<std::size_t>(y) * w + x] = static_cast<std::uint8_t>(sum / (kS * kS));
    }
  }
  return encode_png_gray(t, w, h);
}

struct Args {
  int port = 0;
  std::string web_root;
  double fps = 15.0;
  std::string scenario = "teach";
  bool exit_on_stdin_eof = false;
  double duration_s = 0.0;
  double robot_warning_at_s = -1.0;  ///< < 0: never
  double robot_warning_for_s = 4.0;
};

Args parse_args(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument("missing value after " + k);
      return argv[++i];
    };
    if (k == "--port")
      a.port = std::stoi(value());
    else if (k == "--web-root")
      a.web_root = value();
    else if (k == "--fps")
      a.fps = std::stod(value());
    else if (k == "--scenario")
      a.scenario = value();
    else if (k == "--exit-on-stdin-eof")
      a.exit_on_stdin_eof = true;
    else if (k == "--duration-s")
      a.duration_s = std::stod(value());
    else if (k == "--robot-warning-at-s")
      a.robot_warning_at_s = std::stod(value());
    else if (k == "--robot-warning-for-s")
      a.robot_warning_for_s = std::stod(value());
    else if (k == "--help" || k == "-h") {
      std::cout << "usage: ui_fake_session [--port N] [--web-root DIR] [--fps HZ] "
                   "[--scenario teach|replay|offline] [--exit-on-stdin-eof] [--duration-s S]\n"
                   "       [--robot-warning-at-s S [--robot-warning-for-s D]] (the app's robot\n"
                   "       warning, renewed at 5 Hz from S for D seconds, then cleared)\n";
      std::exit(0);
    } else {
      throw std::invalid_argument("unknown option " + k);
    }
  }
  if (a.port < 0 || a.port > 65535) throw std::invalid_argument("--port must be in [0, 65535]");
  if (!(a.fps > 0 && a.fps <= 60)) throw std::invalid_argument("--fps must be in (0, 60]");
  if (a.scenario != "teach" && a.scenario != "replay" && a.scenario != "offline") {
    throw std::invalid_argument("--scenario must be teach, replay or offline");
  }
  return a;
}

// ------------------------------------------------------------------ the fake session
class FakeSession {
 public:
  FakeSession(UiServer& server, const Args& args) : server_(server), args_(args) {}

  void run() {
    using clock = std::chrono::steady_clock;
    const auto period = std::chrono::duration<double>(1.0 / args_.fps);
    const auto t0 = clock::now();
    auto next = t0;
    setup_scenario();
    for (int tick = 0; !g_quit; ++tick) {
      const double t_s = std::chrono::duration<double>(clock::now() - t0).count();
      if (args_.duration_s > 0 && t_s > args_.duration_s) break;
      while (auto intent = server_.next_intent(std::chrono::milliseconds(0))) handle(*intent);
      step(t_s, period.count(), tick);
      next += std::chrono::duration_cast<clock::duration>(period);
      std::this_thread::sleep_until(next);
    }
  }

 private:
  void setup_scenario() {
    server_.publish_state({{"mode", args_.scenario},
                           {"connection", {{"robot", "connected"}, {"head_locked", true}}},
                           {"recording", false},
                           {"warnings", json::array()},
                           {"stop_reason", nullptr}});
    if (args_.scenario == "teach") {
      publish_teach();
      return;
    }
    // replay / offline: a finished tour of 12 key images along a gentle S-curve.
    json keys = json::array();
    json taught = json::array();
    json replayed = json::array();
    json blind = json::array();  // a stretch driven on odometry alone
    json key_xy = json::array();
    json dummy;
    for (int i = 0; i < 12; ++i) {
      const auto px = scene_.render(0.35 * std::sin(i * 0.5), i * 0.6, dummy);
      server_.publish_image("key/" + std::to_string(i), thumbnail(px));
      keys.push_back({{"index", i},
                      {"n_lines", 14 + (i * 7) % 9},
                      {"n_points", 40 + (i * 13) % 30},
                      {"distance_m", i * 0.6},
                      {"weak", i == 7}});
    }
    for (int k = 0; k <= 110; ++k) {
      const double s = k * 0.06;
      const double x = s, y = 0.8 * std::sin(s * 0.7);
      taught.push_back({x, y});
      if (k % 10 == 0) key_xy.push_back({x, y});
      if (k <= 80) replayed.push_back({x + 0.02, y + 0.05 * std::sin(k * 0.3) + 0.03});
      if (k >= 40 && k <= 50) blind.push_back(replayed.back());
    }
    teach_keys_ = keys;
    server_.publish_state(
        {{"teach", {{"key_images", keys}, {"distance_m", 6.6}}},
         {"map_summary",
          {{"key_images", 12},
           {"length_m", 6.6},
           {"min_lines", 14},
           {"min_points", 40},
           {"weak_key_images", {7}},
           {"path", "maps/fake_tour"}}},
         {"trajectory", {{"taught", taught}, {"replayed", replayed}, {"blind", blind}, {"keys", key_xy}}},
         // A corridor's two walls along the S-curve's band and a table beside it.
         {"floor_plan",
          {{"walls", {{-0.5, 1.6, 7.0, 1.6}, {-0.5, -1.6, 7.0, -1.6}}},
           {"boxes", {{{2.0, -1.4}, {2.8, -1.4}, {2.8, -1.0}, {2.0, -1.0}}}}}},
         {"offline", {{"max_lateral_error_m", 0.081}, {"mean_lateral_error_m", 0.034}}}});
    replaying_ = true;
  }

  void publish_teach() {
    server_.publish_state({{"teach",
                            {{"key_images", teach_keys_},
                             {"distance_m", distance_m_},
                             {"n_lines", n_lines_},
                             {"n_points", n_points_}}},
                           {"drive", {{"v_m_s", v_m_s_}, {"omega_rad_s", omega_rad_s_}}}});
  }

  void handle(const Intent& intent) {
    json line = to_json(intent);
    line["event"] = "intent";
    emit(line);
    switch (intent.kind) {
      case IntentKind::kDrive:
        v_m_s_ = intent.v_m_s;
        omega_rad_s_ = intent.omega_rad_s;
        break;
      case IntentKind::kDriveReleased:
        v_m_s_ = omega_rad_s_ = 0.0;
        break;
      case IntentKind::kEmergencyStop:
        v_m_s_ = omega_rad_s_ = 0.0;
        replaying_ = false;
        server_.publish_state(
            {{"stop_reason", "emergency stop by the operator"}, {"recording", false}});
        recording_ = false;
        break;
      case IntentKind::kStartRecording:
        recording_ = true;
        server_.publish_state({{"recording", true}, {"mode", "teach"}, {"stop_reason", nullptr}});
        break;
      case IntentKind::kStopRecording:
        recording_ = false;
        server_.publish_state({{"recording", false}});
        break;
      case IntentKind::kFinishTeach: {
        recording_ = false;
        json weak = json::array();
        for (const auto& k : teach_keys_) {
          if (k["weak"].get<bool>()) weak.push_back(k["index"]);
        }
        server_.publish_state({{"recording", false},
                               {"map_summary",
                                {{"key_images", teach_keys_.size()},
                                 {"length_m", distance_m_},
                                 {"min_lines", 12},
                                 {"min_points", 35},
                                 {"weak_key_images", weak},
                                 {"path", "maps/fake_tour"}}}});
        break;
      }
      case IntentKind::kStartReplay:
        replaying_ = true;
        replay_distance_m_ = 0.0;
        server_.clear_samples();
        server_.publish_state({{"mode", "replay"}, {"stop_reason", nullptr}});
        break;
    }
  }

  void step(double t_s, double dt_s, int tick) {
    yaw_rad_ += omega_rad_s_ * dt_s;
    distance_m_ += std::abs(v_m_s_) * dt_s;
    if (replaying_) replay_distance_m_ = std::min(6.6, replay_distance_m_ + 0.12 * dt_s);
    const double view_yaw = yaw_rad_ + (replaying_ ? 0.2 * std::sin(t_s * 0.8) : 0.0) + 0.05 * t_s;
    json overlay;
    const auto px = scene_.render(view_yaw, distance_m_ + replay_distance_m_, overlay);
    n_lines_ = static_cast<int>(overlay["lines"][0]["segments"].size());
    n_points_ = static_cast<int>(overlay["points"][0]["uv"].size());
    overlay["t_ns"] = static_cast<std::int64_t>(t_s * 1e9);
    server_.publish_frame(encode_png_gray(px, Scene::kW, Scene::kH), overlay);

    const int every = std::max(1, static_cast<int>(args_.fps / 5));  // state at about 5 Hz
    if (tick % every == 0) {
      server_.publish_state({{"camera", {{"fps_hz", args_.fps}, {"latency_ms", 18.0}}}});
      publish_robot_warning(t_s);
      if (recording_ && tick % (every * 5) == 0) {
        const int index = static_cast<int>(teach_keys_.size());
        server_.publish_image("key/" + std::to_string(index), thumbnail(px));
        teach_keys_.push_back({{"index", index},
                               {"n_lines", n_lines_},
                               {"n_points", n_points_},
                               {"distance_m", distance_m_},
                               {"weak", n_lines_ < 6}});
        if (n_lines_ < 6) {
          server_.publish_state({{"warnings",
                                  {"Few features in view: slow down or turn "
                                   "towards a textured area"}}});
        }
      }
      publish_teach();
      if (replaying_ || args_.scenario != "teach") publish_replay(t_s, px);
    }
  }

  // As the app's supervision does (session/robot_supervision.cpp): the warning renewed while it
  // holds, then null once.
  void publish_robot_warning(double t_s) {
    if (args_.robot_warning_at_s < 0.0 || warning_cleared_) return;
    if (t_s < args_.robot_warning_at_s) return;
    if (t_s < args_.robot_warning_at_s + args_.robot_warning_for_s) {
      server_.publish_state({{"robot_warning",
                              "MoveFailed: the robot refused the move (safety, fake session)"}});
    } else {
      server_.publish_state({{"robot_warning", nullptr}});
      warning_cleared_ = true;
    }
  }

  void publish_replay(double t_s, const std::vector<std::uint8_t>& px) {
    const int k = std::min(10, static_cast<int>(replay_distance_m_ / 0.6));
    const double omega = 0.25 * std::sin(t_s * 0.8) + 0.03 * std::sin(t_s * 5.1);
    const double v = std::abs(omega) > 0.2 ? 0.08 : 0.18;
    server_.publish_state(
        {{"replay",
          {{"state", replaying_ ? "running" : "stopped"},
           {"localisation", {{"ok", true}, {"key_index", 0}, {"detail", "38 matches"}}},
           {"key_index", k},
           {"key_count", 12},
           {"distance_m", replay_distance_m_},
           {"total_m", 6.6}}}});
    server_.publish_samples({{"t_s", t_s},
                             {"distance_m", replay_distance_m_},
                             {"v_m_s", replaying_ ? v : 0.0},
                             {"omega_rad_s", replaying_ ? omega : 0.0},
                             {"n_lines", n_lines_},
                             {"n_points", n_points_},
                             {"n_matched_lines", std::max(0, n_lines_ - 3)}});
    if (k != last_key_) {
      last_key_ = k;
      json dummy;
      server_.publish_image("ip",
                            thumbnail(scene_.render(0.35 * std::sin(k * 0.5), k * 0.6, dummy)));
      server_.publish_image("in", thumbnail(px));
      server_.publish_image(
          "inn", thumbnail(scene_.render(0.35 * std::sin((k + 2) * 0.5), (k + 2) * 0.6, dummy)));
    }
  }

  UiServer& server_;
  Args args_;
  Scene scene_;
  bool recording_ = false;
  bool replaying_ = false;
  bool warning_cleared_ = false;  // the robot warning (--robot-warning-at-s) is over
  double v_m_s_ = 0.0;
  double omega_rad_s_ = 0.0;
  double yaw_rad_ = 0.0;
  double distance_m_ = 0.0;
  double replay_distance_m_ = 0.0;
  int n_lines_ = 0;
  int n_points_ = 0;
  int last_key_ = -1;
  json teach_keys_ = json::array();
};

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = parse_args(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "ui_fake_session: " << e.what() << '\n';
    return 2;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGPIPE, SIG_IGN);

  UiOptions options;
  options.port = static_cast<std::uint16_t>(args.port);
  options.web_root = args.web_root;
  options.log = [](UiLogLevel level, std::string_view text) {
    static constexpr const char* kNames[] = {"debug", "info", "warning", "error"};
    emit({{"event", "log"}, {"level", kNames[static_cast<int>(level)]}, {"text", text}});
  };
  UiServer server(options);
  try {
    server.start();
  } catch (const std::exception& e) {
    std::cerr << "ui_fake_session: " << e.what() << '\n';
    return 1;
  }
  emit({{"event", "listening"}, {"url", server.url()}, {"port", server.port()}});

  std::thread stdin_watch;
  if (args.exit_on_stdin_eof) {
    stdin_watch = std::thread([] {
      char buf[256];
      while (std::fread(buf, 1, sizeof buf, stdin) > 0) {
      }
      g_quit = true;
    });
    stdin_watch.detach();  // blocked in fread; the process exits right after
  }
  FakeSession session(server, args);
  session.run();
  server.stop();
  while (auto intent = server.next_intent(std::chrono::milliseconds(0))) {
    json line = to_json(*intent);
    line["event"] = "intent";
    emit(line);
  }
  emit({{"event", "stopped"}});
  return 0;
}
