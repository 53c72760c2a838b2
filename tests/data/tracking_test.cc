#include "libsamp/data/tracking.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <random>

#include "libsamp/core/error.h"
#include "libsamp/data/observations.h"

namespace samp {
namespace {

Eigen::Isometry3d EgoPose(int frame) {
  // The ego car drives forward 1 m per frame while turning slightly.
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.02 * frame, Eigen::Vector3d::UnitY()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(0, 0, 1.0 * frame);
  return pose;
}

// A detection whose 3D box centre is at `center_in_world`.
ObjectLabel DetectionAt(const Eigen::Vector3d& center_in_world, int frame, double marker) {
  ObjectLabel label;
  label.height = 1.5;
  label.width = 1.6;
  label.length = 3.9;
  label.position = EgoPose(frame).inverse() * center_in_world + Eigen::Vector3d(0, 0.75, 0);
  label.alpha = marker;  // remembers which car made it
  return label;
}

TEST(TrackingTest, TwoCrossingCarsWithAMissAndAFalsePositive) {
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0, 0.1);
  std::vector<FrameDetections> frames;
  for (int t = 0; t < 10; ++t) {
    FrameDetections fd;
    fd.frame = t;
    fd.world_from_camera = EgoPose(t);
    // Car A drives right, car B left at 12 m/s; their paths cross near t = 5,
    // 1.5 m apart in depth.
    const Eigen::Vector3d a(-6 + 1.2 * t + noise(rng), 0.9, 20 + noise(rng));
    const Eigen::Vector3d b(6 - 1.2 * t + noise(rng), 0.9, 21.5 + noise(rng));
    if (t != 6) fd.detections.push_back(DetectionAt(a, t, 1.0));  // A missed in frame 6
    fd.detections.push_back(DetectionAt(b, t, 2.0));
    if (t == 3) fd.detections.push_back(DetectionAt(Eigen::Vector3d(9, 0.9, 35), t, 3.0));  // false positive
    if (t % 2 == 1) std::reverse(fd.detections.begin(), fd.detections.end());  // order must not matter
    frames.push_back(fd);
  }
  TrackerOptions options;
  TrackingSummary summary;
  const std::vector<LinkedTrack> tracks = LinkDetections(frames, options, &summary);
  ASSERT_EQ(tracks.size(), 2u) << summary.BriefReport();
  EXPECT_EQ(summary.num_detections, 20);
  EXPECT_EQ(summary.num_tracks, 2);
  EXPECT_EQ(summary.num_short_tracks, 1);
  EXPECT_EQ(summary.num_short_detections, 1);
  ASSERT_EQ(summary.short_tracks.size(), 1u);
  EXPECT_NE(summary.short_tracks[0].find("frames 3-3"), std::string::npos);
  for (const LinkedTrack& track : tracks) {
    const double marker = track.detections.front().alpha;
    for (const ObjectLabel& d : track.detections) {
      EXPECT_EQ(d.alpha, marker) << "track " << track.id << " switched cars in frame " << d.frame;
      EXPECT_EQ(d.track_id, track.id);
    }
    for (size_t i = 1; i < track.detections.size(); ++i)
      EXPECT_GT(track.detections[i].frame, track.detections[i - 1].frame);
  }
  // Ids in order of first appearance: A was detection 0 in frame 0.
  EXPECT_EQ(tracks[0].id, 0);
  EXPECT_EQ(tracks[1].id, 1);
  EXPECT_EQ(tracks[0].detections.front().alpha, 1.0);
  EXPECT_EQ(tracks[0].detections.size(), 9u);  // frame 6 missing
  EXPECT_EQ(tracks[1].detections.size(), 10u);
  EXPECT_EQ(tracks[0].detections[6].frame, 7);
  // Deterministic.
  const std::vector<LinkedTrack> again = LinkDetections(frames, options, nullptr);
  ASSERT_EQ(again.size(), 2u);
  EXPECT_EQ(again[1].detections.size(), tracks[1].detections.size());
}

// Far cars seen by a 3DOP-like detector (depth noise 0.1 + 0.001 d^2 m along
// the viewing ray: ~1-2 m at 30-45 m) with misses: each car must come out as
// one track, without switches. A gate on the raw distance with a velocity from
// the last two detections broke such tracks into pieces of 2-3 frames.
TEST(TrackingTest, FarNoisyCarsStayOneTrackEach) {
  std::mt19937 rng(5);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  struct Car {
    Eigen::Vector3d start, velocity;  // world, m and m/s
  };
  // Ego drives +z at 10 m/s; cars ahead: one standing, one following, one oncoming, one crossing.
  const Car cars[] = {{{-4.0, 0.9, 40.0}, {0.0, 0.0, 0.0}},
                      {{3.5, 0.9, 35.0}, {0.0, 0.0, 8.0}},
                      {{-1.0, 0.9, 55.0}, {0.0, 0.0, -8.0}},
                      {{-12.0, 0.9, 48.0}, {6.0, 0.0, 0.0}}};
  const int num_cars = 4;
  std::vector<FrameDetections> frames;
  int num_detected = 0;
  for (int t = 0; t < 21; ++t) {
    FrameDetections fd;
    fd.frame = t;
    fd.world_from_camera = Eigen::Isometry3d::Identity();
    fd.world_from_camera.translation() = Eigen::Vector3d(0, 0, 1.0 * t);
    for (int c = 0; c < num_cars; ++c) {
      if (uniform(rng) < 0.05) continue;  // missed
      const Eigen::Vector3d truth = cars[c].start + cars[c].velocity * (0.1 * t);
      const Eigen::Vector3d in_camera = fd.world_from_camera.inverse() * truth;
      Eigen::Vector3d ray(in_camera.x(), 0, in_camera.z());
      const double d = ray.norm();
      ray /= d;
      const Eigen::Vector3d lateral(ray.z(), 0, -ray.x());
      const Eigen::Vector3d noisy = truth + ray * (0.1 + 0.001 * d * d) * unit(rng) +
                                    lateral * (0.05 + 0.005 * d) * unit(rng) +
                                    Eigen::Vector3d(0, 0.05 * unit(rng), 0);
      ObjectLabel label = DetectionAt(Eigen::Vector3d::Zero(), t, double(c));
      label.position = fd.world_from_camera.inverse() * noisy + Eigen::Vector3d(0, 0.75, 0);
      fd.detections.push_back(label);
      ++num_detected;
    }
    frames.push_back(fd);
  }
  TrackingSummary summary;
  const std::vector<LinkedTrack> tracks = LinkDetections(frames, TrackerOptions(), &summary);
  ASSERT_EQ(int(tracks.size()), num_cars) << summary.BriefReport();
  EXPECT_EQ(summary.num_short_tracks, 0) << summary.BriefReport();
  int linked = 0;
  for (const LinkedTrack& track : tracks) {
    const double marker = track.detections.front().alpha;
    for (const ObjectLabel& d : track.detections) EXPECT_EQ(d.alpha, marker) << "switch in frame " << d.frame;
    linked += int(track.detections.size());
  }
  EXPECT_EQ(linked, num_detected);
}

TEST(TrackingTest, TrackEndsAfterTooManyMisses) {
  std::vector<FrameDetections> frames;
  for (int t = 0; t < 10; ++t) {
    FrameDetections fd;
    fd.frame = t;
    fd.world_from_camera = EgoPose(t);
    if (t < 3 || t > 5)  // unseen in frames 3, 4, 5
      fd.detections.push_back(DetectionAt(Eigen::Vector3d(0.5 * t, 0.9, 15), t, 0));
    frames.push_back(fd);
  }
  TrackerOptions options;
  options.max_misses = 2;
  TrackingSummary summary;
  std::vector<LinkedTrack> tracks = LinkDetections(frames, options, &summary);
  ASSERT_EQ(tracks.size(), 2u);
  EXPECT_EQ(tracks[0].detections.size(), 3u);
  EXPECT_EQ(tracks[1].detections.front().frame, 6);
  options.max_misses = 3;
  tracks = LinkDetections(frames, options, &summary);
  ASSERT_EQ(tracks.size(), 1u);
  EXPECT_EQ(tracks[0].detections.size(), 7u);
  // min_track_length 1 keeps single detections.
  options.min_track_length = 1;
  frames.resize(1);
  EXPECT_EQ(LinkDetections(frames, options, &summary).size(), 1u);
  options.min_track_length = 2;
  EXPECT_TRUE(LinkDetections(frames, options, &summary).empty());
  EXPECT_EQ(summary.num_short_tracks, 1);
}

TEST(TrackingTest, NonIncreasingFramesAreAnError) {
  std::vector<FrameDetections> frames(2);
  frames[0].frame = 3;
  frames[1].frame = 3;
  EXPECT_THROW(LinkDetections(frames, TrackerOptions(), nullptr), Error);
}

// Brute force: best (max count, then min cost) assignment.
void BruteForce(const std::vector<double>& cost, int rows, int cols, int* best_count, double* best_cost) {
  *best_count = -1;
  *best_cost = 0;
  std::vector<int> assignment(rows, -1);
  std::vector<char> used(cols, 0);
  std::function<void(int, int, double)> recurse = [&](int row, int count, double total) {
    if (row == rows) {
      if (count > *best_count || (count == *best_count && total < *best_cost - 1e-12)) {
        *best_count = count;
        *best_cost = total;
      }
      return;
    }
    recurse(row + 1, count, total);
    for (int c = 0; c < cols; ++c) {
      const double value = cost[row * cols + c];
      if (used[c] || value >= kNoAssignment) continue;
      used[c] = 1;
      recurse(row + 1, count + 1, total + value);
      used[c] = 0;
    }
  };
  recurse(0, 0, 0.0);
}

TEST(TrackingTest, HungarianMatchesBruteForce) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> value(0, 10), coin(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const int rows = 1 + trial % 5, cols = 1 + (trial / 5) % 6;
    std::vector<double> cost(rows * cols);
    for (double& c : cost) c = coin(rng) < 0.3 ? kNoAssignment : value(rng);
    const std::vector<int> result = SolveAssignment(cost, rows, cols);
    ASSERT_EQ(static_cast<int>(result.size()), rows);
    int count = 0;
    double total = 0;
    std::vector<char> used(cols, 0);
    for (int r = 0; r < rows; ++r) {
      if (result[r] < 0) continue;
      ASSERT_LT(result[r], cols);
      ASSERT_FALSE(used[result[r]]);
      used[result[r]] = 1;
      ASSERT_LT(cost[r * cols + result[r]], kNoAssignment);
      ++count;
      total += cost[r * cols + result[r]];
    }
    int best_count;
    double best_cost;
    BruteForce(cost, rows, cols, &best_count, &best_cost);
    EXPECT_EQ(count, best_count) << "trial " << trial;
    EXPECT_NEAR(total, best_cost, 1e-9) << "trial " << trial;
  }
  EXPECT_TRUE(SolveAssignment({}, 0, 3).empty());
  EXPECT_EQ(SolveAssignment({}, 2, 0), std::vector<int>({-1, -1}));
}

TEST(TrackingTest, TracksFromLabels) {
  auto label = [](int frame, int id, const char* type = "Car") {
    ObjectLabel l;
    l.frame = frame;
    l.track_id = id;
    l.type = type;
    l.position = Eigen::Vector3d(0, 1.6, 10);
    return l;
  };
  std::vector<ObjectLabel> labels = {label(2, 5), label(0, 5), label(1, 5), label(0, 2), label(1, 2),
                                     label(0, -1, "DontCare"), label(4, 9)};
  TrackingSummary summary;
  std::vector<LinkedTrack> tracks = TracksFromLabels(labels, 2, &summary);
  ASSERT_EQ(tracks.size(), 2u);
  EXPECT_EQ(tracks[0].id, 2);
  EXPECT_EQ(tracks[1].id, 5);
  ASSERT_EQ(tracks[1].detections.size(), 3u);
  EXPECT_EQ(tracks[1].detections[0].frame, 0);
  EXPECT_EQ(tracks[1].detections[2].frame, 2);
  EXPECT_EQ(summary.num_short_tracks, 1);  // track 9, one frame
  EXPECT_NE(summary.short_tracks[0].find("track 9"), std::string::npos);
  labels.push_back(label(1, 5));
  try {
    TracksFromLabels(labels, 1, &summary);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("track 5 has two labels in frame 1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace samp
