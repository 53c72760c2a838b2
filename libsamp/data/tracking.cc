#include "libsamp/data/tracking.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "libsamp/core/error.h"
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

// Constant-velocity Kalman filter of a box centre in the world:
// state (position, velocity), 6 x 6 covariance.
struct TrackState {
  std::vector<ObjectLabel> detections;
  Eigen::Matrix<double, 6, 1> state = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Identity();
  int last_frame = 0;
};

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// Covariance of a detected centre (world), from the noise model in the camera.
Eigen::Matrix3d DetectionCovariance(const Eigen::Vector3d& center_in_camera,
                                    const Eigen::Matrix3d& world_from_camera_rotation,
                                    const TrackerOptions& o) {
  Eigen::Vector3d ray(center_in_camera.x(), 0.0, center_in_camera.z());
  const double d = ray.norm();
  ray = d > 1e-9 ? Eigen::Vector3d(ray / d) : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d lateral(ray.z(), 0.0, -ray.x());
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  const double s_depth = o.depth_sigma_a + o.depth_sigma_b * d * d;
  const double s_lateral = o.lateral_sigma_a + o.lateral_sigma_b * d;
  const Eigen::Matrix3d in_camera = s_depth * s_depth * ray * ray.transpose() +
                                    s_lateral * s_lateral * lateral * lateral.transpose() +
                                    o.height_sigma * o.height_sigma * up * up.transpose();
  return world_from_camera_rotation * in_camera * world_from_camera_rotation.transpose();
}

// Prediction dt seconds ahead (white-acceleration process noise).
void Predict(double dt, double acceleration_sigma, Eigen::Matrix<double, 6, 1>* state, Matrix6d* covariance) {
  Matrix6d f = Matrix6d::Identity();
  f.topRightCorner<3, 3>() = dt * Eigen::Matrix3d::Identity();
  const double q = acceleration_sigma * acceleration_sigma;
  Matrix6d noise = Matrix6d::Zero();
  noise.topLeftCorner<3, 3>() = q * dt * dt * dt * dt / 4.0 * Eigen::Matrix3d::Identity();
  noise.topRightCorner<3, 3>() = q * dt * dt * dt / 2.0 * Eigen::Matrix3d::Identity();
  noise.bottomLeftCorner<3, 3>() = noise.topRightCorner<3, 3>();
  noise.bottomRightCorner<3, 3>() = q * dt * dt * Eigen::Matrix3d::Identity();
  *state = f * *state;
  *covariance = f * *covariance * f.transpose() + noise;
}

std::string DescribeShortTrack(const std::vector<ObjectLabel>& detections) {
  std::ostringstream s;
  s << "frames " << detections.front().frame << "-" << detections.back().frame << " ("
    << detections.size() << (detections.size() == 1 ? " detection)" : " detections)");
  return s.str();
}

}  // namespace

bool TrackerOptions::Check() const {
  SAMP_CHECK(depth_sigma_a > 0 && depth_sigma_b >= 0 && lateral_sigma_a > 0 && lateral_sigma_b >= 0 &&
             height_sigma > 0)
      << "TrackerOptions: detector noise sigmas must be > 0 (the *_b terms >= 0)";
  SAMP_CHECK(acceleration_sigma > 0) << "TrackerOptions.acceleration_sigma must be > 0";
  SAMP_CHECK(max_speed > 0) << "TrackerOptions.max_speed must be > 0";
  SAMP_CHECK(gate_chi2 > 0) << "TrackerOptions.gate_chi2 must be > 0";
  SAMP_CHECK(max_misses >= 0) << "TrackerOptions.max_misses must be >= 0";
  SAMP_CHECK(min_track_length >= 1) << "TrackerOptions.min_track_length must be >= 1";
  SAMP_CHECK(frame_rate_hz > 0) << "TrackerOptions.frame_rate_hz must be > 0";
  return true;
}

std::string TrackingSummary::BriefReport() const {
  std::ostringstream s;
  s << num_detections << " detections -> " << num_tracks << " tracks";
  if (num_short_tracks > 0) {
    s << "; dropped " << num_short_tracks << " short track(s) (" << num_short_detections
      << " detections):";
    for (const std::string& t : short_tracks) s << " [" << t << "]";
  }
  return s.str();
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
  std::vector<TrackState> tracks;   // in order of creation
  std::vector<int> active;          // indices into tracks
  int num_detections = 0;
  for (const FrameDetections& frame : frames) {
    // End tracks that missed too many frames.
    active.erase(std::remove_if(active.begin(), active.end(),
                                [&](int t) { return frame.frame - tracks[t].last_frame - 1 > options.max_misses; }),
                 active.end());
    const int num = static_cast<int>(frame.detections.size());
    num_detections += num;
    std::vector<Eigen::Vector3d> centers(num);
    std::vector<Eigen::Matrix3d> noise(num);
    for (int k = 0; k < num; ++k) {
      const Eigen::Vector3d in_camera = DetectionCenter(frame.detections[k]);
      centers[k] = frame.world_from_camera * in_camera;
      noise[k] = DetectionCovariance(in_camera, frame.world_from_camera.linear(), options);
    }

    // Predict every live track to this frame; gate and cost by the squared
    // Mahalanobis distance of each detection to the prediction.
    const int rows = static_cast<int>(active.size());
    std::vector<Eigen::Matrix<double, 6, 1>> predicted(rows);
    std::vector<Matrix6d> predicted_covariance(rows);
    std::vector<double> cost(static_cast<size_t>(rows) * num, kNoAssignment);
    for (int a = 0; a < rows; ++a) {
      const TrackState& track = tracks[active[a]];
      const double dt = (frame.frame - track.last_frame) / options.frame_rate_hz;
      predicted[a] = track.state;
      predicted_covariance[a] = track.covariance;
      Predict(dt, options.acceleration_sigma, &predicted[a], &predicted_covariance[a]);
      for (int k = 0; k < num; ++k) {
        const Eigen::Vector3d innovation = centers[k] - predicted[a].head<3>();
        const Eigen::Matrix3d s = predicted_covariance[a].topLeftCorner<3, 3>() + noise[k];
        const double d2 = innovation.dot(s.ldlt().solve(innovation));
        if (d2 <= options.gate_chi2) cost[static_cast<size_t>(a) * num + k] = d2;
      }
    }
    const std::vector<int> assignment = SolveAssignment(cost, rows, num);
    std::vector<char> taken(num, 0);
    for (int a = 0; a < rows; ++a) {
      const int k = assignment[a];
      if (k < 0) continue;
      taken[k] = 1;
      TrackState& track = tracks[active[a]];
      // Kalman update with the detected centre (H = [I 0]).
      const Matrix6d& p = predicted_covariance[a];
      const Eigen::Matrix3d s = p.topLeftCorner<3, 3>() + noise[k];
      const Eigen::Matrix<double, 6, 3> gain = p.leftCols<3>() * s.inverse();
      track.state = predicted[a] + gain * (centers[k] - predicted[a].head<3>());
      const Matrix6d covariance = p - gain * p.topRows<3>();
      track.covariance = 0.5 * (covariance + covariance.transpose());
      track.last_frame = frame.frame;
      ObjectLabel label = frame.detections[k];
      label.frame = frame.frame;
      track.detections.push_back(label);
    }
    for (int k = 0; k < num; ++k) {
      if (taken[k]) continue;
      TrackState track;
      track.state.head<3>() = centers[k];
      track.covariance.setZero();
      track.covariance.topLeftCorner<3, 3>() = noise[k];
      const double s_v = options.max_speed / 2.0;
      track.covariance.bottomRightCorner<3, 3>() = s_v * s_v * Eigen::Matrix3d::Identity();
      track.last_frame = frame.frame;
      ObjectLabel label = frame.detections[k];
      label.frame = frame.frame;
      track.detections.push_back(label);
      tracks.push_back(track);
      active.push_back(static_cast<int>(tracks.size()) - 1);
    }
  }

  TrackingSummary local;
  TrackingSummary& result = summary != nullptr ? *summary : local;
  result = TrackingSummary();
  result.num_detections = num_detections;
  std::vector<LinkedTrack> linked;
  for (const TrackState& track : tracks) {
    if (static_cast<int>(track.detections.size()) < options.min_track_length) {
      ++result.num_short_tracks;
      result.num_short_detections += static_cast<int>(track.detections.size());
      result.short_tracks.push_back(DescribeShortTrack(track.detections));
      continue;
    }
    LinkedTrack out;
    out.id = static_cast<int>(linked.size());
    out.detections = track.detections;
    for (ObjectLabel& label : out.detections) label.track_id = out.id;
    linked.push_back(out);
  }
  result.num_tracks = static_cast<int>(linked.size());
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
  result.num_tracks = static_cast<int>(tracks.size());
  return tracks;
}

}  // namespace samp
