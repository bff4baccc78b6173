#pragma once
// Outputs of the closed-loop evaluation (docs/evaluation.md): JSON for machines, a fixed-width
// table for people, PNG plots (top view with the world's walls and furniture, lateral deviation,
// omega and feature counts over distance) and a self-contained HTML page gathering them.
//
// JSON (format "pepper.evaluation", version 1): {"format", "version", "evaluations": [ {world,
// features, controller, size, disturbances, disturbance_notes, key_images, taught_length_m,
// teach_frames, summary: {success_rate, lateral_rms_m, lateral_max_m, ...}, runs: [...] } ]}.
// With a single evaluation its "summary" and "runs" are also copied to the top level, so
// `summary.success_rate` works for the common case. Non-finite numbers are written as null.
// Files are written atomically (temp file + rename); failures throw std::runtime_error naming
// the path.

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "evaluation/closed_loop.hpp"

namespace pepper::app::evaluation {

nlohmann::json to_json(const std::vector<Evaluation>& evaluations);

/// One row per evaluation (world x features x disturbances), the columns of the summary.
std::string summary_table(const std::vector<Evaluation>& evaluations);
/// One row per run of one evaluation.
std::string runs_table(const Evaluation& evaluation);

/// Writes text to `path` atomically.
void write_text_file(const std::filesystem::path& path, const std::string& text);

/// PNG plots of one evaluation into `dir` (created), file names prefixed with `prefix`
/// (e.g. "robotics_room_lines+points_"): top_view.png (every run), run<N>_top_view.png (run N
/// alone, N from 1; a failed run marked where it ended), lateral.png, omega.png, features.png.
/// Returns the files written.
std::vector<std::filesystem::path> write_plots(const Evaluation& evaluation,
                                               const TeachResult& teach, const sim::World& world,
                                               const std::filesystem::path& dir,
                                               const std::string& prefix);

/// The key images of one taught map for the report (report::key_image_thumbnails).
struct KeyImageStrip {
  std::string title;  ///< e.g. "robotics_room (lines+points)"
  std::string html;
};

/// An HTML page with the summary table, the per-run tables, every plot of `dir`'s PNGs and the
/// key images of each taught map.
void write_html_report(const std::vector<Evaluation>& evaluations,
                       const std::vector<std::filesystem::path>& plots,
                       const std::vector<KeyImageStrip>& key_images,
                       const std::string& command_line, const std::filesystem::path& path);

}  // namespace pepper::app::evaluation
