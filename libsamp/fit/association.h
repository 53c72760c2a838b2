// Which of a track frame's candidate stereo points a solve uses (SAMP Section
// 3.4, the hard-EM association; docs/fitting.md, "Association"): first by the
// detection gate (data/observations.h), then by the fitted shape and pose, by
// the distance to the surface (kPaper, kRayDepth) or by the disparity
// residual (kDisparity); the even subsample a solve takes of them and their
// effective number of independent observations.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libsamp/core/grid_spec.h"
#include "libsamp/data/track.h"
#include "libsamp/fit/fit_options.h"
#include "libsamp/model/shape_lookup.h"

namespace samp {

// Data of one frame: the associated points and their sigmas.
struct Association {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> sigmas;
  // kDisparity: candidates dropped because they are not in front of the
  // camera (InFrontOfCamera, costs/disparity.h); 0 for the other terms.
  int behind_camera = 0;
};

// First association around the detection's box centre (InDetectionGate):
// kPaper / kRayDepth within `radius` (a sphere); kDisparity also a point whose
// viewing ray passes within `radius` of the centre and whose distance along
// the ray lies within radius + 3 sigma (the point's sigma_d scaled to the
// centre's depth, along the ray) of the centre's: a sphere would cut the
// stereo noise of far cars (sigma of metres along the ray) unevenly about a
// detection that is itself off along the ray, and bias the fit. kDisparity
// drops (and counts) the candidates that are not in front of the camera.
Association AssociateByDetection(const TrackFrame& f, double radius, DataTerm term);

// EM association of kPaper / kRayDepth: the candidates inside the fitted
// shape's inside box (object frame at `pose`) enlarged by em_box_margin with
// |phi_z| below em_distance_threshold. *why counts what was dropped and why.
Association AssociateByFit(const TrackFrame& f, const ShapeLookup& lookup, const Eigen::VectorXd& z,
                           const Eigen::Vector4d& pose, const AlignedBox& box, const FitOptions& options,
                           std::string* why);

// EM association of kDisparity: the candidates whose residual at the fitted
// shape and pose is an inlier of the mixture (|s_i| below the outlier
// threshold): on a ray that meets the shape, a disparity within s_0 sigma of
// the visible surface's; on a ray that misses it, within s_0 silhouette
// sigmas of the silhouette. `cost_options`: the frame's disparity-term
// options (DataTermOptions, track_problem.h). The candidates not in front of
// the camera are dropped and counted (Association::behind_camera). *why says
// how many were dropped and why.
Association AssociateByResiduals(const TrackFrame& f, const ShapeLookup& lookup, const DataCostOptions& cost_options,
                                 const Eigen::VectorXd& z, const Eigen::Vector4d& pose, const FitOptions& options,
                                 std::string* why);

// The points of a frame's association that enter a solve: all of them, or
// `max_points` spread evenly over the association's order (k = floor((j +
// 1/2) n / max_points)); deterministic.
Association SolveSubsample(const Association& a, int max_points);

// Effective number of independent observations of a frame's n associated
// points (docs/fitting.md, "Prior/data balance"): kEffective n pixels per
// point / correlation_area_px (at most n), kMean n.
double EffectivePoints(const TrackFrame& f, int n, const FitOptions& options);

}  // namespace samp
