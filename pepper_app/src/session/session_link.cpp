#include "session/session_link.hpp"

#include <algorithm>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "session/console.hpp"
#include "teach_ui/ui_server.hpp"

namespace pepper::app {

SessionLink::SessionLink(teach_ui::UiServer* ui, std::ostream* events) : ui_(ui), events_(events) {}

std::optional<teach_ui::Intent> SessionLink::poll_intent() {
  if (intent_source_) {
    if (auto i = intent_source_()) return i;
  }
  if (ui_ != nullptr) return ui_->next_intent(std::chrono::milliseconds(0));
  return std::nullopt;
}

bool SessionLink::publish_frame(const core::Frame& frame, const nlohmann::json& overlay) {
  if (ui_ == nullptr || frame.gray.empty()) return false;
  // Frames are due on a fixed schedule, one per period, not a period after the last one sent: a
  // source at the same nominal rate with some jitter (the session loop paced at the camera's
  // 15 Hz) then keeps every frame instead of dropping those that come a few ms early (measured:
  // 9.9 of 15 frames/s sent with "now - last >= period"). The schedule never lags more than half
  // a period behind, so a pause is followed by at most one extra frame.
  const auto now = std::chrono::steady_clock::now();
  if (now < next_frame_due_) return false;
  next_frame_due_ = std::max(next_frame_due_ + min_frame_period, now - min_frame_period / 2);
  std::vector<std::uint8_t> jpeg;
  cv::imencode(".jpg", frame.gray, jpeg, {cv::IMWRITE_JPEG_QUALITY, 80});
  nlohmann::json o = overlay.is_object() ? overlay : nlohmann::json::object();
  o["width_px"] = frame.gray.cols;
  o["height_px"] = frame.gray.rows;
  o["t_ns"] = frame.t_ns;
  ui_->publish_frame(jpeg, std::move(o));
  return true;
}

void SessionLink::publish_state(const nlohmann::json& patch) {
  if (ui_ != nullptr) ui_->publish_state(patch);
}

void SessionLink::publish_samples(const nlohmann::json& samples) {
  if (ui_ != nullptr) ui_->publish_samples(samples);
}

void SessionLink::publish_thumbnail(const std::string& name, const cv::Mat& gray,
                                    int max_width_px) {
  if (ui_ == nullptr || gray.empty()) return;
  cv::Mat small = gray;
  if (gray.cols > max_width_px) {
    cv::resize(gray, small, cv::Size(max_width_px, gray.rows * max_width_px / gray.cols), 0, 0,
               cv::INTER_AREA);
  }
  std::vector<std::uint8_t> jpeg;
  cv::imencode(".jpg", small, jpeg, {cv::IMWRITE_JPEG_QUALITY, 80});
  ui_->publish_image(name, jpeg);
}

void SessionLink::event(const nlohmann::json& e) {
  if (events_ == nullptr) return;
  *events_ << e.dump() << "\n" << std::flush;
}

void SessionLink::progress(const Progress& p) {
  if (console_ != nullptr) console_->progress(p);
}

void SessionLink::end_progress() {
  if (console_ != nullptr) console_->end_progress();
}

void SessionLink::warning(const std::string& text) {
  if (console_ != nullptr) console_->warning(text);
}

void SessionLink::command_event(double v_m_s, double omega_rad_s, bool stop,
                                const std::string& why) {
  if (have_last_command_ && v_m_s == last_v_ && omega_rad_s == last_omega_ && stop == last_stop_) {
    return;
  }
  have_last_command_ = true;
  last_v_ = v_m_s;
  last_omega_ = omega_rad_s;
  last_stop_ = stop;
  event({{"event", "command"},
         {"v_m_s", v_m_s},
         {"omega_rad_s", omega_rad_s},
         {"stop", stop},
         {"why", why}});
}

}  // namespace pepper::app
