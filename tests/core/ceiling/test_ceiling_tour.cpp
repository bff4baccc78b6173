// The ceiling tour's file (ceiling_tour.hpp): an exact round trip (with and without the odometry
// figure, with and without the height check), the taught ceiling recorded (and absent from a
// version-1 file), the height check (absent from a version-2 file), and corruption refused with
// the file named: missing, truncated, a changed number (CRC), another format or version, an
// edited field with the CRC patched to agree; invalid tours are not written.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "core/ceiling/ceiling_tour.hpp"
#include "support/temp_dir.hpp"

namespace pepper::core::ceiling {
namespace {
namespace fs = std::filesystem;

uint32_t crc32(const std::string& b) {  // independent of the library's (IEEE, reflected)
  uint32_t c = 0xFFFFFFFFu;
  for (char ch : b) {
    c ^= static_cast<uint8_t>(ch);
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

CeilingTour sample() {
  CeilingTour t;
  t.frames = 40;
  t.unlocalised_frames = 2;
  t.relay_images = {{0, {0.0, 0.0, 0.0}, {1, 2, 3, 5}},
                    {17, {1.25, -0.031, 0.0123}, {3, 5, 8}},
                    {39, {2.5, 0.4, 0.61}, {8, 13}}};
  t.breaks = {1};
  t.odometry_disagreement_m = 0.0421;
  t.driven_m = 2.61;
  t.ceiling = TaughtCeiling{2.75, 1.577};
  HeightCheck h;
  h.status = HeightCheckStatus::kEstimated;
  h.configured_height_m = 2.75;
  h.configured_above_camera_m = 1.577;
  h.windows = 17;
  h.windows_rejected = 1;
  h.windows_turning = 3;
  h.odometry_m = 12.31;
  h.scale_ratio = 1.0912;
  h.scale_ratio_spread = 0.0071;
  h.scale_ratio_sigma = 0.0017;
  h.estimated_above_camera_m = 1.577 / 1.0912;
  h.estimated_height_m = 2.75 - 1.577 + h.estimated_above_camera_m;
  h.estimated_sigma_m = 0.0023;
  h.disagrees = true;
  t.height_check = h;
  return t;
}

std::string read(const fs::path& f) {
  std::ifstream in(f, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void write(const fs::path& f, const std::string& s) {
  std::ofstream(f, std::ios::binary | std::ios::trunc) << s;
}

void expect_refused(const fs::path& file, const std::string& what) {
  try {
    load_ceiling_tour(file);
    ADD_FAILURE() << "loaded: " << what;
  } catch (const CeilingTourError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(file.string() + ": ", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    EXPECT_EQ(e.path(), file);
  }
}

TEST(CeilingTourFile, RoundTripIsExact) {
  test::TempDir dir("ceiling_tour");
  const fs::path f = dir.path() / "ceiling_tour.json";
  for (const bool with_odometry : {true, false}) {
    CeilingTour t = sample();
    if (!with_odometry) {
      t.odometry_disagreement_m.reset();
      t.height_check->status = HeightCheckStatus::kNoOdometry;
      t.height_check->windows = 0;
      t.height_check->scale_ratio = 0.0;
      t.height_check->disagrees = false;
    }
    save_ceiling_tour(t, f);
    const CeilingTour back = load_ceiling_tour(f);
    EXPECT_EQ(back.frames, t.frames);
    EXPECT_EQ(back.unlocalised_frames, t.unlocalised_frames);
    ASSERT_EQ(back.relay_images.size(), t.relay_images.size());
    for (size_t i = 0; i < t.relay_images.size(); ++i) {
      EXPECT_EQ(back.relay_images[i].frame, t.relay_images[i].frame);
      EXPECT_EQ(back.relay_images[i].T_mosaic_base.x_m, t.relay_images[i].T_mosaic_base.x_m);
      EXPECT_EQ(back.relay_images[i].T_mosaic_base.y_m, t.relay_images[i].T_mosaic_base.y_m);
      EXPECT_EQ(back.relay_images[i].T_mosaic_base.theta_rad,
                t.relay_images[i].T_mosaic_base.theta_rad);
      EXPECT_EQ(back.relay_images[i].landmark_ids, t.relay_images[i].landmark_ids);
    }
    EXPECT_EQ(back.breaks, t.breaks);
    EXPECT_EQ(back.odometry_disagreement_m, t.odometry_disagreement_m);
    EXPECT_EQ(back.driven_m, t.driven_m);
    ASSERT_TRUE(back.ceiling.has_value());
    EXPECT_EQ(back.ceiling->height_m, 2.75);
    EXPECT_EQ(back.ceiling->above_camera_m, 1.577);
    ASSERT_TRUE(back.height_check.has_value());
    const HeightCheck& h = *back.height_check;
    const HeightCheck& want = *t.height_check;
    EXPECT_EQ(h.status, want.status);
    EXPECT_EQ(h.configured_height_m, want.configured_height_m);
    EXPECT_EQ(h.configured_above_camera_m, want.configured_above_camera_m);
    EXPECT_EQ(h.windows, want.windows);
    EXPECT_EQ(h.windows_rejected, want.windows_rejected);
    EXPECT_EQ(h.windows_turning, want.windows_turning);
    EXPECT_EQ(h.odometry_m, want.odometry_m);
    EXPECT_EQ(h.scale_ratio, want.scale_ratio);
    EXPECT_EQ(h.scale_ratio_spread, want.scale_ratio_spread);
    EXPECT_EQ(h.scale_ratio_sigma, want.scale_ratio_sigma);
    EXPECT_EQ(h.estimated_above_camera_m, want.estimated_above_camera_m);
    EXPECT_EQ(h.estimated_height_m, want.estimated_height_m);
    EXPECT_EQ(h.estimated_sigma_m, want.estimated_sigma_m);
    EXPECT_EQ(h.disagrees, want.disagrees);
  }
  {  // not checked at all
    CeilingTour t = sample();
    t.height_check.reset();
    save_ceiling_tour(t, f);
    EXPECT_FALSE(load_ceiling_tour(f).height_check.has_value());
  }
  // No temporary file left beside it.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

TEST(CeilingTourFile, CorruptionIsRefusedNamingTheFile) {
  test::TempDir dir("ceiling_tour");
  const fs::path f = dir.path() / "ceiling_tour.json";
  expect_refused(f, "missing");
  save_ceiling_tour(sample(), f);
  const std::string good = read(f);

  write(f, good.substr(0, good.size() / 2));
  expect_refused(f, "not valid JSON");

  std::string changed = good;
  const size_t at = changed.find("2.61");
  ASSERT_NE(at, std::string::npos);
  changed.replace(at, 4, "2.62");
  write(f, changed);
  expect_refused(f, "CRC-32 mismatch");

  // Edited fields with the CRC patched to agree: the validation names the field.
  auto patched = [&](const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json j = nlohmann::json::parse(good);
    edit(j);
    j.erase("crc32");
    j["crc32"] = crc32(j.dump());
    write(f, j.dump());
  };
  patched([](nlohmann::json& j) { j["format_version"] = 4; });
  expect_refused(f, "format version 4");
  patched([](nlohmann::json& j) { j["format"] = "pepper-ceiling-mosaic"; });
  expect_refused(f, "not a ceiling tour file");
  patched([](nlohmann::json& j) { j["relay_images"][1]["frame"] = 0; });
  expect_refused(f, "frames must increase");
  patched([](nlohmann::json& j) { j["relay_images"][2]["frame"] = 40; });
  expect_refused(f, "outside the tour's frames");
  patched([](nlohmann::json& j) { j["breaks"] = {2}; });
  expect_refused(f, "break 2 names no pair");
  patched([](nlohmann::json& j) { j["unlocalised_frames"] = 41; });
  expect_refused(f, "unlocalised_frames 41");
  patched([](nlohmann::json& j) { j["relay_images"][0]["x_m"] = "zero"; });
  expect_refused(f, "missing or mistyped field");
  patched([](nlohmann::json& j) { j["odometry_disagreement_m"] = -0.1; });
  expect_refused(f, "odometry_disagreement_m");
  patched([](nlohmann::json& j) { j["ceiling"]["above_camera_m"] = 3.0; });
  expect_refused(f, "ceiling: above_camera_m");
  patched([](nlohmann::json& j) { j.erase("ceiling"); });
  expect_refused(f, "missing or mistyped field");
  patched([](nlohmann::json& j) { j.erase("height_check"); });
  expect_refused(f, "missing or mistyped field");
  patched([](nlohmann::json& j) { j["height_check"]["status"] = "guessed"; });
  expect_refused(f, "unknown height check status");
  patched([](nlohmann::json& j) { j["height_check"]["scale_ratio"] = -1.0; });
  expect_refused(f, "height_check: scale_ratio");
  patched([](nlohmann::json& j) { j["height_check"]["windows"] = -2; });
  expect_refused(f, "height_check: window counts");
}

// A tour written before the height check (format version 2) still loads, without it.
TEST(CeilingTourFile, VersionTwoLoadsWithoutTheHeightCheck) {
  test::TempDir dir("ceiling_tour");
  const fs::path f = dir.path() / "ceiling_tour.json";
  save_ceiling_tour(sample(), f);
  nlohmann::json j = nlohmann::json::parse(read(f));
  j["format_version"] = 2;
  j.erase("height_check");
  j.erase("crc32");
  j["crc32"] = crc32(j.dump());
  write(f, j.dump());
  const CeilingTour back = load_ceiling_tour(f);
  EXPECT_FALSE(back.height_check.has_value());
  ASSERT_TRUE(back.ceiling.has_value());
  EXPECT_EQ(back.ceiling->height_m, 2.75);
}

// A tour written before the ceiling was recorded (format version 1) still loads, without it.
TEST(CeilingTourFile, VersionOneLoadsWithoutTheCeiling) {
  test::TempDir dir("ceiling_tour");
  const fs::path f = dir.path() / "ceiling_tour.json";
  save_ceiling_tour(sample(), f);
  nlohmann::json j = nlohmann::json::parse(read(f));
  ASSERT_EQ(j.at("format_version"), kCeilingTourFormatVersion);
  j["format_version"] = 1;
  j.erase("ceiling");
  j.erase("height_check");
  j.erase("crc32");
  j["crc32"] = crc32(j.dump());
  write(f, j.dump());
  const CeilingTour back = load_ceiling_tour(f);
  EXPECT_FALSE(back.ceiling.has_value());
  EXPECT_EQ(back.relay_images.size(), 3u);
}

TEST(CeilingTourFile, InvalidToursAreNotWritten) {
  test::TempDir dir("ceiling_tour");
  const fs::path f = dir.path() / "ceiling_tour.json";
  CeilingTour one = sample();
  one.relay_images.resize(1);
  one.breaks.clear();
  EXPECT_THROW(save_ceiling_tour(one, f), CeilingTourError);
  CeilingTour nan_pose = sample();
  nan_pose.relay_images[1].T_mosaic_base.y_m = std::nan("");
  EXPECT_THROW(save_ceiling_tour(nan_pose, f), CeilingTourError);
  EXPECT_FALSE(fs::exists(f));
}

}  // namespace
}  // namespace pepper::core::ceiling
