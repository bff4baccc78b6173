// The adapter's camera files: ViSP writes, libxml2 lists, ViSP reads back; errors name the file.
#include "visp_adapter/camera_xml.hpp"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

namespace pepper::visp_adapter {
namespace {

std::string fresh(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "pepper_visp_adapter_camera_xml";
  std::filesystem::create_directories(dir);
  const auto path = dir / name;
  std::filesystem::remove(path);
  return path.string();
}

TEST(VispAdapterCameraXml, WriteListReadBothModels) {
  const std::string path = fresh("two_cameras.xml");
  CameraCalibration with{"CameraTop", 640, 480, CameraModel::kPerspectiveWithDistortion,
                         595.0, 596.0, 319.0, 239.0, 0.03, -0.029};
  CameraCalibration without{"CameraTop", 640, 480, CameraModel::kPerspectiveWithoutDistortion,
                            596.26, 597.44, 318.8, 238.32, 0.0, 0.0};
  CameraCalibration bottom{"CameraBottom", 320, 240, CameraModel::kPerspectiveWithoutDistortion,
                           280.0, 281.0, 160.5, 120.5, 0.0, 0.0};
  write_camera_xml(path, with);
  write_camera_xml(path, without);
  write_camera_xml(path, bottom);
  const std::vector<CameraEntry> entries = list_camera_xml(path);
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[0].name, "CameraTop");
  EXPECT_EQ(entries[0].width_px, 640);
  EXPECT_EQ(entries[0].models.size(), 2u);
  EXPECT_EQ(entries[1].name, "CameraBottom");
  EXPECT_EQ(entries[1].height_px, 240);

  const CameraCalibration back = read_camera_xml(path, "CameraTop", CameraModel::kPerspectiveWithDistortion);
  EXPECT_EQ(back.width_px, 640);
  EXPECT_DOUBLE_EQ(back.px, 595.0);
  EXPECT_DOUBLE_EQ(back.v0, 239.0);
  EXPECT_DOUBLE_EQ(back.kud, 0.03);
  EXPECT_DOUBLE_EQ(back.kdu, -0.029);
  const CameraCalibration pinhole =
      read_camera_xml(path, "CameraTop", CameraModel::kPerspectiveWithoutDistortion, 640, 480);
  EXPECT_DOUBLE_EQ(pinhole.px, 596.26);
  EXPECT_EQ(pinhole.kud, 0.0);
  try {
    read_camera_xml(path, "CameraBottom", CameraModel::kPerspectiveWithDistortion);
    FAIL() << "a model the camera does not have was read";
  } catch (const CameraXmlError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.path(), path);
    EXPECT_NE(what.find("'CameraBottom'"), std::string::npos) << what;
    EXPECT_NE(what.find("the file holds"), std::string::npos) << what;
  }
}

TEST(VispAdapterCameraXml, ErrorsNameTheFileAndTheCause) {
  EXPECT_THROW(list_camera_xml("/nonexistent/camera.xml"), CameraXmlError);
  const std::string nan_px = fresh("nan_px.xml");
  std::ofstream(nan_px) << "<root><camera><name>c</name><model><type>perspectiveProjWithoutDistortion"
                           "</type>\n<px>twelve</px><py>1</py><u0>1</u0><v0>1</v0></model></camera></root>";
  try {
    list_camera_xml(nan_px);
    FAIL() << "a non-numeric <px> accepted";
  } catch (const CameraXmlError& e) {
    EXPECT_NE(std::string(e.what()).find("line 2: <px> is not a number: 'twelve'"), std::string::npos)
        << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(nan_px, 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace pepper::visp_adapter
