#include "libsamp/pipeline/fit_output.h"

#include <algorithm>
#include <cmath>

#include "libsamp/core/error.h"
#include "libsamp/viz/surface.h"

namespace samp {

AlignedBox FittedBox(const ShapeLookup& lookup, const Eigen::VectorXd& z) { return lookup.InsideBox(z); }

std::vector<ObjectLabel> FitToLabels(const TrackFit& fit, const Track& track, const ShapeLookup& lookup) {
  SAMP_CHECK(fit.frames.size() == track.frames.size())
      << "track " << track.id << ": fit has " << fit.frames.size() << " frames, track "
      << track.frames.size();
  const PinholeCamera& camera = track.calibration.camera;
  std::vector<ObjectLabel> labels;
  for (size_t k = 0; k < fit.frames.size(); ++k) {
    const FrameFit& f = fit.frames[k];
    const TrackFrame& tf = track.frames[k];
    const Eigen::VectorXd& z = fit.single_frame ? f.shape_code : fit.shape_code;
    AlignedBox box = lookup.InsideBox(z);
    if (box.IsEmpty()) {
      box.min = box.max = Eigen::Vector3d::Zero();
    }
    const Eigen::Isometry3d camera_from_world = tf.world_from_camera.inverse();
    const Eigen::Isometry3d camera_from_object = camera_from_world * f.WorldFromObject();
    ObjectLabel label;
    label.frame = f.frame;
    label.track_id = fit.track_id;
    label.type = fit.type;
    label.truncation = tf.detection.truncation;
    label.occlusion = tf.detection.occlusion;
    label.position = camera_from_object.translation();
    label.rotation_y = WrapAngle(YawOfDirection(camera_from_object.linear() * Eigen::Vector3d::UnitX()));
    label.alpha = WrapAngle(label.rotation_y - std::atan2(label.position.x(), label.position.z()));
    const Eigen::Vector3d size = box.Size();
    label.length = size.x();
    label.height = size.y();
    label.width = size.z();
    label.score = tf.detection.score;
    // 2D box: the projected corners in front of the camera, clipped to the image.
    double x1 = 1e30, y1 = 1e30, x2 = -1e30, y2 = -1e30;
    int in_front = 0;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d corner((c & 1) ? box.max.x() : box.min.x(), (c & 2) ? box.max.y() : box.min.y(),
                                   (c & 4) ? box.max.z() : box.min.z());
      const Eigen::Vector3d p = camera_from_object * corner;
      if (p.z() <= 0.1) continue;
      ++in_front;
      const Eigen::Vector2d uv = camera.Project(p);
      x1 = std::min(x1, uv.x());
      y1 = std::min(y1, uv.y());
      x2 = std::max(x2, uv.x());
      y2 = std::max(y2, uv.y());
    }
    if (in_front == 0) {
      label.box_2d.setZero();
    } else {
      const double w = camera.width - 1.0, h = camera.height - 1.0;
      label.box_2d << std::clamp(x1, 0.0, w), std::clamp(y1, 0.0, h), std::clamp(x2, 0.0, w),
          std::clamp(y2, 0.0, h);
    }
    labels.push_back(label);
  }
  return labels;
}

Mesh FittedSurface(const ShapeLookup& lookup, const Eigen::VectorXd& z) {
  return ExtractSurface(lookup.grid(), lookup.Dense(z), 0.0);
}

PointCloud AlignedObservations(const TrackFit& fit) {
  PointCloud cloud;
  const int n = int(fit.frames.size());
  for (int k = 0; k < n; ++k) {
    const FrameFit& f = fit.frames[k];
    const Eigen::Isometry3d object_from_world = f.WorldFromObject().inverse();
    const double a = n > 1 ? double(k) / (n - 1) : 0.0;
    const Eigen::Matrix<uint8_t, 3, 1> color(uint8_t(255 * a), 64, uint8_t(255 * (1 - a)));
    for (const auto& p : f.points_in_world) {
      cloud.points.push_back((object_from_world * p).cast<float>());
      cloud.colors.push_back(color);
    }
  }
  return cloud;
}

namespace {
nlohmann::json Vec(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}
}  // namespace

nlohmann::json TrackFitToJson(const TrackFit& fit, const AlignedBox& box) {
  nlohmann::json j;
  j["track_id"] = fit.track_id;
  j["sequence"] = fit.sequence;
  j["type"] = fit.type;
  j["mode"] = fit.single_frame ? "single_frame" : "joint";
  j["shape_code"] = Vec(fit.shape_code);
  if (!box.IsEmpty()) {
    j["box_min"] = Vec(box.min);
    j["box_max"] = Vec(box.max);
  }
  nlohmann::json frames = nlohmann::json::array();
  for (const FrameFit& f : fit.frames) {
    nlohmann::json jf;
    jf["frame"] = f.frame;
    jf["time"] = f.time;
    jf["position_world"] = Vec(f.position);
    jf["yaw"] = f.yaw;
    jf["speed"] = f.speed;
    jf["yaw_rate"] = f.yaw_rate;
    jf["motion_model"] = f.motion_model;
    jf["num_points"] = f.num_points;
    jf["effective_points"] = f.effective_points;
    jf["data_cost"] = f.data_cost;
    if (fit.single_frame) jf["shape_code"] = Vec(f.shape_code);
    frames.push_back(jf);
  }
  j["frames"] = frames;
  nlohmann::json s;
  s["initial_cost"] = fit.summary.initial_cost;
  s["final_cost"] = fit.summary.final_cost;
  s["num_iterations"] = fit.summary.num_iterations;
  s["seconds"] = fit.summary.seconds;
  s["usable"] = fit.summary.usable;
  s["association_notes"] = fit.summary.association_notes;
  nlohmann::json solves = nlohmann::json::array();
  for (const SolveReport& r : fit.summary.solves) {
    solves.push_back({{"initial_cost", r.initial_cost},
                      {"final_cost", r.final_cost},
                      {"num_iterations", r.num_iterations},
                      {"seconds", r.seconds},
                      {"median_step_seconds", r.median_step_seconds},
                      {"usable", r.usable},
                      {"num_points", r.num_points},
                      {"termination", r.termination}});
  }
  s["solves"] = solves;
  j["summary"] = s;
  return j;
}

nlohmann::json FitOptionsToJson(const FitOptions& o) {
  nlohmann::json j;
  j["single_frame"] = o.single_frame;
  j["em_iterations"] = o.em_iterations;
  j["em_initial_sigma_scale"] = o.em_initial_sigma_scale;
  j["association_radius"] = o.association_radius;
  j["em_distance_threshold"] = o.em_distance_threshold;
  j["em_box_margin"] = o.em_box_margin;
  j["min_points_per_frame"] = o.min_points_per_frame;
  j["compress_data_blocks"] = o.compress_data_blocks;
  j["huber_threshold"] = o.huber_threshold;
  j["sigma_ground"] = o.sigma_ground;
  j["shape_prior_weight"] = o.shape_prior_weight;
  j["standing_speed"] = o.standing_speed;
  j["max_motion_off_axis"] = o.max_motion_off_axis;
  j["min_speed_significance"] = o.min_speed_significance;
  j["data_term"] = DataTermName(o.data_term);
  j["data_weighting"] = DataWeightingName(o.data_weighting);
  j["correlation_area_px"] = o.correlation_area_px;
  j["silhouette_sigma_px"] = o.silhouette_sigma_px;
  j["outlier_threshold"] = o.outlier_threshold;
  j["straight_yaw_rate"] = o.straight_yaw_rate;
  j["motion_noise"] = {{"speed_noise", o.motion_noise.speed_noise},
                       {"yaw_rate_noise", o.motion_noise.yaw_rate_noise},
                       {"sigma_position", o.motion_noise.sigma_position},
                       {"sigma_height", o.motion_noise.sigma_height},
                       {"sigma_yaw", o.motion_noise.sigma_yaw},
                       {"sigma_speed", o.motion_noise.sigma_speed},
                       {"sigma_yaw_rate", o.motion_noise.sigma_yaw_rate}};
  j["max_iterations"] = o.max_iterations;
  j["max_rejected_steps"] = o.max_rejected_steps;
  j["function_tolerance"] = o.function_tolerance;
  j["gradient_tolerance"] = o.gradient_tolerance;
  j["parameter_tolerance"] = o.parameter_tolerance;
  j["linear_solver"] = o.linear_solver;
  j["num_threads"] = o.num_threads;
  return j;
}

}  // namespace samp
