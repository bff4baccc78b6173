#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "core/memory/visual_memory.hpp"

namespace pepper::core::memory {
namespace {
namespace fs = std::filesystem;

features::ImageFeatures synthetic_features(std::mt19937& rng, const CameraIntrinsics& cam) {
  features::ImageFeatures f;
  f.image_size = {cam.width_px, cam.height_px};
  f.intrinsics = cam;
  f.gray = cv::Mat(cam.height_px, cam.width_px, CV_8UC1);
  cv::randu(f.gray, 0, 255);
  std::uniform_real_distribution<float> u(0.f, 100.f);
  const int n_lines = 5 + static_cast<int>(rng() % 20);
  for (int i = 0; i < n_lines; ++i) {
    features::LineSegment l;
    l.p0_px = {u(rng), u(rng)};
    l.p1_px = {u(rng), u(rng)};
    l.p0_norm = cam.normalize(l.p0_px);
    l.p1_norm = cam.normalize(l.p1_px);
    l.line = {u(rng) * 0.01, u(rng) * 0.01};
    l.length_px = u(rng);
    f.lines.push_back(l);
  }
  f.line_descriptors = cv::Mat(n_lines, features::kLbdDims, CV_32F);
  cv::randu(f.line_descriptors, 0.f, 1.f);
  for (int i = 0; i < 40; ++i) f.corners_px.emplace_back(u(rng), u(rng));
  for (int i = 0; i < 30; ++i) {
    f.keypoints.emplace_back(u(rng), u(rng), 31.f, u(rng), u(rng) * 0.001f, i % 4, -1);
  }
  f.keypoint_descriptors = cv::Mat(30, 32, CV_8U);
  cv::randu(f.keypoint_descriptors, 0, 255);
  return f;
}

VisualMemory synthetic_map(int n) {
  std::mt19937 rng(42);
  VisualMemory map;
  map.camera = CameraIntrinsics::pepper_top_vga().scaled_to(80, 60);  // small: fast tests
  map.parameters_json = R"({"mapping":{"epsilon":40}})";
  for (int i = 0; i < n; ++i) {
    KeyImage k;
    k.source_frame_index = 10 * i;
    k.t_ns = 1'000'000'000LL + 2'000'000'000LL * i;
    k.features = synthetic_features(rng, map.camera);
    map.key_images.push_back(std::move(k));
  }
  return map;
}

uint32_t crc32(const std::vector<char>& b);  // the maps' checksum (below)

class VisualMemoryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::path(PEPPER_BINARY_DIR) / "test_tmp" /
            ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(root_);
    fs::create_directories(root_);
    dir_ = root_ / "map";
    map_ = synthetic_map(3);
    save_map(map_, dir_);
  }
  void TearDown() override { fs::remove_all(root_); }

  // Writes `j` as the map's manifest with a correct checksum: a map that passes the integrity
  // check and holds what the test put in it.
  void write_patched(nlohmann::json j) {
    j.erase("manifest_crc32");
    const std::string canon = j.dump();
    j["manifest_crc32"] = crc32(std::vector<char>(canon.begin(), canon.end()));
    const std::string text = j.dump(2);
    write(dir_ / "manifest.json", std::vector<char>(text.begin(), text.end()));
  }

  // Expects load_map to throw MapError of `kind` naming `file`.
  void expect_error(MapError::Kind kind, const fs::path& file, const LoadOptions& opt = {}) {
    try {
      load_map(dir_, opt);
      FAIL() << "no error for " << file;
    } catch (const MapError& e) {
      EXPECT_EQ(e.kind(), kind) << e.what();
      EXPECT_EQ(e.path().filename(), file.filename()) << e.what();
      EXPECT_NE(std::string(e.what()).find(file.filename().string()), std::string::npos);
    }
  }

  std::vector<char> read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  void write(const fs::path& p, const std::vector<char>& bytes) {
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }

  fs::path root_, dir_;
  VisualMemory map_;
};

TEST_F(VisualMemoryTest, RoundTripKeepsEverything) {
  const VisualMemory back = load_map(dir_);
  ASSERT_EQ(back.key_images.size(), map_.key_images.size());
  EXPECT_EQ(back.camera, map_.camera);
  EXPECT_EQ(nlohmann::json::parse(back.parameters_json)["mapping"]["epsilon"], 40);
  for (size_t i = 0; i < map_.key_images.size(); ++i) {
    const auto& a = map_.key_images[i];
    const auto& b = back.key_images[i];
    EXPECT_EQ(a.source_frame_index, b.source_frame_index);
    EXPECT_EQ(a.t_ns, b.t_ns);
    EXPECT_EQ(b.features.image_size, a.features.image_size);
    EXPECT_EQ(b.features.intrinsics, a.features.intrinsics);
    EXPECT_EQ(cv::norm(a.features.gray, b.features.gray, cv::NORM_INF), 0.0);
    ASSERT_EQ(a.features.lines.size(), b.features.lines.size());
    for (size_t l = 0; l < a.features.lines.size(); ++l) {
      EXPECT_EQ(a.features.lines[l].p0_px, b.features.lines[l].p0_px);
      EXPECT_EQ(a.features.lines[l].p1_norm, b.features.lines[l].p1_norm);
      EXPECT_EQ(a.features.lines[l].line.rho, b.features.lines[l].line.rho);
      EXPECT_EQ(a.features.lines[l].line.theta_rad, b.features.lines[l].line.theta_rad);
      EXPECT_EQ(a.features.lines[l].length_px, b.features.lines[l].length_px);
    }
    EXPECT_EQ(cv::norm(a.features.line_descriptors, b.features.line_descriptors, cv::NORM_INF), 0);
    EXPECT_EQ(a.features.corners_px, b.features.corners_px);
    ASSERT_EQ(a.features.keypoints.size(), b.features.keypoints.size());
    EXPECT_EQ(a.features.keypoints[3].pt, b.features.keypoints[3].pt);
    EXPECT_EQ(a.features.keypoints[3].octave, b.features.keypoints[3].octave);
    EXPECT_EQ(
        cv::norm(a.features.keypoint_descriptors, b.features.keypoint_descriptors, cv::NORM_INF),
        0);
  }
}

TEST_F(VisualMemoryTest, SummaryAndMapInfo) {
  const MapSummary s = read_map_info(dir_);
  EXPECT_EQ(s.key_image_count, 3);
  EXPECT_EQ(s.final_index, 2);
  EXPECT_DOUBLE_EQ(s.taught_duration_s, 4.0);  // (1 + 2*2) s - 1 s
  EXPECT_EQ(s.key_images[1].lines, static_cast<int>(map_.key_images[1].features.lines.size()));
  EXPECT_EQ(s.key_images[2].corners, 40);
  EXPECT_EQ(s.key_images[0].keypoints, 30);
  const MapSummary s2 = summarize(map_);
  EXPECT_EQ(s2.key_images[1].lines, s.key_images[1].lines);
  EXPECT_NE(s.to_text().find("key images: 3"), std::string::npos);
  EXPECT_NE(s.to_text().find("driven: unknown"), std::string::npos);
}

TEST_F(VisualMemoryTest, TruncatedFeaturesNamed) {
  auto bytes = read(dir_ / "key_0001.feat");
  bytes.resize(bytes.size() / 2);
  write(dir_ / "key_0001.feat", bytes);
  expect_error(MapError::Kind::kSizeMismatch, "key_0001.feat");
}

TEST_F(VisualMemoryTest, BitFlipsNamed) {
  auto feat = read(dir_ / "key_0002.feat");
  feat[feat.size() / 3] ^= 0x10;
  write(dir_ / "key_0002.feat", feat);
  expect_error(MapError::Kind::kChecksumMismatch, "key_0002.feat");
  feat[feat.size() / 3] ^= 0x10;
  write(dir_ / "key_0002.feat", feat);
  auto png = read(dir_ / "key_0000.png");
  png[png.size() / 2] ^= 0x01;
  write(dir_ / "key_0000.png", png);
  expect_error(MapError::Kind::kChecksumMismatch, "key_0000.png");
}

TEST_F(VisualMemoryTest, MissingFilesNamed) {
  fs::remove(dir_ / "key_0001.png");
  expect_error(MapError::Kind::kMissingFile, "key_0001.png");
  fs::remove(dir_ / "manifest.json");
  expect_error(MapError::Kind::kMissingFile, "manifest.json");
  EXPECT_THROW(load_map(root_ / "nowhere"), MapError);
}

TEST_F(VisualMemoryTest, WrongVersionNamed) {
  auto j = nlohmann::json::parse(read(dir_ / "manifest.json"));
  j["format_version"] = kMapFormatVersion + 1;
  const std::string text = j.dump(2);
  write(dir_ / "manifest.json", std::vector<char>(text.begin(), text.end()));
  expect_error(MapError::Kind::kWrongVersion, "manifest.json");
}

TEST_F(VisualMemoryTest, EditedOrCorruptManifestNamed) {
  auto j = nlohmann::json::parse(read(dir_ / "manifest.json"));
  j["key_images"][1]["t_ns"] = 5;  // a plausible edit: only the manifest CRC catches it
  std::string text = j.dump(2);
  write(dir_ / "manifest.json", std::vector<char>(text.begin(), text.end()));
  expect_error(MapError::Kind::kChecksumMismatch, "manifest.json");
  text = text.substr(0, text.size() / 2);  // truncated manifest: not JSON
  write(dir_ / "manifest.json", std::vector<char>(text.begin(), text.end()));
  expect_error(MapError::Kind::kMalformed, "manifest.json");
}

TEST_F(VisualMemoryTest, IntrinsicsMismatchNamed) {
  LoadOptions opt;
  opt.expected_camera = CameraIntrinsics::pepper_top_vga();  // the map's camera, other size
  EXPECT_NO_THROW(load_map(dir_, opt));
  opt.expected_camera->fx_px *= 1.01;
  expect_error(MapError::Kind::kIntrinsicsMismatch, "manifest.json", opt);
}

// The map records the camera's projection model and its coefficients (issue 31): a map taught
// through one model refuses a camera with another, and the message names both.
TEST_F(VisualMemoryTest, ProjectionModelIsRecordedAndAMismatchNamesBothModels) {
  const fs::path with_dir = root_ / "map_with_distortion";
  VisualMemory distorted = map_;
  distorted.camera.model = ProjectionModel::kWithDistortion;
  distorted.camera.kud = 0.031;
  distorted.camera.kdu = -0.0302;
  // Each key image's features carry the map's model (the feature file keeps the pinhole part).
  for (KeyImage& k : distorted.key_images) {
    k.features.intrinsics.model = distorted.camera.model;
    k.features.intrinsics.kud = distorted.camera.kud;
    k.features.intrinsics.kdu = distorted.camera.kdu;
  }
  save_map(distorted, with_dir);
  const VisualMemory back = load_map(with_dir);
  EXPECT_EQ(back.camera.model, ProjectionModel::kWithDistortion);
  EXPECT_DOUBLE_EQ(back.camera.kud, 0.031);
  EXPECT_DOUBLE_EQ(back.camera.kdu, -0.0302);
  for (const KeyImage& k : back.key_images) {  // given back to every key image's features
    EXPECT_EQ(k.features.intrinsics.model, ProjectionModel::kWithDistortion);
    EXPECT_DOUBLE_EQ(k.features.intrinsics.kud, 0.031);
    EXPECT_DOUBLE_EQ(k.features.intrinsics.kdu, -0.0302);
  }
  // A key image normalised through another model than the map's is not written.
  VisualMemory mixed = distorted;
  mixed.key_images[1].features.intrinsics.model = ProjectionModel::kWithoutDistortion;
  try {
    save_map(mixed, root_ / "mixed_models");
    FAIL() << "a key image of another camera model written";
  } catch (const MapError& e) {
    EXPECT_EQ(e.kind(), MapError::Kind::kInvalidMap) << e.what();
    EXPECT_NE(std::string(e.what()).find("key image 1"), std::string::npos) << e.what();
  }

  LoadOptions same;
  same.expected_camera = distorted.camera;
  EXPECT_NO_THROW(load_map(with_dir, same));
  LoadOptions pinhole;
  pinhole.expected_camera = map_.camera;  // same focal lengths and centre, no distortion
  for (const auto& [dir, opt] : {std::pair{with_dir, pinhole}, std::pair{dir_, same}}) {
    try {
      load_map(dir, opt);
      FAIL() << "a camera of another model accepted for " << dir;
    } catch (const MapError& e) {
      EXPECT_EQ(e.kind(), MapError::Kind::kIntrinsicsMismatch) << e.what();
      const std::string what = e.what();
      EXPECT_NE(what.find("perspectiveProjWithDistortion"), std::string::npos) << what;
      EXPECT_NE(what.find("perspectiveProjWithoutDistortion"), std::string::npos) << what;
    }
  }
  LoadOptions other_kud = same;
  other_kud.expected_camera->kud = 0.05;
  EXPECT_THROW(load_map(with_dir, other_kud), MapError);
}

// Every single-bit flip and every truncation of a features file ends in a MapError, never a
// crash; with the checksums of the manifest patched to agree (a "consistent" corruption), the
// feature decoder's own checks must catch it.
uint32_t crc32(const std::vector<char>& b) {
  uint32_t c = 0xFFFFFFFFu;
  for (char ch : b) {
    c ^= static_cast<uint8_t>(ch);
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

TEST_F(VisualMemoryTest, NoCrashOnAnyCorruptionOfAFeatureFile) {
  const fs::path feat = dir_ / "key_0001.feat";
  const auto original = read(feat);
  const auto manifest = nlohmann::json::parse(read(dir_ / "manifest.json"));
  auto patch_manifest = [&](const std::vector<char>& bytes) {
    auto j = manifest;
    j["key_images"][1]["features_bytes"] = bytes.size();
    j["key_images"][1]["features_crc32"] = crc32(bytes);
    j.erase("manifest_crc32");
    const std::string canon = j.dump();
    j["manifest_crc32"] = crc32(std::vector<char>(canon.begin(), canon.end()));
    const std::string text = j.dump(2);
    write(dir_ / "manifest.json", std::vector<char>(text.begin(), text.end()));
  };
  int errors = 0, cases = 0;
  const size_t stride = std::max<size_t>(1, original.size() / 150);
  for (size_t off = 0; off < original.size(); off += stride) {
    auto bytes = original;
    bytes[off] ^= static_cast<char>(1 << (off % 8));
    write(feat, bytes);
    patch_manifest(bytes);
    ++cases;
    try {
      load_map(dir_);
    } catch (const MapError& e) {
      ++errors;
      EXPECT_EQ(e.path().filename(), "key_0001.feat") << e.what();
    }
    // Same flip with the file's own trailing CRC-32 recomputed: the structure checks of the
    // decoder are the last line; the flip may hit plain data (loads) or a count/header (error).
    {
      const size_t body = bytes.size() - 4;
      if (off < body) {
        const uint32_t c =
            crc32(std::vector<char>(bytes.begin(), bytes.begin() + static_cast<long>(body)));
        std::memcpy(bytes.data() + body, &c, 4);
        write(feat, bytes);
        patch_manifest(bytes);
        try {
          load_map(dir_);
        } catch (const MapError& e) {
          EXPECT_EQ(e.path().filename(), "key_0001.feat") << e.what();
        }
      }
    }
    auto cut = std::vector<char>(original.begin(), original.begin() + static_cast<long>(off));
    write(feat, cut);
    patch_manifest(cut);
    ++cases;
    try {
      load_map(dir_);
    } catch (const MapError& e) {
      ++errors;
      EXPECT_EQ(e.path().filename(), "key_0001.feat") << e.what();
    }
  }
  EXPECT_EQ(errors, cases);  // every corruption detected (internal CRC or structure)
}

TEST_F(VisualMemoryTest, InterruptedSaveNeverLeavesALoadableHalfMap) {
  // A crash after writing some key images but before the manifest: the temporary folder has no
  // manifest, so it does not load; the previous map is untouched.
  const fs::path half = root_ / "map.tmp-1-0";
  fs::create_directories(half);
  fs::copy_file(dir_ / "key_0000.png", half / "key_0000.png");
  try {
    load_map(half);
    FAIL();
  } catch (const MapError& e) {
    EXPECT_EQ(e.kind(), MapError::Kind::kMissingFile);
    EXPECT_EQ(e.path().filename(), "manifest.json");
  }
  EXPECT_EQ(load_map(dir_).key_images.size(), 3u);
  // Saving over an existing map replaces it and leaves no temporary folder behind.
  save_map(synthetic_map(4), dir_);
  EXPECT_EQ(load_map(dir_).key_images.size(), 4u);
  int siblings = 0;
  for (const auto& e : fs::directory_iterator(root_)) siblings += e.path() != half ? 1 : 0;
  EXPECT_EQ(siblings, 1);
}

// A mode's own files (the ceiling mosaic and tour) are written by save_map's hook into the
// temporary folder: they replace the previous map's together with its key images, or, when the
// hook fails, nothing is replaced and no temporary folder is left.
TEST_F(VisualMemoryTest, ExtraFilesReplaceTheMapTogetherOrNotAtAll) {
  auto write_text = [&](const fs::path& p, const std::string& text) {
    write(p, std::vector<char>(text.begin(), text.end()));
  };
  save_map(synthetic_map(4), dir_, [&](const fs::path& tmp) {
    EXPECT_NE(tmp, dir_);
    EXPECT_TRUE(fs::exists(tmp / "manifest.json"));  // the hook runs once the map is written
    write_text(tmp / "extra.txt", "first");
  });
  EXPECT_EQ(load_map(dir_).key_images.size(), 4u);
  ASSERT_TRUE(fs::exists(dir_ / "extra.txt"));
  EXPECT_EQ(read(dir_ / "extra.txt"), std::vector<char>({'f', 'i', 'r', 's', 't'}));

  EXPECT_THROW(save_map(synthetic_map(5), dir_,
                        [&](const fs::path& tmp) {
                          write_text(tmp / "extra.txt", "second");
                          throw std::runtime_error("disk full");
                        }),
               std::runtime_error);
  EXPECT_EQ(load_map(dir_).key_images.size(), 4u);  // the previous map, whole
  EXPECT_EQ(read(dir_ / "extra.txt"), std::vector<char>({'f', 'i', 'r', 's', 't'}));
  int entries = 0;
  for (const auto& e : fs::directory_iterator(root_)) entries += e.path() != dir_ ? 1 : 0;
  EXPECT_EQ(entries, 0) << "a temporary folder was left beside the map";
}

// The distance driven during teach: kept to the bit when the map has it, NaN when it has not
// (maps saved before the field, plain image folders); a manifest that breaks its rules (some key
// images without it, a decrease) is malformed even with its CRC patched to agree.
TEST_F(VisualMemoryTest, TravelledDistanceRoundTripsOrIsUnknown) {
  EXPECT_TRUE(std::isnan(load_map(dir_).key_images[1].travelled_m));  // SetUp's map has none
  VisualMemory with = synthetic_map(3);
  const double travelled_m[] = {0.0, 0.4125, 0.9};
  for (int i = 0; i < 3; ++i) with.key_images[i].travelled_m = travelled_m[i];
  save_map(with, dir_);
  const VisualMemory back = load_map(dir_);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(back.key_images[i].travelled_m, travelled_m[i]);
  const MapSummary info = read_map_info(dir_);
  EXPECT_EQ(info.key_images[1].travelled_m, 0.4125);
  EXPECT_NE(info.to_text().find("driven: 0.90 m"), std::string::npos) << info.to_text();

  const auto manifest = nlohmann::json::parse(read(dir_ / "manifest.json"));
  auto decreasing = manifest;
  decreasing["key_images"][2]["travelled_m"] = 0.3;
  write_patched(decreasing);
  expect_error(MapError::Kind::kMalformed, "manifest.json");
  auto partial = manifest;
  partial["key_images"][2].erase("travelled_m");
  write_patched(partial);
  expect_error(MapError::Kind::kMalformed, "manifest.json");
  write_patched(manifest);  // the patching itself is sound
  EXPECT_EQ(load_map(dir_).key_images[2].travelled_m, 0.9);
}

// Each key image's odometry (issues 23, 29) round-trips exactly; a manifest without the field,
// as every map saved before it existed, loads with none; one key image may lack it (a frame whose
// reading failed); non-finite numbers are refused.
TEST_F(VisualMemoryTest, OdometryRoundTripsAndOldMapsLoadWithout) {
  VisualMemory with = synthetic_map(3);
  with.key_images[0].odom = OdometryPose{0.0, 0.0, 0.0};
  with.key_images[1].odom = OdometryPose{1.234567890123, -0.5, 3.0};
  // key image 2: none (its frame came without odometry)
  save_map(with, dir_);
  const VisualMemory back = load_map(dir_);
  ASSERT_TRUE(back.key_images[1].odom.has_value());
  EXPECT_EQ(back.key_images[1].odom->x_m, 1.234567890123);
  EXPECT_EQ(back.key_images[1].odom->y_m, -0.5);
  EXPECT_EQ(back.key_images[1].odom->yaw_rad, 3.0);
  ASSERT_TRUE(back.key_images[0].odom.has_value());
  EXPECT_FALSE(back.key_images[2].odom.has_value());
  EXPECT_EQ(read_map_info(dir_).key_images[1].odom->yaw_rad, 3.0);

  const auto manifest = nlohmann::json::parse(read(dir_ / "manifest.json"));
  auto old = manifest;  // a map from before the field: no "odom" anywhere
  for (auto& k : old["key_images"]) k.erase("odom");
  write_patched(old);
  const VisualMemory old_map = load_map(dir_);
  for (const KeyImage& k : old_map.key_images) EXPECT_FALSE(k.odom.has_value());
  EXPECT_EQ(old_map.key_images.size(), 3u);

  auto not_finite = manifest;
  not_finite["key_images"][1]["odom"]["y_m"] = "NaN";
  write_patched(not_finite);
  expect_error(MapError::Kind::kMalformed, "manifest.json");
  auto incomplete = manifest;
  incomplete["key_images"][1]["odom"].erase("yaw_rad");
  write_patched(incomplete);
  expect_error(MapError::Kind::kMalformed, "manifest.json");

  VisualMemory bad = synthetic_map(2);
  bad.key_images[1].odom = OdometryPose{0.0, std::numeric_limits<double>::infinity(), 0.0};
  EXPECT_THROW(save_map(bad, root_ / "bad_odom"), MapError);
  EXPECT_FALSE(fs::exists(root_ / "bad_odom"));
}

// The navigation mode (issue 24): recorded in the manifest and read back; a manifest without it
// (every map saved before the field) is a forward map; an unknown mode is malformed; a run of the
// other mode refuses the map, naming both modes, whatever its camera.
TEST_F(VisualMemoryTest, ModeRoundTripsOldMapsAreForwardAndTheOtherModeIsRefused) {
  EXPECT_EQ(load_map(dir_).mode, NavMode::kForward);  // the default
  VisualMemory ceiling = synthetic_map(2);
  ceiling.mode = NavMode::kCeiling;
  save_map(ceiling, dir_);
  EXPECT_EQ(load_map(dir_).mode, NavMode::kCeiling);
  EXPECT_EQ(summarize(load_map(dir_)).mode, NavMode::kCeiling);
  EXPECT_EQ(read_map_info(dir_).mode, NavMode::kCeiling);
  EXPECT_NE(read_map_info(dir_).to_text().find("mode: ceiling"), std::string::npos);
  LoadOptions ceiling_run;
  ceiling_run.expected_mode = NavMode::kCeiling;
  EXPECT_EQ(load_map(dir_, ceiling_run).key_images.size(), 2u);
  LoadOptions forward_run;
  forward_run.expected_mode = NavMode::kForward;
  forward_run.expected_camera = CameraIntrinsics::pepper_top_vga();  // the mode is checked first
  expect_error(MapError::Kind::kModeMismatch, "manifest.json", forward_run);
  try {
    load_map(dir_, forward_run);
  } catch (const MapError& e) {
    EXPECT_NE(std::string(e.what()).find("taught in ceiling mode"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("this run is in forward mode"), std::string::npos)
        << e.what();
  }
  EXPECT_STREQ(to_string(MapError::Kind::kModeMismatch), "mode_mismatch");

  const auto manifest = nlohmann::json::parse(read(dir_ / "manifest.json"));
  EXPECT_EQ(manifest.at("mode"), "ceiling");
  auto old = manifest;  // a map from before the field
  old.erase("mode");
  write_patched(old);
  EXPECT_EQ(load_map(dir_, forward_run).mode, NavMode::kForward);
  expect_error(MapError::Kind::kModeMismatch, "manifest.json", ceiling_run);
  for (const nlohmann::json& bad : {nlohmann::json("sideways"), nlohmann::json(1)}) {
    auto unknown = manifest;
    unknown["mode"] = bad;
    write_patched(unknown);
    expect_error(MapError::Kind::kMalformed, "manifest.json");
  }
}

TEST_F(VisualMemoryTest, InvalidMapsAreRefused) {
  EXPECT_THROW(save_map(synthetic_map(1), root_ / "one"), MapError);
  VisualMemory no_image = synthetic_map(2);
  no_image.key_images[1].features.gray.release();
  EXPECT_THROW(save_map(no_image, root_ / "no_image"), MapError);
  EXPECT_FALSE(fs::exists(root_ / "no_image"));
  VisualMemory partial = synthetic_map(2);  // travelled_m on one key image only
  partial.key_images[1].travelled_m = 1.0;
  EXPECT_THROW(save_map(partial, root_ / "partial"), MapError);
  VisualMemory decreasing = synthetic_map(2);
  decreasing.key_images[0].travelled_m = 1.0;
  decreasing.key_images[1].travelled_m = 0.5;
  EXPECT_THROW(save_map(decreasing, root_ / "decreasing"), MapError);
  EXPECT_FALSE(fs::exists(root_ / "decreasing"));
}

}  // namespace
}  // namespace pepper::core::memory
