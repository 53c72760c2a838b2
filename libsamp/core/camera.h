// Pinhole camera in the KITTI convention: x right, y down, z forward.
#pragma once

#include <Eigen/Core>

namespace samp {

struct PinholeCamera {
  double fx = 721.5377, fy = 721.5377;  // focal lengths, px
  double cx = 609.5593, cy = 172.854;   // principal point, px
  int width = 1242, height = 375;       // image size, px

  Eigen::Vector2d Project(const Eigen::Vector3d& point_in_camera) const {
    return Eigen::Vector2d(fx * point_in_camera.x() / point_in_camera.z() + cx,
                           fy * point_in_camera.y() / point_in_camera.z() + cy);
  }
  // Unit-depth ray (z = 1) through pixel (u, v).
  Eigen::Vector3d Ray(double u, double v) const {
    return Eigen::Vector3d((u - cx) / fx, (v - cy) / fy, 1.0);
  }
  bool Contains(const Eigen::Vector2d& pixel) const {
    return pixel.x() >= 0 && pixel.y() >= 0 && pixel.x() < width && pixel.y() < height;
  }
};

}  // namespace samp
