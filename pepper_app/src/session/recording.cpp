#include "session/recording.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/camera/intrinsics_json.hpp"

namespace pepper::app {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kFormat = "pepper-recording";
constexpr int kVersion = 2;  // 2: the teach's mode, head pitch and ceiling (issue 24)

core::CameraIntrinsics camera_from_json(const json& j, const fs::path& file) {
  try {
    return core::camera::intrinsics_from_json(j);
  } catch (const std::invalid_argument& e) {
    throw RecordingError(file.string() + ": camera: " + e.what());
  }
}

void write_file_atomically(const fs::path& path, const std::string& content) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw RecordingError(tmp.string() + ": cannot open for writing");
    out << content;
    out.flush();
    if (!out) throw RecordingError(tmp.string() + ": write failed (disk full?)");
  }
  fs::rename(tmp, path);
}

bool is_image_file(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".pgm" ||
         ext == ".ppm";
}

bool finite_numbers(std::initializer_list<double> values) {
  for (const double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

/// What is wrong with a setup to write or one just read ("" when nothing).
std::string setup_problem(const RecordingSetup& s) {
  if (!std::isfinite(s.head_pitch_rad)) return "head_pitch_rad must be a finite number";
  const bool ceiling_mode = s.mode == core::NavMode::kCeiling;
  if (ceiling_mode != s.ceiling.has_value()) {
    return ceiling_mode ? "mode ceiling needs \"ceiling\" {height_m, above_camera_m, "
                          "camera_in_base_m}"
                        : "mode forward has no \"ceiling\"";
  }
  if (!s.ceiling) return "";
  const RecordedCeiling& c = *s.ceiling;
  if (!finite_numbers({c.height_m, c.above_camera_m, c.cam_in_base_x_m, c.cam_in_base_y_m})) {
    return "ceiling: height_m, above_camera_m, camera_in_base_m {x_m, y_m} must be finite numbers";
  }
  if (!(c.above_camera_m > 0.0)) return "ceiling: above_camera_m must be > 0";
  return "";
}

json setup_to_json(const RecordingSetup& s) {
  json j{{"mode", core::to_string(s.mode)}, {"head_pitch_rad", s.head_pitch_rad}};
  if (s.ceiling) {
    j["ceiling"] = {{"height_m", s.ceiling->height_m},
                    {"above_camera_m", s.ceiling->above_camera_m},
                    {"camera_in_base_m",
                     {{"x_m", s.ceiling->cam_in_base_x_m}, {"y_m", s.ceiling->cam_in_base_y_m}}}};
  }
  return j;
}

/// The setup of a version-2 manifest; nullopt when it has no "mode" (replay's recordings).
std::optional<RecordingSetup> setup_from_json(const json& m, const fs::path& file) {
  if (!m.contains("mode")) return std::nullopt;
  const auto bad = [&](const std::string& what) {
    return RecordingError(file.string() + ": " + what);
  };
  const auto number = [](const json& o, const char* key) {
    return o.is_object() && o.contains(key) && o[key].is_number()
               ? o[key].get<double>()
               : std::numeric_limits<double>::quiet_NaN();
  };
  RecordingSetup s;
  const std::optional<core::NavMode> mode =
      m["mode"].is_string() ? core::nav_mode_from_string(m["mode"].get<std::string>())
                            : std::nullopt;
  if (!mode) throw bad("mode " + m["mode"].dump() + ": must be \"forward\" or \"ceiling\"");
  s.mode = *mode;
  s.head_pitch_rad = number(m, "head_pitch_rad");
  if (m.contains("ceiling") && !m["ceiling"].is_null()) {
    const json& c = m["ceiling"];
    const json in_base = c.is_object() ? c.value("camera_in_base_m", json()) : json();
    s.ceiling = RecordedCeiling{number(c, "height_m"), number(c, "above_camera_m"),
                                number(in_base, "x_m"), number(in_base, "y_m")};
  }
  if (const std::string p = setup_problem(s); !p.empty()) throw bad(p);
  return s;
}

}  // namespace

RecordingWriter::RecordingWriter(fs::path folder, const core::CameraIntrinsics& camera,
                                 const std::string& source, const std::string& config_json,
                                 const std::optional<RecordingSetup>& setup)
    : folder_(std::move(folder)) {
  if (setup) {
    if (const std::string p = setup_problem(*setup); !p.empty()) {
      throw RecordingError(folder_.string() + ": recording setup: " + p);
    }
  }
  if (fs::exists(folder_) && !fs::is_empty(folder_)) {
    throw RecordingError(folder_.string() + ": recording folder exists and is not empty");
  }
  std::error_code ec;
  fs::create_directories(folder_ / "frames", ec);
  if (ec) throw RecordingError(folder_.string() + ": cannot create: " + ec.message());
  json config = json::parse(config_json, nullptr, /*allow_exceptions=*/false);
  if (config.is_discarded()) config = json::object();
  json manifest{{"format", kFormat}, {"version", kVersion},
                {"camera", core::camera::intrinsics_to_json(camera)}, {"source", source},
                {"config", config}};
  if (setup) manifest.update(setup_to_json(*setup));
  write_file_atomically(folder_ / "recording.json", manifest.dump(2) + "\n");
  index_.open(folder_ / "frames.jsonl", std::ios::app);
  if (!index_) throw RecordingError((folder_ / "frames.jsonl").string() + ": cannot open");
}

void RecordingWriter::append(const core::Frame& frame, double v_m_s, double omega_rad_s) {
  if (frame.gray.empty() || frame.gray.type() != CV_8UC1) {
    throw RecordingError("recording: frame " + std::to_string(count_) + " is not 8-bit grey");
  }
  std::ostringstream name;
  name << "frames/" << std::setw(6) << std::setfill('0') << count_ << ".png";
  const fs::path final_path = folder_ / name.str();
  const fs::path tmp_path = folder_ / (name.str() + ".tmp.png");
  if (!cv::imwrite(tmp_path.string(), frame.gray)) {
    throw RecordingError(tmp_path.string() + ": cannot write frame");
  }
  fs::rename(tmp_path, final_path);
  json line{{"index", count_},
            {"t_ns", frame.t_ns},
            {"file", name.str()},
            {"v_m_s", v_m_s},
            {"omega_rad_s", omega_rad_s}};
  if (frame.odom) {
    line["odom"] = {
        {"x_m", frame.odom->x_m}, {"y_m", frame.odom->y_m}, {"yaw_rad", frame.odom->yaw_rad}};
  }
  index_ << line.dump() << '\n';
  index_.flush();
  if (!index_) throw RecordingError((folder_ / "frames.jsonl").string() + ": write failed");
  ++count_;
}

core::CameraIntrinsics session_camera(const core::CameraIntrinsics& reported,
                                      const std::optional<core::CameraIntrinsics>& calibration) {
  return calibration ? calibration->scaled_to(reported.width_px, reported.height_px) : reported;
}

Recording read_recording(const fs::path& folder,
                         const std::optional<core::CameraIntrinsics>& camera_override,
                         double nominal_fps) {
  if (!fs::is_directory(folder)) {
    throw RecordingError(folder.string() + ": not a folder");
  }
  Recording rec;
  rec.folder = folder;
  const fs::path manifest_path = folder / "recording.json";
  if (fs::exists(manifest_path)) {
    std::ifstream in(manifest_path);
    json manifest = json::parse(in, nullptr, /*allow_exceptions=*/false);
    if (manifest.is_discarded() || !manifest.is_object()) {
      throw RecordingError(manifest_path.string() + ": not valid JSON");
    }
    if (manifest.value("format", "") != kFormat) {
      throw RecordingError(manifest_path.string() + ": not a pepper recording (format field)");
    }
    const json version = manifest.value("version", json(0));
    rec.version = version.is_number_integer() ? version.get<int>() : 0;
    if (rec.version < 1 || rec.version > kVersion) {
      throw RecordingError(manifest_path.string() + ": unsupported version " + version.dump() +
                           " (this build reads 1 to " + std::to_string(kVersion) + ")");
    }
    // Version 1 has no setup: its mode is not known (map build asks for it).
    if (rec.version >= 2) rec.setup = setup_from_json(manifest, manifest_path);
    rec.config = manifest.value("config", json());
    rec.camera = camera_override ? *camera_override
                                 : camera_from_json(manifest.value("camera", json()), manifest_path);
    rec.source = manifest.value("source", "");
    rec.commands_known = true;
    const fs::path index_path = folder / "frames.jsonl";
    std::ifstream index(index_path);
    if (!index) throw RecordingError(index_path.string() + ": missing");
    std::string line;
    int line_no = 0;
    while (std::getline(index, line)) {
      ++line_no;
      if (line.empty()) continue;
      json j = json::parse(line, nullptr, false);
      if (j.is_discarded() || !j.is_object() || !j.contains("file")) {
        if (index.peek() == EOF) {
          rec.warnings.push_back(index_path.string() + ": line " + std::to_string(line_no) +
                                 " is incomplete (interrupted write); skipped");
          break;
        }
        throw RecordingError(index_path.string() + ": line " + std::to_string(line_no) +
                             " is not a frame record");
      }
      RecordedFrame f;
      f.index = j.value("index", static_cast<int64_t>(rec.frames.size()));
      f.t_ns = j.value("t_ns", int64_t{0});
      f.file = folder / j["file"].get<std::string>();
      f.v_m_s = j.value("v_m_s", 0.0);
      f.omega_rad_s = j.value("omega_rad_s", 0.0);
      if (!std::isfinite(f.v_m_s) || !std::isfinite(f.omega_rad_s)) {
        throw RecordingError(index_path.string() + ": line " + std::to_string(line_no) +
                             ": v_m_s / omega_rad_s must be finite numbers");
      }
      if (j.contains("odom")) {
        const json& o = j["odom"];
        const auto number = [&](const char* key) -> double {
          if (!o.is_object() || !o.contains(key) || !o[key].is_number()) {
            return std::numeric_limits<double>::quiet_NaN();
          }
          return o[key].get<double>();
        };
        f.odom = core::OdometryPose{number("x_m"), number("y_m"), number("yaw_rad")};
        if (!std::isfinite(f.odom->x_m) || !std::isfinite(f.odom->y_m) ||
            !std::isfinite(f.odom->yaw_rad)) {
          throw RecordingError(
              index_path.string() + ": line " + std::to_string(line_no) +
              ": odom must be {\"x_m\", \"y_m\", \"yaw_rad\"} with finite numbers");
        }
      }
      rec.frames.push_back(std::move(f));
    }
  } else {
    if (!camera_override) {
      throw RecordingError(folder.string() +
                           ": no recording.json here; for a plain image folder give the camera "
                           "intrinsics with --camera FILE");
    }
    rec.camera = *camera_override;
    rec.source = "plain image folder";
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(folder)) {
      if (entry.is_regular_file() && is_image_file(entry.path())) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    if (!(nominal_fps > 0.0)) throw RecordingError("nominal_fps must be > 0");
    for (std::size_t i = 0; i < files.size(); ++i) {
      RecordedFrame f;
      f.index = static_cast<int64_t>(i);
      f.t_ns = static_cast<int64_t>(static_cast<double>(i) * 1e9 / nominal_fps);
      f.file = files[i];
      rec.frames.push_back(std::move(f));
    }
  }
  if (rec.frames.empty()) throw RecordingError(folder.string() + ": recording has no frames");
  return rec;
}

core::Frame load_frame(const Recording& recording, std::size_t i) {
  if (i >= recording.frames.size()) {
    throw RecordingError("frame " + std::to_string(i) + " out of range (recording has " +
                         std::to_string(recording.frames.size()) + ")");
  }
  const RecordedFrame& rf = recording.frames[i];
  cv::Mat image = cv::imread(rf.file.string(), cv::IMREAD_UNCHANGED);
  if (image.empty()) throw RecordingError(rf.file.string() + ": missing or unreadable image");
  cv::Mat gray;
  if (image.channels() == 3) {
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  } else {
    gray = image;
  }
  if (gray.depth() != CV_8U) gray.convertTo(gray, CV_8U, 1.0 / 256.0);
  core::Frame frame;
  frame.gray = gray;
  frame.t_ns = rf.t_ns;
  frame.index = rf.index;
  frame.odom = rf.odom;
  return frame;
}

}  // namespace pepper::app
