#include "session/ceiling_teach.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

#include "core/ceiling/landmarks.hpp"
#include "core/ceiling/observation.hpp"
#include "core/geometry/floor_lines.hpp"

namespace pepper::app {

namespace cc = core::ceiling;

namespace {

// The setup of a camera `cam_height_m` above the floor and `cam_in_base_m` from the rotation
// axis under a ceiling `ceiling_height_m` above the floor; `not_above` is the refusal's text.
CeilingCameraSetup ceiling_camera_setup(double ceiling_height_m, double cam_height_m,
                                        cv::Point2d cam_in_base_m,
                                        const core::CameraIntrinsics& camera,
                                        double head_pitch_rad, const std::string& not_above) {
  CeilingCameraSetup s;
  s.camera.intrinsics = camera;
  s.camera.head_pitch_rad = head_pitch_rad;
  s.camera.ceiling_above_cam_m = ceiling_height_m - cam_height_m;
  if (!(s.camera.ceiling_above_cam_m > 0.0)) throw std::invalid_argument(not_above);
  s.ceiling_height_m = ceiling_height_m;
  s.cam_in_base_m = cam_in_base_m;
  return s;
}

}  // namespace

CeilingCameraSetup ceiling_camera_of_mock(const sim::MockRobot& robot,
                                          const core::CameraIntrinsics& camera,
                                          double head_pitch_rad) {
  const Eigen::Vector3d t = robot.options().mount.T_base_cam(0.0, head_pitch_rad).translation();
  const double ceiling_m = robot.world().ceiling_height_m;
  return ceiling_camera_setup(ceiling_m, t.z(), {t.x(), t.y()}, camera, head_pitch_rad,
                              "ceiling mode: the world's ceiling (" + std::to_string(ceiling_m) +
                                  " m) is not above the camera");
}

CeilingCameraSetup ceiling_camera_of_pepper(double ceiling_height_m,
                                            const core::CameraIntrinsics& camera,
                                            double head_pitch_rad) {
  const core::geometry::CameraOnBase mount = core::geometry::pepper_top_camera(head_pitch_rad);
  return ceiling_camera_setup(
      ceiling_height_m, mount.height_m, {mount.forward_m, 0.0}, camera, head_pitch_rad,
      "ceiling mode: robot.ceiling_height_m = " + std::to_string(ceiling_height_m) +
          " m is not above Pepper's camera (" + std::to_string(mount.height_m) +
          " m): measure the ceiling's height above the floor and set it, e.g. --set "
          "robot.ceiling_height_m=2.7");
}

CeilingCameraSetup ceiling_camera_for(const sim::MockRobot* mock, double ceiling_height_m,
                                      const core::CameraIntrinsics& camera, double head_pitch_rad) {
  return mock ? ceiling_camera_of_mock(*mock, camera, head_pitch_rad)
              : ceiling_camera_of_pepper(ceiling_height_m, camera, head_pitch_rad);
}

RecordedCeiling to_recorded(const CeilingCameraSetup& setup) {
  return {setup.ceiling_height_m, setup.camera.ceiling_above_cam_m, setup.cam_in_base_m.x,
          setup.cam_in_base_m.y};
}

CeilingCameraSetup ceiling_setup_of_recorded(const RecordedCeiling& recorded,
                                             const core::CameraIntrinsics& camera,
                                             double head_pitch_rad, double ceiling_height_m) {
  const cv::Point2d cam_in_base_m(recorded.cam_in_base_x_m, recorded.cam_in_base_y_m);
  if (!(ceiling_height_m > 0.0) || ceiling_height_m == recorded.height_m) {
    // As recorded, bit for bit (no height recomputed through a subtraction).
    CeilingCameraSetup s = ceiling_camera_setup(
        recorded.height_m, recorded.height_m - recorded.above_camera_m, cam_in_base_m, camera,
        head_pitch_rad, "ceiling mode: the recorded ceiling is not above the camera");
    s.camera.ceiling_above_cam_m = recorded.above_camera_m;
    return s;
  }
  const double cam_height_m = recorded.height_m - recorded.above_camera_m;
  return ceiling_camera_setup(ceiling_height_m, cam_height_m, cam_in_base_m, camera,
                              head_pitch_rad,
                              "ceiling mode: robot.ceiling_height_m = " +
                                  std::to_string(ceiling_height_m) +
                                  " m is not above the recorded camera (" +
                                  std::to_string(cam_height_m) + " m above the floor)");
}

// Why a store on disk (issue 24) and not a bounded window of frames in RAM: which frames become
// relay images is only known at finish(). select_relay_images runs over the builder's KEPT
// sightings (MosaicBuilder::kept_sightings): a landmark counts in every frame that saw it once
// it has min_observations sightings, and any later frame can bring it there (the tour passing
// under that ceiling again, a loop), so a late frame can change which early frames satisfy the
// relay conditions; no window of frames is provably enough. Nor the teach's recording
// (RecordingWriter), though it writes the same PNGs: it is optional (a teach without
// --recording has none), `map build` feeds the teacher from a recording it only reads, and the
// teacher would depend on another component's file numbering and on files the operator may
// move or delete during the teach. A store of our own costs one more PNG write per frame when
// the teach also records (3.7 ms at VGA measured in tests/app/session/
// test_ceiling_teach_memory.cpp) and its disk space until the teacher goes.
namespace {

namespace fs = std::filesystem;

std::string store_error(const fs::path& path, const std::string& what) {
  return "ceiling teach: frame store: " + path.string() + ": " + what;
}

fs::path store_parent(const fs::path& parent) {
  if (!parent.empty()) return parent;
  try {
    return fs::temp_directory_path();
  } catch (const fs::filesystem_error& e) {
    throw std::runtime_error(
        "ceiling teach: frame store: no temporary folder for the teach's frames (" +
        std::string(e.what()) + "): set TMPDIR to a writable folder with room");
  }
}

}  // namespace

TeachFrameStore::TeachFrameStore(const fs::path& parent) {
  const fs::path where = store_parent(parent);
  static std::atomic<uint64_t> counter{0};
  std::random_device entropy;
  for (int attempt = 0; attempt < 16; ++attempt) {
    char name[96];
    std::snprintf(
        name, sizeof name, "pepper_ceiling_teach_%ld_%llu_%08x", static_cast<long>(::getpid()),
        static_cast<unsigned long long>(counter.fetch_add(1)), static_cast<unsigned>(entropy()));
    const fs::path candidate = where / name;
    std::error_code ec;
    // create_directory (not _directories): the parent must exist; false when the name is taken.
    if (fs::create_directory(candidate, ec)) {
      dir_ = candidate;
      return;
    }
    if (ec) {
      throw std::runtime_error(store_error(
          candidate, "cannot create the folder for the teach's frames (" + ec.message() +
                         "): set TMPDIR to a writable folder with room"));
    }
  }
  throw std::runtime_error(store_error(where, "no free folder name for the teach's frames"));
}

TeachFrameStore::~TeachFrameStore() {
  std::error_code ec;  // never throws: a folder already gone is fine
  fs::remove_all(dir_, ec);
}

fs::path TeachFrameStore::file_of(size_t index) const {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%08zu.png", index);
  return dir_ / name;
}

void TeachFrameStore::put(size_t index, const cv::Mat& gray) {
  const fs::path file = file_of(index);
  if (gray.empty() || gray.type() != CV_8UC1) {
    throw std::invalid_argument(store_error(file, "a frame must be a non-empty CV_8UC1 image"));
  }
  if (size_.empty()) size_ = gray.size();
  if (gray.size() != size_) {
    throw std::invalid_argument(store_error(file, "a frame of another size than the first"));
  }
  // PNG: lossless, so finish() extracts the key images' features from the very pixels taught.
  bool written = false;
  std::string why = "cv::imwrite failed (folder gone? disk full?)";
  try {
    written = cv::imwrite(file.string(), gray);
  } catch (const cv::Exception& e) {
    why = e.what();
  }
  std::error_code ec;
  const uintmax_t bytes = written ? fs::file_size(file, ec) : 0;
  if (!written || ec) {
    throw std::runtime_error(store_error(file, "cannot write the teach frame: " + why));
  }
  if (file_bytes_.size() <= index) file_bytes_.resize(index + 1, 0);
  bytes_on_disk_ += bytes - file_bytes_[index];
  file_bytes_[index] = static_cast<uint32_t>(bytes);
}

cv::Mat TeachFrameStore::get(size_t index) const {
  const fs::path file = file_of(index);
  std::error_code ec;
  if (!fs::exists(file, ec)) {
    throw std::runtime_error(store_error(file, "the teach frame is missing (folder removed?)"));
  }
  cv::Mat image;
  try {
    image = cv::imread(file.string(), cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(store_error(file, std::string("cannot read it: ") + e.what()));
  }
  if (image.empty()) {
    throw std::runtime_error(store_error(file, "cannot read the teach frame (damaged?)"));
  }
  if (image.type() != CV_8UC1 || image.size() != size_) {
    throw std::runtime_error(store_error(file, "not the teach frame written there"));
  }
  return image;
}

namespace {

cc::MosaicBuilderOptions builder_options(const CeilingTeachOptions& o) {
  cc::MosaicBuilderOptions b = o.builder;
  b.px_per_m = o.px_per_m;
  return b;
}

}  // namespace

std::optional<std::string> ceiling_height_warning(const cc::HeightCheck& h) {
  if (!h.estimated() || !h.disagrees) return std::nullopt;
  // s > 1: the mosaic is longer than the odometry, the configured ceiling too high.
  const double off = h.scale_ratio - 1.0;
  char text[640];
  std::snprintf(text, sizeof text,
                "ceiling height: the odometry measures the ceiling %.2f m above the floor "
                "(+- %.3f m, %d stretches, %.1f m), not the configured %.2f m: every distance of "
                "this map is %.0f %% too %s. Measure the ceiling's height again and teach again "
                "with it (e.g. --set robot.ceiling_height_m=%.2f); the odometry's own scale error "
                "(a few %%) is in this figure",
                h.estimated_height_m, h.estimated_sigma_m, h.windows, h.odometry_m,
                h.configured_height_m, std::abs(off) * 100.0, off > 0.0 ? "long" : "short",
                h.estimated_height_m);
  return std::string(text);
}

CeilingTeacher::CeilingTeacher(const CeilingCameraSetup& setup,
                               const core::CameraIntrinsics& camera,
                               const core::features::FeatureExtractorOptions& extractor,
                               CeilingTeachOptions options)
    : setup_(setup),
      camera_(camera),
      extractor_(camera, extractor),
      options_(options),
      view_(std::make_unique<cc::CanonicalView>(
          setup.camera, cc::fit_frame(setup.camera, options.px_per_m, options.max_forward_m))),
      builder_(builder_options(options)) {
  options_.relay.check();
  options_.height_check.check();
  store_ = std::make_unique<TeachFrameStore>(options_.frame_store_parent);
}

cc::MosaicFrameResult CeilingTeacher::add_frame(const core::Frame& frame, double travelled_m) {
  cv::Mat seen;
  const cv::Mat canonical = view_->warp(frame.gray, &seen);
  const cc::CeilingObservation obs =
      cc::observe(*view_, setup_.cam_in_base_m, cc::extract_landmarks(canonical, seen));
  // The image to disk now (the relay images are chosen at the end), before the builder's step:
  // a failed write leaves the teacher as it was, so the frames so far still make a map.
  store_->put(frames_.size(), frame.gray);
  cc::MosaicFrameResult r = builder_.add_frame(obs, frame.odom);
  if (!r.localised) ++unlocalised_;
  frames_.push_back({frame.t_ns, travelled_m, frame.odom});
  return r;
}

core::features::FeatureOverlay CeilingTeacher::overlay(
    const cc::MosaicFrameResult& result) const {
  core::features::FeatureOverlay o;
  for (const cc::LandmarkSighting& s : result.sightings) {
    if (o.points_px.size() >= core::features::FeatureOverlay::kMaxPoints) break;
    if (const auto p = view_->to_image(s.p_canon_px)) {
      o.points_px.emplace_back(static_cast<float>(p->x), static_cast<float>(p->y));
    }
  }
  return o;
}

CeilingMap CeilingTeacher::finish(const std::string& parameters_json) const {
  if (frames_.size() < 2) {
    throw std::runtime_error("ceiling teach: " + std::to_string(frames_.size()) +
                             " frame(s) taught, at least 2 needed");
  }
  CeilingMap out;
  out.mosaic = builder_.mosaic();
  if (out.mosaic.landmarks.empty()) {
    throw std::runtime_error(
        "ceiling teach: the mosaic kept no landmark (no ceiling texture seen with the head at " +
        std::to_string(setup_.camera.head_pitch_rad) + " rad?)");
  }
  const auto sightings = builder_.kept_sightings();
  const cc::RelaySelection relays = cc::select_relay_images(sightings, options_.relay);
  const auto& results = builder_.frames();

  // A pair of relay images that fails the paper's conditions (too few shared landmarks: the
  // ceiling was plain or hidden between them) is still one chain where the builder posed every
  // frame from the one to the other, by a fit or, through a loss, by the odometry prior, and
  // none was re-localised without the odometry: the two relay poses are consistent and the
  // replay drives between them on its own odometry where it finds no fix (linked). Only the
  // others, where the chain itself was cut, are breaks (docs/method/ceiling.md "The odometry as
  // the motion prior"). Runs of linked pairs are thinned to relay images spaced for arcs.
  const size_t n_relays = relays.relay_frames.size();
  if (n_relays < 2) {  // the selection keeps the first and the last of >= 2 frames
    throw std::runtime_error("ceiling teach: " + std::to_string(n_relays) +
                             " relay image(s) selected from " + std::to_string(frames_.size()) +
                             " frames, at least 2 needed");
  }
  std::vector<uint8_t> cut(n_relays - 1, 0), linked(n_relays - 1, 0);
  for (const size_t b : relays.breaks) {
    const size_t from = relays.relay_frames.at(b), to = relays.relay_frames.at(b + 1);
    bool chained = true;
    for (size_t f = from; f <= to && chained; ++f) {
      chained = results.at(f).localised && (f == from || !results.at(f).relocalised);
    }
    (chained ? linked : cut).at(b) = 1;
  }
  std::vector<cc::PlanarPose> relay_poses;
  for (const size_t f : relays.relay_frames) relay_poses.push_back(results.at(f).T_mosaic_base);
  const std::vector<size_t> kept = cc::thin_linked_relays(
      relay_poses, linked, options_.relay.linked_step_m, options_.relay.linked_step_rad);

  out.map.mode = core::NavMode::kCeiling;
  out.map.camera = camera_;
  out.map.parameters_json = parameters_json;
  for (size_t j = 0; j < kept.size(); ++j) {
    const size_t f = relays.relay_frames.at(kept[j]);
    const Kept& k = frames_.at(f);
    core::memory::KeyImage key;
    key.source_frame_index = static_cast<int64_t>(f);
    key.t_ns = k.t_ns;
    key.travelled_m = k.travelled_m;
    key.odom = k.odom;
    key.features = extractor_.extract(store_->get(f), core::features::kPartsAll);
    out.map.key_images.push_back(std::move(key));

    cc::RelayImageRecord rec;
    rec.frame = static_cast<int64_t>(f);
    rec.T_mosaic_base = results.at(f).T_mosaic_base;
    for (const auto& s : sightings.at(f)) rec.landmark_ids.push_back(s.id);
    out.tour.relay_images.push_back(std::move(rec));
    // A kept pair is a break where one of the selection's pairs it spans was cut.
    if (j + 1 < kept.size() &&
        std::any_of(cut.begin() + static_cast<std::ptrdiff_t>(kept[j]),
                    cut.begin() + static_cast<std::ptrdiff_t>(kept[j + 1]),
                    [](uint8_t c) { return c != 0; })) {
      out.tour.breaks.push_back(static_cast<int64_t>(j));
    }
  }
  out.tour.frames = static_cast<int64_t>(frames_.size());
  out.tour.ceiling = cc::TaughtCeiling{setup_.ceiling_height_m, setup_.camera.ceiling_above_cam_m};
  out.tour.unlocalised_frames = unlocalised_;
  const double first_m = frames_.front().travelled_m, last_m = frames_.back().travelled_m;
  out.tour.driven_m = std::isfinite(first_m) && std::isfinite(last_m) ? last_m - first_m : 0.0;

  // Drift indicator: the chained pose against the odometry (both from the first frame) at the
  // last localised frame. Neither is the truth: a large gap says one of them drifted.
  for (size_t i = results.size(); i-- > 0;) {
    if (!results[i].localised) continue;
    const auto& o0 = frames_.front().odom;
    const auto& oi = frames_[i].odom;
    if (o0 && oi) {
      const cc::PlanarPose T_0_i = cc::odometry_motion(*o0, *oi);
      out.tour.odometry_disagreement_m = std::hypot(T_0_i.x_m - results[i].T_mosaic_base.x_m,
                                                    T_0_i.y_m - results[i].T_mosaic_base.y_m);
    }
    break;
  }

  // The configured ceiling height against the odometry (core/ceiling/height_check.hpp).
  std::vector<std::optional<core::OdometryPose>> odometry;
  odometry.reserve(frames_.size());
  for (const Kept& k : frames_) odometry.push_back(k.odom);
  out.tour.height_check = cc::check_ceiling_height(
      cc::height_check_frames(results, odometry), setup_.cam_in_base_m, setup_.ceiling_height_m,
      setup_.camera.ceiling_above_cam_m, options_.height_check);
  return out;
}

}  // namespace pepper::app
