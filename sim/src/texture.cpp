// Procedural and image textures for the mock world (see texture.hpp).
#include "sim/texture.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <stdexcept>

#include "sim/world.hpp"

namespace pepper::sim {

namespace {

constexpr std::array<std::pair<TextureKind, const char*>, 11> kKindNames{{
    {TextureKind::kUniform, "uniform"},
    {TextureKind::kChecker, "checker"},
    {TextureKind::kNoise, "noise"},
    {TextureKind::kWood, "wood"},
    {TextureKind::kBrick, "brick"},
    {TextureKind::kStripes, "stripes"},
    {TextureKind::kTiles, "tiles"},
    {TextureKind::kBooks, "books"},
    {TextureKind::kWindow, "window"},
    {TextureKind::kDoor, "door"},
    {TextureKind::kImage, "image"},
}};

bool is_pow2(int n) { return n > 0 && (n & (n - 1)) == 0; }

// Deterministic hash of integer coordinates to [0, 1).
double hash01(int x, int y, uint32_t seed) {
  uint64_t h = static_cast<uint64_t>(static_cast<uint32_t>(x)) * 0x9E3779B97F4A7C15ULL ^
               static_cast<uint64_t>(static_cast<uint32_t>(y)) * 0xC2B2AE3D27D4EB4FULL ^
               (static_cast<uint64_t>(seed) + 1) * 0x165667B19E3779F9ULL;
  h ^= h >> 33;
  h *= 0xFF51AFD7ED558CCDULL;
  h ^= h >> 33;
  h *= 0xC4CEB9FE1A85EC53ULL;
  h ^= h >> 33;
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

// Tileable value noise with period `period` lattice cells; returns [-1, 1].
double value_noise(double x, double y, int period, uint32_t seed) {
  const int xi = static_cast<int>(std::floor(x));
  const int yi = static_cast<int>(std::floor(y));
  const double fx = x - xi, fy = y - yi;
  const double sx = fx * fx * (3 - 2 * fx), sy = fy * fy * (3 - 2 * fy);
  auto at = [&](int a, int b) {
    const int pa = ((a % period) + period) % period;
    const int pb = ((b % period) + period) % period;
    return 2.0 * hash01(pa, pb, seed) - 1.0;
  };
  const double top = at(xi, yi) + sx * (at(xi + 1, yi) - at(xi, yi));
  const double bot = at(xi, yi + 1) + sx * (at(xi + 1, yi + 1) - at(xi, yi + 1));
  return top + sy * (bot - top);
}

// Fractal noise over an S x S texture, roughly in [-1, 1].
double fractal(int x, int y, int size, double feature_px, int octaves, uint32_t seed) {
  double sum = 0.0, amp = 1.0, norm = 0.0;
  double cell = std::max(2.0, feature_px * size / 256.0);
  for (int o = 0; o < octaves && cell >= 1.0; ++o) {
    const int period = std::max(1, static_cast<int>(std::lround(size / cell)));
    const double c = static_cast<double>(size) / period;  // exact divisor for tiling
    sum += amp * value_noise(x / c, y / c, period, seed + 101u * o);
    norm += amp;
    amp *= 0.5;
    cell *= 0.5;
  }
  return norm > 0 ? sum / norm : 0.0;
}

cv::Mat generate(const TextureSpec& s) {
  const int S = s.size_px;
  cv::Mat img(S, S, CV_8UC1);
  const double m = s.mean, c = s.contrast;
  auto put = [&](int x, int y, double v) { img.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(v); };
  const int cells = std::max(1, s.cells);
  switch (s.kind) {
    case TextureKind::kUniform:
      img.setTo(cv::Scalar(std::clamp(m, 0.0, 255.0)));
      break;
    case TextureKind::kChecker:
      for (int y = 0; y < S; ++y)
        for (int x = 0; x < S; ++x)
          put(x, y, m + ((((x * cells) / S) + ((y * cells) / S)) % 2 ? c : -c));
      break;
    case TextureKind::kNoise:
      for (int y = 0; y < S; ++y)
        for (int x = 0; x < S; ++x)
          put(x, y, m + c * fractal(x, y, S, s.feature_px, s.octaves, s.seed));
      break;
    case TextureKind::kWood: {
      // `cells` planks across v; grain along u, bent by low-frequency noise.
      const int plank = std::max(4, S / cells);
      for (int y = 0; y < S; ++y) {
        for (int x = 0; x < S; ++x) {
          const int p = y / plank;
          const double bend = 6.0 * fractal(x, y, S, 64.0, 2, s.seed + 7u * p);
          const double grain =
              std::sin((y + bend) * 2.0 * M_PI * 7.0 / plank + hash01(p, 0, s.seed) * 6.0);
          const double fine = fractal(x, y, S, 4.0, 2, s.seed + 3u);
          double v = m + c * (0.45 * grain + 0.25 * fine + 0.5 * (hash01(p, 1, s.seed) - 0.5));
          if (y % plank == 0) v = m - 1.5 * c;  // joint between planks
          put(x, y, v);
        }
      }
      break;
    }
    case TextureKind::kBrick: {
      const int bh = std::max(4, S / cells);
      const int bw = 2 * bh;
      for (int y = 0; y < S; ++y) {
        const int row = y / bh;
        const int shift = (row % 2) ? bw / 2 : 0;
        for (int x = 0; x < S; ++x) {
          const int col = ((x + shift) % S) / bw;
          const bool mortar = (y % bh) < 2 || ((x + shift) % bw) < 2;
          const double fine = fractal(x, y, S, 6.0, 2, s.seed);
          const double v =
              mortar ? m + 0.8 * c
                     : m - 0.3 * c + c * (hash01(col, row, s.seed) - 0.5) + 0.3 * c * fine;
          put(x, y, v);
        }
      }
      break;
    }
    case TextureKind::kStripes:
      for (int y = 0; y < S; ++y)
        for (int x = 0; x < S; ++x)
          put(x, y, m + c * (2.0 * hash01((x * cells) / S, 0, s.seed) - 1.0));
      break;
    case TextureKind::kTiles: {
      const int t = std::max(4, S / cells);
      const int grout = std::max(1, t / 24);
      for (int y = 0; y < S; ++y)
        for (int x = 0; x < S; ++x) {
          const bool g = (x % t) < grout || (y % t) < grout;
          const double fine = fractal(x, y, S, 8.0, 3, s.seed);
          put(x, y,
              g ? m - c : m + 0.3 * c * (hash01(x / t, y / t, s.seed) - 0.5) + 0.25 * c * fine);
        }
      break;
    }
    case TextureKind::kBooks: {
      // `rows` shelves; each has a board (light) at the bottom and a row of book spines.
      const int rows = std::max(1, s.rows);
      const int shelf = S / rows;
      const int board = std::max(2, shelf / 10);
      img.setTo(cv::Scalar(std::clamp(m - 1.6 * c, 0.0, 255.0)));  // back of the shelf
      for (int r = 0; r < rows; ++r) {
        const int y_bottom = (r + 1) * shelf;
        int x = 0, book = 0;
        while (x < S) {
          const int w = 3 + static_cast<int>(hash01(book, r, s.seed) * 10.0 * S / 256.0);
          const double h = shelf * (0.55 + 0.35 * hash01(book, r + 99, s.seed));
          const double g = m + c * (2.0 * hash01(book, r + 7, s.seed) - 1.0);
          const bool gap = hash01(book, r + 31, s.seed) < 0.08;
          for (int xx = x; xx < std::min(S, x + w); ++xx)
            for (int y = y_bottom - board - static_cast<int>(h); y < y_bottom - board; ++y)
              if (!gap && y >= 0) put(xx, y, (xx == x) ? g - 0.5 * c : g);
          x += w;
          ++book;
        }
        for (int y = y_bottom - board; y < y_bottom; ++y)
          for (int xx = 0; xx < S; ++xx) put(xx, y, m + 1.2 * c);
      }
      break;
    }
    case TextureKind::kWindow: {
      const int cols = cells, rows = std::max(1, s.rows);
      const int bar = std::max(2, S / 40);
      for (int y = 0; y < S; ++y)
        for (int x = 0; x < S; ++x) {
          const int cx = (x * cols) % S, cy = (y * rows) % S;
          const bool mull = cx < bar * cols || cy < bar * rows || x >= S - bar || y >= S - bar;
          // Sky/outside: brighter at the top, faint structure far away.
          const double outside = m + 0.2 * c * (1.0 - static_cast<double>(y) / S) +
                                 0.15 * c * fractal(x, y, S, 48.0, 3, s.seed);
          put(x, y, mull ? m - 2.5 * c : outside);
        }
      break;
    }
    case TextureKind::kDoor: {
      // Two recessed panels, a handle on the right at 45% height.
      const double frame = 0.12 * S;
      for (int y = 0; y < S; ++y)
        for (int x = 0; x < S; ++x) {
          const double fine = fractal(x, y, S, 24.0, 3, s.seed);
          double v = m + 0.2 * c * fine;
          const bool in_x = x > frame && x < S - frame;
          const bool p1 = in_x && y > 0.08 * S && y < 0.42 * S;
          const bool p2 = in_x && y > 0.52 * S && y < 0.92 * S;
          if (p1 || p2) v -= 0.35 * c;
          const bool edge1 = in_x && (std::abs(y - 0.08 * S) < 1.5 || std::abs(y - 0.42 * S) < 1.5);
          const bool edge2 = in_x && (std::abs(y - 0.52 * S) < 1.5 || std::abs(y - 0.92 * S) < 1.5);
          const bool edgex = (y > 0.08 * S && y < 0.92 * S) &&
                             (std::abs(x - frame) < 1.5 || std::abs(x - (S - frame)) < 1.5);
          if (edge1 || edge2 || edgex) v -= c;
          if (x > 0.82 * S && x < 0.93 * S && y > 0.46 * S && y < 0.49 * S) v = m - 2.0 * c;
          put(x, y, v);
        }
      break;
    }
    case TextureKind::kImage:
      break;
  }
  return img;
}

int pow2_near(int n, int max_n) {
  int p = 1;
  while (p * 2 <= n) p *= 2;
  if (p * 2 <= max_n && (n - p) > (2 * p - n)) p *= 2;  // nearer to the next power
  return std::min(p, max_n);
}

}  // namespace

const char* to_string(TextureKind kind) {
  for (const auto& [k, name] : kKindNames)
    if (k == kind) return name;
  return "unknown";
}

TextureKind texture_kind_from_string(const std::string& name) {
  std::string all;
  for (const auto& [k, n] : kKindNames) {
    if (name == n) return k;
    all += all.empty() ? n : std::string(", ") + n;
  }
  throw std::invalid_argument("unknown texture type '" + name + "' (one of: " + all + ")");
}

Texture::Texture(std::string name, const cv::Mat& level0, bool repeat)
    : name_(std::move(name)), repeat_(repeat) {
  if (level0.type() != CV_8UC1 || !is_pow2(level0.cols) || !is_pow2(level0.rows))
    throw std::invalid_argument("Texture '" + name_ +
                                "': level 0 must be CV_8UC1 with power-of-two sides");
  levels_.push_back(level0.clone());
  mean_ = cv::mean(level0)[0];
  while (levels_.back().cols > 1 && levels_.back().rows > 1) {
    cv::Mat half;
    cv::resize(levels_.back(), half, cv::Size(levels_.back().cols / 2, levels_.back().rows / 2), 0,
               0, cv::INTER_AREA);
    levels_.push_back(half);
  }
}

std::vector<std::string> validate(const TextureSpec& spec, const std::filesystem::path& base_dir,
                                  const std::string& where) {
  std::vector<std::string> errors;
  auto bad = [&](const std::string& what) { errors.push_back(where + "." + what); };
  if (spec.kind == TextureKind::kImage) {
    if (spec.file.empty()) {
      bad("file: required for type image");
    } else if (!std::filesystem::exists(base_dir / spec.file)) {
      bad("file: '" + (base_dir / spec.file).string() + "' does not exist");
    }
    if (!(spec.max_size_px >= 16 && spec.max_size_px <= 2048 && is_pow2(spec.max_size_px)))
      bad("max_size_px: must be a power of two in [16, 2048]");
  } else {
    if (!(spec.size_px >= 16 && spec.size_px <= 1024 && is_pow2(spec.size_px)))
      bad("size_px = " + std::to_string(spec.size_px) + ": must be a power of two in [16, 1024]");
  }
  if (!(spec.mean >= 0 && spec.mean <= 255)) bad("mean: must be in [0, 255]");
  if (!(spec.contrast >= 0 && spec.contrast <= 255)) bad("contrast: must be in [0, 255]");
  if (!(spec.cells >= 1 && spec.cells <= 256)) bad("cells: must be in [1, 256]");
  if (!(spec.rows >= 1 && spec.rows <= 64)) bad("rows: must be in [1, 64]");
  if (!(spec.octaves >= 1 && spec.octaves <= 8)) bad("octaves: must be in [1, 8]");
  if (!(spec.feature_px >= 1 && spec.feature_px <= 256)) bad("feature_px: must be in [1, 256]");
  return errors;
}

Texture make_texture(const TextureSpec& spec, const std::filesystem::path& base_dir) {
  const auto errors = validate(spec, base_dir, "textures." + spec.name);
  if (!errors.empty()) throw WorldError(errors.front());
  if (spec.kind != TextureKind::kImage) return Texture(spec.name, generate(spec), spec.repeat);
  const std::filesystem::path file = base_dir / spec.file;
  cv::Mat img = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  if (img.empty())
    throw WorldError("textures." + spec.name + ".file: cannot read image '" + file.string() + "'");
  const int w = pow2_near(img.cols, spec.max_size_px);
  const int h = pow2_near(img.rows, spec.max_size_px);
  cv::Mat resized;
  cv::resize(img, resized, cv::Size(w, h), 0, 0, w < img.cols ? cv::INTER_AREA : cv::INTER_LINEAR);
  return Texture(spec.name, resized, spec.repeat);
}

}  // namespace pepper::sim
