#include "libsamp/fit/association.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "libsamp/core/pose.h"
#include "libsamp/data/observations.h"
#include "libsamp/fit/costs/disparity.h"

namespace samp {

Association AssociateByDetection(const TrackFrame& f, double radius, DataTerm term) {
  Association a;
  DetectionGate gate;  // in the world frame
  gate.camera_centre = f.world_from_camera.translation();
  gate.optical_axis = f.world_from_camera.linear().col(2);
  gate.box_centre = f.world_from_camera * DetectionCenter(f.detection);
  gate.radius = radius;
  gate.ray_sigmas = term == DataTerm::kDisparity ? 3.0 : 0.0;
  const double centre_depth = (gate.box_centre - gate.camera_centre).dot(gate.optical_axis);
  const Eigen::Vector3d axis = gate.optical_axis.normalized();  // as DataTermOptions gives it the cost
  a.points.reserve(f.candidate_points_in_world.size());
  a.sigmas.reserve(f.candidate_points_in_world.size());
  for (size_t i = 0; i < f.candidate_points_in_world.size(); ++i) {
    const Eigen::Vector3d& p = f.candidate_points_in_world[i];
    if (term == DataTerm::kDisparity && !InFrontOfCamera(p, gate.camera_centre, axis)) {
      ++a.behind_camera;
      continue;
    }
    if (gate.ray_sigmas > 0.0) {
      // The point's sigma_d at the centre's depth (sigma_d grows with z^2:
      // the point's own sigma would let far background pass).
      const double depth_ratio = centre_depth / std::max((p - gate.camera_centre).dot(gate.optical_axis), 1e-3);
      gate.depth_sigma_at_centre = f.candidate_sigmas[i] * depth_ratio * depth_ratio;
    }
    if (InDetectionGate(gate, p)) {
      a.points.push_back(p);
      a.sigmas.push_back(f.candidate_sigmas[i]);
    }
  }
  return a;
}

Association AssociateByFit(const TrackFrame& f, const ShapeLookup& lookup, const Eigen::VectorXd& z,
                           const Eigen::Vector4d& pose, const AlignedBox& box,
                           const FitOptions& options, std::string* why) {
  Association a;
  int outside_box = 0, too_far = 0;
  const Eigen::Isometry3d object_from_world = ObjectFromWorld(pose.head<3>(), pose[3]);
  const Eigen::Vector3d lo = box.min - Eigen::Vector3d::Constant(options.em_box_margin);
  const Eigen::Vector3d hi = box.max + Eigen::Vector3d::Constant(options.em_box_margin);
  // phi_z from the dense grid of z (the same value as lookup.Evaluate(z, o), bit for bit).
  const double* phi_z = lookup.DenseCached(z.data());
  a.points.reserve(f.candidate_points_in_world.size());
  a.sigmas.reserve(f.candidate_points_in_world.size());
  auto keep_if_near = [&](size_t i, double phi) {
    if (std::abs(phi) >= options.em_distance_threshold) {
      ++too_far;
      return;
    }
    a.points.push_back(f.candidate_points_in_world[i]);
    a.sigmas.push_back(f.candidate_sigmas[i]);
  };
  // The candidates inside the box in order, their phi two at a time
  // (DenseValuePair, the value of EvaluateDenseValue): the pending pair's
  // indices and points (per axis).
  const ShapeLookup::DenseValuePair pair(lookup, phi_z);
  size_t pending[2];
  double x[2], y[2], z_axis[2];
  int num_pending = 0;
  for (size_t i = 0; i < f.candidate_points_in_world.size(); ++i) {
    const Eigen::Vector3d o = object_from_world * f.candidate_points_in_world[i];
    if ((o.array() < lo.array()).any() || (o.array() > hi.array()).any()) {
      ++outside_box;
      continue;
    }
    pending[num_pending] = i;
    x[num_pending] = o.x();
    y[num_pending] = o.y();
    z_axis[num_pending] = o.z();
    if (++num_pending < 2) continue;
    double phi[2];
    pair.Evaluate(x, y, z_axis, phi);
    keep_if_near(pending[0], phi[0]);
    keep_if_near(pending[1], phi[1]);
    num_pending = 0;
  }
  if (num_pending == 1) {
    const double o[3] = {x[0], y[0], z_axis[0]};
    keep_if_near(pending[0], lookup.EvaluateDenseValue(phi_z, o));
  }
  std::ostringstream s;
  s << a.points.size() << " of " << f.candidate_points_in_world.size() << " candidates kept; " << outside_box
    << " outside the fitted box + " << options.em_box_margin << " m, " << too_far << " with |phi| >= "
    << options.em_distance_threshold << " m";
  *why = s.str();
  return a;
}

Association AssociateByResiduals(const TrackFrame& f, const ShapeLookup& lookup, const DataCostOptions& cost_options,
                                 const Eigen::VectorXd& z, const Eigen::Vector4d& pose, const FitOptions& options,
                                 std::string* why) {
  Association a;
  std::ostringstream s;
  if (f.candidate_points_in_world.empty()) {
    *why = "no candidate points (none inside the detection's 2D box above the road)";
    return a;
  }
  // The disparity term needs a positive depth: the others are dropped and counted.
  std::vector<Eigen::Vector3d> points;
  std::vector<double> sigmas;
  points.reserve(f.candidate_points_in_world.size());
  sigmas.reserve(f.candidate_points_in_world.size());
  for (size_t i = 0; i < f.candidate_points_in_world.size(); ++i) {
    if (!InFrontOfCamera(f.candidate_points_in_world[i], cost_options.camera_in_world,
                         cost_options.camera_axis_in_world)) {
      ++a.behind_camera;
      continue;
    }
    points.push_back(f.candidate_points_in_world[i]);
    sigmas.push_back(f.candidate_sigmas[i]);
  }
  if (points.empty()) {
    s << "no candidate point in front of the camera (" << a.behind_camera << " behind it)";
    *why = s.str();
    return a;
  }
  const DisparityCost cost(&lookup, points, sigmas, cost_options);
  const std::vector<RayResidual> residuals = cost.RayResiduals(z.data(), pose.data());
  int in_front = 0, behind = 0, missing = 0;
  for (size_t i = 0; i < residuals.size(); ++i) {
    const RayResidual& r = residuals[i];
    if (std::abs(r.value) < options.outlier_threshold) {
      a.points.push_back(points[i]);
      a.sigmas.push_back(sigmas[i]);
    } else if (!r.hit) {
      ++missing;
    } else if (r.value > 0.0) {
      ++in_front;
    } else {
      ++behind;
    }
  }
  s << a.points.size() << " of " << f.candidate_points_in_world.size() << " candidates kept; " << in_front
    << " in front of the fitted surface, " << behind << " behind it (by > " << options.outlier_threshold
    << " sigma_disp), " << missing << " on rays missing the shape by > " << options.outlier_threshold
    << " silhouette sigmas";
  if (a.behind_camera > 0) s << ", " << a.behind_camera << " not in front of the camera";
  *why = s.str();
  return a;
}

Association SolveSubsample(const Association& a, int max_points) {
  const size_t n = a.points.size();
  if (max_points <= 0 || n <= size_t(max_points)) return a;
  Association out;
  out.points.resize(size_t(max_points));
  out.sigmas.resize(size_t(max_points));
  for (size_t j = 0; j < size_t(max_points); ++j) {
    const size_t k = std::min(n - 1, size_t((double(j) + 0.5) * double(n) / double(max_points)));
    out.points[j] = a.points[k];
    out.sigmas[j] = a.sigmas[k];
  }
  return out;
}

double EffectivePoints(const TrackFrame& f, int n, const FitOptions& options) {
  if (options.data_weighting == DataWeighting::kMean) return double(n);
  return std::min(double(n), n * f.candidate_pixels_per_point / options.correlation_area_px);
}

}  // namespace samp
