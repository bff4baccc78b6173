// qi messaging over loopback: image streaming throughput (getImageRemote VGA grey), move round
// trip latency (p50/p99), and the cost of decoding a VGA image reply. Compare with PROTOCOL.md
// section 10 (libqi 4 client against libqi's fake robot on the same kind of machine).
//
//   build-qi/bench/bench_qi --benchmark_counters_tabular=true
//
// The served robot returns one precomputed frame (no rendering) so the figures measure the
// protocol path: server encode + loopback TCP/TLS + client decode.
// BM_WatchdogStopLatency: how long after the app's last move() the robot receives the stop.
// BM_DeadmanStopLatency: how long after the app's last move() the robot stops by itself.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <opencv2/core.hpp>
#include <thread>
#include <vector>

#include "naoqi_bridge/qi/image_remote.hpp"
#include "naoqi_bridge/qi/mock_server.hpp"
#include "naoqi_bridge/qi/qi_bridge.hpp"
#include "naoqi_bridge/qi/session.hpp"
#include "sim/synthetic_pattern_robot.hpp"

namespace qi = pepper::naoqi_bridge::qi;
namespace sim = pepper::sim;

namespace {

/// A SimRobot whose camera returns a fixed image (shared buffer, new timestamp each capture).
class StaticFrameRobot : public sim::SyntheticPatternRobot {
 public:
  pepper::core::Frame capture(int width_px, int height_px) override {
    if (image_.cols != width_px || image_.rows != height_px) {
      image_ = SyntheticPatternRobot::capture(width_px, height_px).gray;
    }
    pepper::core::Frame f;
    f.gray = image_;
    t_ns_ += 33'333'333;
    f.t_ns = t_ns_;
    f.index = index_++;
    return f;
  }

 private:
  cv::Mat image_;
  std::int64_t t_ns_ = 0;
  std::int64_t index_ = 0;
};

struct Fixture {
  StaticFrameRobot robot;
  qi::MockNaoqiServer server;
  explicit Fixture(bool tls) : server(robot, options(tls)) { server.start(); }
  static qi::MockServerOptions options(bool tls) {
    qi::MockServerOptions o;
    if (tls) {
      o.listen_url = "tcps://127.0.0.1:0";
      o.user = "nao";
      o.password = "bench";
    }
    return o;
  }
  qi::SessionOptions session_options(bool tls) const {
    qi::SessionOptions s;
    if (tls) {
      s.user = "nao";
      s.password = "bench";
    }
    return s;
  }
};

void get_image_remote(benchmark::State& state, bool tls, int resolution, int w, int h) {
  Fixture fx(tls);
  qi::QiSession session(fx.session_options(tls));
  session.connect(fx.server.url());
  const auto video = session.service("ALVideoDevice");
  const std::string handle =
      session
          .call(video, "subscribeCamera", "(siiii)",
                {qi::Value::string("bench"), qi::Value::int32(0), qi::Value::int32(resolution),
                 qi::Value::int32(0), qi::Value::int32(30)})
          .as_string();
  cv::Mat out(h, w, CV_8UC1);
  for (auto _ : state) {
    const qi::Message m =
        session.call_async(video, "getImageRemote", "(s)", {qi::Value::string(handle)})
            .get_message();
    const qi::ImageRemote img = qi::decode_image_remote(m.bytes(), {}, m.payload);
    std::memcpy(out.data, img.pixels.data, img.pixels.size);
    benchmark::DoNotOptimize(out.data);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(w) * h);
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_GetImageRemoteVgaGreyTcp(benchmark::State& s) { get_image_remote(s, false, 2, 640, 480); }
void BM_GetImageRemoteVgaGreyTlsLogin(benchmark::State& s) {
  get_image_remote(s, true, 2, 640, 480);
}
void BM_GetImageRemoteQvgaGreyTcp(benchmark::State& s) { get_image_remote(s, false, 1, 320, 240); }

/// The bridge path: one request always in flight while the previous frame is handed out; with
/// the odometry read alongside each image (the default) or not, to show what it costs.
void next_frame_vga_pipelined(benchmark::State& state, bool read_odometry) {
  Fixture fx(false);
  qi::QiBridgeOptions o;
  o.url = fx.server.url();
  o.head_resend_period = std::chrono::milliseconds(0);
  o.read_odometry = read_odometry;
  qi::QiBridge bridge(o);
  bridge.connect();
  bridge.start_camera({});
  for (auto _ : state) {
    auto f = bridge.next_frame(std::chrono::milliseconds(3000));
    if (!f) state.SkipWithError("no frame");
    benchmark::DoNotOptimize(f);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetBytesProcessed(state.iterations() * 640 * 480);
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_QiBridgeNextFrameVgaPipelined(benchmark::State& s) { next_frame_vga_pipelined(s, true); }
void BM_QiBridgeNextFrameVgaPipelinedNoOdometry(benchmark::State& s) {
  next_frame_vga_pipelined(s, false);
}

void move_round_trip(benchmark::State& state, bool tls) {
  Fixture fx(tls);
  qi::QiSession session(fx.session_options(tls));
  session.connect(fx.server.url());
  const auto motion = session.service("ALMotion");
  std::vector<double> us;
  us.reserve(100000);
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    session.call(motion, "move", "(fff)",
                 {qi::Value::float32(0.1f), qi::Value::float32(0.f), qi::Value::float32(0.f)});
    us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(us.begin(), us.end());
  if (!us.empty()) {
    state.counters["p50_us"] = us[us.size() / 2];
    state.counters["p99_us"] = us[std::min(us.size() - 1, us.size() * 99 / 100)];
  }
}
void BM_MoveRoundTripTcp(benchmark::State& s) { move_round_trip(s, false); }
void BM_MoveRoundTripTlsLogin(benchmark::State& s) { move_round_trip(s, true); }

/// Watchdog: time from the app's last move() until the robot (server side) receives the stop,
/// with the default 300 ms watchdog. Wall clock, polled every 0.5 ms on the server's command log.
void BM_WatchdogStopLatency(benchmark::State& state) {
  Fixture fx(false);
  qi::QiBridgeOptions o;
  o.url = fx.server.url();
  o.head_resend_period = std::chrono::milliseconds(0);
  o.deadman_horizon = std::chrono::milliseconds(0);  // plain move: only the watchdog stops it
  qi::QiBridge bridge(o);
  bridge.connect();
  std::vector<double> ms;
  for (auto _ : state) {
    bridge.move({0.1, 0.0, 0.0});
    const auto t0 = std::chrono::steady_clock::now();
    const std::size_t seen = fx.robot.command_log().size();
    double latency_ms = -1.0;
    while (latency_ms < 0.0) {
      std::this_thread::sleep_for(std::chrono::microseconds(500));
      const auto elapsed = std::chrono::steady_clock::now() - t0;
      const auto log = fx.robot.command_log();
      for (std::size_t i = seen; i < log.size(); ++i) {
        const auto& v = log[i].velocity;
        if (log[i].stop_move || (v.v_x_m_s == 0.0 && v.v_y_m_s == 0.0 && v.omega_rad_s == 0.0)) {
          latency_ms = std::chrono::duration<double, std::milli>(elapsed).count();
          break;
        }
      }
      if (elapsed > std::chrono::seconds(5)) {
        state.SkipWithError("no stop within 5 s");
        return;
      }
    }
    ms.push_back(latency_ms);
    state.SetIterationTime(latency_ms / 1000.0);
  }
  std::sort(ms.begin(), ms.end());
  if (!ms.empty()) {
    state.counters["p50_ms"] = ms[ms.size() / 2];
    state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
    state.counters["max_ms"] = ms.back();
  }
}

/// Robot-side deadman (issue 23): time from the app's last move() until the robot stops the base
/// by itself (the moveTo's horizon ends, default 250 ms), with the laptop-side watchdog pushed out
/// of the way (10 s) as if the app were frozen. Same polling as above.
void BM_DeadmanStopLatency(benchmark::State& state) {
  Fixture fx(false);
  qi::QiBridgeOptions o;
  o.url = fx.server.url();
  o.head_resend_period = std::chrono::milliseconds(0);
  o.watchdog_timeout = std::chrono::milliseconds(10000);
  qi::QiBridge bridge(o);
  bridge.connect();
  if (!bridge.robot_side_deadman()) {
    state.SkipWithError("the mock's ALMotion has no moveTo(ffff)");
    return;
  }
  std::vector<double> ms;
  for (auto _ : state) {
    bridge.move({0.1, 0.0, 0.2});
    const auto t0 = std::chrono::steady_clock::now();
    const std::size_t seen = fx.robot.command_log().size();
    double latency_ms = -1.0;
    while (latency_ms < 0.0) {
      std::this_thread::sleep_for(std::chrono::microseconds(500));
      const auto elapsed = std::chrono::steady_clock::now() - t0;
      const auto log = fx.robot.command_log();
      for (std::size_t i = seen; i < log.size(); ++i) {
        if (log[i].stop_move) {
          latency_ms = std::chrono::duration<double, std::milli>(elapsed).count();
          break;
        }
      }
      if (elapsed > std::chrono::seconds(5)) {
        state.SkipWithError("no robot-side stop within 5 s");
        return;
      }
    }
    ms.push_back(latency_ms);
    state.SetIterationTime(latency_ms / 1000.0);
  }
  std::sort(ms.begin(), ms.end());
  if (!ms.empty()) {
    state.counters["p50_ms"] = ms[ms.size() / 2];
    state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
    state.counters["max_ms"] = ms.back();
  }
}

std::shared_ptr<const std::vector<std::uint8_t>> vga_reply_payload() {
  qi::ImageRemote img;
  img.width_px = 640;
  img.height_px = 480;
  img.layers = 1;
  std::vector<std::uint8_t> pixels(640 * 480, 7);
  img.pixels = qi::RawBytes::copy_of(pixels);
  auto payload = std::make_shared<std::vector<std::uint8_t>>();
  qi::Writer w(*payload);
  qi::encode_image_remote(img, w);
  return payload;
}

/// Decoding a VGA reply: walks the 12 dynamics, pixels as a view (no copy).
void BM_DecodeImageRemoteVgaView(benchmark::State& state) {
  const auto payload = vga_reply_payload();
  for (auto _ : state) {
    auto img = qi::decode_image_remote(*payload, {}, payload);
    benchmark::DoNotOptimize(img.pixels.data);
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(payload->size()));
}

/// Decoding plus the one copy into the frame's cv::Mat, as QiBridge::next_frame does.
void BM_DecodeImageRemoteVgaToMat(benchmark::State& state) {
  const auto payload = vga_reply_payload();
  for (auto _ : state) {
    auto img = qi::decode_image_remote(*payload, {}, payload);
    cv::Mat m(img.height_px, img.width_px, CV_8UC1);
    std::memcpy(m.data, img.pixels.data, img.pixels.size);
    benchmark::DoNotOptimize(m.data);
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(payload->size()));
}

}  // namespace

BENCHMARK(BM_GetImageRemoteVgaGreyTcp)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GetImageRemoteVgaGreyTlsLogin)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GetImageRemoteQvgaGreyTcp)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_QiBridgeNextFrameVgaPipelined)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_QiBridgeNextFrameVgaPipelinedNoOdometry)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_MoveRoundTripTcp)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_MoveRoundTripTlsLogin)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_WatchdogStopLatency)->UseManualTime()->Iterations(30)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DeadmanStopLatency)->UseManualTime()->Iterations(30)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeImageRemoteVgaView)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DecodeImageRemoteVgaToMat)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
