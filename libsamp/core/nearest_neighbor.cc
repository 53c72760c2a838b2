#include "libsamp/core/nearest_neighbor.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "libsamp/core/error.h"

namespace samp {

size_t RadiusNearestNeighbor::CellHash::operator()(const Eigen::Vector3i& c) const {
  uint64_t h = uint64_t(uint32_t(c.x())) * 0x9e3779b97f4a7c15ULL;
  h ^= uint64_t(uint32_t(c.y())) * 0xc2b2ae3d27d4eb4fULL + (h << 6) + (h >> 2);
  h ^= uint64_t(uint32_t(c.z())) * 0x165667b19e3779f9ULL + (h << 6) + (h >> 2);
  return size_t(h);
}

Eigen::Vector3i RadiusNearestNeighbor::Cell(const Eigen::Vector3d& p) const {
  return Eigen::Vector3i(int(std::floor(p.x() / cell_size_)), int(std::floor(p.y() / cell_size_)),
                         int(std::floor(p.z() / cell_size_)));
}

RadiusNearestNeighbor::RadiusNearestNeighbor(const std::vector<Eigen::Vector3d>& points,
                                             double max_radius, double cell_size)
    : max_radius_(max_radius), cell_size_(cell_size > 0.0 ? cell_size : max_radius / 4.0) {
  SAMP_CHECK(max_radius > 0 && std::isfinite(max_radius))
      << "RadiusNearestNeighbor: max_radius must be > 0, got " << max_radius;
  SAMP_CHECK(cell_size >= 0 && std::isfinite(cell_size))
      << "RadiusNearestNeighbor: cell_size must be >= 0 (0 = max_radius / 4), got " << cell_size;
  SAMP_CHECK(points.size() < size_t(std::numeric_limits<uint32_t>::max()))
      << "RadiusNearestNeighbor: too many points";
  std::vector<std::pair<Eigen::Vector3i, uint32_t>> keyed;
  keyed.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    SAMP_CHECK(points[i].allFinite()) << "RadiusNearestNeighbor: point " << i << " is not finite";
    keyed.emplace_back(Cell(points[i]), uint32_t(i));
  }
  std::sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) {
    if (a.first.x() != b.first.x()) return a.first.x() < b.first.x();
    if (a.first.y() != b.first.y()) return a.first.y() < b.first.y();
    if (a.first.z() != b.first.z()) return a.first.z() < b.first.z();
    return a.second < b.second;
  });
  points_.reserve(points.size());
  for (size_t i = 0; i < keyed.size(); ++i) {
    if (i == 0 || keyed[i].first != keyed[i - 1].first) {
      cells_[keyed[i].first] = {uint32_t(i), uint32_t(i)};
    }
    cells_[keyed[i].first].second = uint32_t(i + 1);
    points_.push_back(points[keyed[i].second]);
  }
}

double RadiusNearestNeighbor::Distance(const Eigen::Vector3d& query) const {
  // Shells of cells at Chebyshev cell distance r = 0, 1, ...: a point in shell
  // r + 1 or beyond is farther than r * cell_size_ from the query, so the search
  // stops once the best distance found is within that bound.
  const Eigen::Vector3i centre = Cell(query);
  const int max_shell = int(std::ceil(max_radius_ / cell_size_));
  double best_squared = max_radius_ * max_radius_;
  bool found = false;
  for (int r = 0; r <= max_shell; ++r) {
    for (int dz = -r; dz <= r; ++dz) {
      for (int dy = -r; dy <= r; ++dy) {
        const bool on_face = std::abs(dz) == r || std::abs(dy) == r;
        for (int dx = -r; dx <= r; dx += (on_face ? 1 : 2 * std::max(r, 1))) {
          const auto it = cells_.find(centre + Eigen::Vector3i(dx, dy, dz));
          if (it == cells_.end()) continue;
          for (uint32_t i = it->second.first; i < it->second.second; ++i) {
            const double d2 = (points_[i] - query).squaredNorm();
            if (d2 <= best_squared) {
              best_squared = d2;
              found = true;
            }
          }
        }
      }
    }
    if (found && best_squared <= (r * cell_size_) * (r * cell_size_)) break;
  }
  return found ? std::sqrt(best_squared) : std::numeric_limits<double>::infinity();
}

}  // namespace samp
