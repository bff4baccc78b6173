// The shared JSON form of intrinsics (files, map manifests, recordings).
#include "core/camera/intrinsics_json.hpp"

#include <gtest/gtest.h>

namespace pepper::core::camera {
namespace {

TEST(IntrinsicsJson, RoundTripKeepsEveryValue) {
  const CameraIntrinsics k = CameraIntrinsics::pepper_top_vga();
  const CameraIntrinsics back = intrinsics_from_json(intrinsics_to_json(k));
  EXPECT_EQ(back.width_px, k.width_px);
  EXPECT_EQ(back.height_px, k.height_px);
  EXPECT_EQ(back.fx_px, k.fx_px);
  EXPECT_EQ(back.fy_px, k.fy_px);
  EXPECT_EQ(back.cx_px, k.cx_px);
  EXPECT_EQ(back.cy_px, k.cy_px);
}

TEST(IntrinsicsJson, MissingOrBadKeysAndInvalidValuesAreNamed) {
  nlohmann::json j = intrinsics_to_json(CameraIntrinsics::pepper_top_vga());
  j.erase("cy_px");
  try {
    intrinsics_from_json(j);
    FAIL() << "missing key accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cy_px"), std::string::npos) << e.what();
  }
  j["cy_px"] = "240";
  EXPECT_THROW(intrinsics_from_json(j), std::invalid_argument);
  j["cy_px"] = 240.0;
  j["fx_px"] = -1.0;
  try {
    intrinsics_from_json(j);
    FAIL() << "negative focal length accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fx_px"), std::string::npos) << e.what();
  }
  EXPECT_THROW(intrinsics_from_json(nlohmann::json::array()), std::invalid_argument);
}

TEST(IntrinsicsJson, ProjectionModelRoundTripsAndOldJsonIsWithoutDistortion) {
  CameraIntrinsics k = CameraIntrinsics::pepper_top_vga();
  k.model = ProjectionModel::kWithDistortion;
  k.kud = 0.031;
  k.kdu = -0.0302;
  const nlohmann::json j = intrinsics_to_json(k);
  EXPECT_EQ(j["model"], "perspectiveProjWithDistortion");
  EXPECT_EQ(intrinsics_from_json(j), k);
  // JSON written before the model was recorded (maps, recordings): the pinhole, as it was.
  nlohmann::json old = j;
  old.erase("model");
  old.erase("kud");
  old.erase("kdu");
  const CameraIntrinsics back = intrinsics_from_json(old);
  EXPECT_EQ(back.model, ProjectionModel::kWithoutDistortion);
  EXPECT_EQ(back.kud, 0.0);
  nlohmann::json bad = j;
  bad["model"] = "fisheye";
  try {
    intrinsics_from_json(bad);
    FAIL() << "unknown model accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fisheye"), std::string::npos) << e.what();
  }
  // Coefficients without the model that uses them are refused (validate()).
  old["kud"] = 0.03;
  EXPECT_THROW(intrinsics_from_json(old), std::invalid_argument);
}

}  // namespace
}  // namespace pepper::core::camera
