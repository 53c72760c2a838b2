// The paper's evaluation measures (docs/evaluation.md): accuracy, completeness
// and F1 of an estimated point set against a true one at a distance threshold
// tau, and the pose errors (translation, absolute yaw). Exact nearest
// neighbours (voxel hashing with a bounded search). Free functions and an
// immutable index: thread-safe.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace samp {

// Exact nearest-neighbour queries within a maximal radius over a fixed point set.
// Points are hashed into cubic cells of edge max_radius / 4; a query visits
// shells of cells around its own, nearest first, and stops as soon as no
// unvisited cell can hold a nearer point (or beyond max_radius).
class RadiusNearestNeighbor {
 public:
  // Copies `points`. max_radius > 0.
  RadiusNearestNeighbor(const std::vector<Eigen::Vector3d>& points, double max_radius);

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

// For each query point, the distance to its nearest reference point, or +inf
// beyond max_distance.
std::vector<double> NearestDistances(const std::vector<Eigen::Vector3d>& queries,
                                     const std::vector<Eigen::Vector3d>& reference,
                                     double max_distance);

struct ShapeScores {
  double accuracy = 0.0;      // share of estimated points with a true point within tau
  double completeness = 0.0;  // share of true points with an estimated point within tau
  double f1 = 0.0;            // harmonic mean (0 when both are 0)
};

// Both directions of nearest-neighbour distances between an estimated and a
// true point set, enough to score any tau <= max_tau.
struct ShapeComparison {
  std::vector<double> estimated_to_truth;  // per estimated point
  std::vector<double> truth_to_estimated;  // per true point
  double max_tau = 0.0;

  // Scores at tau (<= max_tau). An empty estimated set has accuracy 0; an
  // empty true set completeness 0.
  ShapeScores At(double tau) const;
};

ShapeComparison CompareShapes(const std::vector<Eigen::Vector3d>& estimated,
                              const std::vector<Eigen::Vector3d>& truth, double max_tau);

// Absolute yaw difference in degrees, in [0, 180] (wrapped; a 180-degree flip counts as 180).
double YawErrorDeg(double estimated_yaw, double true_yaw);

// Mean and median of a list (0 for an empty list).
double Mean(const std::vector<double>& values);
double Median(std::vector<double> values);

}  // namespace samp
