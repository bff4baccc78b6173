// Ceiling teach memory (issue 24; docs/method/ceiling.md "Teach memory"): the CeilingTeacher
// keeps every frame's grey image in its frame store on disk (TeachFrameStore), not in RAM, and
// the map it makes is the one the images kept in memory give. One short scripted teach of the
// shipped worlds/robotics_room.yaml (QVGA, head at -0.7 rad, the scripted teach's first 220
// frames: 2.9 m of its first straight), rendered once and kept by the test, serves every test.
// The reference map is computed here from those in-memory frames by the pipeline the teacher ran
// before its frame store (canonical view, landmarks, MosaicBuilder, select_relay_images, the
// key images' features extracted from the frames themselves).
// Measured (one run, the [measured] lines): 798 landmarks, relay frames 0 75 179 219, identical;
// resident set +0.00-0.07 MB over 200 frames (+11.5-13.5 MB when the test kept clones of the
// images, as the teacher did before); PNGs 35.3 kB per QVGA frame, 134.2 kB per VGA frame
// (3.7 ms per VGA write); ~6 s for the suite.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/ceiling/canonical_view.hpp"
#include "core/ceiling/landmarks.hpp"
#include "core/ceiling/mosaic_builder.hpp"
#include "core/ceiling/observation.hpp"
#include "core/ceiling/relay_images.hpp"
#include "core/features/image_features.hpp"
#include "session/ceiling_teach.hpp"
#include "sim/mock_robot.hpp"
#include "sim/teach_driver.hpp"
#include "sim/world.hpp"
#include "support/temp_dir.hpp"

namespace pepper::app {
namespace {

namespace fs = std::filesystem;
namespace cc = core::ceiling;
using ::testing::HasSubstr;

constexpr int kWidthPx = 320, kHeightPx = 240;
constexpr double kPitchRad = -0.7;  // robot.ceiling_head_pitch_rad's default
constexpr size_t kFrames = 220;

struct Taught {
  std::vector<core::Frame> frames;  // the test's own copies
  std::vector<double> travelled_m;
  core::CameraIntrinsics camera;
  CeilingCameraSetup setup;
};

std::shared_ptr<const sim::World> room() {
  static const auto w = std::make_shared<const sim::World>(
      sim::load_world(fs::path(PEPPER_SOURCE_DIR) / "worlds" / "robotics_room.yaml"));
  return w;
}

// The scripted teach's drive (sim::TeachDriver on the world's scenario), as `teach --scripted`.
std::vector<core::Frame> render_teach(sim::MockRobot& robot, int width_px, int height_px,
                                      size_t frames) {
  robot.set_joint_angles({"HeadPitch"}, {kPitchRad});
  sim::TeachDriver driver(robot.world().scenario);
  std::vector<core::Frame> out;
  int64_t t0_ns = -1;
  while (out.size() < frames && !driver.done()) {
    core::Frame frame = robot.capture(width_px, height_px);
    if (t0_ns < 0) t0_ns = frame.t_ns;
    // A bridge may reuse its buffer; the odometry as the mock bridge reads it.
    frame.gray = frame.gray.clone();
    frame.odom = robot.odometry(sim::OdometrySource::kWheels);
    out.push_back(frame);
    robot.command_velocity(driver.command(robot.ground_truth().base, (frame.t_ns - t0_ns) * 1e-9));
  }
  robot.stop_move();
  return out;
}

const Taught& taught() {
  static const Taught* t = [] {
    auto* out = new Taught;
    sim::MockRobot robot(room());
    out->frames = render_teach(robot, kWidthPx, kHeightPx, kFrames);
    out->camera = robot.intrinsics(kWidthPx, kHeightPx);
    out->setup = ceiling_camera_of_mock(robot, out->camera, kPitchRad);
    double travelled_m = 0.0;  // along the odometry, as the teach's DriveOdometer roughly does
    for (size_t i = 0; i < out->frames.size(); ++i) {
      const auto& a = out->frames[i > 0 ? i - 1 : 0].odom;
      const auto& b = out->frames[i].odom;
      if (a && b) travelled_m += std::hypot(b->x_m - a->x_m, b->y_m - a->y_m);
      out->travelled_m.push_back(travelled_m);
    }
    return out;
  }();
  return *t;
}

void teach(CeilingTeacher& teacher, size_t frames) {
  const Taught& t = taught();
  for (size_t i = 0; i < frames; ++i) teacher.add_frame(t.frames[i], t.travelled_m[i]);
}

bool same_mat(const cv::Mat& a, const cv::Mat& b) {
  if (a.empty() || b.empty()) return a.empty() && b.empty();
  if (a.size() != b.size() || a.type() != b.type()) return false;
  const cv::Mat a1 = a.reshape(1), b1 = b.reshape(1);
  return cv::countNonZero(a1 != b1) == 0;
}

void expect_same_features(const core::features::ImageFeatures& got,
                          const core::features::ImageFeatures& want, size_t frame) {
  SCOPED_TRACE("relay frame " + std::to_string(frame));
  EXPECT_TRUE(same_mat(got.gray, want.gray)) << "the key image's pixels";
  ASSERT_EQ(got.keypoints.size(), want.keypoints.size());
  for (size_t i = 0; i < got.keypoints.size(); ++i) {
    EXPECT_EQ(got.keypoints[i].pt, want.keypoints[i].pt) << i;
    EXPECT_EQ(got.keypoints[i].angle, want.keypoints[i].angle) << i;
    EXPECT_EQ(got.keypoints[i].octave, want.keypoints[i].octave) << i;
  }
  EXPECT_TRUE(same_mat(got.keypoint_descriptors, want.keypoint_descriptors));
  ASSERT_EQ(got.lines.size(), want.lines.size());
  for (size_t i = 0; i < got.lines.size(); ++i) {
    EXPECT_EQ(got.lines[i].p0_px, want.lines[i].p0_px) << i;
    EXPECT_EQ(got.lines[i].p1_px, want.lines[i].p1_px) << i;
  }
  EXPECT_TRUE(same_mat(got.line_descriptors, want.line_descriptors));
  EXPECT_EQ(got.corners_px, want.corners_px);
}

// The resident set of this process, bytes (Linux /proc/self/statm, second field in pages).
int64_t resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  int64_t size_pages = 0, resident_pages = 0;
  statm >> size_pages >> resident_pages;
  return resident_pages * static_cast<int64_t>(::sysconf(_SC_PAGESIZE));
}

size_t files_in(const fs::path& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

// The main promise: the same relay frames, key images (pixels and features) and mosaic as the
// frames kept in memory give.
TEST(CeilingTeachMemory, MapIsTheOneTheImagesKeptInMemoryGive) {
  const Taught& t = taught();
  ASSERT_EQ(t.frames.size(), kFrames);
  const CeilingTeachOptions options;
  const core::features::FeatureExtractorOptions extractor_options;
  CeilingTeacher teacher(t.setup, t.camera, extractor_options, options);
  teach(teacher, t.frames.size());
  const CeilingMap cm = teacher.finish();

  // The reference: the pipeline over the frames in memory.
  const cc::CanonicalView view(
      t.setup.camera, cc::fit_frame(t.setup.camera, options.px_per_m, options.max_forward_m));
  cc::MosaicBuilderOptions builder_options = options.builder;
  builder_options.px_per_m = options.px_per_m;
  cc::MosaicBuilder builder(builder_options);
  for (const core::Frame& f : t.frames) {
    cv::Mat seen;
    const cv::Mat canonical = view.warp(f.gray, &seen);
    builder.add_frame(
        cc::observe(view, t.setup.cam_in_base_m, cc::extract_landmarks(canonical, seen)), f.odom);
  }
  const cc::RelaySelection relays =
      cc::select_relay_images(builder.kept_sightings(), options.relay);
  const core::features::FeatureExtractor extractor(t.camera, extractor_options);

  ASSERT_GE(relays.relay_frames.size(), 3u) << "a tour with relay images between its ends";
  ASSERT_EQ(cm.map.key_images.size(), relays.relay_frames.size());
  ASSERT_EQ(cm.tour.relay_images.size(), relays.relay_frames.size());
  for (size_t k = 0; k < relays.relay_frames.size(); ++k) {
    const size_t f = relays.relay_frames[k];
    const core::memory::KeyImage& key = cm.map.key_images[k];
    EXPECT_EQ(key.source_frame_index, static_cast<int64_t>(f));
    EXPECT_EQ(cm.tour.relay_images[k].frame, static_cast<int64_t>(f));
    EXPECT_EQ(key.t_ns, t.frames[f].t_ns);
    EXPECT_EQ(key.travelled_m, t.travelled_m[f]);
    ASSERT_TRUE(key.odom.has_value());
    EXPECT_EQ(key.odom->x_m, t.frames[f].odom->x_m);
    expect_same_features(key.features,
                         extractor.extract(t.frames[f].gray, core::features::kPartsAll), f);
  }
  std::vector<int64_t> breaks(relays.breaks.begin(), relays.breaks.end());
  EXPECT_EQ(cm.tour.breaks, breaks);
  EXPECT_EQ(cm.tour.frames, static_cast<int64_t>(t.frames.size()));
  const cc::Mosaic& want = builder.mosaic();
  ASSERT_EQ(cm.mosaic.landmarks.size(), want.landmarks.size());
  EXPECT_EQ(cm.mosaic.px_per_m, want.px_per_m);
  for (size_t i = 0; i < want.landmarks.size(); ++i) {
    EXPECT_EQ(cm.mosaic.landmarks[i].id, want.landmarks[i].id) << i;
    EXPECT_EQ(cm.mosaic.landmarks[i].position_m, want.landmarks[i].position_m) << i;
    EXPECT_EQ(cm.mosaic.landmarks[i].orientation_rad, want.landmarks[i].orientation_rad) << i;
    EXPECT_EQ(cm.mosaic.landmarks[i].observations, want.landmarks[i].observations) << i;
    EXPECT_TRUE(same_mat(cm.mosaic.landmarks[i].descriptor, want.landmarks[i].descriptor)) << i;
  }
  std::string frames_text;
  for (const size_t f : relays.relay_frames) frames_text += " " + std::to_string(f);
  std::printf("[measured] %zu frames (%.2f m), %zu landmarks, relay frames%s: identical\n",
              t.frames.size(), t.travelled_m.back(), want.landmarks.size(), frames_text.c_str());
}

// The teacher holds no image in RAM: its own per-frame record has no pixels, every image is a
// file once add_frame() returns, and the process does not grow by the images' size.
TEST(CeilingTeachMemory, HoldsNoImageInMemory) {
  const Taught& t = taught();
  // Before the frame store a record held a 76.8 kB QVGA image (307 kB at VGA).
  EXPECT_LE(CeilingTeacher::frame_record_bytes(), 128u);
  CeilingTeacher teacher(t.setup, t.camera, core::features::FeatureExtractorOptions{});
  constexpr size_t kWarmup = 20;  // the first frames allocate the pipeline's buffers
  teach(teacher, kWarmup);
  const int64_t rss_before = resident_bytes();
  uint64_t disk_before = teacher.frame_store_bytes();
  for (size_t i = kWarmup; i < t.frames.size(); ++i) {
    teacher.add_frame(t.frames[i], t.travelled_m[i]);
    const size_t seen = static_cast<size_t>(teacher.frames_seen());
    ASSERT_EQ(seen, i + 1);
    // The records: at most the vector's doubling over the frames, no image.
    ASSERT_LE(teacher.frame_records_bytes(), 2 * seen * CeilingTeacher::frame_record_bytes());
    ASSERT_GT(teacher.frame_store_bytes(), disk_before) << "frame " << i << " not on disk";
    disk_before = teacher.frame_store_bytes();
  }
  const int64_t rss_growth = resident_bytes() - rss_before;
  const size_t added = t.frames.size() - kWarmup;
  EXPECT_EQ(files_in(teacher.frame_store_dir()), t.frames.size());
  // Kept in RAM, the 200 images would be 200 x 76.8 kB = 15.4 MB on top of the builder's own
  // records (a few hundred kB); half of that bounds the growth with room for the allocator.
  const int64_t images_bytes = static_cast<int64_t>(added) * kWidthPx * kHeightPx;
  EXPECT_LT(rss_growth, images_bytes / 2) << "the process grew as if it kept the images";
  std::printf(
      "[measured] %zu frames: resident set %+.2f MB (kept images would be %.1f MB), records "
      "%zu B/frame, PNGs %.1f kB/frame at QVGA\n",
      added, rss_growth / 1e6, images_bytes / 1e6, CeilingTeacher::frame_record_bytes(),
      teacher.frame_store_bytes() / 1e3 / static_cast<double>(t.frames.size()));
}

// The folder goes with the teacher: after finish(), without finish(), when finish() throws.
TEST(CeilingTeachMemory, FrameStoreFolderIsRemovedWithTheTeacher) {
  const Taught& t = taught();
  const core::features::FeatureExtractorOptions extractor;
  fs::path dir;
  {
    CeilingTeacher teacher(t.setup, t.camera, extractor);
    dir = teacher.frame_store_dir();
    EXPECT_TRUE(fs::is_directory(dir)) << dir;
    EXPECT_EQ(dir.parent_path(), fs::temp_directory_path()) << "in $TMPDIR";
    EXPECT_THAT(dir.filename().string(), HasSubstr("pepper_ceiling_teach_"));
    teach(teacher, 30);
    EXPECT_EQ(files_in(dir), 30u);
    teacher.finish();
  }
  EXPECT_FALSE(fs::exists(dir)) << "after finish() and the teacher";
  {
    CeilingTeacher teacher(t.setup, t.camera, extractor);
    dir = teacher.frame_store_dir();
    teach(teacher, 10);
  }
  EXPECT_FALSE(fs::exists(dir)) << "without finish()";
  // Two teachers at once never share a folder.
  {
    CeilingTeacher a(t.setup, t.camera, extractor), b(t.setup, t.camera, extractor);
    EXPECT_NE(a.frame_store_dir(), b.frame_store_dir());
  }
  // finish() throws (one frame is no tour) and the exception leaves the teacher's scope.
  try {
    [&] {
      CeilingTeacher teacher(t.setup, t.camera, extractor);
      dir = teacher.frame_store_dir();
      teach(teacher, 1);
      teacher.finish();
    }();
    FAIL() << "a one-frame tour was finished";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("at least 2 needed"));
  }
  EXPECT_FALSE(fs::exists(dir)) << "when finish() threw";
  // ... and when it threw on a damaged frame store.
  try {
    [&] {
      CeilingTeacher teacher(t.setup, t.camera, extractor);
      dir = teacher.frame_store_dir();
      teach(teacher, 10);
      fs::remove(teacher.frame_store_dir() / "frame_00000000.png");
      teacher.finish();
    }();
    FAIL() << "a map was made without its first relay image";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("missing"));
  }
  EXPECT_FALSE(fs::exists(dir)) << "when finish() threw";
  // A teacher moved (std::optional in the teach session) keeps its one folder.
  {
    CeilingTeacher a(t.setup, t.camera, extractor);
    dir = a.frame_store_dir();
    CeilingTeacher b(std::move(a));
    EXPECT_EQ(b.frame_store_dir(), dir);
    EXPECT_TRUE(fs::is_directory(dir));
  }
  EXPECT_FALSE(fs::exists(dir)) << "after the moved teacher";
}

// Disk errors: a clear std::runtime_error naming the path, never a different map.
TEST(CeilingTeachMemory, DiskFailuresNameThePath) {
  const Taught& t = taught();
  const core::features::FeatureExtractorOptions extractor;
  const test::TempDir scratch("pepper_ceiling_memory_disk");
  const fs::path& scratch_dir = scratch.path();

  // The folder cannot be created: its parent is a file, or does not exist.
  const fs::path file = scratch_dir / "a_file";
  std::ofstream(file) << "not a folder\n";
  for (const fs::path& parent : {file, scratch_dir / "no_such_folder"}) {
    CeilingTeachOptions options;
    options.frame_store_parent = parent;
    try {
      CeilingTeacher teacher(t.setup, t.camera, extractor, options);
      ADD_FAILURE() << "a frame store in " << parent;
    } catch (const std::runtime_error& e) {
      EXPECT_THAT(e.what(), HasSubstr(parent.string())) << e.what();
      EXPECT_THAT(e.what(), HasSubstr("TMPDIR")) << e.what();
    }
  }
  // A parent given: the folder is made in it.
  {
    CeilingTeachOptions options;
    options.frame_store_parent = scratch_dir;
    CeilingTeacher teacher(t.setup, t.camera, extractor, options);
    EXPECT_EQ(teacher.frame_store_dir().parent_path(), scratch_dir);
  }

  // The folder deleted behind the teacher's back before finish().
  {
    CeilingTeacher teacher(t.setup, t.camera, extractor);
    teach(teacher, 40);
    const fs::path dir = teacher.frame_store_dir();
    fs::remove_all(dir);
    try {
      teacher.finish();
      ADD_FAILURE() << "a map without its frames";
    } catch (const std::runtime_error& e) {
      EXPECT_THAT(e.what(), HasSubstr((dir / "frame_00000000.png").string())) << e.what();
    }
    // Writing the next frame fails the same way, and the teacher stays as it was.
    try {
      teacher.add_frame(t.frames[40], t.travelled_m[40]);
      ADD_FAILURE() << "a frame written into a removed folder";
    } catch (const std::runtime_error& e) {
      EXPECT_THAT(e.what(), HasSubstr((dir / "frame_00000040.png").string())) << e.what();
      EXPECT_THAT(e.what(), HasSubstr("cannot write")) << e.what();
    }
    EXPECT_EQ(teacher.frames_seen(), 40);
  }

  // A relay image damaged on disk (truncated): refused, not read as another image.
  {
    CeilingTeacher teacher(t.setup, t.camera, extractor);
    teach(teacher, 40);
    const fs::path last = teacher.frame_store_dir() / "frame_00000039.png";  // always a relay
    fs::resize_file(last, fs::file_size(last) / 2);
    try {
      teacher.finish();
      ADD_FAILURE() << "a map from a truncated image";
    } catch (const std::runtime_error& e) {
      EXPECT_THAT(e.what(), HasSubstr(last.string())) << e.what();
    }
  }
}

// The store on its own: the pixels back bit for bit, and what the images cost on disk at VGA
// (the figure in docs/method/ceiling.md "Teach memory"; the QVGA one is printed above).
TEST(CeilingTeachMemory, FrameStoreGivesThePixelsBackAndItsCostAtVga) {
  sim::MockRobot robot(room());
  constexpr size_t kVgaFrames = 30;
  const std::vector<core::Frame> frames = render_teach(robot, 640, 480, kVgaFrames);
  ASSERT_EQ(frames.size(), kVgaFrames);
  fs::path dir;
  {
    TeachFrameStore store;
    dir = store.dir();
    const auto start = std::chrono::steady_clock::now();
    for (size_t i = 0; i < frames.size(); ++i) store.put(i, frames[i].gray);
    const double put_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count() /
        static_cast<double>(frames.size());
    for (size_t i = 0; i < frames.size(); ++i) {
      EXPECT_TRUE(same_mat(store.get(i), frames[i].gray)) << i;
    }
    // Written again: replaced, and the count stays the files'.
    const uint64_t bytes = store.bytes_on_disk();
    store.put(0, frames[0].gray);
    EXPECT_EQ(store.bytes_on_disk(), bytes);
    uint64_t on_disk = 0;
    for (const auto& e : fs::directory_iterator(dir)) on_disk += fs::file_size(e.path());
    EXPECT_EQ(on_disk, bytes);
    const double per_frame_kb = bytes / 1e3 / static_cast<double>(frames.size());
    std::printf(
        "[measured] VGA PNG %.1f kB/frame (raw 307.2 kB): %.0f MB per minute at 15 fps; "
        "%.1f ms per write\n",
        per_frame_kb, per_frame_kb * 15 * 60 / 1e3, put_ms);
    // An image of another kind or size is refused before anything is written.
    EXPECT_THROW(store.put(1, cv::Mat(240, 320, CV_8UC1, cv::Scalar(0))), std::invalid_argument);
    EXPECT_THROW(store.put(1, cv::Mat(480, 640, CV_8UC3, cv::Scalar(0))), std::invalid_argument);
    EXPECT_TRUE(same_mat(store.get(1), frames[1].gray));
  }
  EXPECT_FALSE(fs::exists(dir));
}

// The teach view's overlay (docs/teach_ui.md "Feature overlay"): every landmark of a frame's
// result drawn in the camera image where the canonical view says it was seen, inside the image.
TEST(CeilingTeachOverlay, DrawsTheFramesLandmarksWhereTheCameraSawThem) {
  const Taught& t = taught();
  const CeilingTeachOptions options;
  CeilingTeacher teacher(t.setup, t.camera, core::features::FeatureExtractorOptions{}, options);
  const cc::CanonicalView view(
      t.setup.camera, cc::fit_frame(t.setup.camera, options.px_per_m, options.max_forward_m));
  size_t drawn = 0;
  for (size_t i = 0; i < 40; ++i) {
    const cc::MosaicFrameResult r = teacher.add_frame(t.frames[i], t.travelled_m[i]);
    const core::features::FeatureOverlay o = teacher.overlay(r);
    EXPECT_TRUE(o.lines.empty());
    EXPECT_EQ(o.key_index, -1);
    ASSERT_EQ(o.points_px.size(),
              std::min(r.sightings.size(), core::features::FeatureOverlay::kMaxPoints))
        << "frame " << i;
    for (size_t k = 0; k < o.points_px.size(); ++k) {
      const cv::Point2f& p = o.points_px[k];
      EXPECT_GE(p.x, -1.0f);
      EXPECT_LE(p.x, static_cast<float>(kWidthPx));
      EXPECT_GE(p.y, -1.0f);
      EXPECT_LE(p.y, static_cast<float>(kHeightPx));
      const auto back = view.to_canonical(cv::Point2d(p.x, p.y));
      ASSERT_TRUE(back.has_value());
      EXPECT_NEAR(back->x, r.sightings[k].p_canon_px.x, 0.5) << "frame " << i << " point " << k;
      EXPECT_NEAR(back->y, r.sightings[k].p_canon_px.y, 0.5) << "frame " << i << " point " << k;
    }
    drawn += o.points_px.size();
  }
  EXPECT_GT(drawn, 40u * 10u) << "a ceiling with texture gives landmarks on every frame";
  // The teach panel's mosaic count is the map's.
  EXPECT_GT(teacher.mosaic_landmarks(), 0u);
  EXPECT_EQ(teacher.mosaic_landmarks(), teacher.finish().mosaic.landmarks.size());
}

}  // namespace
}  // namespace pepper::app
