// One solve of a track fit as a Ceres problem (SAMP Sections 3.2-3.4;
// docs/fitting.md): the data term of every frame with enough associated
// points, the shape prior, the ground prior, the motion term between
// consecutive frames and the detections' sizes and positions as
// observations, each weighted as FitOptions::data_weighting says.
#pragma once

#include <ceres/problem.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libsamp/data/track.h"
#include "libsamp/fit/association.h"
#include "libsamp/fit/fit_options.h"
#include "libsamp/fit/costs/data_cost.h"
#include "libsamp/model/shape_lookup.h"

namespace samp {

// The parameters of a track fit, which the problem's blocks point into.
struct TrackState {
  std::vector<Eigen::VectorXd> codes;  // 1 (joint) or T (single frame)
  std::vector<Eigen::Vector4d> poses;  // (tx, ty, tz, theta) per frame
  std::vector<Eigen::Vector2d> velocities;  // (v, omega) per frame
  std::vector<std::string> models;     // motion model into each frame (MotionModelName)
};

// Adds every term of one solve to `problem` (parameter blocks in *state),
// with each point's sigma multiplied by sigma_scale. Sets state->models to
// the motion models used. Returns the number of data points in the problem.
int BuildTrackProblem(const ShapeLookup& lookup, const Track& track, const std::vector<Association>& data,
                      double sigma_scale, const FitOptions& options, TrackState* state, ceres::Problem* problem);

// The data-term options of frame f with weight w (FitOptions -> DataCostOptions).
DataCostOptions DataTermOptions(const Track& track, const TrackFrame& f, const FitOptions& options, double weight);

// The data term of frame f as optimised, with weight 1: the mean of rho over
// the points a solve takes of `association` (SolveSubsample), at (z, pose).
double FrameDataCost(const ShapeLookup& lookup, const Track& track, const TrackFrame& f,
                     const Association& association, const Eigen::VectorXd& z, const Eigen::Vector4d& pose,
                     const FitOptions& options);

// The share of T observations with AR(1)-correlated errors (correlation
// exp(-1 / tau) between neighbours) that their mean counts as independent:
// N_eff / T = T / sum_ij rho^|i - j| (1 for T = 1 or tau = 0; -> (1 - rho) / (1 + rho)).
double CorrelatedObservationShare(int num_observations, double tau);

}  // namespace samp
