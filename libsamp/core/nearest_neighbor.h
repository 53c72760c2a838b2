// Exact nearest-neighbour queries over a fixed point set (voxel hashing with a
// bounded shell search): the one grid used by the evaluation (eval/metrics.h,
// accuracy and completeness) and the inspector (viz/inspect.h, encoding
// distances). Immutable after construction: Distance() is thread-safe.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace samp {

// Points are hashed into cubic cells of edge `cell_size` (default max_radius /
// 4); a query visits shells of cells around its own, nearest first, and stops
// as soon as no unvisited cell can hold a nearer point (or beyond max_radius).
class RadiusNearestNeighbor {
 public:
  // Copies `points`. max_radius > 0; cell_size > 0 or 0 for max_radius / 4.
  RadiusNearestNeighbor(const std::vector<Eigen::Vector3d>& points, double max_radius,
                        double cell_size = 0.0);

  // Distance to the nearest point if it is <= max_radius, else +infinity
  // (also when the set is empty).
  double Distance(const Eigen::Vector3d& query) const;

  size_t size() const { return points_.size(); }
  double max_radius() const { return max_radius_; }

 private:
  struct CellHash {
    size_t operator()(const Eigen::Vector3i& c) const;
  };
  struct CellEqual {
    bool operator()(const Eigen::Vector3i& a, const Eigen::Vector3i& b) const { return a == b; }
  };
  Eigen::Vector3i Cell(const Eigen::Vector3d& p) const;

  std::vector<Eigen::Vector3d> points_;  // sorted by cell
  double max_radius_;
  double cell_size_;
  // Cell -> [begin, end) into points_.
  std::unordered_map<Eigen::Vector3i, std::pair<uint32_t, uint32_t>, CellHash, CellEqual> cells_;
};

}  // namespace samp
