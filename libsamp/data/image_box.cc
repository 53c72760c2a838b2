#include "libsamp/data/image_box.h"

#include <algorithm>
#include <cmath>

namespace samp {

bool ProjectBox(const ObjectLabel& label, const PinholeCamera& camera, Eigen::Vector4d* box_2d) {
  const double c = std::cos(label.rotation_y), s = std::sin(label.rotation_y);
  double x1 = 1e18, y1 = 1e18, x2 = -1e18, y2 = -1e18;
  bool any = false;
  for (int i = 0; i < 8; ++i) {
    const double lx = (i & 1 ? 0.5 : -0.5) * label.length;
    const double lz = (i & 2 ? 0.5 : -0.5) * label.width;
    const double ly = (i & 4) ? -label.height : 0.0;
    // camera_from_object = [R_y(ry) | position], R_y = [[c, 0, s], [0, 1, 0], [-s, 0, c]].
    const Eigen::Vector3d p = label.position + Eigen::Vector3d(c * lx + s * lz, ly, -s * lx + c * lz);
    if (p.z() < 0.1) continue;
    const Eigen::Vector2d uv = camera.Project(p);
    x1 = std::min(x1, uv.x());
    y1 = std::min(y1, uv.y());
    x2 = std::max(x2, uv.x());
    y2 = std::max(y2, uv.y());
    any = true;
  }
  if (!any) return false;
  x1 = std::clamp(x1, 0.0, camera.width - 1.0);
  x2 = std::clamp(x2, 0.0, camera.width - 1.0);
  y1 = std::clamp(y1, 0.0, camera.height - 1.0);
  y2 = std::clamp(y2, 0.0, camera.height - 1.0);
  if (x2 - x1 < 2.0 || y2 - y1 < 2.0) return false;
  *box_2d = Eigen::Vector4d(x1, y1, x2, y2);
  return true;
}

double AreaShareInside(const Eigen::Vector4d& box, const std::vector<Eigen::Vector4d>& regions) {
  const double width = box[2] - box[0], height = box[3] - box[1];
  if (!(width > 0 && height > 0)) return 0.0;
  // The regions clipped to the box; the union's area over the grid of their edges.
  std::vector<Eigen::Vector4d> clipped;
  std::vector<double> xs = {box[0], box[2]}, ys = {box[1], box[3]};
  for (const Eigen::Vector4d& r : regions) {
    const Eigen::Vector4d c(std::max(r[0], box[0]), std::max(r[1], box[1]), std::min(r[2], box[2]),
                            std::min(r[3], box[3]));
    if (!(c[2] > c[0] && c[3] > c[1])) continue;
    clipped.push_back(c);
    xs.push_back(c[0]), xs.push_back(c[2]);
    ys.push_back(c[1]), ys.push_back(c[3]);
  }
  if (clipped.empty()) return 0.0;
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
  std::sort(ys.begin(), ys.end());
  ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
  double inside = 0.0;
  for (size_t i = 0; i + 1 < xs.size(); ++i) {
    const double u = 0.5 * (xs[i] + xs[i + 1]);
    for (size_t j = 0; j + 1 < ys.size(); ++j) {
      const double v = 0.5 * (ys[j] + ys[j + 1]);
      for (const Eigen::Vector4d& c : clipped) {
        if (u > c[0] && u < c[2] && v > c[1] && v < c[3]) {
          inside += (xs[i + 1] - xs[i]) * (ys[j + 1] - ys[j]);
          break;
        }
      }
    }
  }
  return std::clamp(inside / (width * height), 0.0, 1.0);
}

}  // namespace samp
