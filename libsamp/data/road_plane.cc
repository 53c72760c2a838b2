#include "libsamp/data/road_plane.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/data/sequence_option_table.h"

namespace samp {
namespace {


// Plane through the inliers' centroid with the normal of least variance,
// oriented up (n.y < 0).
Eigen::Vector4d FitPlaneLeastSquares(const std::vector<Eigen::Vector3d>& points,
                                     const std::vector<int>& indices) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int i : indices) centroid += points[i];
  centroid /= static_cast<double>(indices.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (int i : indices) {
    const Eigen::Vector3d q = points[i] - centroid;
    scatter += q * q.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter);
  Eigen::Vector3d normal = solver.eigenvectors().col(0);  // smallest eigenvalue first
  if (normal.y() > 0) normal = -normal;
  return Eigen::Vector4d(normal.x(), normal.y(), normal.z(), -normal.dot(centroid));
}

}  // namespace

void RoadPlaneOptions::Check() const { RoadPlaneOptionTable().Check(*this); }

std::string RoadPlaneSummary::BriefReport() const {
  std::ostringstream s;
  if (success) {
    s << "road plane: " << num_inliers << " of " << num_points << " points inliers, rms "
      << rms_inlier_distance << " m";
  } else {
    s << "road plane estimation failed: " << message;
  }
  return s.str();
}

namespace {

// The stereo points that may lie on the road (below the camera, in front of
// it, nearer than max_depth), at most max_points of them (a seeded subsample).
std::vector<Eigen::Vector3d> RoadCandidates(const std::vector<StereoPoint>& stereo_points,
                                            const RoadPlaneOptions& options, std::mt19937_64* rng) {
  std::vector<Eigen::Vector3d> points;
  for (const StereoPoint& p : stereo_points) {
    const Eigen::Vector3d& x = p.point_in_camera;
    if (x.allFinite() && x.y() > options.min_point_height_below_camera && x.z() > 0 &&
        x.z() < options.max_depth)
      points.push_back(x);
  }
  if (static_cast<int>(points.size()) > options.max_points) {
    // Partial Fisher-Yates with a portable index draw.
    for (int i = 0; i < options.max_points; ++i) {
      const size_t j = i + (*rng)() % (points.size() - i);
      std::swap(points[i], points[j]);
    }
    points.resize(options.max_points);
  }
  return points;
}

// A road plane the camera could stand on: tilted at most max_tilt_deg, the
// camera between min_ and max_camera_height above it.
bool Plausible(const Eigen::Vector4d& plane, const RoadPlaneOptions& options) {
  const double cos_max_tilt = std::cos(options.max_tilt_deg * kPi / 180.0);
  return -plane.y() >= cos_max_tilt && plane[3] >= options.min_camera_height &&
         plane[3] <= options.max_camera_height;
}

// The points within inlier_threshold of the plane (their indices appended to
// *inliers when given); returns their number.
int CountInliers(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector4d& plane,
                 const RoadPlaneOptions& options, std::vector<int>* inliers) {
  int count = 0;
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    if (std::abs(plane.head<3>().dot(points[i]) + plane[3]) < options.inlier_threshold) {
      ++count;
      if (inliers != nullptr) inliers->push_back(i);
    }
  }
  return count;
}

// RANSAC over plausible planes through three points; *best_count the best
// plane's inliers (-1 when no sample was plausible).
Eigen::Vector4d RansacPlane(const std::vector<Eigen::Vector3d>& points, const RoadPlaneOptions& options,
                            const Eigen::Vector4d& fallback, std::mt19937_64* rng, int* best_count) {
  const int n = static_cast<int>(points.size());
  Eigen::Vector4d best = fallback;
  *best_count = -1;
  for (int it = 0; it < options.iterations; ++it) {
    const int a = static_cast<int>((*rng)() % n), b = static_cast<int>((*rng)() % n),
              c = static_cast<int>((*rng)() % n);
    Eigen::Vector3d normal = (points[b] - points[a]).cross(points[c] - points[a]);
    const double norm = normal.norm();
    if (norm < 1e-9) continue;  // degenerate sample
    normal /= norm;
    if (normal.y() > 0) normal = -normal;
    const Eigen::Vector4d plane(normal.x(), normal.y(), normal.z(), -normal.dot(points[a]));
    if (!Plausible(plane, options)) continue;
    const int count = CountInliers(points, plane, options, nullptr);
    if (count > *best_count) {
      *best_count = count;
      best = plane;
    }
  }
  return best;
}

}  // namespace

Eigen::Vector4d EstimateRoadPlane(const std::vector<StereoPoint>& stereo_points,
                                  const RoadPlaneOptions& options, RoadPlaneSummary* summary) {
  options.Check();
  RoadPlaneSummary local;
  RoadPlaneSummary& result = summary != nullptr ? *summary : local;
  result = RoadPlaneSummary();
  const Eigen::Vector4d kDefault(0, -1, 0, 1.65);

  std::mt19937_64 rng(options.seed);
  const std::vector<Eigen::Vector3d> points = RoadCandidates(stereo_points, options, &rng);
  const int n = static_cast<int>(points.size());
  result.num_points = n;
  if (n < options.min_inliers || n < 3) {
    std::ostringstream s;
    s << "only " << n << " stereo points below the camera within " << options.max_depth << " m";
    result.message = s.str();
    return kDefault;
  }
  int best_count = -1;
  const Eigen::Vector4d best = RansacPlane(points, options, kDefault, &rng, &best_count);
  if (best_count < options.min_inliers) {
    std::ostringstream s;
    s << "best of " << options.iterations << " plausible hypotheses has "
      << std::max(best_count, 0) << " inliers (< " << options.min_inliers << ")";
    result.message = s.str();
    return kDefault;
  }
  // Two rounds of least squares on the inliers.
  Eigen::Vector4d plane = best;
  std::vector<int> inliers;
  for (int round = 0; round < 2; ++round) {
    inliers.clear();
    CountInliers(points, plane, options, &inliers);
    if (static_cast<int>(inliers.size()) < options.min_inliers) break;
    const Eigen::Vector4d refined = FitPlaneLeastSquares(points, inliers);
    if (!Plausible(refined, options)) break;
    plane = refined;
  }
  inliers.clear();
  CountInliers(points, plane, options, &inliers);
  if (static_cast<int>(inliers.size()) < options.min_inliers) {
    result.message = "the refined plane lost its inliers";
    return kDefault;
  }
  double sum_sq = 0;
  for (int i : inliers) {
    const double r = plane.head<3>().dot(points[i]) + plane[3];
    sum_sq += r * r;
  }
  result.success = true;
  result.num_inliers = static_cast<int>(inliers.size());
  result.rms_inlier_distance = std::sqrt(sum_sq / inliers.size());
  return plane;
}

}  // namespace samp
