// 2D image boxes of labels (x1 y1 x2 y2, px; ObjectLabel::box_2d): the box a
// 3D box projects to, and how much of a box lies inside a set of regions
// (KITTI's DontCare boxes, `samp calibrate-detector`). Pure functions;
// thread-safe.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "libsamp/core/camera.h"
#include "libsamp/data/track.h"

namespace samp {

// The 2D box of a 3D box label (projected corners, clipped to the image); false
// when no corner lies in front of the camera or the box misses the image.
bool ProjectBox(const ObjectLabel& label, const PinholeCamera& camera, Eigen::Vector4d* box_2d);

// The share of `box`'s area inside the union of `regions` (each x1 y1 x2 y2,
// px; they may overlap, so a box spread over two adjacent regions counts
// whole), in [0, 1]; 0 when the box has no area.
double AreaShareInside(const Eigen::Vector4d& box, const std::vector<Eigen::Vector4d>& regions);

}  // namespace samp
