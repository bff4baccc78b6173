// The ceiling mosaic's file: an exact round trip, and every corruption (missing, truncated, bit
// flips, edited fields with the CRC patched to agree, wrong format or version) refused with the
// file named; invalid mosaics are not saved.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>

#include "core/ceiling/mosaic.hpp"

namespace pepper::core::ceiling {
namespace {
namespace fs = std::filesystem;

uint32_t crc32(const std::string& b) {
  uint32_t c = 0xFFFFFFFFu;
  for (char ch : b) {
    c ^= static_cast<uint8_t>(ch);
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

Mosaic sample() {
  Mosaic m;
  m.px_per_m = 80.0;
  cv::RNG rng(7);
  for (int i = 0; i < 25; ++i) {
    MosaicLandmark l;
    l.id = 3 * i + 1;
    l.position_m = {rng.uniform(-5.0, 5.0), rng.uniform(-5.0, 5.0)};
    l.orientation_rad = rng.uniform(-3.14, 3.14);
    l.observations = 1 + i % 4;
    l.descriptor = cv::Mat(1, kMosaicDescriptorBytes, CV_8U);
    rng.fill(l.descriptor, cv::RNG::UNIFORM, 0, 256);
    m.landmarks.push_back(l);
  }
  return m;
}

class MosaicFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::path(PEPPER_BINARY_DIR) / "test_tmp" /
        ("mosaic_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    file_ = dir_ / "mosaic.json";
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string read() const {
    std::ifstream in(file_, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  void write(const std::string& text) const {
    std::ofstream(file_, std::ios::binary | std::ios::trunc) << text;
  }
  void write_patched(nlohmann::json j) const {
    j.erase("crc32");
    j["crc32"] = crc32(j.dump());
    write(j.dump());
  }
  void expect_refused(const std::string& what) const {
    SCOPED_TRACE(what);
    try {
      load_mosaic(file_);
      FAIL() << "loaded a corrupt mosaic";
    } catch (const MosaicError& e) {
      EXPECT_EQ(e.path(), file_);
      EXPECT_EQ(std::string(e.what()).rfind(file_.string(), 0), 0u) << e.what();
    }
  }
  fs::path dir_, file_;
};

TEST_F(MosaicFile, RoundTripIsExact) {
  const Mosaic m = sample();
  save_mosaic(m, file_);
  const Mosaic back = load_mosaic(file_);
  EXPECT_EQ(back.px_per_m, m.px_per_m);
  ASSERT_EQ(back.landmarks.size(), m.landmarks.size());
  for (size_t i = 0; i < m.landmarks.size(); ++i) {
    EXPECT_EQ(back.landmarks[i].id, m.landmarks[i].id);
    EXPECT_EQ(back.landmarks[i].position_m, m.landmarks[i].position_m);
    EXPECT_EQ(back.landmarks[i].orientation_rad, m.landmarks[i].orientation_rad);
    EXPECT_EQ(back.landmarks[i].observations, m.landmarks[i].observations);
    EXPECT_EQ(cv::norm(back.landmarks[i].descriptor, m.landmarks[i].descriptor, cv::NORM_INF), 0);
  }
  // Saving again replaces the file and leaves no temporary file beside it.
  save_mosaic(Mosaic{}, file_);
  EXPECT_TRUE(load_mosaic(file_).landmarks.empty());
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(MosaicFile, EveryCorruptionIsRefusedNamingTheFile) {
  save_mosaic(sample(), file_);
  const std::string good = read();
  fs::remove(file_);
  expect_refused("missing");
  for (size_t cut : {size_t{0}, size_t{1}, good.size() / 2, good.size() - 3}) {
    write(good.substr(0, cut));
    expect_refused("truncated to " + std::to_string(cut));
  }
  // Every 37th byte with one bit flipped: a parse error, a CRC mismatch or a bad field.
  for (size_t i = 0; i < good.size(); i += 37) {
    std::string flipped = good;
    flipped[i] = static_cast<char>(flipped[i] ^ 0x04);
    write(flipped);
    expect_refused("bit flip at " + std::to_string(i));
  }
  const auto j = nlohmann::json::parse(good);
  auto version = j;
  version["format_version"] = 2;
  write_patched(version);
  expect_refused("version 2");
  auto format = j;
  format["format"] = "pepper-visual-memory";
  write_patched(format);
  expect_refused("other format");
  auto duplicate = j;
  duplicate["landmarks"][1]["id"] = duplicate["landmarks"][0]["id"];
  write_patched(duplicate);
  expect_refused("duplicate id");
  auto short_descriptor = j;
  short_descriptor["landmarks"][2]["descriptor"] = "abcd";
  write_patched(short_descriptor);
  expect_refused("short descriptor");
  auto not_finite = j;
  not_finite["landmarks"][3]["x_m"] = nullptr;  // how JSON writes NaN
  write_patched(not_finite);
  expect_refused("x_m null");
  auto no_observation = j;
  no_observation["landmarks"][4]["observations"] = 0;
  write_patched(no_observation);
  expect_refused("observations 0");
  auto scale = j;
  scale["px_per_m"] = -1.0;
  write_patched(scale);
  expect_refused("negative scale");
  write_patched(j);  // the patching itself is sound
  EXPECT_EQ(load_mosaic(file_).landmarks.size(), 25u);
}

TEST_F(MosaicFile, InvalidMosaicsAreNotSaved) {
  Mosaic bad = sample();
  bad.landmarks[5].position_m.x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(save_mosaic(bad, file_), MosaicError);
  bad = sample();
  bad.landmarks[2].descriptor = cv::Mat(1, 16, CV_8U, cv::Scalar(0));
  EXPECT_THROW(save_mosaic(bad, file_), MosaicError);
  bad = sample();
  bad.landmarks[1].id = bad.landmarks[0].id;
  EXPECT_THROW(save_mosaic(bad, file_), MosaicError);
  EXPECT_FALSE(fs::exists(file_));
  EXPECT_THROW(save_mosaic(sample(), dir_ / "no_such_folder" / "mosaic.json"), MosaicError);
}

}  // namespace
}  // namespace pepper::core::ceiling
