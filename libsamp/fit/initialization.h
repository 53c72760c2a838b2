// Initial states of a track (SAMP Section 3.4; docs/fitting.md,
// "Initialisation"): poses from the detections projected onto the road plane,
// velocity by Theil-Sen over the detections, yaw from the detections
// (standing) or the first-to-last chord (moving), 180-degree detection flips
// resolved.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "libsamp/data/track.h"
#include "libsamp/fit/fit_options.h"

namespace samp {

struct InitialState {
  std::vector<Eigen::Vector4d> poses;      // (tx, ty, tz, theta)
  std::vector<Eigen::Vector2d> velocities; // (v, omega)
  bool standing = false;
};
InitialState InitializeTrack(const Track& track, const FitOptions& options);

}  // namespace samp
