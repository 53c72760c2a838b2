#include "libsamp/data/tracking.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <unordered_map>

#include "libsamp/core/assignment.h"
#include "libsamp/core/error.h"
#include "libsamp/core/json_text.h"
#include "libsamp/core/json_fields.h"
#include "libsamp/core/pose.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/observations.h"
#include "libsamp/data/track_joining.h"
#include "libsamp/data/track_observation.h"

namespace samp {
namespace {

using tracking_internal::AxisDifference;
using tracking_internal::JoinFragments;
using tracking_internal::MeanAxis;
using tracking_internal::Observation;
using tracking_internal::ProcessNoise;
using tracking_internal::ResolveSwitches;
using tracking_internal::Transition;
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


// The gated association costs of one frame: the active tracks predicted to
// `time` (rows) against the frame's observations `obs` (columns). Pairs are
// formed within the position gate only: the gate's squared Mahalanobis
// distance bounds the distance by sqrt(gate x the largest eigenvalue of the
// innovation covariance).
struct FramePairs {
  std::vector<Vector4d> predicted;
  std::vector<Matrix4d> predicted_covariance;
  std::vector<SparseCost> pairs;
  std::map<std::pair<int, int>, unsigned> outliers_of_pair;  // cues outside their gates
};

FramePairs GatedPairs(const std::vector<OnlineTrack>& tracks, const std::vector<int>& active, double time,
                      const std::vector<int>& obs, const std::vector<Observation>& observations,
                      const TrackerOptions& o) {
  const int rows = static_cast<int>(active.size()), cols = static_cast<int>(obs.size());
  FramePairs out;
  out.predicted.resize(rows);
  out.predicted_covariance.resize(rows);
  double largest_observation_variance = 0.0;
  for (int k : obs)
    largest_observation_variance =
        std::max(largest_observation_variance, LargestEigenvalue(observations[k].ground_covariance));
  const GroundHash hash(observations, obs, 5.0);
  for (int a = 0; a < rows; ++a) {
    const OnlineTrack& track = tracks[active[a]];
    const double dt = time - track.time;
    const Matrix4d transition = Transition(dt);
    out.predicted[a] = transition * track.state;
    out.predicted_covariance[a] =
        transition * track.covariance * transition.transpose() + ProcessNoise(dt, o.acceleration_sigma);
    const double radius =
        std::sqrt(o.gate_chi2 * (LargestEigenvalue(out.predicted_covariance[a].topLeftCorner<2, 2>()) +
                                 largest_observation_variance)) + 1e-6;
    for (int k : hash.Near(out.predicted[a].head<2>(), radius, cols)) {
      unsigned outliers = 0;
      const double c =
          AssociationCost(track, out.predicted[a], out.predicted_covariance[a], observations[obs[k]], o, &outliers);
      if (c >= kNoAssignment) continue;
      out.pairs.push_back({a, k, c});
      if (outliers != 0) out.outliers_of_pair[{a, k}] = outliers;
    }
  }
  return out;
}

// Kalman update of a track predicted to `time` with the detected ground
// position (H = [I 0]).
void UpdateTrack(const Vector4d& predicted, const Matrix4d& p, const Observation& ob, double time,
                 OnlineTrack* track) {
  const Eigen::Matrix2d s = p.topLeftCorner<2, 2>() + ob.ground_covariance;
  const Eigen::Matrix<double, 4, 2> gain = p.leftCols<2>() * s.inverse();
  track->state = predicted + gain * (ob.ground - predicted.head<2>());
  const Matrix4d covariance = p - gain * p.topRows<2>();
  track->covariance = 0.5 * (covariance + covariance.transpose());
  track->time = time;
}

// A new track at an unassigned observation: at rest, speed std. dev. max_speed / 2.
OnlineTrack StartTrack(int index, const Observation& ob, double time, const TrackerOptions& o) {
  OnlineTrack track;
  track.state.head<2>() = ob.ground;
  track.covariance.setZero();
  track.covariance.topLeftCorner<2, 2>() = ob.ground_covariance;
  const double s_v = o.max_speed / 2.0;
  track.covariance.bottomRightCorner<2, 2>() = s_v * s_v * Eigen::Matrix2d::Identity();
  track.time = time;
  AddObservation(index, ob, 0u, &track);
  track.confirmed = track.Count() >= o.confirm_hits;
  return track;
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
    const FramePairs gated = GatedPairs(tracks, active, time, obs, observations, o);
    const std::vector<int> assignment = SolveSparseAssignment(gated.pairs, rows, cols);
    std::vector<char> taken(cols, 0);
    for (int a = 0; a < rows; ++a) {
      const int k = assignment[a];
      if (k < 0) continue;
      taken[k] = 1;
      const auto outlying = gated.outliers_of_pair.find({a, k});
      OnlineTrack& track = tracks[active[a]];
      const Observation& ob = observations[obs[k]];
      UpdateTrack(gated.predicted[a], gated.predicted_covariance[a], ob, time, &track);
      AddObservation(obs[k], ob, outlying == gated.outliers_of_pair.end() ? 0u : outlying->second, &track);
      if (track.Count() >= o.confirm_hits) track.confirmed = true;
    }
    for (int k = 0; k < cols; ++k) {
      if (taken[k]) continue;
      tracks.push_back(StartTrack(obs[k], observations[obs[k]], time, o));
      active.push_back(static_cast<int>(tracks.size()) - 1);
    }
  }
  std::vector<std::vector<int>> result;
  for (OnlineTrack& t : tracks) result.push_back(std::move(t.members));
  return result;
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

// The observations of every frame, with exact duplicates (the same box
// twice in one frame: within 1 cm, 0.5 degrees) dropped and counted.
struct FrameObservations {
  std::vector<Observation> observations;
  std::vector<std::vector<int>> of_frame;  // indices into `observations`, per frame
  int num_duplicates = 0;
  std::vector<std::string> duplicates;  // "frame F: N duplicate(s)"
};

// Earlier detections of one frame by 1 m cell of their bottom centre (camera x, z).
class DetectionCells {
 public:
  bool HasDuplicate(const ObjectLabel& label) const {
    const double x = label.position.x(), z = label.position.z();
    for (int dx = -1; dx <= 1; ++dx)
      for (int dz = -1; dz <= 1; ++dz) {
        const auto it = seen_.find(Key(x + dx, z + dz));
        if (it == seen_.end()) continue;
        for (const ObjectLabel* other : it->second)
          if (SameBox(*other, label)) return true;
      }
    return false;
  }
  void Add(const ObjectLabel* label) { seen_[Key(label->position.x(), label->position.z())].push_back(label); }

 private:
  static int64_t Key(double x, double z) {
    const auto i = int64_t(std::floor(std::clamp(x, -1e6, 1e6))), j = int64_t(std::floor(std::clamp(z, -1e6, 1e6)));
    return int64_t((uint64_t(i) << 32) ^ (uint64_t(j) & 0xffffffffu));
  }
  static bool SameBox(const ObjectLabel& a, const ObjectLabel& b) {
    return (a.position - b.position).norm() <= 0.01 && std::abs(a.height - b.height) <= 0.01 &&
           std::abs(a.width - b.width) <= 0.01 && std::abs(a.length - b.length) <= 0.01 &&
           std::abs(AxisDifference(a.rotation_y, b.rotation_y)) <= 0.5 * kPi / 180.0;
  }
  std::unordered_map<int64_t, std::vector<const ObjectLabel*>> seen_;
};

FrameObservations CollectObservations(const std::vector<FrameDetections>& frames, const TrackerOptions& options) {
  const GroundFrame ground = MakeGroundFrame(frames);
  FrameObservations out;
  out.of_frame.resize(frames.size());
  for (size_t f = 0; f < frames.size(); ++f) {
    DetectionCells cells;
    int frame_duplicates = 0;
    for (const ObjectLabel& label : frames[f].detections) {
      SAMP_CHECK(label.height > 0 && label.width > 0 && label.length > 0 && label.position.allFinite() &&
                 std::isfinite(label.rotation_y))
          << "LinkDetections: frame " << frames[f].frame << ": a detection has a non-positive size or "
          << "a non-finite position/yaw";
      if (cells.HasDuplicate(label)) {
        ++frame_duplicates;
        continue;
      }
      cells.Add(&label);
      out.of_frame[f].push_back(static_cast<int>(out.observations.size()));
      out.observations.push_back(
          MakeObservation(label, frames[f].frame, frames[f].world_from_camera, ground, options));
    }
    if (frame_duplicates > 0) {
      out.num_duplicates += frame_duplicates;
      out.duplicates.push_back("frame " + std::to_string(frames[f].frame) + ": " +
                               std::to_string(frame_duplicates) +
                               (frame_duplicates == 1 ? " duplicate" : " duplicates"));
    }
  }
  return out;
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



std::vector<LinkedTrack> LinkDetections(const std::vector<FrameDetections>& frames,
                                        const TrackerOptions& options, TrackingSummary* summary) {
  options.Check();
  for (size_t i = 1; i < frames.size(); ++i)
    SAMP_CHECK(frames[i].frame > frames[i - 1].frame)
        << "LinkDetections: frames must increase (" << frames[i - 1].frame << " then "
        << frames[i].frame << ")";
  TrackingSummary local;
  TrackingSummary& result = summary != nullptr ? *summary : local;
  result = TrackingSummary();
  const FrameObservations collected = CollectObservations(frames, options);
  const std::vector<Observation>& observations = collected.observations;
  std::vector<std::vector<int>> tracks = LinkOnline(frames, collected.of_frame, observations, options);
  result.num_detections = static_cast<int>(observations.size()) + collected.num_duplicates;
  result.num_duplicates = collected.num_duplicates;
  result.duplicates = collected.duplicates;
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
