#include "libsamp/eval/eval_report.h"

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/json_text.h"
#include "libsamp/core/util.h"
#include "libsamp/viz/image.h"
#include "libsamp/viz/plot.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

const char* const kMatchingNames[kNumMatchings] = {"per track", "per frame"};
const char* const kMatchingKeys[kNumMatchings] = {"per_track", "per_frame"};

std::string WindowName(const PoseWindow& w) {
  return Fixed(w.min_distance, 0) + "-" + Fixed(w.max_distance, 0) + " m";
}

// The rows of a pose table: each window, then ">= first window", then "all".
std::vector<std::pair<std::string, PoseWindow>> PoseRows(const MethodPoseResult& p) {
  std::vector<std::pair<std::string, PoseWindow>> rows;
  for (const PoseWindow& w : p.windows) rows.emplace_back(WindowName(w), w);
  rows.emplace_back(">= " + Fixed(p.beyond_first.min_distance, 0) + " m", p.beyond_first);
  rows.emplace_back("all", p.all);
  return rows;
}

void WritePlots(const EvalOptions& options, const EvalSummary& summary) {
  const fs::path out(options.output_folder);
  struct Figure {
    const char* file;
    const char* title;
    const char* y_label;
    int which;
  };
  for (const Figure& fig : {Figure{"f1_vs_tau.png", "F1 score", "F1 [%]", 0},
                            Figure{"accuracy_vs_tau.png", "Accuracy", "accuracy [%]", 1},
                            Figure{"completeness_vs_tau.png", "Completeness", "completeness [%]", 2}}) {
    std::vector<PlotSeries> series;
    const Marker markers[] = {Marker::kCircle, Marker::kSquare, Marker::kTriangle, Marker::kDiamond};
    for (size_t m = 0; m < summary.shape.size(); ++m) {
      const MethodShapeResult& s = summary.shape[m];
      PlotSeries p;
      p.label = s.method;
      p.x = summary.taus;
      const std::vector<double>& values = fig.which == 0 ? s.f1 : fig.which == 1 ? s.accuracy : s.completeness;
      for (double v : values) p.y.push_back(100.0 * v);
      p.marker = markers[m % 4];
      series.push_back(p);
    }
    LinePlotOptions plot;
    plot.title = std::string(fig.title) + " vs. threshold (" + std::to_string(summary.shape.empty() ? 0 : summary.shape[0].num_evaluated) + " car-frames)";
    plot.x_label = "tau [m]";
    plot.y_label = fig.y_label;
    plot.y_min = 0.0;
    plot.y_max = 100.0;
    plot.legend = LegendPosition::kBottomRight;
    if (!series.empty()) WritePng((out / fig.file).string(), DrawLinePlot(series, plot));
  }
  if (summary.pose.empty() || summary.pose[0].windows.empty()) return;
  std::vector<std::string> categories;
  for (const PoseWindow& w : summary.pose[0].windows) categories.push_back(WindowName(w));
  for (int which = 0; which < 2; ++which) {
    std::vector<BarSeries> series;
    for (const MethodPoseResult& p : summary.pose) {
      BarSeries s;
      s.label = p.method;
      for (const PoseWindow& w : p.windows) {
        const double value = which == 0 ? w.translation_median : w.yaw_median_deg;
        s.values.push_back(w.count > 0 ? value : std::nan(""));
      }
      series.push_back(s);
    }
    BarPlotOptions plot;
    plot.title = which == 0 ? "Median translation error" : "Median yaw error";
    plot.x_label = "distance to the camera";
    plot.y_label = which == 0 ? "error [m]" : "error [deg]";
    plot.show_values = true;
    plot.value_precision = which == 0 ? 2 : 1;
    plot.legend = LegendPosition::kTopLeft;
    WritePng((out / (which == 0 ? "translation_vs_distance.png" : "yaw_vs_distance.png")).string(),
             DrawBarPlot(categories, series, plot));
  }
}

std::string ShapeCsv(const EvalOptions& options, const EvalSummary& summary) {
  std::ostringstream shape_csv;
  shape_csv << "method,matching,tau,accuracy,completeness,f1,car_frames\n";
  for (int k = 0; k < kNumMatchings; ++k) {
    for (const MethodShapeResult& s : k == kPerTrack ? summary.shape : summary.shape_per_frame) {
      for (size_t i = 0; i < options.taus.size(); ++i) {
        shape_csv << s.method << "," << kMatchingKeys[k] << "," << options.taus[i] << "," << Fixed(s.accuracy[i], 6)
                  << "," << Fixed(s.completeness[i], 6) << "," << Fixed(s.f1[i], 6) << "," << s.num_evaluated
                  << "\n";
      }
    }
  }
  return shape_csv.str();
}

std::string PoseCsv(const EvalSummary& summary) {
  std::ostringstream pose_csv;
  pose_csv << "method,matching,window,min_distance,max_distance,count,translation_mean,translation_median,"
              "yaw_mean_deg,yaw_median_deg\n";
  for (int k = 0; k < kNumMatchings; ++k) {
    for (const MethodPoseResult& p : k == kPerTrack ? summary.pose : summary.pose_per_frame) {
      for (const auto& [name, w] : PoseRows(p)) {
        pose_csv << p.method << "," << kMatchingKeys[k] << "," << name << "," << w.min_distance << ","
                 << w.max_distance << "," << w.count << "," << Fixed(w.translation_mean, 6) << ","
                 << Fixed(w.translation_median, 6) << "," << Fixed(w.yaw_mean_deg, 6) << ","
                 << Fixed(w.yaw_median_deg, 6) << "\n";
      }
    }
  }
  return pose_csv.str();
}

// per_object.csv (every car-frame, method and matching) and per_car.csv (the
// matched ones of the pose methods).
void CarFrameCsvs(const EvalResults& results, std::string* per_object, std::string* per_car) {
  const size_t headline = results.summary.HeadlineIndex();
  const std::vector<EvalMethod>& methods = results.methods;
  std::ostringstream object_csv;
  object_csv << "sequence,track_id,frame,distance,segment_pixels,true_points,method,matching,matched,"
                "translation_error,yaw_error_deg,estimated_points,accuracy,completeness,f1\n";
  std::ostringstream car_csv;
  car_csv << "sequence,track_id,frame,distance,method,matching,output_track,along_ray_offset,lateral_offset,"
             "vertical_offset,h,w,l,true_h,true_w,true_l,translation_error,yaw_error_deg,f1\n";
  for (const CarFrameRecord& r : results.records) {
    for (int k = 0; k < kNumMatchings; ++k) {
      for (size_t m = 0; m < methods.size(); ++m) {
        const MethodCarFrame& mr = r.methods[k][m];
        object_csv << r.sequence << "," << r.track_id << "," << r.frame << "," << Fixed(r.distance, 3) << ","
                   << r.segment_pixels << "," << r.num_true_points << "," << methods[m].name << ","
                   << kMatchingKeys[k] << "," << (mr.matched ? 1 : 0) << ",";
        if (mr.matched && methods[m].pose) {
          object_csv << Fixed(mr.translation_error, 4) << "," << Fixed(mr.yaw_error_deg, 3);
        } else {
          object_csv << ",";
        }
        object_csv << "," << mr.num_estimated_points << ",";
        if (mr.has_shape) {
          const ShapeScores& s = mr.scores[headline];
          object_csv << Fixed(s.accuracy, 4) << "," << Fixed(s.completeness, 4) << "," << Fixed(s.f1, 4);
        } else {
          object_csv << ",,";
        }
        object_csv << "\n";
        if (!mr.matched || !methods[m].pose) continue;
        car_csv << r.sequence << "," << r.track_id << "," << r.frame << "," << Fixed(r.distance, 3) << ","
                << methods[m].name << "," << kMatchingKeys[k] << "," << mr.output_track << ","
                << Fixed(mr.along_ray_offset, 4) << "," << Fixed(mr.lateral_offset, 4) << ","
                << Fixed(mr.vertical_offset, 4) << "," << Fixed(mr.size[0], 3) << "," << Fixed(mr.size[1], 3) << ","
                << Fixed(mr.size[2], 3) << "," << Fixed(r.true_size[0], 3) << "," << Fixed(r.true_size[1], 3) << ","
                << Fixed(r.true_size[2], 3) << "," << Fixed(mr.translation_error, 4) << ","
                << Fixed(mr.yaw_error_deg, 3) << "," << (mr.has_shape ? Fixed(mr.scores[headline].f1, 4) : "")
                << "\n";
      }
    }
  }
  *per_object = object_csv.str();
  *per_car = car_csv.str();
}

std::string TrackingCsv(const EvalSummary& summary) {
  std::ostringstream tracking_csv;
  tracking_csv << "method,true_cars,true_boxes,output_tracks,output_boxes,matches,tracks_per_car,main_track_share,"
                  "id_switches,fragmentations,missed_cars,false_tracks,misses,false_positives,mota,motp\n";
  for (const MethodTrackingResult& t : summary.tracking) {
    const TrackingCounts& c = t.counts;
    tracking_csv << t.method << "," << c.true_cars << "," << c.true_boxes << "," << c.output_tracks << ","
                 << c.output_boxes << "," << c.matches << "," << Fixed(c.TracksPerCar(), 4) << ","
                 << Fixed(c.MainTrackShare(), 4) << "," << c.id_switches << "," << c.fragmentations << ","
                 << c.missed_cars << "," << c.false_tracks << "," << c.misses << "," << c.false_positives << ","
                 << Fixed(c.Mota(), 4) << "," << Fixed(c.Motp(), 4) << "\n";
  }
  return tracking_csv.str();
}

std::string ResultsJson(const EvalOptions& options, const EvalResults& results) {
  const EvalSummary& summary = results.summary;
  nlohmann::json j;
  j["options"] = nlohmann::json::parse(options.ToJson());
  j["num_car_frames"] = results.records.size();
  j["num_tracks"] = summary.num_gt_tracks;
  for (int k = 0; k < kNumMatchings; ++k) {
    const std::string suffix = k == kPerTrack ? "" : "_per_frame";
    for (const MethodShapeResult& s : k == kPerTrack ? summary.shape : summary.shape_per_frame) {
      j["shape" + suffix].push_back({{"method", s.method},
                                     {"taus", options.taus},
                                     {"accuracy", s.accuracy},
                                     {"completeness", s.completeness},
                                     {"f1", s.f1},
                                     {"car_frames", s.num_evaluated},
                                     {"matched", s.num_matched}});
    }
    for (const MethodPoseResult& p : k == kPerTrack ? summary.pose : summary.pose_per_frame) {
      nlohmann::json windows = nlohmann::json::array();
      for (const auto& [name, w] : PoseRows(p)) {
        windows.push_back({{"window", name},
                           {"min_distance", w.min_distance},
                           {"max_distance", w.max_distance},
                           {"count", w.count},
                           {"translation_mean", w.translation_mean},
                           {"translation_median", w.translation_median},
                           {"yaw_mean_deg", w.yaw_mean_deg},
                           {"yaw_median_deg", w.yaw_median_deg}});
      }
      j["pose" + suffix].push_back({{"method", p.method}, {"windows", windows}, {"matched", p.num_matched}});
    }
  }
  for (const MethodTrackingResult& t : summary.tracking) {
    const TrackingCounts& c = t.counts;
    j["tracking"].push_back({{"method", t.method},
                             {"true_cars", c.true_cars},
                             {"true_boxes", c.true_boxes},
                             {"output_tracks", c.output_tracks},
                             {"output_boxes", c.output_boxes},
                             {"matches", c.matches},
                             {"tracks_per_car", c.TracksPerCar()},
                             {"main_track_share", c.MainTrackShare()},
                             {"id_switches", c.id_switches},
                             {"fragmentations", c.fragmentations},
                             {"missed_cars", c.missed_cars},
                             {"false_tracks", c.false_tracks},
                             {"misses", c.misses},
                             {"false_positives", c.false_positives},
                             {"mota", c.Mota()},
                             {"motp", c.Motp()}});
  }
  for (const DiagnosticsBand& b : summary.diagnostics) {
    j["diagnostics"].push_back({{"method", b.method},
                                {"min_distance", b.min_distance},
                                {"max_distance", b.max_distance},
                                {"count", b.count},
                                {"along_ray_offset_median", b.along_ray_offset},
                                {"abs_lateral_offset_median", b.abs_lateral_offset},
                                {"abs_vertical_offset_median", b.abs_vertical_offset},
                                {"size_error_median", {b.size_error[0], b.size_error[1], b.size_error[2]}},
                                {"f1_median", b.f1},
                                {"shape_count", b.num_shape}});
  }
  return DumpJson(j, 2) + "\n";
}

// The shape tables of matching k: at the headline tau, and F1 over tau.
void MarkdownShape(const EvalOptions& options, const EvalResults& results, int k, std::ostringstream& md) {
  const EvalSummary& summary = results.summary;
  const std::vector<CarFrameRecord>& records = results.records;
  const size_t headline = summary.HeadlineIndex();
  const std::string tau = Fixed(options.headline_tau, 2);
  const std::vector<MethodShapeResult>& shape_results = k == kPerTrack ? summary.shape : summary.shape_per_frame;
  const std::string matching = std::string(" (") + kMatchingNames[k] + " matching)";
  if (shape_results.empty()) {
    if (k != kPerTrack) return;
    md << "### Shape\n\nNo shape figures: ";
    if (results.without_maps) {
      md << "KITTI tracking's ground truth has no depth maps. " << records.size() << " true car-frames evaluated "
         << "(Car labels with a 2D box of at least " << Fixed(options.min_box_height_px, 0) << " px, occlusion "
         << "at most " << options.max_occlusion << " and truncation at most " << Fixed(options.max_truncation, 2)
         << "; " << summary.num_gt_tracks << " tracks, " << options.sequences.size() << " sequences).\n";
    } else {
      md << "no method with surfaces (the stereo baseline left out, results without meshes).\n";
    }
    return;
  }
  md << "### Shape at tau = " << tau << " m" << matching << "\n\n";
  const int common_shape = shape_results.empty() ? 0 : shape_results[0].num_evaluated;
  md << common_shape << " car-frames matched by every method (of " << records.size()
     << " with >= " << options.min_segment_pixels << " visible pixels, " << summary.num_gt_tracks
     << " tracks, " << options.sequences.size() << " sequences).";
  md << (k == kPerTrack ? " Each true car is matched to one output track (the one sharing most IoU-matched "
                          "frames with it): a fragmented or swapped track costs.\n\n"
                        : " Each true car-frame is matched to the nearest box of any track within " +
                              Fixed(options.per_frame_distance, 1) + " m: abstracts from tracking errors.\n\n");
  md << "| Method | Accuracy [%] | Completeness [%] | F1 [%] | Matched car-frames |\n";
  md << "|---|---:|---:|---:|---:|\n";
  for (const MethodShapeResult& s : shape_results) {
    md << "| " << s.method << " | " << Fixed(100 * s.accuracy[headline], 2) << " | "
       << Fixed(100 * s.completeness[headline], 2) << " | " << Fixed(100 * s.f1[headline], 2) << " | "
       << s.num_matched << " / " << records.size() << " |\n";
  }
  md << "\n### F1 [%] over tau" << matching << "\n\n| Method |";
  for (double t : options.taus) md << " " << Fixed(t, 2) << " |";
  md << "\n|---|";
  for (size_t i = 0; i < options.taus.size(); ++i) md << "---:|";
  md << "\n";
  for (const MethodShapeResult& s : shape_results) {
    md << "| " << s.method << " |";
    for (double v : s.f1) md << " " << Fixed(100 * v, 2) << " |";
    md << "\n";
  }
}

// The pose table of matching k by distance window.
void MarkdownPose(const EvalResults& results, int k, std::ostringstream& md) {
  const EvalSummary& summary = results.summary;
  const std::vector<MethodPoseResult>& pose_results = k == kPerTrack ? summary.pose : summary.pose_per_frame;
  const std::string matching = std::string(" (") + kMatchingNames[k] + " matching)";
  md << "\n### Pose" << matching << "\n\n";
  const int common_pose = pose_results.empty() ? 0 : pose_results[0].all.count;
  md << common_pose << " car-frames matched by every method. Translation error of the object "
     << "origin (m), absolute yaw error (deg, 180-degree flips count fully).\n\n";
  md << "| Method | Distance | n | Transl. mean | Transl. median | Yaw mean | Yaw median |\n";
  md << "|---|---|---:|---:|---:|---:|---:|\n";
  for (const MethodPoseResult& p : pose_results) {
    for (const auto& [name, w] : PoseRows(p)) {
      md << "| " << p.method << " | " << name
         << " | " << w.count << " | " << Fixed(w.translation_mean, 3) << " | "
         << Fixed(w.translation_median, 3) << " | " << Fixed(w.yaw_mean_deg, 2) << " | "
         << Fixed(w.yaw_median_deg, 2) << " |\n";
    }
  }
  md << "\n";
}

// The CLEAR-MOT table of the results (none when there is no result).
void MarkdownTracking(const EvalOptions& options, const EvalSummary& summary, std::ostringstream& md) {
  if (summary.tracking.empty()) return;
  md << "### Tracking (CLEAR-MOT, per-frame matching within " << Fixed(options.per_frame_distance, 1)
     << " m)\n\n";
  md << "| Method | True cars | Output tracks | Tracks per car | Main track [%] | IDSW | FRAG | Missed cars "
        "| False tracks | FN | FP | MOTA [%] | MOTP [m] |\n";
  md << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const MethodTrackingResult& t : summary.tracking) {
    const TrackingCounts& c = t.counts;
    md << "| " << t.method << " | " << c.true_cars << " | " << c.output_tracks << " | "
       << Fixed(c.TracksPerCar(), 2) << " | " << Fixed(100 * c.MainTrackShare(), 1) << " | " << c.id_switches
       << " | " << c.fragmentations << " | " << c.missed_cars << " | " << c.false_tracks << " | " << c.misses
       << " | " << c.false_positives << " | " << Fixed(100 * c.Mota(), 1) << " | " << Fixed(c.Motp(), 3)
       << " |\n";
  }
  md << "\n";
}

// The per-car diagnostics by distance band.
void MarkdownDiagnostics(const EvalOptions& options, const EvalResults& results, std::ostringstream& md) {
  const EvalSummary& summary = results.summary;
  const int num_windows = results.num_windows;
  const std::string tau = Fixed(options.headline_tau, 2);
  md << "### Per-car diagnostics (per-frame matching, medians)\n\n"
     << "Offset of the estimated origin from the true one along the viewing ray (+ = farther), |across| and "
        "|vertical|; estimated minus true box size; F1 at tau = "
     << tau << " m. Every car-frame the method matched (per_car.csv has them all).\n\n";
  md << "| Method | Distance | n | Along ray [m] | Across [m] | Vertical [m] | dh [m] | dw [m] | dl [m] | F1 [%] |\n";
  md << "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const DiagnosticsBand& b : summary.diagnostics) {
    const bool all = b.min_distance == 0.0 && b.max_distance == num_windows * options.distance_window &&
                     num_windows > 1;
    md << "| " << b.method << " | "
       << (all ? std::string("all") : Fixed(b.min_distance, 0) + "-" + Fixed(b.max_distance, 0) + " m") << " | "
       << b.count << " | " << Fixed(b.along_ray_offset, 3) << " | " << Fixed(b.abs_lateral_offset, 3) << " | "
       << Fixed(b.abs_vertical_offset, 3) << " | " << Fixed(b.size_error[0], 3) << " | "
       << Fixed(b.size_error[1], 3) << " | " << Fixed(b.size_error[2], 3) << " | "
       << (b.num_shape > 0 ? Fixed(100 * b.f1, 2) : std::string("-")) << " |\n";
  }
}

}  // namespace

std::string EvalMarkdown(const EvalOptions& options, const EvalResults& results) {
  std::ostringstream md;
  for (int k = 0; k < kNumMatchings; ++k) {
    MarkdownShape(options, results, k, md);
    MarkdownPose(results, k, md);
  }
  MarkdownTracking(options, results.summary, md);
  MarkdownDiagnostics(options, results, md);
  return md.str();
}

void WriteEvalReport(const EvalOptions& options, const EvalResults& results) {
  const EvalSummary& summary = results.summary;
  const fs::path out(options.output_folder);
  fs::create_directories(out);
  WriteTextFileAtomically((out / "results.md").string(), summary.markdown);
  WriteTextFileAtomically((out / "shape.csv").string(), ShapeCsv(options, summary));
  WriteTextFileAtomically((out / "pose.csv").string(), PoseCsv(summary));
  std::string per_object, per_car;
  CarFrameCsvs(results, &per_object, &per_car);
  WriteTextFileAtomically((out / "per_object.csv").string(), per_object);
  WriteTextFileAtomically((out / "per_car.csv").string(), per_car);
  WriteTextFileAtomically((out / "tracking.csv").string(), TrackingCsv(summary));
  WriteTextFileAtomically((out / "results.json").string(), ResultsJson(options, results));
  WritePlots(options, summary);
}

}  // namespace samp
