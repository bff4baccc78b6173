// Scanline rasteriser of the mock robot's camera (see renderer.hpp for the contract).
//
// Per quad: transform to the camera, clip against the near plane (Sutherland-Hodgman), project,
// clip against the image rectangle, then fill rows. For the quad's plane n . P = c (camera frame)
// and the ray d = ((u - cx)/fx, (v - cy)/fy, 1), the point seen is P = d * c / (n . d), hence
// 1/z = (n . d) / c and (texcoord)/z are affine in (u, v): w = w0 + wx u + wy v, etc.
#include "sim/renderer.hpp"

#include "core/camera/distortion.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <stdexcept>

namespace pepper::sim {

namespace {

constexpr int kMaxVerts = 16;
constexpr int kMipBlockPx = 16;

struct Poly {
  std::array<Eigen::Vector3d, kMaxVerts> v;
  int n = 0;
};

// Keeps the part of `in` where dot(p) >= 0 for the affine function f(p) = a . p + b.
template <typename F>
void clip_poly(const Poly& in, Poly& out, F f) {
  out.n = 0;
  if (in.n == 0) return;
  for (int i = 0; i < in.n; ++i) {
    const Eigen::Vector3d& p = in.v[i];
    const Eigen::Vector3d& q = in.v[(i + 1) % in.n];
    const double fp = f(p);
    const double fq = f(q);
    if (fp >= 0.0) {
      if (out.n < kMaxVerts) out.v[out.n++] = p;
    }
    if ((fp >= 0.0) != (fq >= 0.0)) {
      const double t = fp / (fp - fq);
      if (out.n < kMaxVerts) out.v[out.n++] = p + t * (q - p);
    }
  }
}

struct Affine {
  float c0 = 0, cx = 0, cy = 0;
};

struct Prepared {
  Poly screen;  // x = u_px, y = v_px (z unused)
  Affine w, U, V;
  double min_depth = 0.0;
  float scale = 1.0f;  // radiance per texel grey level
  float blend = 0.0f;  // reflectivity: fraction of what is already in the buffer kept
  const Texture* tex = nullptr;
};

inline int fast_floor(float f) {
  const int i = static_cast<int>(f);
  return i - (f < static_cast<float>(i));
}

// Bilinear sample of one mip level; coordinates in level-0 texels.
inline float sample(const cv::Mat& level, float inv_scale, bool repeat, float u, float v) {
  const float fx = u * inv_scale - 0.5f;
  const float fy = v * inv_scale - 0.5f;
  int x0 = fast_floor(fx);
  int y0 = fast_floor(fy);
  const float ax = fx - static_cast<float>(x0);
  const float ay = fy - static_cast<float>(y0);
  int x1, y1;
  if (repeat) {
    const int mx = level.cols - 1;
    const int my = level.rows - 1;
    x1 = (x0 + 1) & mx;
    y1 = (y0 + 1) & my;
    x0 &= mx;
    y0 &= my;
  } else {
    x1 = std::clamp(x0 + 1, 0, level.cols - 1);
    y1 = std::clamp(y0 + 1, 0, level.rows - 1);
    x0 = std::clamp(x0, 0, level.cols - 1);
    y0 = std::clamp(y0, 0, level.rows - 1);
  }
  const uint8_t* r0 = level.ptr<uint8_t>(y0);
  const uint8_t* r1 = level.ptr<uint8_t>(y1);
  const float top = static_cast<float>(r0[x0]) + ax * static_cast<float>(r0[x1] - r0[x0]);
  const float bot = static_cast<float>(r1[x0]) + ax * static_cast<float>(r1[x1] - r1[x0]);
  return top + ay * (bot - top);
}

uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

double light_factor(const LightingCondition& light, LightGroup group) {
  switch (group) {
    case LightGroup::kAmbient:
      return light.ambient;
    case LightGroup::kWindows:
      return light.windows;
    case LightGroup::kLamps:
      return light.lamps;
  }
  return 1.0;
}

// Shading by orientation so that two walls meeting at a corner differ (a fixed key light).
double orientation_factor(const Quad& q, double key_light_rad) {
  if (q.light != LightGroup::kAmbient) return 1.0;
  const Eigen::Vector3d n = q.axis_u.cross(q.axis_v);
  if (std::abs(n.z()) > 0.7) return q.origin_m.z() > 1.0 ? 0.85 : 1.0;
  const Eigen::Vector2d h = n.head<2>().normalized();
  const double c = std::abs(h.x() * std::cos(key_light_rad) + h.y() * std::sin(key_light_rad));
  return 0.72 + 0.28 * c;
}

}  // namespace

std::vector<std::string> RenderOptions::validate() const {
  std::vector<std::string> errors;
  auto bad = [&](const std::string& name, double value, const char* range) {
    std::ostringstream os;
    os << name << " = " << value << " must be " << range;
    errors.push_back(os.str());
  };
  if (!(near_m > 0.0 && near_m < 1.0)) bad("near_m", near_m, "in (0, 1) m");
  if (!(background_grey >= 0.0 && background_grey <= 255.0))
    bad("background_grey", background_grey, "in [0, 255]");
  if (!(exposure_gain > 0.0 && std::isfinite(exposure_gain)))
    bad("exposure_gain", exposure_gain, "finite and > 0");
  if (!(vignetting >= 0.0 && vignetting < 1.0)) bad("vignetting", vignetting, "in [0, 1)");
  if (!(motion_blur_exposure_s >= 0.0 && motion_blur_exposure_s <= 0.2))
    bad("motion_blur_exposure_s", motion_blur_exposure_s, "in [0, 0.2] s");
  if (!(noise_sigma_grey >= 0.0 && noise_sigma_grey <= 50.0))
    bad("noise_sigma_grey", noise_sigma_grey, "in [0, 50]");
  return errors;
}

Renderer::Renderer(RenderOptions options) : options_(std::move(options)) {
  const auto errors = options_.validate();
  if (!errors.empty()) throw std::invalid_argument("RenderOptions: " + errors.front());
  // Gaussian noise table (Box-Muller on our own generator: identical on every platform).
  noise_table_.resize(4096);
  uint64_t state = 0x5EEDULL;
  for (size_t i = 0; i < noise_table_.size(); i += 2) {
    const double u1 = (static_cast<double>(splitmix64(state) >> 11) + 0.5) * 0x1.0p-53;
    const double u2 = (static_cast<double>(splitmix64(state) >> 11) + 0.5) * 0x1.0p-53;
    const double r = std::sqrt(-2.0 * std::log(u1));
    // Stored in 1/64 grey level units of a unit Gaussian (scaled by sigma when applied).
    noise_table_[i] = static_cast<int16_t>(std::lround(64.0 * r * std::cos(2 * M_PI * u2)));
    noise_table_[i + 1] = static_cast<int16_t>(std::lround(64.0 * r * std::sin(2 * M_PI * u2)));
  }
}

struct Renderer::Impl {
  // Prepares a quad for rasterisation; false when nothing of it is in view.
  static bool prepare(const Quad& q, const Eigen::Isometry3d& T_cam_world,
                      const core::CameraIntrinsics& k, double near_m, Prepared& out) {
    const Eigen::Matrix3d R = T_cam_world.linear();
    const Eigen::Vector3d p0 = T_cam_world * q.origin_m;
    const Eigen::Vector3d a = R * q.axis_u;
    const Eigen::Vector3d b = R * q.axis_v;
    const Eigen::Vector3d n = a.cross(b);
    const double c = n.dot(p0);
    if (std::abs(c) < 1e-9) return false;  // plane through the optical centre: seen edge-on

    Poly cam;
    cam.n = 4;
    cam.v[0] = p0;
    cam.v[1] = p0 + q.size_u_m * a;
    cam.v[2] = p0 + q.size_u_m * a + q.size_v_m * b;
    cam.v[3] = p0 + q.size_v_m * b;
    Poly clipped;
    clip_poly(cam, clipped, [near_m](const Eigen::Vector3d& p) { return p.z() - near_m; });
    if (clipped.n < 3) return false;

    Poly s;
    s.n = clipped.n;
    double min_z = std::numeric_limits<double>::infinity();
    for (int i = 0; i < clipped.n; ++i) {
      const Eigen::Vector3d& p = clipped.v[i];
      min_z = std::min(min_z, p.z());
      s.v[i] = {k.fx_px * p.x() / p.z() + k.cx_px, k.fy_px * p.y() / p.z() + k.cy_px, 0.0};
    }
    const double xmax = k.width_px - 0.5;
    const double ymax = k.height_px - 0.5;
    Poly t1, t2;
    clip_poly(s, t1, [](const Eigen::Vector3d& p) { return p.x() + 0.5; });
    clip_poly(t1, t2, [xmax](const Eigen::Vector3d& p) { return xmax - p.x(); });
    clip_poly(t2, t1, [](const Eigen::Vector3d& p) { return p.y() + 0.5; });
    clip_poly(t1, out.screen, [ymax](const Eigen::Vector3d& p) { return ymax - p.y(); });
    if (out.screen.n < 3) return false;
    out.min_depth = min_z;

    // d = (ix u + ox, iy v + oy, 1).
    const double ix = 1.0 / k.fx_px, ox = -k.cx_px / k.fx_px;
    const double iy = 1.0 / k.fy_px, oy = -k.cy_px / k.fy_px;
    const double w0 = (n.x() * ox + n.y() * oy + n.z()) / c;
    const double wx = n.x() * ix / c;
    const double wy = n.y() * iy / c;
    out.w = {static_cast<float>(w0), static_cast<float>(wx), static_cast<float>(wy)};
    const Texture& tex = *out.tex;
    auto texcoord = [&](const Eigen::Vector3d& axis, double offset_m, double texels_per_m) {
      const double kk = offset_m - axis.dot(p0);
      Affine f;
      f.c0 =
          static_cast<float>(texels_per_m * (axis.x() * ox + axis.y() * oy + axis.z() + kk * w0));
      f.cx = static_cast<float>(texels_per_m * (axis.x() * ix + kk * wx));
      f.cy = static_cast<float>(texels_per_m * (axis.y() * iy + kk * wy));
      return f;
    };
    out.U = texcoord(a, q.offset_u_m, tex.width_px() / q.tile_u_m);
    out.V = texcoord(b, q.offset_v_m, tex.height_px() / q.tile_v_m);
    return true;
  }

  static void fill(const Prepared& p, int width, float* radiance, float* inv_depth, bool mipmaps,
                   RenderStats& stats) {
    const Poly& s = p.screen;
    double ymin = s.v[0].y(), ymax = s.v[0].y();
    for (int i = 1; i < s.n; ++i) {
      ymin = std::min(ymin, s.v[i].y());
      ymax = std::max(ymax, s.v[i].y());
    }
    const int row0 = static_cast<int>(std::ceil(ymin));
    const int row1 = static_cast<int>(std::ceil(ymax)) - 1;
    const Texture& tex = *p.tex;
    const int top_level = tex.levels() - 1;
    const bool repeat = tex.repeat();
    bool any = false;
    for (int row = row0; row <= row1; ++row) {
      const double y = row;
      double xl = std::numeric_limits<double>::infinity();
      double xr = -xl;
      for (int i = 0; i < s.n; ++i) {
        const Eigen::Vector3d& a = s.v[i];
        const Eigen::Vector3d& b = s.v[(i + 1) % s.n];
        if ((a.y() <= y && y < b.y()) || (b.y() <= y && y < a.y())) {
          const double x = a.x() + (y - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
          xl = std::min(xl, x);
          xr = std::max(xr, x);
        }
      }
      if (!(xl < xr)) continue;
      const int x0 = std::max(0, static_cast<int>(std::ceil(xl)));
      const int x1 = std::min(width - 1, static_cast<int>(std::ceil(xr)) - 1);
      if (x1 < x0) continue;
      any = true;
      const float fy = static_cast<float>(row);
      const float wrow = p.w.c0 + p.w.cy * fy;
      const float urow = p.U.c0 + p.U.cy * fy;
      const float vrow = p.V.c0 + p.V.cy * fy;
      float* rad = radiance + static_cast<size_t>(row) * width;
      float* zb = inv_depth + static_cast<size_t>(row) * width;
      for (int bx = x0; bx <= x1; bx += kMipBlockPx) {
        const int bend = std::min(x1, bx + kMipBlockPx - 1);
        int level = 0;
        if (mipmaps && top_level > 0) {
          const float xm = 0.5f * static_cast<float>(bx + bend);
          const float w = wrow + p.w.cx * xm;
          if (w > 0.0f) {
            const float iz = 1.0f / w;
            const float u = (urow + p.U.cx * xm) * iz;
            const float v = (vrow + p.V.cx * xm) * iz;
            const float dudx = (p.U.cx - u * p.w.cx) * iz, dvdx = (p.V.cx - v * p.w.cx) * iz;
            const float dudy = (p.U.cy - u * p.w.cy) * iz, dvdy = (p.V.cy - v * p.w.cy) * iz;
            const float rho2 = std::max(dudx * dudx + dvdx * dvdx, dudy * dudy + dvdy * dvdy);
            if (rho2 > 1.0f) {
              level = static_cast<int>(0.5f * std::log2(rho2) + 0.3f);
              level = std::min(level, top_level);
            }
          }
        }
        const cv::Mat& lev = tex.level(level);
        const float inv_scale = 1.0f / static_cast<float>(1 << level);
        for (int x = bx; x <= bend; ++x) {
          const float fx = static_cast<float>(x);
          const float w = wrow + p.w.cx * fx;
          if (w <= zb[x]) continue;
          const float iz = 1.0f / w;
          const float u = (urow + p.U.cx * fx) * iz;
          const float v = (vrow + p.V.cx * fx) * iz;
          const float t = sample(lev, inv_scale, repeat, u, v) * p.scale;
          rad[x] = p.blend > 0.0f ? t + p.blend * rad[x] : t;
          zb[x] = w;
          ++stats.pixels_shaded;
        }
      }
    }
    if (any) ++stats.quads_drawn;
  }
};

// The lens of a camera with ViSP's distortion model (core/camera/distortion.hpp): the rasteriser
// has drawn the pinhole image; every output pixel takes it at the undistorted position of its own
// centre (ViSP's pixel -> meter conversion, kdu), bilinearly for the radiance, nearest for the
// depth. The lens acts before the sensor, so before exposure, vignetting, blur and noise. The maps
// are kept for the last camera (built again when the intrinsics change).
void Renderer::distort_through_lens(const core::CameraIntrinsics& k) {
  const int W = k.width_px, H = k.height_px;
  if (!(lens_for_ == k) || lens_map_x_.empty()) {
    lens_map_x_.create(H, W, CV_32FC1);
    lens_map_y_.create(H, W, CV_32FC1);
    for (int y = 0; y < H; ++y) {
      float* mx = lens_map_x_.ptr<float>(y);
      float* my = lens_map_y_.ptr<float>(y);
      for (int x = 0; x < W; ++x) {
        const cv::Point2d pinhole_px = k.denormalize(
            core::camera::pixel_to_norm(k, {static_cast<double>(x), static_cast<double>(y)}));
        mx[x] = static_cast<float>(pinhole_px.x);
        my[x] = static_cast<float>(pinhole_px.y);
      }
    }
    lens_for_ = k;
  }
  lens_scratch_.resize(radiance_.size());
  // Outside the pinhole image (a lens with kud < 0 sees wider): the background, no surface.
  // Each remap writes into the scratch buffer, which then swaps with the buffer it replaces.
  auto through_lens = [&](std::vector<float>& buffer, int interpolation, double outside) {
    cv::Mat out(H, W, CV_32FC1, lens_scratch_.data());
    cv::remap(cv::Mat(H, W, CV_32FC1, buffer.data()), out, lens_map_x_, lens_map_y_, interpolation,
              cv::BORDER_CONSTANT, cv::Scalar(outside));
    buffer.swap(lens_scratch_);
  };
  through_lens(radiance_, cv::INTER_LINEAR, options_.background_grey);
  through_lens(inv_depth_, cv::INTER_NEAREST, 0.0);
}

cv::Mat Renderer::render(const World& world, const ViewState& view) {
  cv::Mat out;
  render(world, view, out);
  return out;
}

void Renderer::render(const World& world, const ViewState& view, cv::Mat& out) {
  const core::CameraIntrinsics& k = view.intrinsics;
  const auto kerr = k.validate();
  if (!kerr.empty()) throw std::invalid_argument("Renderer::render: intrinsics: " + kerr.front());
  const int W = k.width_px, H = k.height_px;
  const size_t npx = static_cast<size_t>(W) * H;
  if (W != width_px_ || H != height_px_) {
    width_px_ = W;
    height_px_ = H;
    radiance_.assign(npx, 0.0f);
    inv_depth_.assign(npx, 0.0f);
    gain_map_.resize(npx);
    // Vignetting: cos^4-like fall-off approximated by 1 - vignetting * (r / r_corner)^2.
    const double rc2 = 0.25 * (static_cast<double>(W) * W + static_cast<double>(H) * H);
    for (int y = 0; y < H; ++y) {
      for (int x = 0; x < W; ++x) {
        const double dx = x - 0.5 * (W - 1), dy = y - 0.5 * (H - 1);
        gain_map_[static_cast<size_t>(y) * W + x] =
            static_cast<float>(1.0 - options_.vignetting * (dx * dx + dy * dy) / rc2);
      }
    }
  }
  std::fill(radiance_.begin(), radiance_.end(), static_cast<float>(options_.background_grey));
  std::fill(inv_depth_.begin(), inv_depth_.end(), 0.0f);
  stats_ = {};

  const Eigen::Isometry3d T_cam_world = view.T_world_cam.inverse();
  scratch_quads_.clear();
  world.moving_quads(view.t_s, scratch_quads_, view.robot_base_m);

  std::vector<Prepared> normal;
  std::vector<Prepared> mirrored;
  std::vector<Prepared> floors;
  normal.reserve(world.quads.size() + scratch_quads_.size());
  bool reflective = false;
  for (const Quad& q : world.quads) reflective = reflective || q.reflectivity > 0.0;

  auto add = [&](const Quad& q, std::vector<Prepared>& list, float blend) {
    Prepared p;
    p.tex = &world.textures.at(static_cast<size_t>(q.texture));
    if (!Impl::prepare(q, T_cam_world, k, options_.near_m, p)) return;
    const double shade = q.brightness * light_factor(view.light, q.light) *
                         orientation_factor(q, world.key_light_rad);
    p.scale = static_cast<float>(shade * (1.0 - blend));
    p.blend = blend;
    list.push_back(p);
  };
  auto add_all = [&](const Quad& q) {
    if (reflective && q.is_floor && q.reflectivity > 0.0) {
      add(q, floors, static_cast<float>(q.reflectivity));
      return;
    }
    add(q, normal, 0.0f);
    if (reflective && !q.is_floor) {
      Quad m = q;
      m.origin_m.z() = -m.origin_m.z();
      m.axis_u.z() = -m.axis_u.z();
      m.axis_v.z() = -m.axis_v.z();
      add(m, mirrored, 0.0f);
    }
  };
  for (const Quad& q : world.quads) add_all(q);
  for (const Quad& q : scratch_quads_) add_all(q);

  auto by_depth = [](const Prepared& a, const Prepared& b) { return a.min_depth < b.min_depth; };
  std::stable_sort(normal.begin(), normal.end(), by_depth);
  std::stable_sort(mirrored.begin(), mirrored.end(), by_depth);
  float* rad = radiance_.data();
  float* zb = inv_depth_.data();
  if (!floors.empty()) {
    for (const Prepared& p : mirrored) Impl::fill(p, W, rad, zb, options_.mipmaps, stats_);
    for (const Prepared& p : floors) Impl::fill(p, W, rad, zb, options_.mipmaps, stats_);
  }
  for (const Prepared& p : normal) Impl::fill(p, W, rad, zb, options_.mipmaps, stats_);
  if (k.model == core::ProjectionModel::kWithDistortion) {
    distort_through_lens(k);  // swaps the buffers: take their pointers again
    rad = radiance_.data();
    zb = inv_depth_.data();
  }

  // Exposure and vignetting, then 8 bits.
  out.create(H, W, CV_8UC1);
  const float gain = static_cast<float>(options_.exposure_gain);
  for (int y = 0; y < H; ++y) {
    uint8_t* o = out.ptr<uint8_t>(y);
    const float* r = rad + static_cast<size_t>(y) * W;
    const float* g = gain_map_.data() + static_cast<size_t>(y) * W;
    for (int x = 0; x < W; ++x) {
      const float val = r[x] * g[x] * gain + 0.5f;
      o[x] = static_cast<uint8_t>(std::clamp(val, 0.0f, 255.0f));
    }
  }
  // Rotational motion blur: a yaw rate sweeps the image horizontally by fx * omega * shutter.
  const double blur_px =
      std::abs(view.yaw_rate_cam_rad_s) * options_.motion_blur_exposure_s * k.fx_px;
  if (blur_px >= 1.5) {
    const int ksize = std::min(W / 4 + 1, static_cast<int>(std::lround(blur_px)));
    if (ksize >= 2) cv::blur(out, out, cv::Size(ksize, 1));
  }
  if (options_.optics_blur) {
    const double sigma = 0.6 * W / 640.0;
    if (sigma >= 0.3) cv::GaussianBlur(out, out, cv::Size(3, 3), sigma, sigma);
  }
  if (options_.noise_sigma_grey > 0.0) {
    uint64_t state = options_.noise_seed * 0x9E3779B97F4A7C15ULL ^ (view.frame_index + 1);
    splitmix64(state);
    const int sigma_q = static_cast<int>(std::lround(options_.noise_sigma_grey * 256.0));
    uint8_t* o = out.ptr<uint8_t>(0);  // continuous (created above, blurs keep it)
    const size_t n = out.total();
    for (size_t i = 0; i < n; i += 4) {
      uint64_t bits = splitmix64(state);
      for (size_t j = i; j < std::min(n, i + 4); ++j) {
        const int noise_64 = noise_table_[bits & 4095];  // unit Gaussian * 64
        bits >>= 16;
        // value + noise_64 / 64 * sigma, rounded: sigma_q = sigma * 256.
        const int delta = (noise_64 * sigma_q + (1 << 13)) >> 14;
        o[j] = static_cast<uint8_t>(std::clamp(static_cast<int>(o[j]) + delta, 0, 255));
      }
    }
  }
}

cv::Mat Renderer::depth_m() const {
  cv::Mat d(height_px_, width_px_, CV_32FC1);
  for (int y = 0; y < height_px_; ++y) {
    float* row = d.ptr<float>(y);
    for (int x = 0; x < width_px_; ++x) {
      const float w = inv_depth_[static_cast<size_t>(y) * width_px_ + x];
      row[x] = w > 0.0f ? 1.0f / w : std::numeric_limits<float>::infinity();
    }
  }
  return d;
}

}  // namespace pepper::sim
