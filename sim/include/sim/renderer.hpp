#pragma once
// Renderer: what the simulated top head camera sees in a World, as an 8-bit grey image.
//
// Our own scanline rasteriser (ViSP's vpImageSimulator has no near-plane clipping,
// ARCHITECTURE.md): every quad is clipped against the near plane z_cam >= near_m and the image
// rectangle, then filled row by row with a z-buffer. Inside a planar quad, 1/z and the texture
// coordinates divided by z are affine in the pixel coordinates, so each pixel costs one reciprocal
// (exact perspective-correct interpolation); texels are sampled bilinearly from the mipmap level
// chosen from the texel footprint of a 16-pixel block. A shiny floor (Quad::reflectivity > 0)
// blends in the mirror image of the scene. Post-processing, in order: exposure (light level x
// exposure_gain x vignetting), rotational motion blur, optics blur, sensor noise.
//
// Frames (docs/conventions.md): T_world_cam maps camera coordinates (x right, y down, z forward)
// to the world (z up). Pixel centres are at integer coordinates, so a 3D point projects to
// u_px = fx * X / Z + cx_px, v_px = fy * Y / Z + cy_px and lands in the pixel round(u_px, v_px).
// Intrinsics with ViSP's distortion model (core/camera/intrinsics.hpp, e.g. Pepper's kud ~ 0.03)
// render through the lens: the point lands at core::camera::norm_to_pixel(k, (X/Z, Y/Z)) instead
// (the pinhole image resampled before exposure; within a fraction of a pixel, kud and kdu being
// two fits of one lens).
// Determinism: the output depends only on the world, the view and the options; the noise is drawn
// from a generator seeded with (noise_seed, frame_index). Rendering is single-threaded.
// Thread-safety: a Renderer owns scratch buffers: one renderer per thread.

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/camera/intrinsics.hpp"
#include "sim/world.hpp"

namespace pepper::sim {

struct RenderOptions {
  double near_m = 0.02;                  ///< near clipping plane, metres (> 0)
  double background_grey = 10.0;         ///< where no surface is seen, grey level
  double exposure_gain = 1.0;            ///< multiplies every radiance (camera exposure), > 0
  double vignetting = 0.15;              ///< relative brightness lost at the image corners, [0, 1)
  double motion_blur_exposure_s = 0.02;  ///< shutter time for rotational motion blur (0 = off)
  bool optics_blur = true;               ///< 3x3 Gaussian (sigma 0.6 px at VGA) for the lens
  double noise_sigma_grey = 1.5;         ///< additive Gaussian sensor noise, grey levels (0 = off)
  uint64_t noise_seed = 1;
  bool mipmaps = true;  ///< false: always sample level 0 (aliasing; for tests)

  /// Messages naming each invalid field and its range; empty when valid.
  std::vector<std::string> validate() const;
};

/// Everything about one view: camera pose and intrinsics, light, time (moving obstacles), motion.
struct ViewState {
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  core::CameraIntrinsics intrinsics = core::CameraIntrinsics::pepper_top_vga();
  LightingCondition light;
  double t_s = 0.0;                 ///< simulated time, for moving obstacles
  /// The robot's base (x, y) in the world, if the camera is on one: people who keep clear of
  /// the robot (MovingObstacle::keep_clear_m) step aside from it.
  std::optional<Eigen::Vector2d> robot_base_m;
  double yaw_rate_cam_rad_s = 0.0;  ///< rotation rate about the camera's vertical (motion blur)
  uint64_t frame_index = 0;         ///< selects the noise of this frame
};

struct RenderStats {
  int quads_drawn = 0;        ///< quads with at least one visible row after clipping
  int64_t pixels_shaded = 0;  ///< pixels that passed the depth test
};

class Renderer {
 public:
  /// Throws std::invalid_argument naming the bad field when options are invalid.
  explicit Renderer(RenderOptions options = {});

  /// Renders into `out` (reallocated to CV_8UC1 of the intrinsics' size if needed). Throws
  /// std::invalid_argument for invalid intrinsics.
  void render(const World& world, const ViewState& view, cv::Mat& out);
  cv::Mat render(const World& world, const ViewState& view);

  /// Depth along the optical axis (metres) of each pixel in the last render, +inf where empty.
  cv::Mat depth_m() const;

  const RenderOptions& options() const { return options_; }
  const RenderStats& last_stats() const { return stats_; }

 private:
  void distort_through_lens(const core::CameraIntrinsics& k);
  struct Impl;
  RenderOptions options_;
  RenderStats stats_;
  std::vector<float> radiance_;   // grey levels before exposure
  std::vector<float> inv_depth_;  // 1 / z_cam, 0 = nothing
  std::vector<float> gain_map_;   // vignetting, per pixel
  // Lens (distortion model only): the pinhole pixel each output pixel samples, for lens_for_.
  core::CameraIntrinsics lens_for_;
  cv::Mat lens_map_x_, lens_map_y_;
  std::vector<float> lens_scratch_;
  int width_px_ = 0;
  int height_px_ = 0;
  std::vector<int16_t> noise_table_;
  std::vector<Quad> scratch_quads_;
};

}  // namespace pepper::sim
