#include "libsamp/data/tracking.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <unordered_map>

#include "libsamp/core/json_text.h"
#include "libsamp/core/error.h"
#include "libsamp/core/json_fields.h"
#include "libsamp/core/pose.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/observations.h"

namespace samp {
namespace {

// Hungarian method (shortest augmenting paths with potentials) for rows <= cols,
// finite costs. Returns for each row its column.
std::vector<int> HungarianRowsLeCols(const std::vector<double>& cost, int rows, int cols) {
  const double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> u(rows + 1, 0.0), v(cols + 1, 0.0), min_v(cols + 1);
  std::vector<int> row_of_col(cols + 1, 0), way(cols + 1, 0);
  std::vector<char> used(cols + 1);
  for (int i = 1; i <= rows; ++i) {
    row_of_col[0] = i;
    int j0 = 0;
    std::fill(min_v.begin(), min_v.end(), kInf);
    std::fill(used.begin(), used.end(), 0);
    do {
      used[j0] = 1;
      const int i0 = row_of_col[j0];
      double delta = kInf;
      int j1 = 0;
      for (int j = 1; j <= cols; ++j) {
        if (used[j]) continue;
        const double reduced = cost[(i0 - 1) * cols + (j - 1)] - u[i0] - v[j];
        if (reduced < min_v[j]) {
          min_v[j] = reduced;
          way[j] = j0;
        }
        if (min_v[j] < delta) {
          delta = min_v[j];
          j1 = j;
        }
      }
      for (int j = 0; j <= cols; ++j) {
        if (used[j]) {
          u[row_of_col[j]] += delta;
          v[j] -= delta;
        } else {
          min_v[j] -= delta;
        }
      }
      j0 = j1;
    } while (row_of_col[j0] != 0);
    do {
      const int j1 = way[j0];
      row_of_col[j0] = row_of_col[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  std::vector<int> col_of_row(rows, -1);
  for (int j = 1; j <= cols; ++j)
    if (row_of_col[j] != 0) col_of_row[row_of_col[j] - 1] = j - 1;
  return col_of_row;
}


using Matrix4d = Eigen::Matrix4d;
using Vector4d = Eigen::Vector4d;

// The world's ground plane: up = the mean of the cameras' up axes (-y), e1
// along the first camera's x axis, e2 = up x e1 (forward for a level camera).
struct GroundFrame {
  Eigen::Vector3d up = -Eigen::Vector3d::UnitY();
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitX();
  Eigen::Vector3d e2 = Eigen::Vector3d::UnitZ();
};

GroundFrame MakeGroundFrame(const std::vector<FrameDetections>& frames) {
  GroundFrame g;
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  for (const FrameDetections& f : frames) up += f.world_from_camera.linear() * -Eigen::Vector3d::UnitY();
  if (up.norm() < 1e-9) return g;
  g.up = up.normalized();
  Eigen::Vector3d x = frames.front().world_from_camera.linear() * Eigen::Vector3d::UnitX();
  x -= g.up * g.up.dot(x);
  if (x.norm() < 1e-6) x = g.up.unitOrthogonal();
  g.e1 = x.normalized();
  g.e2 = g.up.cross(g.e1);
  return g;
}

// A detection in the ground plane.
struct Observation {
  int frame = 0;
  double time = 0.0;
  ObjectLabel label;             // as given, frame set
  Eigen::Vector2d ground;        // bottom centre, ground-plane coordinates (e1, e2)
  Eigen::Matrix2d ground_covariance;
  double height = 0.0, height_variance = 0.0;  // along up
  Eigen::Vector3d size;          // h, w, l
  double axis = 0.0;             // heading in the ground plane modulo pi, [0, pi)
};

// Angle difference modulo pi, in [-pi/2, pi/2).
double AxisDifference(double a, double b) {
  double d = std::fmod(a - b, kPi);
  if (d < -kPi / 2) d += kPi;
  if (d >= kPi / 2) d -= kPi;
  return d;
}

// Mean axis (modulo pi) of angles: the mean of the doubled-angle unit vectors.
double MeanAxis(const std::vector<double>& axes) {
  double c = 0, s = 0;
  for (double a : axes) c += std::cos(2 * a), s += std::sin(2 * a);
  double mean = 0.5 * std::atan2(s, c);
  if (mean < 0) mean += kPi;
  return mean;
}

}  // namespace

Eigen::Matrix3d DetectionCovariance(const Eigen::Vector3d& p, const TrackerOptions& o) {
  Eigen::Vector3d ray(p.x(), 0.0, p.z());
  const double d = ray.norm();
  ray = d > 1e-9 ? Eigen::Vector3d(ray / d) : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d across(ray.z(), 0.0, -ray.x());
  const Eigen::Vector3d vertical = Eigen::Vector3d::UnitY();
  const double s_along = o.along_sigma_a + o.along_sigma_b * d + o.along_sigma_c * d * d;
  const double s_across = o.across_sigma_a + o.across_sigma_b * d;
  const double s_vertical = o.vertical_sigma_a + o.vertical_sigma_b * d;
  return s_along * s_along * ray * ray.transpose() + s_across * s_across * across * across.transpose() +
         s_vertical * s_vertical * vertical * vertical.transpose();
}

namespace {

Observation MakeObservation(const ObjectLabel& label, int frame, const Eigen::Isometry3d& world_from_camera,
                            const GroundFrame& g, const TrackerOptions& o) {
  Observation obs;
  obs.frame = frame;
  obs.time = frame / o.frame_rate_hz;
  obs.label = label;
  obs.label.frame = frame;
  const Eigen::Vector3d& p = label.position;  // bottom centre, camera
  const Eigen::Matrix3d in_camera = DetectionCovariance(p, o);
  const Eigen::Matrix3d& r = world_from_camera.linear();
  const Eigen::Matrix3d in_world = r * in_camera * r.transpose();
  Eigen::Matrix<double, 3, 2> e;
  e.col(0) = g.e1;
  e.col(1) = g.e2;
  const Eigen::Vector3d p_world = world_from_camera * p;
  obs.ground = e.transpose() * p_world;
  obs.ground_covariance = e.transpose() * in_world * e;
  obs.height = g.up.dot(p_world);
  obs.height_variance = g.up.dot(in_world * g.up);
  obs.size = Eigen::Vector3d(label.height, label.width, label.length);
  // The object's x axis (front) in the camera is (cos ry, 0, -sin ry).
  const Eigen::Vector3d front = r * Eigen::Vector3d(std::cos(label.rotation_y), 0.0, -std::sin(label.rotation_y));
  double axis = std::atan2(g.e2.dot(front), g.e1.dot(front));
  axis = std::fmod(axis + 2 * kPi, kPi);
  obs.axis = axis;
  return obs;
}

// White-acceleration process noise of the 2-D constant-velocity model over dt.
Matrix4d ProcessNoise(double dt, double acceleration_sigma) {
  const double q = acceleration_sigma * acceleration_sigma;
  const double t = std::abs(dt);
  Matrix4d noise = Matrix4d::Zero();
  noise.topLeftCorner<2, 2>() = q * t * t * t * t / 4.0 * Eigen::Matrix2d::Identity();
  noise.topRightCorner<2, 2>() = q * dt * dt * dt / 2.0 * Eigen::Matrix2d::Identity();
  noise.bottomLeftCorner<2, 2>() = noise.topRightCorner<2, 2>();
  noise.bottomRightCorner<2, 2>() = q * t * t * Eigen::Matrix2d::Identity();
  return noise;
}

Matrix4d Transition(double dt) {
  Matrix4d f = Matrix4d::Identity();
  f.topRightCorner<2, 2>() = dt * Eigen::Matrix2d::Identity();
  return f;
}

// A track of the online stage.
struct OnlineTrack {
  std::vector<int> members;  // observation indices, increasing frames
  Vector4d state = Vector4d::Zero();  // ground position, velocity
  Matrix4d covariance = Matrix4d::Identity();
  double time = 0.0;         // of the state
  int last_frame = 0;
  bool confirmed = false;
  Eigen::Vector3d size_sum = Eigen::Vector3d::Zero();
  double height_sum = 0.0;
  // Detections in size_sum and height_sum (all of them unless robust_cues
  // left an outlying cue out).
  int size_count = 0, height_count = 0;
  Eigen::Vector2d axis_vector = Eigen::Vector2d(1, 0);  // smoothed (cos 2a, sin 2a)
  int Count() const { return static_cast<int>(members.size()); }
  double Axis() const {
    double a = 0.5 * std::atan2(axis_vector.y(), axis_vector.x());
    return a < 0 ? a + kPi : a;
  }
};

// Cues of an observation outside their gates (bits), for robust_cues.
constexpr unsigned kSizeOutlier = 1, kHeightOutlier = 2, kAxisOutlier = 4;

int CountBits(unsigned mask) { return int((mask & 1) != 0) + int((mask & 2) != 0) + int((mask & 4) != 0); }

// The association cost of an observation to a track predicted to its time
// (state and covariance given), or kNoAssignment outside a gate. With
// robust_cues a single cue outside its gate costs the gate's value and is
// flagged in *outliers; two or more forbid the pair.
double AssociationCost(const OnlineTrack& track, const Vector4d& predicted, const Matrix4d& predicted_covariance,
                       const Observation& obs, const TrackerOptions& o, unsigned* outliers) {
  *outliers = 0;
  const Eigen::Vector2d innovation = obs.ground - predicted.head<2>();
  const Eigen::Matrix2d s = predicted_covariance.topLeftCorner<2, 2>() + obs.ground_covariance;
  const double d2_position = innovation.dot(s.ldlt().solve(innovation));
  if (!(d2_position <= o.gate_chi2)) return kNoAssignment;
  const double n_size = track.size_count, n_height = track.height_count;
  double d2_size = o.size_gate_chi2;  // no size yet (every earlier one outlying): the gate's value
  if (n_size > 0) {
    const Eigen::Vector3d size_difference = obs.size - track.size_sum / n_size;
    d2_size = size_difference.squaredNorm() / (o.size_sigma * o.size_sigma * (1.0 + 1.0 / n_size));
  }
  if (!(d2_size <= o.size_gate_chi2)) {
    if (!o.robust_cues) return kNoAssignment;
    d2_size = o.size_gate_chi2;
    *outliers |= kSizeOutlier;
  }
  double d2_height = o.height_gate_chi2;
  if (n_height > 0) {
    const double height_difference = obs.height - track.height_sum / n_height;
    d2_height = height_difference * height_difference / (obs.height_variance * (1.0 + 1.0 / n_height));
  }
  if (!(d2_height <= o.height_gate_chi2)) {
    if (!o.robust_cues) return kNoAssignment;
    d2_height = o.height_gate_chi2;
    *outliers |= kHeightOutlier;
  }
  double axis_difference = AxisDifference(obs.axis, track.Axis());
  const double axis_gate = o.yaw_gate_deg * kPi / 180.0;
  if (std::abs(axis_difference) > axis_gate) {
    if (!o.robust_cues) return kNoAssignment;
    axis_difference = axis_gate;
    *outliers |= kAxisOutlier;
  }
  if (CountBits(*outliers) > 1) return kNoAssignment;
  const double s_yaw = o.yaw_sigma_deg * kPi / 180.0;
  const double d2_axis = axis_difference * axis_difference / (1.5 * s_yaw * s_yaw);
  return d2_position + d2_size + d2_height + d2_axis + (track.confirmed ? 0.0 : o.tentative_penalty);
}

// Adds an observation to a track; cues flagged in `outliers` do not update its means.
void AddObservation(int index, const Observation& obs, unsigned outliers, OnlineTrack* track) {
  track->members.push_back(index);
  track->last_frame = obs.frame;
  if (!(outliers & kSizeOutlier)) track->size_sum += obs.size, ++track->size_count;
  if (!(outliers & kHeightOutlier)) track->height_sum += obs.height, ++track->height_count;
  if (outliers & kAxisOutlier) return;
  const Eigen::Vector2d v(std::cos(2 * obs.axis), std::sin(2 * obs.axis));
  if (track->Count() == 1) {
    track->axis_vector = v;
  } else {
    const Eigen::Vector2d mixed = 0.5 * track->axis_vector + 0.5 * v;
    if (mixed.norm() > 1e-9) track->axis_vector = mixed.normalized();
  }
}

// Largest eigenvalue of a symmetric 2x2 matrix.
double LargestEigenvalue(const Eigen::Matrix2d& m) {
  const double mean = 0.5 * (m(0, 0) + m(1, 1));
  const double half = 0.5 * (m(0, 0) - m(1, 1));
  return mean + std::sqrt(half * half + m(0, 1) * m(1, 0));
}

// The observations of one frame in a grid of square cells (ground plane), so
// that a track meets only the observations within its gate's radius.
class GroundHash {
 public:
  GroundHash(const std::vector<Observation>& observations, const std::vector<int>& members, double cell)
      : cell_(cell) {
    for (int k = 0; k < int(members.size()); ++k) cells_[Key(Cell(observations[members[k]].ground))].push_back(k);
  }
  // Indices (into `members`) of the observations within `radius` of `center`
  // (a superset), increasing.
  std::vector<int> Near(const Eigen::Vector2d& center, double radius, int num_members) const {
    std::vector<int> out;
    const Eigen::Vector2i lo = Cell(center - Eigen::Vector2d::Constant(radius));
    const Eigen::Vector2i hi = Cell(center + Eigen::Vector2d::Constant(radius));
    const double span = (double(hi.x()) - lo.x() + 1) * (double(hi.y()) - lo.y() + 1);
    if (!(span <= 4.0 * num_members)) {  // a wide gate: every observation
      out.resize(num_members);
      for (int k = 0; k < num_members; ++k) out[k] = k;
      return out;
    }
    for (int x = lo.x(); x <= hi.x(); ++x)
      for (int y = lo.y(); y <= hi.y(); ++y) {
        const auto it = cells_.find(Key(Eigen::Vector2i(x, y)));
        if (it != cells_.end()) out.insert(out.end(), it->second.begin(), it->second.end());
      }
    std::sort(out.begin(), out.end());
    return out;
  }

 private:
  Eigen::Vector2i Cell(const Eigen::Vector2d& p) const {
    const double limit = 1e9;  // far-off (or non-finite) positions share the border cells
    auto index = [&](double v) {
      const double c = std::floor(v / cell_);
      return int(std::isfinite(c) ? std::clamp(c, -limit, limit) : limit);
    };
    return Eigen::Vector2i(index(p.x()), index(p.y()));
  }
  static int64_t Key(const Eigen::Vector2i& c) {
    return int64_t((uint64_t(int64_t(c.x())) << 32) ^ (uint64_t(int64_t(c.y())) & 0xffffffffu));
  }
  double cell_;
  std::unordered_map<int64_t, std::vector<int>> cells_;
};

// The least-cost assignment of a sparse cost list (row, col, cost; allowed
// pairs only), solved per connected group of rows and columns: the same
// optimum as SolveAssignment over the dense matrix, in time linear in the
// number of groups of bounded size. Returns the column of each row or -1.
struct SparseCost {
  int row, col;
  double cost;
};

std::vector<int> SolveSparseAssignment(const std::vector<SparseCost>& pairs, int rows, int cols) {
  std::vector<int> parent(rows + cols);
  for (int i = 0; i < rows + cols; ++i) parent[i] = i;
  std::function<int(int)> find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (const SparseCost& p : pairs) {
    const int a = find(p.row), b = find(rows + p.col);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  std::map<int, std::pair<std::vector<int>, std::vector<int>>> groups;  // root -> rows, cols (increasing)
  for (const SparseCost& p : pairs) groups[find(p.row)];
  for (int r = 0; r < rows; ++r) {
    auto it = groups.find(find(r));
    if (it != groups.end()) it->second.first.push_back(r);
  }
  for (int c = 0; c < cols; ++c) {
    auto it = groups.find(find(rows + c));
    if (it != groups.end()) it->second.second.push_back(c);
  }
  std::vector<int> local_index(rows + cols, -1);
  for (const auto& [root, members] : groups) {
    for (size_t i = 0; i < members.first.size(); ++i) local_index[members.first[i]] = int(i);
    for (size_t j = 0; j < members.second.size(); ++j) local_index[rows + members.second[j]] = int(j);
  }
  std::map<int, std::vector<double>> matrices;
  for (const auto& [root, members] : groups)
    matrices[root].assign(members.first.size() * members.second.size(), kNoAssignment);
  for (const SparseCost& p : pairs) {
    const auto& members = groups.at(find(p.row));
    matrices[find(p.row)][size_t(local_index[p.row]) * members.second.size() + local_index[rows + p.col]] = p.cost;
  }
  std::vector<int> result(rows, -1);
  for (const auto& [root, members] : groups) {
    const int r = int(members.first.size()), c = int(members.second.size());
    const std::vector<int> local = SolveAssignment(matrices.at(root), r, c);
    for (int i = 0; i < r; ++i)
      if (local[i] >= 0) result[members.first[i]] = members.second[local[i]];
  }
  return result;
}

// The online stage: returns the tracks (observation indices), in order of creation.
std::vector<std::vector<int>> LinkOnline(const std::vector<FrameDetections>& frames,
                                         const std::vector<std::vector<int>>& observations_of_frame,
                                         const std::vector<Observation>& observations, const TrackerOptions& o) {
  std::vector<OnlineTrack> tracks;
  std::vector<int> active;
  for (size_t f = 0; f < frames.size(); ++f) {
    const int frame = frames[f].frame;
    const double time = frame / o.frame_rate_hz;
    active.erase(std::remove_if(active.begin(), active.end(),
                                [&](int t) {
                                  const int missed = frame - tracks[t].last_frame - 1;
                                  return missed > (tracks[t].confirmed ? o.max_misses : o.tentative_max_misses);
                                }),
                 active.end());
    const std::vector<int>& obs = observations_of_frame[f];
    const int rows = static_cast<int>(active.size()), cols = static_cast<int>(obs.size());
    std::vector<Vector4d> predicted(rows);
    std::vector<Matrix4d> predicted_covariance(rows);
    // Pairs within the position gate only: the gate's squared Mahalanobis
    // distance bounds the distance by sqrt(gate x the largest eigenvalue of
    // the innovation covariance).
    double largest_observation_variance = 0.0;
    for (int k : obs)
      largest_observation_variance =
          std::max(largest_observation_variance, LargestEigenvalue(observations[k].ground_covariance));
    const GroundHash hash(observations, obs, 5.0);
    std::vector<SparseCost> pairs;
    std::map<std::pair<int, int>, unsigned> outliers_of_pair;
    for (int a = 0; a < rows; ++a) {
      const OnlineTrack& track = tracks[active[a]];
      const double dt = time - track.time;
      const Matrix4d transition = Transition(dt);
      predicted[a] = transition * track.state;
      predicted_covariance[a] = transition * track.covariance * transition.transpose() +
                                ProcessNoise(dt, o.acceleration_sigma);
      const double radius =
          std::sqrt(o.gate_chi2 * (LargestEigenvalue(predicted_covariance[a].topLeftCorner<2, 2>()) +
                                   largest_observation_variance)) + 1e-6;
      for (int k : hash.Near(predicted[a].head<2>(), radius, cols)) {
        unsigned outliers = 0;
        const double c = AssociationCost(track, predicted[a], predicted_covariance[a], observations[obs[k]], o,
                                         &outliers);
        if (c >= kNoAssignment) continue;
        pairs.push_back({a, k, c});
        if (outliers != 0) outliers_of_pair[{a, k}] = outliers;
      }
    }
    const std::vector<int> assignment = SolveSparseAssignment(pairs, rows, cols);
    std::vector<char> taken(cols, 0);
    for (int a = 0; a < rows; ++a) {
      const int k = assignment[a];
      if (k < 0) continue;
      taken[k] = 1;
      const auto outlying = outliers_of_pair.find({a, k});
      OnlineTrack& track = tracks[active[a]];
      const Observation& ob = observations[obs[k]];
      // Kalman update with the detected ground position (H = [I 0]).
      const Matrix4d& p = predicted_covariance[a];
      const Eigen::Matrix2d s = p.topLeftCorner<2, 2>() + ob.ground_covariance;
      const Eigen::Matrix<double, 4, 2> gain = p.leftCols<2>() * s.inverse();
      track.state = predicted[a] + gain * (ob.ground - predicted[a].head<2>());
      const Matrix4d covariance = p - gain * p.topRows<2>();
      track.covariance = 0.5 * (covariance + covariance.transpose());
      track.time = time;
      AddObservation(obs[k], ob, outlying == outliers_of_pair.end() ? 0u : outlying->second, &track);
      if (track.Count() >= o.confirm_hits) track.confirmed = true;
    }
    for (int k = 0; k < cols; ++k) {
      if (taken[k]) continue;
      const Observation& ob = observations[obs[k]];
      OnlineTrack track;
      track.state.head<2>() = ob.ground;
      track.covariance.setZero();
      track.covariance.topLeftCorner<2, 2>() = ob.ground_covariance;
      const double s_v = o.max_speed / 2.0;
      track.covariance.bottomRightCorner<2, 2>() = s_v * s_v * Eigen::Matrix2d::Identity();
      track.time = time;
      AddObservation(obs[k], ob, 0u, &track);
      track.confirmed = track.Count() >= o.confirm_hits;
      tracks.push_back(std::move(track));
      active.push_back(static_cast<int>(tracks.size()) - 1);
    }
  }
  std::vector<std::vector<int>> result;
  for (OnlineTrack& t : tracks) result.push_back(std::move(t.members));
  return result;
}

// Weighted least-squares constant-velocity fit of observations in the ground
// plane, state (position, velocity) at time t_ref, with a zero-velocity prior
// of std. dev. max_speed / 2 and a model error growing with the time from t_ref.
struct MotionFit {
  Vector4d state = Vector4d::Zero();
  Matrix4d covariance = Matrix4d::Identity();
  double time = 0.0;
};

MotionFit FitConstantVelocity(const std::vector<Observation>& observations, const std::vector<int>& members,
                              double t_ref, const TrackerOptions& o) {
  const double s_v = o.max_speed / 2.0;
  Matrix4d information = Matrix4d::Zero();
  information.bottomRightCorner<2, 2>() = Eigen::Matrix2d::Identity() / (s_v * s_v);
  Vector4d rhs = Vector4d::Zero();
  for (int m : members) {
    const Observation& ob = observations[m];
    const double dt = ob.time - t_ref;
    Eigen::Matrix<double, 2, 4> a;
    a << 1, 0, dt, 0, 0, 1, 0, dt;
    const double model = 0.5 * o.acceleration_sigma * dt * dt;
    const Eigen::Matrix2d w = (ob.ground_covariance + model * model * Eigen::Matrix2d::Identity()).inverse();
    information += a.transpose() * w * a;
    rhs += a.transpose() * w * ob.ground;
  }
  MotionFit fit;
  fit.time = t_ref;
  fit.covariance = information.inverse();
  fit.state = fit.covariance * rhs;
  return fit;
}

MotionFit Extrapolate(const MotionFit& fit, double time, const TrackerOptions& o) {
  const double dt = time - fit.time;
  const Matrix4d f = Transition(dt);
  MotionFit out;
  out.time = time;
  out.state = f * fit.state;
  out.covariance = f * fit.covariance * f.transpose() + ProcessNoise(dt, o.acceleration_sigma);
  return out;
}

// The cost of continuing `head` (observations, increasing frames) with `tail`
// (all later): squared Mahalanobis distance of the two constant-velocity fits
// (each of fit_window observations next to the gap) at the gap's middle, plus
// size, height and axis terms; kNoAssignment beyond the axis gate.
double LinkCost(const std::vector<Observation>& observations, const std::vector<int>& head,
                const std::vector<int>& tail, const TrackerOptions& o) {
  const size_t k = static_cast<size_t>(o.fit_window);
  const std::vector<int> h(head.end() - std::min(k, head.size()), head.end());
  const std::vector<int> t(tail.begin(), tail.begin() + std::min(k, tail.size()));
  const double t_head = observations[h.back()].time, t_tail = observations[t.front()].time;
  const double t_mid = 0.5 * (t_head + t_tail);
  const MotionFit a = Extrapolate(FitConstantVelocity(observations, h, t_head, o), t_mid, o);
  const MotionFit b = Extrapolate(FitConstantVelocity(observations, t, t_tail, o), t_mid, o);
  const Vector4d difference = a.state - b.state;
  const double d2_motion = difference.dot((a.covariance + b.covariance).ldlt().solve(difference));
  auto means = [&](const std::vector<int>& members, Eigen::Vector3d* size, double* height, double* height_var,
                   double* axis) {
    *size = Eigen::Vector3d::Zero();
    *height = *height_var = 0.0;
    std::vector<double> axes;
    for (int m : members) {
      *size += observations[m].size;
      *height += observations[m].height;
      *height_var += observations[m].height_variance;
      axes.push_back(observations[m].axis);
    }
    *size /= double(members.size());
    if (o.robust_cues) {  // the median of each dimension: one wrong box does not move it
      for (int i = 0; i < 3; ++i) {
        std::vector<double> v;
        for (int m : members) v.push_back(observations[m].size[i]);
        std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
        (*size)[i] = v[v.size() / 2];
      }
    }
    *height /= double(members.size());
    *height_var /= double(members.size()) * double(members.size());
    *axis = MeanAxis(axes);
  };
  Eigen::Vector3d size_h, size_t;
  double height_h, height_t, var_h, var_t, axis_h, axis_t;
  means(h, &size_h, &height_h, &var_h, &axis_h);
  means(t, &size_t, &height_t, &var_t, &axis_t);
  const double nh = double(h.size()), nt = double(t.size());
  double d2_size = (size_h - size_t).squaredNorm() / (o.size_sigma * o.size_sigma * (1.0 / nh + 1.0 / nt));
  double d2_height = (height_h - height_t) * (height_h - height_t) / (var_h + var_t);
  double axis_difference = AxisDifference(axis_h, axis_t);
  int outlying_cues = 0;
  if (std::abs(axis_difference) > o.yaw_gate_deg * kPi / 180.0) {
    if (!o.robust_cues) return kNoAssignment;
    axis_difference = o.yaw_gate_deg * kPi / 180.0;
    ++outlying_cues;
  }
  if (o.robust_cues) {  // a single cue outside its gate costs the gate's value
    if (!(d2_size <= o.size_gate_chi2)) d2_size = o.size_gate_chi2, ++outlying_cues;
    if (!(d2_height <= o.height_gate_chi2)) d2_height = o.height_gate_chi2, ++outlying_cues;
    if (outlying_cues > 1) return kNoAssignment;
  }
  const double s_yaw = o.yaw_sigma_deg * kPi / 180.0;
  const double turn = 0.5 * (t_tail - t_head);  // a turning car: up to ~0.5 rad/s
  const double d2_axis = axis_difference * axis_difference / (s_yaw * s_yaw * (1.0 / nh + 1.0 / nt) + turn * turn);
  return d2_motion + d2_size + d2_height + d2_axis;
}

int FirstFrame(const std::vector<Observation>& obs, const std::vector<int>& t) { return obs[t.front()].frame; }
int LastFrame(const std::vector<Observation>& obs, const std::vector<int>& t) { return obs[t.back()].frame; }

// Joins fragment ends to later fragment starts (one-to-one, Hungarian on the
// gated link costs). Returns the number of joins.
int JoinFragments(const std::vector<Observation>& observations, const TrackerOptions& o,
                  std::vector<std::vector<int>>* tracks) {
  std::vector<std::vector<int>>& t = *tracks;
  const int n = static_cast<int>(t.size());
  std::vector<double> cost(static_cast<size_t>(n) * n, kNoAssignment);
  bool any = false;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      // A single detection (a false positive, mostly) joins nothing.
      if (i == j || t[i].size() < 2 || t[j].size() < 2) continue;
      const int gap = FirstFrame(observations, t[j]) - LastFrame(observations, t[i]) - 1;
      if (gap < 0 || gap > o.max_join_gap) continue;
      const double c = LinkCost(observations, t[i], t[j], o);
      if (c <= o.join_gate_chi2) {
        cost[static_cast<size_t>(i) * n + j] = c;
        any = true;
      }
    }
  }
  if (!any) return 0;
  const std::vector<int> next = SolveAssignment(cost, n, n);
  std::vector<char> has_previous(n, 0);
  int joins = 0;
  for (int i = 0; i < n; ++i)
    if (next[i] >= 0) has_previous[next[i]] = 1, ++joins;
  std::vector<std::vector<int>> joined;
  for (int i = 0; i < n; ++i) {
    if (has_previous[i]) continue;
    std::vector<int> chain;
    for (int j = i; j >= 0; j = next[j]) chain.insert(chain.end(), t[j].begin(), t[j].end());
    joined.push_back(std::move(chain));
  }
  t = std::move(joined);
  return joins;
}

// Cost of a link inside a track; 0 when one side is empty.
double InnerCost(const std::vector<Observation>& observations, const std::vector<int>& head,
                 const std::vector<int>& tail, const TrackerOptions& o) {
  if (head.empty() || tail.empty()) return 0.0;
  const int gap = FirstFrame(observations, tail) - LastFrame(observations, head) - 1;
  if (gap > o.max_join_gap) return kNoAssignment;
  return std::min(kNoAssignment, LinkCost(observations, head, tail, o));
}

// Two tracks whose detections come within `radius` (ground plane) in frames at
// most one apart.
bool ComeClose(const std::vector<Observation>& observations, const std::vector<int>& a, const std::vector<int>& b,
               double radius) {
  for (int i : a)
    for (int j : b)
      if (std::abs(observations[i].frame - observations[j].frame) <= 1 &&
          (observations[i].ground - observations[j].ground).norm() <= radius)
        return true;
  return false;
}

// Swaps tails between pairs of tracks while the best swap lowers the sum of
// the two link costs by more than swap_margin. Returns the number of swaps.
int ResolveSwitches(const std::vector<Observation>& observations, const TrackerOptions& o,
                    std::vector<std::vector<int>>* tracks) {
  std::vector<std::vector<int>>& t = *tracks;
  constexpr double kSwapRadius = 5.0;  // m: only tracks that come this close can have switched
  int swaps = 0;
  for (int pass = 0; pass < 1000; ++pass) {
    double best_gain = o.swap_margin;
    int best_x = -1, best_y = -1, best_split = 0;
    for (size_t x = 0; x < t.size(); ++x) {
      for (size_t y = x + 1; y < t.size(); ++y) {
        const int lo = std::max(FirstFrame(observations, t[x]), FirstFrame(observations, t[y]));
        const int hi = std::min(LastFrame(observations, t[x]), LastFrame(observations, t[y]));
        if (lo > hi + o.max_join_gap + 1) continue;  // far apart in time
        if (!ComeClose(observations, t[x], t[y], kSwapRadius)) continue;
        std::set<int> splits;
        for (int m : t[x]) splits.insert(observations[m].frame);
        for (int m : t[y]) splits.insert(observations[m].frame);
        for (int s : splits) {
          auto split = [&](const std::vector<int>& track, std::vector<int>* head, std::vector<int>* tail) {
            head->clear(), tail->clear();
            for (int m : track) (observations[m].frame < s ? head : tail)->push_back(m);
          };
          std::vector<int> xh, xt, yh, yt;
          split(t[x], &xh, &xt);
          split(t[y], &yh, &yt);
          // Both tracks continue across the split, each part with two detections at least:
          // links of different lengths are not comparable by their costs.
          if (xh.size() < 2 || yh.size() < 2 || xt.size() < 2 || yt.size() < 2) continue;
          const double current = InnerCost(observations, xh, xt, o) + InnerCost(observations, yh, yt, o);
          const double swapped_a = InnerCost(observations, xh, yt, o), swapped_b = InnerCost(observations, yh, xt, o);
          if (swapped_a >= kNoAssignment || swapped_b >= kNoAssignment) continue;
          if (swapped_a > o.join_gate_chi2 || swapped_b > o.join_gate_chi2) continue;
          const double gain = std::min(current, 1e12) - (swapped_a + swapped_b);
          if (gain > best_gain) best_gain = gain, best_x = int(x), best_y = int(y), best_split = s;
        }
      }
    }
    if (best_x < 0) break;
    std::vector<int> xh, xt, yh, yt;
    for (int m : t[best_x]) (observations[m].frame < best_split ? xh : xt).push_back(m);
    for (int m : t[best_y]) (observations[m].frame < best_split ? yh : yt).push_back(m);
    xh.insert(xh.end(), yt.begin(), yt.end());
    yh.insert(yh.end(), xt.begin(), xt.end());
    t[best_x] = std::move(xh);
    t[best_y] = std::move(yh);
    t.erase(std::remove_if(t.begin(), t.end(), [](const std::vector<int>& v) { return v.empty(); }), t.end());
    ++swaps;
  }
  return swaps;
}

std::string DescribeShortTrack(const std::vector<ObjectLabel>& detections) {
  std::ostringstream s;
  s << "frames " << detections.front().frame << "-" << detections.back().frame << " ("
    << detections.size() << (detections.size() == 1 ? " detection)" : " detections)");
  return s.str();
}

double MedianLength(std::vector<int> lengths) {
  if (lengths.empty()) return 0.0;
  std::sort(lengths.begin(), lengths.end());
  const size_t n = lengths.size();
  return n % 2 == 1 ? lengths[n / 2] : 0.5 * (lengths[n / 2 - 1] + lengths[n / 2]);
}

// Fills the counts of kept tracks, their median length and the warning.
void FinishSummary(const std::vector<LinkedTrack>& tracks, int warn_median_length, int num_frames,
                   TrackingSummary* summary) {
  summary->num_tracks = static_cast<int>(tracks.size());
  std::vector<int> lengths;
  for (const LinkedTrack& t : tracks) lengths.push_back(static_cast<int>(t.detections.size()));
  summary->median_track_length = MedianLength(lengths);
  const double shortest = std::min(double(warn_median_length), 0.5 * num_frames);
  if (!tracks.empty() && summary->median_track_length < shortest) {
    std::ostringstream w;
    w << "median track length " << summary->median_track_length << " detections < " << shortest
      << " (" << tracks.size() << " tracks of " << summary->num_detections
      << " detections): the tracker may be splitting cars; check the detector noise options "
         "(--tracker-*, docs/sequence_format.md) or give tracks with --tracks";
    summary->warnings.push_back(w.str());
  }
}

}  // namespace

std::string TrackerOptions::ToJson() const { return DumpJson(OptionsToJson(*this)); }

std::string TrackingSummary::BriefReport() const {
  std::ostringstream s;
  s << num_detections << " detections -> " << num_tracks << " tracks (median " << median_track_length
    << " detections";
  if (num_online_tracks > 0)
    s << "; " << num_online_tracks << " online, " << num_joins << " joins, " << num_swaps << " swaps";
  s << ")";
  if (num_short_tracks > 0) {
    s << "; dropped " << num_short_tracks << " short track(s) (" << num_short_detections
      << " detections):";
    for (const std::string& t : short_tracks) s << " [" << t << "]";
  }
  if (num_duplicates > 0) {
    s << "; dropped " << num_duplicates << " duplicate detection(s):";
    for (const std::string& d : duplicates) s << " [" << d << "]";
  }
  for (const std::string& w : warnings) s << "; WARNING: " << w;
  return s.str();
}

std::string TrackingSummary::ToJson() const {
  nlohmann::json j = {{"detections", num_detections},
                            {"tracks", num_tracks},
                            {"median_track_length", median_track_length},
                            {"online_tracks", num_online_tracks},
                            {"joins", num_joins},
                            {"swaps", num_swaps},
                            {"short_tracks_dropped", num_short_tracks},
                            {"short_track_detections", num_short_detections},
                            {"warnings", warnings}};
  if (num_duplicates > 0) j["duplicates"] = num_duplicates;  // added with duplicate flagging: only when some
  return DumpJson(j);
}

std::vector<int> SolveAssignment(const std::vector<double>& cost, int rows, int cols) {
  SAMP_CHECK(rows >= 0 && cols >= 0 && cost.size() == static_cast<size_t>(rows) * cols)
      << "SolveAssignment: cost matrix size " << cost.size() << " != " << rows << " x " << cols;
  std::vector<int> result(rows, -1);
  if (rows == 0 || cols == 0) return result;
  // Forbidden entries get a cost above any sum of allowed ones: the optimum
  // first maximises the number of allowed pairs, then minimises their cost.
  double sum_allowed = 0;
  for (double c : cost) {
    SAMP_CHECK(!std::isnan(c)) << "SolveAssignment: NaN cost";
    if (c < kNoAssignment) sum_allowed += std::abs(c);
  }
  const double big = 2 * sum_allowed + 1;
  const bool transpose = rows > cols;
  const int r = transpose ? cols : rows, c = transpose ? rows : cols;
  std::vector<double> work(static_cast<size_t>(r) * c);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      const double value = cost[static_cast<size_t>(i) * cols + j];
      const double w = value < kNoAssignment ? value : big;
      if (transpose) work[static_cast<size_t>(j) * c + i] = w; else work[static_cast<size_t>(i) * c + j] = w;
    }
  const std::vector<int> assigned = HungarianRowsLeCols(work, r, c);
  for (int k = 0; k < r; ++k) {
    const int row = transpose ? assigned[k] : k;
    const int col = transpose ? k : assigned[k];
    if (row < 0 || col < 0) continue;
    if (cost[static_cast<size_t>(row) * cols + col] < kNoAssignment) result[row] = col;
  }
  return result;
}


std::vector<LinkedTrack> LinkDetections(const std::vector<FrameDetections>& frames,
                                        const TrackerOptions& options, TrackingSummary* summary) {
  options.Check();
  for (size_t i = 1; i < frames.size(); ++i)
    SAMP_CHECK(frames[i].frame > frames[i - 1].frame)
        << "LinkDetections: frames must increase (" << frames[i - 1].frame << " then "
        << frames[i].frame << ")";
  const GroundFrame ground = MakeGroundFrame(frames);
  std::vector<Observation> observations;
  std::vector<std::vector<int>> observations_of_frame(frames.size());
  int num_duplicates = 0;
  std::vector<std::string> duplicates;
  for (size_t f = 0; f < frames.size(); ++f) {
    // Earlier detections of this frame by 1 m cell of their bottom centre (camera x, z).
    std::unordered_map<int64_t, std::vector<const ObjectLabel*>> seen;
    auto cell_key = [](double x, double z) {
      const auto i = int64_t(std::floor(std::clamp(x, -1e6, 1e6))), j = int64_t(std::floor(std::clamp(z, -1e6, 1e6)));
      return int64_t((uint64_t(i) << 32) ^ (uint64_t(j) & 0xffffffffu));
    };
    int frame_duplicates = 0;
    for (const ObjectLabel& label : frames[f].detections) {
      SAMP_CHECK(label.height > 0 && label.width > 0 && label.length > 0 && label.position.allFinite() &&
                 std::isfinite(label.rotation_y))
          << "LinkDetections: frame " << frames[f].frame << ": a detection has a non-positive size or "
          << "a non-finite position/yaw";
      bool duplicate = false;
      const double x = label.position.x(), z = label.position.z();
      for (int dx = -1; dx <= 1 && !duplicate; ++dx)
        for (int dz = -1; dz <= 1 && !duplicate; ++dz) {
          const auto it = seen.find(cell_key(x + dx, z + dz));
          if (it == seen.end()) continue;
          for (const ObjectLabel* other : it->second) {
            if ((other->position - label.position).norm() <= 0.01 &&
                std::abs(other->height - label.height) <= 0.01 && std::abs(other->width - label.width) <= 0.01 &&
                std::abs(other->length - label.length) <= 0.01 &&
                std::abs(AxisDifference(other->rotation_y, label.rotation_y)) <= 0.5 * kPi / 180.0) {
              duplicate = true;
              break;
            }
          }
        }
      if (duplicate) {
        ++frame_duplicates;
        continue;
      }
      seen[cell_key(x, z)].push_back(&label);
      observations_of_frame[f].push_back(static_cast<int>(observations.size()));
      observations.push_back(
          MakeObservation(label, frames[f].frame, frames[f].world_from_camera, ground, options));
    }
    if (frame_duplicates > 0) {
      num_duplicates += frame_duplicates;
      duplicates.push_back("frame " + std::to_string(frames[f].frame) + ": " + std::to_string(frame_duplicates) +
                           (frame_duplicates == 1 ? " duplicate" : " duplicates"));
    }
  }

  std::vector<std::vector<int>> tracks = LinkOnline(frames, observations_of_frame, observations, options);
  TrackingSummary local;
  TrackingSummary& result = summary != nullptr ? *summary : local;
  result = TrackingSummary();
  result.num_detections = static_cast<int>(observations.size()) + num_duplicates;
  result.num_duplicates = num_duplicates;
  result.duplicates = std::move(duplicates);
  result.num_online_tracks = static_cast<int>(tracks.size());
  for (int round = 0; round < 2; ++round) {
    const int swaps = options.resolve_switches ? ResolveSwitches(observations, options, &tracks) : 0;
    const int joins = options.join_fragments ? JoinFragments(observations, options, &tracks) : 0;
    result.num_swaps += swaps;
    result.num_joins += joins;
    if (swaps == 0 && joins == 0) break;
  }

  // Ids in order of first appearance (first frame, then detection index).
  for (std::vector<int>& t : tracks) std::sort(t.begin(), t.end());
  std::sort(tracks.begin(), tracks.end(),
            [](const std::vector<int>& a, const std::vector<int>& b) { return a.front() < b.front(); });
  std::vector<LinkedTrack> linked;
  for (const std::vector<int>& t : tracks) {
    std::vector<ObjectLabel> detections;
    for (int m : t) detections.push_back(observations[m].label);
    if (static_cast<int>(detections.size()) < options.min_track_length) {
      ++result.num_short_tracks;
      result.num_short_detections += static_cast<int>(detections.size());
      result.short_tracks.push_back(DescribeShortTrack(detections));
      continue;
    }
    LinkedTrack out;
    out.id = static_cast<int>(linked.size());
    out.detections = std::move(detections);
    for (ObjectLabel& label : out.detections) label.track_id = out.id;
    linked.push_back(std::move(out));
  }
  FinishSummary(linked, options.warn_median_length, static_cast<int>(frames.size()), &result);
  return linked;
}

std::vector<LinkedTrack> TracksFromLabels(const std::vector<ObjectLabel>& labels,
                                          int min_track_length, TrackingSummary* summary) {
  SAMP_CHECK(min_track_length >= 1) << "TracksFromLabels: min_track_length must be >= 1";
  std::map<int, std::vector<ObjectLabel>> by_id;
  int num_detections = 0;
  for (const ObjectLabel& label : labels) {
    if (label.track_id < 0 || SameObjectType(label.type, "DontCare")) continue;
    SAMP_CHECK(label.frame >= 0) << "TracksFromLabels: label of track " << label.track_id
                                 << " has no frame";
    by_id[label.track_id].push_back(label);
    ++num_detections;
  }
  TrackingSummary local;
  TrackingSummary& result = summary != nullptr ? *summary : local;
  result = TrackingSummary();
  result.num_detections = num_detections;
  std::vector<LinkedTrack> tracks;
  for (auto& [id, detections] : by_id) {
    std::stable_sort(detections.begin(), detections.end(),
                     [](const ObjectLabel& a, const ObjectLabel& b) { return a.frame < b.frame; });
    for (size_t i = 1; i < detections.size(); ++i)
      SAMP_CHECK(detections[i].frame != detections[i - 1].frame)
          << "tracking labels: track " << id << " has two labels in frame " << detections[i].frame;
    if (static_cast<int>(detections.size()) < min_track_length) {
      ++result.num_short_tracks;
      result.num_short_detections += static_cast<int>(detections.size());
      result.short_tracks.push_back("track " + std::to_string(id) + ": " + DescribeShortTrack(detections));
      continue;
    }
    tracks.push_back(LinkedTrack{id, detections});
  }
  FinishSummary(tracks, 0, 0, &result);
  return tracks;
}

}  // namespace samp
