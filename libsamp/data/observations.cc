#include "libsamp/data/observations.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "libsamp/core/error.h"
#include "libsamp/core/util.h"
#include "libsamp/data/observation_option_table.h"
#include "libsamp/data/stereo.h"

namespace samp {

void ObservationOptions::Check() const { ObservationOptionTable().Check(*this); }

Eigen::Vector4d TransformPlane(const Eigen::Vector4d& plane_in_a, const Eigen::Isometry3d& b_from_a) {
  const Eigen::Vector3d normal_in_b = b_from_a.linear() * plane_in_a.head<3>();
  const double d_in_b = plane_in_a[3] - normal_in_b.dot(b_from_a.translation());
  return Eigen::Vector4d(normal_in_b.x(), normal_in_b.y(), normal_in_b.z(), d_in_b);
}

Eigen::Vector3d DetectionCenter(const ObjectLabel& detection) {
  return detection.position - Eigen::Vector3d(0, detection.height / 2, 0);
}

double SignedDistanceToBox(const ObjectLabel& detection, const Eigen::Vector3d& point_in_camera) {
  const Eigen::Vector3d d = point_in_camera - DetectionCenter(detection);
  const double c = std::cos(detection.rotation_y), s = std::sin(detection.rotation_y);
  // Box axes in the camera: length along (c, 0, -s), width along (s, 0, c).
  const Eigen::Vector3d q(std::abs(c * d.x() - s * d.z()) - detection.length / 2,
                          std::abs(d.y()) - detection.height / 2,
                          std::abs(s * d.x() + c * d.z()) - detection.width / 2);
  const double outside = q.cwiseMax(0.0).norm();
  const double inside = std::min(q.maxCoeff(), 0.0);
  return outside + inside;
}

bool InDetectionGate(const DetectionGate& gate, const Eigen::Vector3d& point) {
  const double radius_sq = gate.radius * gate.radius;
  if ((point - gate.box_centre).squaredNorm() <= radius_sq) return true;
  if (gate.ray_sigmas <= 0.0) return false;
  const Eigen::Vector3d ray = point - gate.camera_centre;
  const Eigen::Vector3d centre = gate.box_centre - gate.camera_centre;
  const double length = ray.norm();
  const Eigen::Vector3d u = ray / length;
  const double along = centre.dot(u);
  const double lateral_sq = std::max(0.0, centre.squaredNorm() - along * along);
  if (lateral_sq > radius_sq) return false;
  // The noise at the box centre's depth (not the point's: far background has
  // sigma of tens of metres and would pass any gate).
  const double sigma_ray = gate.depth_sigma_at_centre / std::max(u.dot(gate.optical_axis), 1e-3);
  return std::abs(length - along) <= gate.radius + gate.ray_sigmas * sigma_ray;
}

namespace {

// Whether the point (camera frame) lies nearer to one of the rivals' boxes
// than to the detection's (SignedDistanceToBox).
bool ClaimedByRival(const ObjectLabel& detection, const std::vector<ObjectLabel>& rivals,
                    const Eigen::Vector3d& point_in_camera) {
  if (rivals.empty()) return false;
  const double own = SignedDistanceToBox(detection, point_in_camera);
  for (const ObjectLabel& rival : rivals)
    if (SignedDistanceToBox(rival, point_in_camera) < own) return true;
  return false;
}

}  // namespace

int ExtractObservations(const cv::Mat& disparity_px, const StereoCalibration& calibration,
                        const ObservationOptions& options, int track_id, TrackFrame* frame,
                        const std::vector<ObjectLabel>& rivals) {
  options.Check();
  SAMP_CHECK(frame != nullptr) << "ExtractObservations: frame is null";
  SAMP_CHECK(disparity_px.type() == CV_32FC1) << "ExtractObservations: expected a CV_32FC1 disparity";
  const ObjectLabel& detection = frame->detection;
  const Eigen::Vector4d& box = detection.box_2d;
  const double margin_u = options.box_margin * (box[2] - box[0]);
  const double margin_v = options.box_margin * (box[3] - box[1]);
  const int u0 = std::max(0, static_cast<int>(std::floor(box[0] - margin_u)));
  const int v0 = std::max(0, static_cast<int>(std::floor(box[1] - margin_v)));
  const int u1 = std::min(disparity_px.cols - 1, static_cast<int>(std::ceil(box[2] + margin_u)));
  const int v1 = std::min(disparity_px.rows - 1, static_cast<int>(std::ceil(box[3] + margin_v)));

  frame->candidate_points_in_world.clear();
  frame->candidate_sigmas.clear();
  frame->candidate_pixels.clear();
  frame->candidate_disparities_px.clear();
  if (u1 < u0 || v1 < v0) return 0;

  const Eigen::Vector3d center_in_camera = DetectionCenter(detection);
  const Eigen::Vector4d& plane = frame->ground_plane_in_world;
  DetectionGate gate;  // in the camera frame
  gate.box_centre = center_in_camera;
  gate.radius = options.max_distance_to_detection;
  gate.ray_sigmas = options.depth_gate_sigmas;
  gate.depth_sigma_at_centre = DepthSigma(center_in_camera.z(), options.sigma_disparity_px, calibration);
  const cv::Rect roi(u0, v0, u1 - u0 + 1, v1 - v0 + 1);
  const std::vector<StereoPoint> stereo =
      DisparityToPoints(disparity_px, calibration, options.min_disparity_px, 1, roi);

  std::vector<Eigen::Vector3d> points_in_world;
  std::vector<float> depths;
  std::vector<const StereoPoint*> kept;
  for (const StereoPoint& p : stereo) {
    if (!InDetectionGate(gate, p.point_in_camera)) continue;
    const Eigen::Vector3d point_in_world = frame->world_from_camera * p.point_in_camera;
    if (plane.head<3>().dot(point_in_world) + plane[3] <= options.min_height_above_road) continue;
    if (options.nearest_box_claims && ClaimedByRival(detection, rivals, p.point_in_camera)) continue;
    points_in_world.push_back(point_in_world);
    depths.push_back(static_cast<float>(p.point_in_camera.z()));
    kept.push_back(&p);
  }
  const int total = static_cast<int>(points_in_world.size());

  std::vector<int> keep(total);
  for (int i = 0; i < total; ++i) keep[i] = i;
  if (options.max_points_per_frame > 0 && total > options.max_points_per_frame) {
    std::mt19937_64 rng(SplitMix64(options.seed ^ SplitMix64(static_cast<std::uint64_t>(track_id) * 1000003ULL +
                                                             static_cast<std::uint64_t>(frame->frame))));
    for (int i = 0; i < options.max_points_per_frame; ++i) {
      const int j = i + static_cast<int>(rng() % static_cast<std::uint64_t>(total - i));
      std::swap(keep[i], keep[j]);
    }
    keep.resize(options.max_points_per_frame);
    std::sort(keep.begin(), keep.end());
  }
  frame->candidate_pixels_per_point = keep.empty() ? 1.0 : double(total) / double(keep.size());
  frame->candidate_points_in_world.reserve(keep.size());
  frame->candidate_sigmas.reserve(keep.size());
  frame->candidate_pixels.reserve(keep.size());
  frame->candidate_disparities_px.reserve(keep.size());
  for (int i : keep) {
    frame->candidate_points_in_world.push_back(points_in_world[i]);
    frame->candidate_pixels.emplace_back(kept[i]->u, kept[i]->v);
    frame->candidate_disparities_px.push_back(kept[i]->disparity_px);
    frame->candidate_sigmas.push_back(DepthSigma(depths[i], options.sigma_disparity_px, calibration));
  }
  return total;
}

}  // namespace samp
