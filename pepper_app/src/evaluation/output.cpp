#include "evaluation/output.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "report/html_report.hpp"
#include "report/plot.hpp"

namespace pepper::app::evaluation {
namespace {

using nlohmann::json;

json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

std::string fmt(const char* f, double v) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

json summary_json(const Summary& s) {
  return {{"runs", s.runs},
          {"successes", s.successes},
          {"success_rate", s.success_rate},
          {"lateral_rms_m", num(s.lateral_rms_m)},
          {"lateral_max_m", num(s.lateral_max_m)},
          {"verified_lines_mean", num(s.verified_lines_mean)},
          {"verified_points_mean", num(s.verified_points_mean)},
          {"final_error_mean_m", num(s.final_error_mean_m)},
          {"final_error_max_m", num(s.final_error_max_m)},
          {"key_images_per_m", num(s.key_images_per_m)},
          {"converged_from_max_m", num(s.converged_from_max_m)},
          {"omega_rate_rms_rad_s2", num(s.omega_rate_rms_rad_s2)},
          {"arrival_judged", s.arrival_judged},
          {"arrival_agreed", s.arrival_agreed},
          {"step_ms_median", num(s.step_ms_median)},
          {"step_ms_p95", num(s.step_ms_p95)}};
}

json run_json(const RunResult& r) {
  json reacquisitions = json::array();
  for (const RunResult::Reacquisition& q : r.reacquisitions) {
    reacquisitions.push_back({{"blind_m", num(q.blind_m)},
                              {"blind_rad", num(q.blind_rad)},
                              {"corrected_m", num(q.corrected_m)},
                              {"corrected_rad", num(q.corrected_rad)}});
  }
  return {{"index", r.index},
          {"start", {{"x_m", r.start_x_m}, {"y_m", r.start_y_m}, {"yaw_rad", r.start_yaw_rad},
                     {"lateral_m", num(r.start_lateral_m)}}},
          {"light_factor", r.light_factor},
          {"success", r.success},
          {"outcome", r.outcome},
          {"detail", r.detail},
          {"tour_complete", r.tour_complete},
          {"travelled_m", r.travelled_m},
          {"lateral_rms_m", num(r.lateral_rms_m)},
          {"lateral_max_m", num(r.lateral_max_m)},
          {"verified_lines_mean", num(r.verified_lines_mean)},
          {"verified_points_mean", num(r.verified_points_mean)},
          {"converged_from_m", num(r.converged_from_m)},
          {"first_under_5cm_m", num(r.first_under_5cm_m)},
          {"final_error_m", num(r.final_error_m)},
          {"arrival", {{"verdict", r.arrival_verdict},
                       {"source", r.arrival_source},
                       {"offset_m", num(r.arrival_offset_m)}}},
          {"omega_rate_rms_rad_s2", num(r.omega_rate_rms_rad_s2)},
          {"step_ms_median", num(r.step_ms_median)},
          {"step_ms_p95", num(r.step_ms_p95)},
          {"frames", r.frames},
          {"frames_dropped", r.frames_dropped},
          {"lost_frames", r.lost_frames},
          {"dead_reckoning_frames", r.dead_reckoning_frames},
          {"line_heading_frames", r.line_heading_frames},
          {"reacquisitions", std::move(reacquisitions)},
          {"sim_s", r.sim_s},
          {"wall_s", r.wall_s}};
}

std::string pad(const std::string& s, size_t w) {
  return s.size() >= w ? s + " " : s + std::string(w - s.size(), ' ');
}

}  // namespace

json to_json(const std::vector<Evaluation>& evaluations) {
  json out = {{"format", "pepper.evaluation"}, {"version", 1}};
  json list = json::array();
  for (const Evaluation& e : evaluations) {
    json runs = json::array();
    for (const RunResult& r : e.runs) runs.push_back(run_json(r));
    list.push_back({{"world", e.world_name},
                    {"mode", e.mode},
                    {"features", e.features},
                    {"controller", e.controller},
                    {"size", e.size},
                    {"lens", e.lens},
                    {"disturbances", e.disturbances},
                    {"disturbance_notes", e.disturbance_notes},
                    {"key_images", e.key_images},
                    {"taught_length_m", e.taught_length_m},
                    {"teach_frames", e.teach_frames},
                    {"summary", summary_json(e.summary)},
                    {"runs", runs}});
  }
  out["evaluations"] = list;
  if (evaluations.size() == 1) {
    out["summary"] = list[0]["summary"];
    out["runs"] = list[0]["runs"];
  }
  return out;
}

std::string summary_table(const std::vector<Evaluation>& evaluations) {
  std::ostringstream os;
  const std::vector<std::pair<std::string, size_t>> cols = {
      {"world", 20},      {"features", 13},    {"disturbance", 13}, {"success", 8},
      {"conv m", 7},      {"lat rms cm", 11}, {"lat max cm", 11},  {"end err cm", 11}, {"KI/m", 6},
      {"dw rms", 8},      {"IN lines/pts", 13}, {"step ms p50", 12}, {"p95", 6}};
  for (const auto& [name, w] : cols) os << pad(name, w);
  os << "\n";
  for (const Evaluation& e : evaluations) {
    std::string dist;
    for (const auto& d : e.disturbances) dist += (dist.empty() ? "" : ",") + d;
    if (dist.empty()) dist = "none";
    const Summary& s = e.summary;
    os << pad(e.world_name, 20) << pad(e.features, 13) << pad(dist, 13)
       << pad(std::to_string(s.successes) + "/" + std::to_string(s.runs), 8)
       << pad(fmt("%.2f", s.converged_from_max_m), 7)
       << pad(fmt("%.1f", 100 * s.lateral_rms_m), 11) << pad(fmt("%.1f", 100 * s.lateral_max_m), 11)
       << pad(fmt("%.1f", 100 * s.final_error_mean_m), 11) << pad(fmt("%.2f", s.key_images_per_m), 6)
       << pad(fmt("%.2f", s.omega_rate_rms_rad_s2), 8)
       << pad(fmt("%.0f", s.verified_lines_mean) + "/" + fmt("%.0f", s.verified_points_mean), 13)
       << pad(fmt("%.1f", s.step_ms_median), 12)
       << pad(fmt("%.1f", s.step_ms_p95), 6) << "\n";
  }
  return os.str();
}

std::string runs_table(const Evaluation& e) {
  std::ostringstream os;
  os << pad("run", 5) << pad("outcome", 11) << pad("start lat cm", 13) << pad("yaw deg", 8)
     << pad("dist m", 8) << pad("conv m", 7) << pad("lat rms cm", 11) << pad("lat max cm", 11) << pad("end err cm", 11)
     << pad("dw rms", 8) << pad("step p50", 9) << pad("p95", 6) << "\n";
  for (const RunResult& r : e.runs) {
    os << pad(std::to_string(r.index + 1), 5) << pad(r.outcome, 11)
       << pad(fmt("%+.1f", 100 * r.start_lateral_m), 13)
       << pad(fmt("%+.1f", r.start_yaw_rad * 180 / M_PI), 8) << pad(fmt("%.2f", r.travelled_m), 8)
       << pad(r.converged_from_m < 0 ? std::string("never") : fmt("%.2f", r.converged_from_m), 7)
       << pad(fmt("%.1f", 100 * r.lateral_rms_m), 11) << pad(fmt("%.1f", 100 * r.lateral_max_m), 11)
       << pad(fmt("%.1f", 100 * r.final_error_m), 11) << pad(fmt("%.2f", r.omega_rate_rms_rad_s2), 8)
       << pad(fmt("%.1f", r.step_ms_median), 9) << pad(fmt("%.1f", r.step_ms_p95), 6);
    if (r.light_factor != 0.0) os << " light x" << fmt("%.2f", r.light_factor);
    if (!r.arrival_verdict.empty()) {
      os << " " << r.arrival_verdict;
      if (std::isfinite(r.arrival_offset_m)) {
        os << " (est. " << fmt("%.1f", 100 * r.arrival_offset_m) << " cm, " << r.arrival_source
           << ")";
      }
    }
    if (!r.detail.empty()) os << " " << r.detail;
    os << "\n";
  }
  return os.str();
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  const std::filesystem::path tmp = path.string() + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f << text;
    f.flush();
    if (!f) throw std::runtime_error("cannot write " + tmp.string());
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error("cannot rename " + tmp.string() + " to " + path.string());
}

std::vector<std::filesystem::path> write_plots(const Evaluation& e, const TeachResult& teach,
                                               const sim::World& world,
                                               const std::filesystem::path& dir,
                                               const std::string& prefix) {
  std::filesystem::create_directories(dir);
  std::vector<std::filesystem::path> files;
  auto save = [&](const cv::Mat& img, const std::string& name) {
    const std::filesystem::path p = dir / (prefix + name);
    const std::filesystem::path tmp = dir / (prefix + "tmp_" + name);
    if (!cv::imwrite(tmp.string(), img)) throw std::runtime_error("cannot write " + tmp.string());
    std::filesystem::rename(tmp, p);
    files.push_back(p);
  };
  const cv::Scalar grey(150, 150, 150), black(30, 30, 30);

  // Top view: walls, furniture footprints, taught path, replayed paths; one with every run, and a
  // small one per run (`run<N>_top_view.png`) for the matrix index (combine.py --html), where a
  // failed run is seen on its own with a red mark where it ended.
  auto top_view = [&](const std::vector<const RunResult*>& runs, const std::string& title,
                      int width_px, int height_px, bool numbered) {
    std::vector<report::Series> s;
    for (size_t i = 0; i < world.walls.size(); ++i) {
      const auto& w = world.walls[i];
      s.push_back({i == 0 ? "walls" : "", {w.a_m.x(), w.b_m.x()}, {w.a_m.y(), w.b_m.y()}, black, 2});
    }
    for (size_t i = 0; i < world.boxes.size(); ++i) {
      const auto corners = world.boxes[i].corners_m();
      report::Series r{i == 0 ? "furniture (taught)" : "", {}, {}, grey, 1};
      for (int k = 0; k <= 4; ++k) {  // closed outline
        r.x.push_back(corners[static_cast<size_t>(k % 4)].x());
        r.y.push_back(corners[static_cast<size_t>(k % 4)].y());
      }
      s.push_back(r);
    }
    report::Series taught{"taught", {}, {}, cv::Scalar(0, 0, 0), 3};
    for (const auto& p : teach.path_m) {
      taught.x.push_back(p.x());
      taught.y.push_back(p.y());
    }
    s.push_back(taught);
    // The key images where they were taught, numbered on the large view (every one, or every
    // 5th / 10th / ... on a long tour, so that the numbers stay legible), unnumbered on a run's
    // own small view; the report's key-image strip has the same numbers.
    report::Series keys{"key images", {}, {}, report::palette(4), 1, true};
    const std::size_t n_keys = teach.key_m.size();
    const std::size_t stride = n_keys <= 20 ? 1 : 5 * ((n_keys + 99) / 100);
    for (std::size_t k = 0; k < n_keys; ++k) {
      keys.x.push_back(teach.key_m[k].x());
      keys.y.push_back(teach.key_m[k].y());
      if (numbered) keys.point_labels.push_back(k % stride == 0 ? std::to_string(k) : "");
    }
    s.push_back(keys);
    // Where each run drove on odometry alone (vision blind, issue 29), as markers over the paths.
    report::Series blind{"driven on odometry alone", {}, {}, cv::Scalar(0, 0, 220), 1, true};
    report::Series ended{"", {}, {}, cv::Scalar(0, 0, 255), 4, true};
    for (const RunResult* r : runs) {
      report::Series rs{"run " + std::to_string(r->index + 1) + (r->success ? "" : " (" + r->outcome + ")"),
                        {}, {}, report::palette(r->index + 1), 1};
      for (const RunSample& smp : r->samples) {
        rs.x.push_back(smp.x_m);
        rs.y.push_back(smp.y_m);
        if (smp.dead_reckoning) {
          blind.x.push_back(smp.x_m);
          blind.y.push_back(smp.y_m);
        }
      }
      if (!r->success && !r->samples.empty()) {
        ended.label = "where it ended (" + r->outcome + ")";
        ended.x.push_back(r->samples.back().x_m);
        ended.y.push_back(r->samples.back().y_m);
      }
      s.push_back(rs);
    }
    s.push_back(blind);
    if (!ended.x.empty()) s.push_back(ended);
    return report::render_plot({title, "x (m)", "y (m)", width_px, height_px, true}, s);
  };
  {
    std::vector<const RunResult*> all;
    for (const RunResult& r : e.runs) all.push_back(&r);
    save(top_view(all, e.world_name + ": taught and replayed paths (" + e.features + ")", 1000, 800, true),
         "top_view.png");
    for (const RunResult& r : e.runs) {
      const std::string n = std::to_string(r.index + 1);
      save(top_view({&r}, "run " + n + (r.success ? ": " : ": FAILED, ") + r.outcome, 480, 400, false),
           "run" + n + "_top_view.png");
    }
  }
  auto over_distance = [&](const std::string& title, const std::string& ylabel, auto value,
                           const std::string& name) {
    std::vector<report::Series> s;
    for (const RunResult& r : e.runs) {
      report::Series rs{"run " + std::to_string(r.index + 1), {}, {}, report::palette(r.index + 1), 1};
      for (const RunSample& smp : r.samples) {
        rs.x.push_back(smp.travelled_m);
        rs.y.push_back(value(smp));
      }
      s.push_back(rs);
    }
    save(report::render_plot({title, "distance travelled (m)", ylabel, 1000, 380, false}, s), name);
  };
  over_distance(e.world_name + ": lateral deviation from the taught path (> 0 left)", "cm",
                [](const RunSample& smp) { return 100.0 * smp.lateral_m; }, "lateral.png");
  over_distance(e.world_name + ": commanded omega", "rad/s",
                [](const RunSample& smp) { return smp.omega_rad_s; }, "omega.png");
  // Feature counts of the first run (lines and points verified with IN).
  if (!e.runs.empty()) {
    const RunResult& r = e.runs.front();
    report::Series l{"lines (verified with IN)", {}, {}, report::palette(0), 1};
    report::Series p{"points (verified with IN)", {}, {}, report::palette(1), 1};
    for (const RunSample& smp : r.samples) {
      if (!smp.frame_received) continue;
      l.x.push_back(smp.travelled_m);
      l.y.push_back(smp.n_lines);
      p.x.push_back(smp.travelled_m);
      p.y.push_back(smp.n_points);
    }
    save(report::render_plot({e.world_name + ": feature counts, run 1 (" + e.features + ")",
                              "distance travelled (m)", "count", 1000, 380, false},
                             {l, p}),
         "features.png");
  }
  return files;
}

void write_html_report(const std::vector<Evaluation>& evaluations,
                       const std::vector<std::filesystem::path>& plots,
                       const std::vector<KeyImageStrip>& key_images,
                       const std::string& command_line, const std::filesystem::path& path) {
  report::HtmlReport page("Closed-loop evaluation");
  page.heading("Closed-loop evaluation");
  page.preformatted(command_line);
  page.preformatted(summary_table(evaluations));
  for (const Evaluation& e : evaluations) {
    std::string dist;
    for (const auto& d : e.disturbances) dist += (dist.empty() ? "" : ", ") + d;
    page.heading(e.world_name + " / " + e.features + " / " + (dist.empty() ? "no disturbance" : dist));
    for (const auto& n : e.disturbance_notes) page.paragraph(n);
    page.preformatted(runs_table(e));
  }
  for (const auto& p : plots) {
    const cv::Mat img = cv::imread(p.string(), cv::IMREAD_COLOR);
    if (!img.empty()) page.image(img, p.filename().string());
  }
  for (const KeyImageStrip& k : key_images) {
    page.heading("Key images: " + k.title + " (numbered as on the top view)");
    page.raw_html(k.html);
  }
  page.write(path);
}

}  // namespace pepper::app::evaluation
