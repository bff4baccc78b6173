#pragma once
// Grey textures of the simulated world: procedural patterns (checker, noise, wood, brick, ...)
// or image files, stored as a mipmap pyramid of 8-bit levels for the renderer.
//
// Units: a texture has no physical size of its own; the surface that uses it says how many metres
// one repetition covers (`tile_m`), or stretches it once over the surface (posters).
// Sizes: every level is a power of two in both directions (so that repeating textures wrap with a
// mask); image files are resized to the nearest power of two, at most `max_size_px`.
// Determinism: procedural textures depend only on their spec (the seed is part of it).
// Failure: make_texture() throws WorldError (world.hpp) naming the texture and the file.
// Thread-safety: a built Texture is immutable and may be shared between renderers.

#include <cstdint>
#include <filesystem>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

namespace pepper::sim {

/// Which pattern a texture shows. Values are the YAML names (texture_kind_from_string).
enum class TextureKind {
  kUniform,  ///< flat grey `mean`
  kChecker,  ///< `cells` x `cells` squares of mean +- contrast
  kNoise,    ///< fractal value noise (plaster, carpet, concrete), `octaves`, `feature_px`
  kWood,     ///< grain along u with rings and knots
  kBrick,    ///< running-bond bricks with mortar lines
  kStripes,  ///< `cells` vertical stripes of random greys
  kTiles,    ///< square tiles with grout lines (floors, ceilings), `cells` per side
  kBooks,    ///< shelf boards with rows of book spines
  kWindow,   ///< bright panes with mullions (`cells` x `rows`)
  kDoor,     ///< panelled door with a handle
  kImage,    ///< image file (`file`), converted to grey
};

const char* to_string(TextureKind kind);
/// Throws std::invalid_argument listing the valid names when `name` is unknown.
TextureKind texture_kind_from_string(const std::string& name);

/// Parameters of one texture (YAML `textures: NAME: {...}`).
struct TextureSpec {
  std::string name;
  TextureKind kind = TextureKind::kUniform;
  double mean = 128.0;         ///< mean grey, 0..255
  double contrast = 40.0;      ///< amplitude of the pattern, grey levels
  int cells = 8;               ///< pattern-specific count (checker cells, stripes, tiles, panes)
  int rows = 2;                ///< window rows, book shelves
  double feature_px = 16.0;    ///< noise: size of the largest blob, texels at 256 px
  int octaves = 4;             ///< noise: number of octaves
  uint32_t seed = 1;           ///< procedural randomness
  int size_px = 256;           ///< procedural: side of level 0 (power of two, 16..1024)
  std::filesystem::path file;  ///< kImage: path relative to the world file's folder
  int max_size_px = 512;       ///< kImage: longest side of level 0 after resizing
  bool repeat = true;          ///< wrap around (tiled surfaces) or clamp at the border (posters)
};

/// A mipmap pyramid of 8-bit grey levels; level 0 is the full resolution.
class Texture {
 public:
  Texture() = default;
  /// Builds the pyramid (box-filtered halving down to 1x1 in the smaller direction) from `level0`
  /// (CV_8UC1, power-of-two sides; throws std::invalid_argument otherwise).
  Texture(std::string name, const cv::Mat& level0, bool repeat);

  const std::string& name() const { return name_; }
  bool repeat() const { return repeat_; }
  int levels() const { return static_cast<int>(levels_.size()); }
  const cv::Mat& level(int i) const { return levels_.at(static_cast<size_t>(i)); }
  int width_px() const { return levels_.empty() ? 0 : levels_[0].cols; }
  int height_px() const { return levels_.empty() ? 0 : levels_[0].rows; }
  double mean() const { return mean_; }

 private:
  std::string name_;
  bool repeat_ = true;
  double mean_ = 0.0;
  std::vector<cv::Mat> levels_;
};

/// Generates (procedural) or loads (kImage, relative to `base_dir`) the texture of `spec`.
Texture make_texture(const TextureSpec& spec, const std::filesystem::path& base_dir);

/// Messages naming each invalid field of `spec` (prefixed with `where`); empty when valid.
/// Checks that image files exist.
std::vector<std::string> validate(const TextureSpec& spec, const std::filesystem::path& base_dir,
                                  const std::string& where);

}  // namespace pepper::sim
