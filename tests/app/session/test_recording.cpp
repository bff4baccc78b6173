#include "session/recording.hpp"

#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "support/temp_dir.hpp"

namespace pepper::app {
namespace {

core::Frame make_frame(int i) {
  core::Frame f;
  f.gray = cv::Mat(48, 64, CV_8UC1, cv::Scalar(10 * i));
  f.gray.at<uint8_t>(5, 7) = 255;
  f.t_ns = 1'000'000'000LL + i * 66'666'667LL;
  f.index = i;
  return f;
}

TEST(Recording, WriteThenReadRoundTripKeepsPixelsStampsAndCommands) {
  test::TempDir tmp;
  const auto folder = tmp.path() / "rec";
  const auto camera = core::CameraIntrinsics::pepper_top_vga().scaled_to(64, 48);
  {
    RecordingWriter writer(folder, camera, "mock:test");
    for (int i = 0; i < 3; ++i) writer.append(make_frame(i), 0.15, -0.1 * i);
    EXPECT_EQ(writer.frame_count(), 3);
  }
  const Recording rec = read_recording(folder, std::nullopt);
  ASSERT_EQ(rec.frames.size(), 3u);
  EXPECT_TRUE(rec.warnings.empty());
  EXPECT_EQ(rec.source, "mock:test");
  EXPECT_NEAR(rec.camera.fx_px, camera.fx_px, 1e-9);
  EXPECT_EQ(rec.frames[2].t_ns, make_frame(2).t_ns);
  EXPECT_NEAR(rec.frames[2].omega_rad_s, -0.2, 1e-12);
  const core::Frame back = load_frame(rec, 1);
  EXPECT_EQ(cv::countNonZero(back.gray != make_frame(1).gray), 0);
  EXPECT_EQ(back.t_ns, make_frame(1).t_ns);
}

TEST(Recording, InterruptedIndexLineIsSkippedWithAWarning) {
  test::TempDir tmp;
  const auto folder = tmp.path() / "rec";
  {
    RecordingWriter writer(folder, core::CameraIntrinsics::pepper_top_vga(), "x");
    writer.append(make_frame(0), 0, 0);
    writer.append(make_frame(1), 0, 0);
  }
  {  // a crash in the middle of appending the third line
    std::ofstream out(folder / "frames.jsonl", std::ios::app);
    out << "{\"index\": 2, \"t_ns\": 12";
  }
  const Recording rec = read_recording(folder, std::nullopt);
  EXPECT_EQ(rec.frames.size(), 2u);
  ASSERT_EQ(rec.warnings.size(), 1u);
  EXPECT_NE(rec.warnings[0].find("incomplete"), std::string::npos);
}

TEST(Recording, CorruptLineInTheMiddleIsAnErrorNamingTheFile) {
  test::TempDir tmp;
  const auto folder = tmp.path() / "rec";
  {
    RecordingWriter writer(folder, core::CameraIntrinsics::pepper_top_vga(), "x");
    writer.append(make_frame(0), 0, 0);
  }
  {
    std::ofstream out(folder / "frames.jsonl", std::ios::app);
    out << "garbage\n{\"index\":1,\"file\":\"frames/000000.png\"}\n";
  }
  try {
    read_recording(folder, std::nullopt);
    FAIL() << "expected RecordingError";
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("frames.jsonl: line 2"), std::string::npos) << e.what();
  }
}

TEST(Recording, WrongVersionAndMissingFrameAreClearErrors) {
  test::TempDir tmp;
  const auto folder = tmp.path() / "rec";
  {
    RecordingWriter writer(folder, core::CameraIntrinsics::pepper_top_vga(), "x");
    writer.append(make_frame(0), 0, 0);
  }
  std::filesystem::remove(folder / "frames" / "000000.png");
  const Recording rec = read_recording(folder, std::nullopt);
  EXPECT_THROW(load_frame(rec, 0), RecordingError);
  {
    std::ofstream out(folder / "recording.json", std::ios::trunc);
    out << R"({"format":"pepper-recording","version":99})";
  }
  try {
    read_recording(folder, std::nullopt);
    FAIL();
  } catch (const RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("unsupported version 99"), std::string::npos) << e.what();
  }
}

// Format version 2 (issue 24): a teach says how it ran, so that map build rebuilds its map.
TEST(Recording, TeachSetupRoundTripsAndVersionOneHasNone) {
  test::TempDir tmp;
  const auto camera = core::CameraIntrinsics::pepper_top_vga().scaled_to(64, 48);
  RecordingSetup ceiling{core::NavMode::kCeiling, -0.7, RecordedCeiling{2.8, 1.63, -0.077, 0.001}};
  {
    RecordingWriter writer(tmp.path() / "ceiling", camera, "mock:test", "{}", ceiling);
    writer.append(make_frame(0), 0, 0);
  }
  const Recording rec = read_recording(tmp.path() / "ceiling", std::nullopt);
  EXPECT_EQ(rec.version, 2);
  ASSERT_TRUE(rec.setup.has_value());
  EXPECT_EQ(rec.setup->mode, core::NavMode::kCeiling);
  EXPECT_EQ(rec.setup->head_pitch_rad, -0.7);
  ASSERT_TRUE(rec.setup->ceiling.has_value());
  EXPECT_EQ(rec.setup->ceiling->height_m, 2.8);  // exact: JSON keeps every digit
  EXPECT_EQ(rec.setup->ceiling->above_camera_m, 1.63);
  EXPECT_EQ(rec.setup->ceiling->cam_in_base_x_m, -0.077);
  EXPECT_EQ(rec.setup->ceiling->cam_in_base_y_m, 0.001);
  {
    RecordingWriter writer(tmp.path() / "forward", camera, "mock:test", "{}",
                           RecordingSetup{core::NavMode::kForward, 0.0, std::nullopt});
    writer.append(make_frame(0), 0, 0);
  }
  const Recording fwd = read_recording(tmp.path() / "forward", std::nullopt);
  ASSERT_TRUE(fwd.setup.has_value());
  EXPECT_EQ(fwd.setup->mode, core::NavMode::kForward);
  EXPECT_FALSE(fwd.setup->ceiling.has_value());
  {  // replay's recordings say nothing
    RecordingWriter writer(tmp.path() / "replay", camera, "mock:test");
    writer.append(make_frame(0), 0, 0);
  }
  EXPECT_FALSE(read_recording(tmp.path() / "replay", std::nullopt).setup.has_value());
  // Version 1, written before issue 24: read, without a setup.
  {
    std::ofstream out(tmp.path() / "replay" / "recording.json", std::ios::trunc);
    out << R"({"format":"pepper-recording","version":1,"mode":"ceiling",)"
        << R"("camera":{"width_px":64,"height_px":48,"fx_px":60,"fy_px":60,"cx_px":32,)"
        << R"("cy_px":24},"config":{"robot":{"ceiling_height_m":2.5}}})";
  }
  const Recording v1 = read_recording(tmp.path() / "replay", std::nullopt);
  EXPECT_EQ(v1.version, 1);
  EXPECT_FALSE(v1.setup.has_value());
  EXPECT_EQ(v1.config["robot"]["ceiling_height_m"], 2.5);
  // A setup that disagrees with itself is not written.
  EXPECT_THROW(RecordingWriter(tmp.path() / "bad", camera, "x", "{}",
                               RecordingSetup{core::NavMode::kCeiling, -0.7, std::nullopt}),
               RecordingError);
}

TEST(Recording, MalformedSetupIsAClearError) {
  test::TempDir tmp;
  const auto folder = tmp.path() / "rec";
  {
    RecordingWriter writer(folder, core::CameraIntrinsics::pepper_top_vga(), "x", "{}",
                           RecordingSetup{core::NavMode::kCeiling, -0.7,
                                          RecordedCeiling{2.8, 1.6, 0.0, 0.0}});
    writer.append(make_frame(0), 0, 0);
  }
  std::ifstream in(folder / "recording.json");
  const nlohmann::json good = nlohmann::json::parse(in);
  const auto refused_with = [&](nlohmann::json m, const std::string& part) {
    std::ofstream(folder / "recording.json", std::ios::trunc) << m.dump();
    try {
      read_recording(folder, std::nullopt);
      ADD_FAILURE() << "read: " << m.dump();
    } catch (const RecordingError& e) {
      EXPECT_NE(std::string(e.what()).find("recording.json: "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  nlohmann::json m = good;
  m["mode"] = "up";
  refused_with(m, "mode \"up\"");
  m = good;
  m.erase("ceiling");
  refused_with(m, "mode ceiling needs");
  m = good;
  m["ceiling"]["above_camera_m"] = -1.0;
  refused_with(m, "above_camera_m must be > 0");
  m = good;
  m["ceiling"]["camera_in_base_m"].erase("x_m");
  refused_with(m, "finite numbers");
  m = good;
  m.erase("head_pitch_rad");
  refused_with(m, "head_pitch_rad");
}

TEST(Recording, PlainImageFolderNeedsCameraAndIsReadInNameOrder) {
  test::TempDir tmp;
  cv::Mat colour(30, 40, CV_8UC3, cv::Scalar(0, 0, 200));
  cv::imwrite((tmp.path() / "b.png").string(), colour);
  cv::imwrite((tmp.path() / "a.jpg").string(), colour);
  std::ofstream(tmp.path() / "notes.txt") << "not an image";
  EXPECT_THROW(read_recording(tmp.path(), std::nullopt), RecordingError);
  const auto camera = core::CameraIntrinsics::pepper_top_vga().scaled_to(40, 30);
  const Recording rec = read_recording(tmp.path(), camera, 10.0);
  ASSERT_EQ(rec.frames.size(), 2u);
  EXPECT_EQ(rec.frames[0].file.filename(), "a.jpg");
  EXPECT_EQ(rec.frames[1].t_ns, 100'000'000);
  const core::Frame f = load_frame(rec, 1);
  EXPECT_EQ(f.gray.type(), CV_8UC1);  // colour converted to grey
}

TEST(Recording, WriterRefusesANonEmptyFolder) {
  test::TempDir tmp;
  std::ofstream(tmp.path() / "keep.txt") << "x";
  EXPECT_THROW(RecordingWriter(tmp.path(), core::CameraIntrinsics::pepper_top_vga(), "x"),
               RecordingError);
}

}  // namespace
}  // namespace pepper::app
