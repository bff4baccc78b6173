// Intrinsics files: ViSP camera XML (shipped file and files written here), YAML and JSON.
#include "core/camera/intrinsics_io.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "core/camera/distortion.hpp"

namespace pepper::core::camera {
namespace {

const std::string kXml = std::string(PEPPER_SOURCE_DIR) + "/tests/core/camera/data/pepper_top_qvga.xml";

std::string temp_file(const std::string& name, const std::string& content) {
  const auto dir = std::filesystem::temp_directory_path() / "pepper_intrinsics_io_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path) << content;
  return path;
}

TEST(IntrinsicsIo, VispXmlFirstCameraWithoutDistortion) {
  const CameraIntrinsics k =
      load_visp_camera_xml(kXml, "", 0, 0, ProjectionModel::kWithoutDistortion);
  EXPECT_EQ(k.width_px, 320);
  EXPECT_EQ(k.height_px, 240);
  EXPECT_DOUBLE_EQ(k.fx_px, 298.13);
  EXPECT_DOUBLE_EQ(k.fy_px, 298.72);
  EXPECT_DOUBLE_EQ(k.cx_px, 159.15);
  EXPECT_DOUBLE_EQ(k.cy_px, 118.91);
  // Normalisation by hand: ((100 - 159.15) / 298.13, (50 - 118.91) / 298.72).
  const cv::Point2d n = k.normalize({100.0, 50.0});
  EXPECT_NEAR(n.x, -0.198403381, 1e-9);
  EXPECT_NEAR(n.y, -0.230684253, 1e-9);
  // No model asked: the first camera's model with distortion (it has both).
  const CameraIntrinsics d = load_visp_camera_xml(kXml);
  EXPECT_EQ(d.model, ProjectionModel::kWithDistortion);
  EXPECT_DOUBLE_EQ(d.kud, 0.03);
}

TEST(IntrinsicsIo, VispXmlSelectsBySizeAndName) {
  const CameraIntrinsics vga = load_visp_camera_xml(kXml, "Camera", 640, 480);
  EXPECT_DOUBLE_EQ(vga.fx_px, 596.26);
  EXPECT_DOUBLE_EQ(vga.cy_px, 238.32);
  EXPECT_EQ(vga, CameraIntrinsics::pepper_top_vga());
  const CameraIntrinsics bottom = load_visp_camera_xml(kXml, "bottom");
  EXPECT_DOUBLE_EQ(bottom.fx_px, 280.0);
  EXPECT_DOUBLE_EQ(bottom.cx_px, 160.5);
}

TEST(IntrinsicsIo, DispatchOnExtension) { EXPECT_EQ(load_intrinsics(kXml), load_visp_camera_xml(kXml)); }

TEST(IntrinsicsIo, ErrorsNameTheFile) {
  const std::string missing = "/nonexistent/dir/camera.xml";
  try {
    load_intrinsics(missing);
    FAIL() << "expected IntrinsicsFileError";
  } catch (const IntrinsicsFileError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos);
    EXPECT_EQ(e.path(), missing);
  }
  const std::string corrupt = temp_file("corrupt.xml", "<root><camera><name>x</name>");
  EXPECT_THROW(load_visp_camera_xml(corrupt), IntrinsicsFileError);
  try {
    load_visp_camera_xml(kXml, "nosuchcamera");
    FAIL();
  } catch (const IntrinsicsFileError& e) {
    EXPECT_NE(std::string(e.what()).find("nosuchcamera"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find(kXml), std::string::npos);
  }
  EXPECT_THROW(load_visp_camera_xml(kXml, "", 1024, 768), IntrinsicsFileError);
  const std::string bad_number = temp_file(
      "bad_number.xml",
      "<root><camera><name>c</name><image_width>320</image_width><image_height>240</image_height>"
      "<model><type>perspectiveProjWithoutDistortion</type><px>abc</px><py>1</py><u0>1</u0>"
      "<v0>1</v0></model></camera></root>");
  try {
    load_visp_camera_xml(bad_number);
    FAIL();
  } catch (const IntrinsicsFileError& e) {
    EXPECT_NE(std::string(e.what()).find("<px> is not a number: 'abc'"), std::string::npos) << e.what();
  }
  const std::string negative = temp_file(
      "negative.xml",
      "<root><camera><name>c</name><image_width>320</image_width><image_height>240</image_height>"
      "<model><type>perspectiveProjWithoutDistortion</type><px>-5</px><py>1</py><u0>1</u0>"
      "<v0>1</v0></model></camera></root>");
  try {
    load_visp_camera_xml(negative);
    FAIL();
  } catch (const IntrinsicsFileError& e) {
    EXPECT_NE(std::string(e.what()).find("fx_px"), std::string::npos);
  }
}

// Written by ViSP 3.5's own vpXmlParserCamera::save (Debian libvisp-core3.5), camera "CameraTop"
// at 320x240: first initPersProjWithDistortion(298.1, 298.7, 159.1, 118.9, kud 0.031,
// kdu -0.0302), then initPersProjWithoutDistortion(298.1, 298.7, 159.1, 118.9) into the same file.
const std::string kVispWritten =
    std::string(PEPPER_SOURCE_DIR) + "/tests/core/camera/data/visp_written_with_distortion.xml";

TEST(IntrinsicsIo, FileWrittenByViSPWithDistortion) {
  const CameraIntrinsics d =
      load_visp_camera_xml(kVispWritten, "CameraTop", 0, 0, ProjectionModel::kWithDistortion);
  EXPECT_EQ(d.model, ProjectionModel::kWithDistortion);
  EXPECT_EQ(d.width_px, 320);
  EXPECT_EQ(d.height_px, 240);
  EXPECT_DOUBLE_EQ(d.fx_px, 298.1);
  EXPECT_DOUBLE_EQ(d.fy_px, 298.7);
  EXPECT_DOUBLE_EQ(d.cx_px, 159.1);
  EXPECT_DOUBLE_EQ(d.cy_px, 118.9);
  EXPECT_DOUBLE_EQ(d.kud, 0.031);
  EXPECT_DOUBLE_EQ(d.kdu, -0.0302);
  // The pinhole model when asked for.
  const CameraIntrinsics p =
      load_visp_camera_xml(kVispWritten, "CameraTop", 0, 0, ProjectionModel::kWithoutDistortion);
  EXPECT_EQ(p.model, ProjectionModel::kWithoutDistortion);
  EXPECT_EQ(p.kud, 0.0);
  EXPECT_DOUBLE_EQ(p.fx_px, 298.1);
  // No model asked: the one with distortion, since the features are undistorted through it
  // (intrinsics_io.hpp).
  EXPECT_EQ(load_intrinsics(kVispWritten), d);
}

TEST(IntrinsicsIo, BothModelsRoundTripThroughViSP) {
  const std::string path = temp_file("round_trip.xml", "");
  std::filesystem::remove(path);  // ViSP adds to an existing file; start from none
  CameraIntrinsics with = CameraIntrinsics::pepper_top_vga();
  with.model = ProjectionModel::kWithDistortion;
  with.kud = 0.0297;
  with.kdu = -0.0288;
  with.fx_px = 595.5;  // a distortion fit has its own focal lengths
  const CameraIntrinsics without = CameraIntrinsics::pepper_top_vga();
  save_visp_camera_xml(with, path, "CameraTop");
  save_visp_camera_xml(without, path, "CameraTop");
  EXPECT_EQ(load_visp_camera_xml(path, "CameraTop", 640, 480, ProjectionModel::kWithDistortion), with);
  EXPECT_EQ(load_visp_camera_xml(path, "CameraTop", 640, 480, ProjectionModel::kWithoutDistortion),
            without);
  EXPECT_EQ(load_visp_camera_xml(path), with);  // the model with distortion when not named
  // ViSP does not overwrite a model: say so rather than keep the old values silently.
  try {
    save_visp_camera_xml(with, path, "CameraTop");
    FAIL() << "second write of the same model accepted";
  } catch (const IntrinsicsFileError& e) {
    EXPECT_NE(std::string(e.what()).find("already holds"), std::string::npos) << e.what();
  }
  // A file with only the distortion model: read, and recorded as such.
  const std::string only = temp_file("only_distortion.xml", "");
  std::filesystem::remove(only);
  save_visp_camera_xml(with, only, "CameraTop");
  EXPECT_EQ(load_intrinsics(only), with);
}

TEST(IntrinsicsIo, ShippedPepperCalibrationLoadsAtBothSizes) {
  const std::string shipped = std::string(PEPPER_SOURCE_DIR) + "/cameras/pepper_top.xml";
  constexpr auto kPinhole = ProjectionModel::kWithoutDistortion;
  const CameraIntrinsics vga = load_visp_camera_xml(shipped, "CameraTop", 640, 480, kPinhole);
  EXPECT_EQ(vga, CameraIntrinsics::pepper_top_vga());
  const CameraIntrinsics qvga = load_visp_camera_xml(shipped, "CameraTop", 320, 240, kPinhole);
  EXPECT_DOUBLE_EQ(qvga.fx_px, 298.13);
  EXPECT_DOUBLE_EQ(qvga.cy_px, 118.91);
  // With distortion (the default when no model is named): the calibration's own fit, kud about
  // 0.03 (PEPPER.md), the same lens coefficients at both sizes (normalised units), and VGA is
  // QVGA scaled about pixel centres (to the file's 4 decimals).
  const CameraIntrinsics lens_qvga = load_visp_camera_xml(shipped, "CameraTop", 320, 240);
  const CameraIntrinsics lens_vga = load_visp_camera_xml(shipped, "CameraTop", 640, 480);
  for (const CameraIntrinsics& k : {lens_qvga, lens_vga}) {
    EXPECT_EQ(k.model, ProjectionModel::kWithDistortion);
    EXPECT_TRUE(k.validate().empty());
    EXPECT_NEAR(k.kud, 0.0275, 1e-4);
    EXPECT_NEAR(k.kdu, -0.0274, 1e-4);
  }
  EXPECT_EQ(lens_qvga.width_px, 320);
  EXPECT_EQ(lens_vga.width_px, 640);
  EXPECT_DOUBLE_EQ(lens_qvga.fx_px, 300.0232);
  // The core's constant for the same calibration (what `evaluate --lens pepper` renders with).
  const CameraIntrinsics constant = CameraIntrinsics::pepper_top_vga_with_distortion();
  EXPECT_EQ(constant.model, lens_vga.model);
  EXPECT_EQ(constant.kud, lens_vga.kud);
  EXPECT_EQ(constant.kdu, lens_vga.kdu);
  EXPECT_NEAR(constant.fx_px, lens_vga.fx_px, 1e-9);
  EXPECT_NEAR(constant.fy_px, lens_vga.fy_px, 1e-9);
  EXPECT_NEAR(constant.cx_px, lens_vga.cx_px, 1e-9);
  EXPECT_NEAR(constant.cy_px, lens_vga.cy_px, 1e-9);
  const CameraIntrinsics scaled = lens_qvga.scaled_to(640, 480);
  EXPECT_NEAR(lens_vga.fx_px, scaled.fx_px, 1e-4);
  EXPECT_NEAR(lens_vga.fy_px, scaled.fy_px, 1e-4);
  EXPECT_NEAR(lens_vga.cx_px, scaled.cx_px, 1e-4);
  EXPECT_NEAR(lens_vga.cy_px, scaled.cy_px, 1e-4);
  EXPECT_EQ(lens_vga.kud, lens_qvga.kud);
  EXPECT_EQ(lens_vga.kdu, lens_qvga.kdu);
  // The two fits of one lens agree: undistorting then distorting the image's corner returns it
  // within a quarter of a pixel (measured 0.15 px at VGA: kud and kdu are separate fits, not
  // exact inverses, core/camera/distortion.hpp).
  const cv::Point2d corner_px(0.0, 0.0);
  const cv::Point2d back =
      camera::norm_to_pixel(lens_vga, camera::pixel_to_norm(lens_vga, corner_px));
  EXPECT_LT(cv::norm(back - corner_px), 0.25);
  EXPECT_EQ(load_intrinsics(shipped), lens_qvga);  // the first camera of the file
}

TEST(IntrinsicsIo, MalformedXmlNamesTheFileAndTheCause) {
  const std::string broken = temp_file(
      "broken.xml", "<root>\n<camera><name>CameraTop</name>\n<model><px>3</model></camera></root>\n");
  try {
    load_intrinsics(broken);
    FAIL() << "malformed XML accepted";
  } catch (const IntrinsicsFileError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(broken, 0), 0u) << what;  // starts with the path
    EXPECT_NE(what.find("not a well-formed XML file"), std::string::npos) << what;
    EXPECT_NE(what.find("line 3"), std::string::npos) << what;
  }
  const std::string not_visp = temp_file("not_visp.xml", "<opencv_storage><a>1</a></opencv_storage>");
  try {
    load_intrinsics(not_visp);
    FAIL() << "non-ViSP XML accepted";
  } catch (const IntrinsicsFileError& e) {
    EXPECT_NE(std::string(e.what()).find(not_visp), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("<root>"), std::string::npos) << e.what();
  }
  try {
    load_visp_camera_xml(kXml, "bottom", 0, 0, ProjectionModel::kWithDistortion);
    FAIL() << "missing model accepted";
  } catch (const IntrinsicsFileError& e) {
    EXPECT_NE(std::string(e.what()).find("perspectiveProjWithDistortion"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(kXml), std::string::npos) << e.what();
  }
}

TEST(IntrinsicsIo, YamlAndJsonRoundTrip) {
  const CameraIntrinsics k = CameraIntrinsics::pepper_top_vga();
  for (const char* name : {"k.yaml", "k.json"}) {
    const std::string path = temp_file(name, "");
    save_intrinsics_plain(k, path);
    EXPECT_EQ(load_intrinsics(path), k) << name;
  }
}

TEST(IntrinsicsIo, PlainFormsByHand) {
  const std::string yaml = temp_file(
      "hand.yaml", "width_px: 320\nheight_px: 240\nfx_px: 300\nfy_px: 301\ncx_px: 160\ncy_px: 120\n");
  const CameraIntrinsics k = load_intrinsics(yaml);
  EXPECT_EQ(k.width_px, 320);
  EXPECT_DOUBLE_EQ(k.fy_px, 301.0);
  const std::string json = temp_file("hand.json", R"({"width_px": 320, "height_px": 240, "fx_px": 300,
      "fy_px": 301, "cx_px": 160, "cy_px": 120})");
  EXPECT_EQ(load_intrinsics(json), k);
  EXPECT_THROW(load_intrinsics(temp_file("missing_key.yaml", "width_px: 320\n")), IntrinsicsFileError);
  EXPECT_THROW(load_intrinsics(temp_file("broken.json", "{ not json")), IntrinsicsFileError);
  EXPECT_THROW(load_intrinsics(temp_file("k.txt", "")), IntrinsicsFileError);
}

}  // namespace
}  // namespace pepper::core::camera
