#include "libsamp/data/tracking.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/data/detector_noise.h"
#include "libsamp/data/observations.h"
#include "tests/testing/expect_error.h"

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
  // The tracker's noise model is the detector's (the 3DOP-like one above).
  TrackerOptions options;
  options.along_sigma_a = 0.1, options.along_sigma_b = 0.0, options.along_sigma_c = 0.001;
  options.across_sigma_a = 0.05, options.across_sigma_b = 0.005;
  options.vertical_sigma_a = 0.05, options.vertical_sigma_b = 0.0;
  TrackingSummary summary;
  const std::vector<LinkedTrack> tracks = LinkDetections(frames, options, &summary);
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
  options.join_fragments = false;
  TrackingSummary summary;
  std::vector<LinkedTrack> tracks = LinkDetections(frames, options, &summary);
  ASSERT_EQ(tracks.size(), 2u);
  EXPECT_EQ(tracks[0].detections.size(), 3u);
  EXPECT_EQ(tracks[1].detections.front().frame, 6);
  // The second stage joins the two fragments: their motions agree across the gap.
  options.join_fragments = true;
  tracks = LinkDetections(frames, options, &summary);
  ASSERT_EQ(tracks.size(), 1u);
  EXPECT_EQ(summary.num_online_tracks, 2);
  EXPECT_EQ(summary.num_joins, 1);
  EXPECT_EQ(tracks[0].detections.size(), 7u);
  options.max_misses = 3;
  options.join_fragments = false;
  tracks = LinkDetections(frames, options, &summary);
  ASSERT_EQ(tracks.size(), 1u);
  EXPECT_EQ(summary.num_joins, 0);
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

// ---------------------------------------------------------------------------
// Sequences with the errors of a stereo 3D detector (issue 11's model): the
// bottom centre errs along the viewing ray by 0.25 + 0.015 d m (std. dev.),
// across it by 0.1 + 0.005 d m, vertically by 0.25 m, each error temporally
// correlated (AR(1), 0.5 from frame to frame); box dimensions by 0.3 m, yaw by
// 5 degrees; a share of boxes turned by 180 degrees, misses, false positives.
// Ground truth rides in each detection's alpha (car index, -1 = false
// positive), which the tracker ignores.

struct SimCar {
  std::function<Eigen::Vector3d(double)> position;  // world bottom centre at time t
  std::function<double(double)> yaw;                // world ry at time t
  Eigen::Vector3d size = Eigen::Vector3d(1.5, 1.7, 4.2);  // h, w, l
  std::vector<int> missed_frames;                   // frames without a detection
};

struct DetectorModel {
  double along_a = 0.25, along_b = 0.015, across_a = 0.1, across_b = 0.005, vertical = 0.25;
  double size = 0.3, yaw_deg = 5.0, flip = 0.07, miss = 0.05, correlation = 0.5;
  double false_positives_per_frame = 0.3;
};

struct SimEgo {
  double speed = 8.0;     // m/s along its heading
  double yaw_rate = 0.02; // rad/s
};

constexpr double kRoadY = 1.65;  // the road below the first camera (world y down)
constexpr int kNumFrames = 21;

Eigen::Isometry3d SimEgoPose(const SimEgo& ego, int frame) {
  const double t = frame / 10.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  const double yaw = ego.yaw_rate * t;
  pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  // Integrated heading (small yaw rate): forward is +z rotated by yaw about y.
  const double s = ego.speed * t;
  pose.translation() = Eigen::Vector3d(s * std::sin(yaw / 2), 0.0, s * std::cos(yaw / 2));
  return pose;
}

struct SimSequence {
  std::vector<FrameDetections> frames;
  std::vector<int> detections_per_car;
};

SimSequence Simulate(const std::vector<SimCar>& cars, const SimEgo& ego, const DetectorModel& model,
                     unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  SimSequence sim;
  sim.detections_per_car.assign(cars.size(), 0);
  std::vector<Eigen::Vector3d> error(cars.size(), Eigen::Vector3d::Zero());  // along, across, vertical (unit)
  const double rho = model.correlation, innovation = std::sqrt(1 - rho * rho);
  for (size_t c = 0; c < cars.size(); ++c) error[c] = Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
  for (int f = 0; f < kNumFrames; ++f) {
    const double t = f / 10.0;
    FrameDetections fd;
    fd.frame = f;
    fd.world_from_camera = SimEgoPose(ego, f);
    const Eigen::Isometry3d camera_from_world = fd.world_from_camera.inverse();
    for (size_t c = 0; c < cars.size(); ++c) {
      if (f > 0)
        for (int i = 0; i < 3; ++i) error[c][i] = rho * error[c][i] + innovation * unit(rng);
      const Eigen::Vector3d p = camera_from_world * cars[c].position(t);
      if (p.z() < 4.0 || p.z() > 50.0 || std::abs(p.x()) > 0.9 * p.z()) continue;  // out of view
      const bool missed = std::count(cars[c].missed_frames.begin(), cars[c].missed_frames.end(), f) > 0 ||
                          uniform(rng) < model.miss;
      const bool flipped = uniform(rng) < model.flip;
      const double size_noise[3] = {unit(rng), unit(rng), unit(rng)};
      const double yaw_noise = unit(rng);
      if (missed) continue;
      Eigen::Vector3d ray(p.x(), 0, p.z());
      const double d = ray.norm();
      ray /= d;
      const Eigen::Vector3d across(ray.z(), 0, -ray.x());
      ObjectLabel label;
      label.position = p + ray * (model.along_a + model.along_b * d) * error[c][0] +
                       across * (model.across_a + model.across_b * d) * error[c][1] +
                       Eigen::Vector3d(0, model.vertical * error[c][2], 0);
      label.height = std::max(0.5, cars[c].size[0] + model.size * size_noise[0]);
      label.width = std::max(0.5, cars[c].size[1] + model.size * size_noise[1]);
      label.length = std::max(0.5, cars[c].size[2] + model.size * size_noise[2]);
      const double ry = cars[c].yaw(t);
      const Eigen::Vector3d front =
          camera_from_world.linear() * Eigen::Vector3d(std::cos(ry), 0, -std::sin(ry));
      label.rotation_y = std::atan2(-front.z(), front.x()) + model.yaw_deg * M_PI / 180 * yaw_noise +
                         (flipped ? M_PI : 0.0);
      label.alpha = double(c);
      fd.detections.push_back(label);
      ++sim.detections_per_car[c];
    }
    // False positives on clutter: anywhere beside the road, 6-45 m ahead.
    const int num_fp = int(model.false_positives_per_frame + uniform(rng));
    for (int k = 0; k < num_fp; ++k) {
      ObjectLabel label;
      const double z = 6 + 39 * uniform(rng);
      label.position = Eigen::Vector3d((uniform(rng) < 0.5 ? -1 : 1) * (5 + 5 * uniform(rng)), kRoadY, z);
      label.height = 1.5, label.width = 1.7, label.length = 4.0;
      label.rotation_y = M_PI * uniform(rng);
      label.alpha = -1.0;
      fd.detections.push_back(label);
    }
    // The detector's output order carries no meaning.
    std::shuffle(fd.detections.begin(), fd.detections.end(), rng);
    sim.frames.push_back(std::move(fd));
  }
  return sim;
}

struct TrackingFigures {
  int cars = 0;            // cars with at least one detection
  int tracks_on_cars = 0;  // sum over cars of the tracks holding one of its detections
  int id_switches = 0;     // changes of track id along a car's detections
  int detections = 0;      // of the cars
  int in_main_track = 0;   // detections in the car's main track (the one with most of them)
  int longest_false_track = 0;  // detections of a track made mostly of false positives
  void Add(const TrackingFigures& o) {
    cars += o.cars, tracks_on_cars += o.tracks_on_cars, id_switches += o.id_switches;
    detections += o.detections, in_main_track += o.in_main_track;
    longest_false_track = std::max(longest_false_track, o.longest_false_track);
  }
  double TracksPerCar() const { return double(tracks_on_cars) / std::max(1, cars); }
  double SwitchesPerCar() const { return double(id_switches) / std::max(1, cars); }
  double MainShare() const { return double(in_main_track) / std::max(1, detections); }
  std::string Report() const {
    std::ostringstream s;
    s << cars << " cars: " << TracksPerCar() << " tracks per car, " << id_switches << " ID switches, "
      << 100 * MainShare() << " % in the main track, longest false track " << longest_false_track;
    return s.str();
  }
};

TrackingFigures Score(const std::vector<LinkedTrack>& tracks, const SimSequence& sim) {
  TrackingFigures f;
  const int num_cars = int(sim.detections_per_car.size());
  std::vector<std::map<int, int>> count(num_cars);          // car -> track -> detections
  std::vector<std::vector<std::pair<int, int>>> seen(num_cars);  // car -> (frame, track)
  for (const LinkedTrack& t : tracks) {
    int false_positives = 0;
    for (const ObjectLabel& d : t.detections) {
      const int c = int(std::lround(d.alpha));
      if (c < 0) {
        ++false_positives;
        continue;
      }
      ++count[c][t.id];
      seen[c].push_back({d.frame, t.id});
    }
    if (2 * false_positives > int(t.detections.size()))
      f.longest_false_track = std::max(f.longest_false_track, int(t.detections.size()));
  }
  for (int c = 0; c < num_cars; ++c) {
    if (sim.detections_per_car[c] == 0) continue;
    ++f.cars;
    f.detections += sim.detections_per_car[c];
    f.tracks_on_cars += int(count[c].size());
    int main = 0;
    for (const auto& [id, n] : count[c]) main = std::max(main, n);
    f.in_main_track += main;
    std::sort(seen[c].begin(), seen[c].end());
    for (size_t i = 1; i < seen[c].size(); ++i) f.id_switches += seen[c][i].second != seen[c][i - 1].second;
  }
  return f;
}

double Time(int frame) { return frame / 10.0; }

// Parked cars in a row on the right (bumper gaps of 0.8 m), the ego driving past.
std::vector<SimCar> ParkedRow() {
  std::vector<SimCar> cars;
  for (int i = 0; i < 7; ++i) {
    SimCar car;
    const Eigen::Vector3d p(4.5, kRoadY, 12.0 + 5.0 * i);
    car.position = [p](double) { return p; };
    car.yaw = [](double) { return -M_PI / 2; };  // heading +z
    cars.push_back(car);
  }
  return cars;
}

// Moving traffic on straight lanes: ahead, oncoming, overtaking.
std::vector<SimCar> StraightTraffic() {
  auto straight = [](Eigen::Vector3d start, Eigen::Vector3d velocity) {
    SimCar car;
    car.position = [start, velocity](double t) { return Eigen::Vector3d(start + velocity * t); };
    const double ry = std::atan2(-velocity.z(), velocity.x());
    car.yaw = [ry](double) { return ry; };
    return car;
  };
  return {straight({0.2, kRoadY, 15}, {0, 0, 10}), straight({-3.5, kRoadY, 48}, {0, 0, -10}),
          straight({-3.3, kRoadY, 30}, {0, 0, -8}), straight({3.5, kRoadY, 22}, {0, 0, 12})};
}

// A car turning left across the road ahead, one turning right.
std::vector<SimCar> TurningTraffic() {
  auto turning = [](Eigen::Vector3d start, double heading, double speed, double yaw_rate) {
    SimCar car;
    // heading: world ry; front = (cos ry, 0, -sin ry).
    car.position = [=](double t) {
      const double r = speed / yaw_rate;
      // Integrate a circular arc in the x-z plane.
      const double a0 = heading, a1 = heading + yaw_rate * t;
      return Eigen::Vector3d(start + r * Eigen::Vector3d(std::sin(a1) - std::sin(a0), 0, std::cos(a1) - std::cos(a0)));
    };
    car.yaw = [=](double t) { return heading + yaw_rate * t; };
    return car;
  };
  return {turning({2.0, kRoadY, 20}, -M_PI / 2, 6.0, 0.4), turning({-2.0, kRoadY, 32}, M_PI / 2, 5.0, -0.45)};
}

// Two cars crossing in the image at different depths, two oncoming cars passing each other.
std::vector<SimCar> CrossingTraffic() {
  auto straight = [](Eigen::Vector3d start, Eigen::Vector3d velocity) {
    SimCar car;
    car.position = [start, velocity](double t) { return Eigen::Vector3d(start + velocity * t); };
    const double ry = std::atan2(-velocity.z(), velocity.x());
    car.yaw = [ry](double) { return ry; };
    return car;
  };
  return {straight({-9, kRoadY, 22}, {9, 0, 0}), straight({9, kRoadY, 28}, {-9, 0, 0}),
          straight({-1.7, kRoadY, 20}, {0, 0, 7}), straight({-5.0, kRoadY, 44}, {0, 0, -8})};
}

TrackingFigures RunScenes(const std::vector<SimCar>& cars, const DetectorModel& model, const TrackerOptions& options,
                          int num_seeds, unsigned first_seed, std::vector<TrackingSummary>* summaries = nullptr) {
  TrackingFigures total;
  for (int s = 0; s < num_seeds; ++s) {
    const SimSequence sim = Simulate(cars, SimEgo(), model, first_seed + s);
    TrackingSummary summary;
    const std::vector<LinkedTrack> tracks = LinkDetections(sim.frames, options, &summary);
    total.Add(Score(tracks, sim));
    if (summaries != nullptr) summaries->push_back(summary);
  }
  return total;
}

TEST(TrackingStereoDetector, ParkedRowOneTrackPerCar) {
  const TrackingFigures f = RunScenes(ParkedRow(), DetectorModel(), TrackerOptions(), 10, 100);
  EXPECT_LE(f.TracksPerCar(), 1.10) << f.Report();
  EXPECT_LE(f.SwitchesPerCar(), 0.1) << f.Report();
  EXPECT_GE(f.MainShare(), 0.95) << f.Report();
  EXPECT_LE(f.longest_false_track, 3) << f.Report();
}

TEST(TrackingStereoDetector, StraightTrafficOneTrackPerCar) {
  const TrackingFigures f = RunScenes(StraightTraffic(), DetectorModel(), TrackerOptions(), 10, 200);
  EXPECT_LE(f.TracksPerCar(), 1.10) << f.Report();
  EXPECT_LE(f.SwitchesPerCar(), 0.1) << f.Report();
  EXPECT_GE(f.MainShare(), 0.95) << f.Report();
  EXPECT_LE(f.longest_false_track, 3) << f.Report();
}

TEST(TrackingStereoDetector, TurningCarsOneTrackEach) {
  const TrackingFigures f = RunScenes(TurningTraffic(), DetectorModel(), TrackerOptions(), 10, 300);
  EXPECT_LE(f.TracksPerCar(), 1.10) << f.Report();
  EXPECT_LE(f.SwitchesPerCar(), 0.1) << f.Report();
  EXPECT_GE(f.MainShare(), 0.95) << f.Report();
}

TEST(TrackingStereoDetector, CrossingCarsKeepTheirIdentities) {
  const TrackingFigures f = RunScenes(CrossingTraffic(), DetectorModel(), TrackerOptions(), 10, 400);
  EXPECT_LE(f.TracksPerCar(), 1.15) << f.Report();
  EXPECT_LE(f.SwitchesPerCar(), 0.1) << f.Report();
  EXPECT_GE(f.MainShare(), 0.95) << f.Report();
}

// Far cars (38-48 m: along-ray std. dev. ~0.85 m) with half of the boxes
// turned by 180 degrees: the axis gate is modulo 180 degrees.
TEST(TrackingStereoDetector, FarFlippedCarsOneTrackEach) {
  auto straight = [](Eigen::Vector3d start, Eigen::Vector3d velocity, double ry) {
    SimCar car;
    car.position = [start, velocity](double t) { return Eigen::Vector3d(start + velocity * t); };
    car.yaw = [ry](double) { return ry; };
    return car;
  };
  // The ego stands; two parked cars, one driving away, one crossing far ahead.
  const std::vector<SimCar> cars = {straight({-4.5, kRoadY, 40}, {0, 0, 0}, -M_PI / 2),
                                    straight({4.5, kRoadY, 46}, {0, 0, 0}, -M_PI / 2),
                                    straight({0.0, kRoadY, 38}, {0, 0, 5}, -M_PI / 2),
                                    straight({-12, kRoadY, 44}, {6, 0, 0}, 0.0)};
  DetectorModel model;
  model.flip = 0.5;
  TrackingFigures total;
  for (int s = 0; s < 10; ++s) {
    SimEgo ego;
    ego.speed = 0.0;
    const SimSequence sim = Simulate(cars, ego, model, 500 + s);
    total.Add(Score(LinkDetections(sim.frames, TrackerOptions(), nullptr), sim));
  }
  EXPECT_LE(total.TracksPerCar(), 1.10) << total.Report();
  EXPECT_LE(total.SwitchesPerCar(), 0.1) << total.Report();
  EXPECT_GE(total.MainShare(), 0.95) << total.Report();
}

// Cars missed for 1, 2 and 3 consecutive frames keep their tracks.
TEST(TrackingStereoDetector, MissedFramesKeepTheTrack) {
  std::vector<SimCar> cars = StraightTraffic();
  cars[0].missed_frames = {5};
  cars[1].missed_frames = {8, 9};
  cars[2].missed_frames = {10, 11, 12};
  cars[3].missed_frames = {3, 4, 5};
  DetectorModel model;
  model.miss = 0.0;
  const TrackingFigures f = RunScenes(cars, model, TrackerOptions(), 10, 600);
  EXPECT_EQ(f.tracks_on_cars, f.cars) << f.Report();
  EXPECT_EQ(f.id_switches, 0) << f.Report();
  EXPECT_EQ(f.in_main_track, f.detections) << f.Report();
}

// Regression (issue 12): with the old noise model (vertical 0.05 m, along the
// ray 0.1 + 0.001 d^2, across 0.05 + 0.005 d, no second stage) a stereo
// detector's errors split ~30 cars into ~170 tracks of 2-3 detections. The
// defaults keep one track per car, and the summary warns about short tracks.
TEST(TrackingStereoDetector, RegressionOldNoiseModelSplitsTracks) {
  std::vector<SimCar> cars = ParkedRow();
  for (const SimCar& c : StraightTraffic()) cars.push_back(c);
  TrackerOptions old_model;
  old_model.along_sigma_a = 0.1, old_model.along_sigma_b = 0.0, old_model.along_sigma_c = 0.001;
  old_model.across_sigma_a = 0.05, old_model.across_sigma_b = 0.005;
  old_model.vertical_sigma_a = 0.05, old_model.vertical_sigma_b = 0.0;
  old_model.max_misses = 2;
  old_model.confirm_hits = 1;
  old_model.join_fragments = false;
  old_model.resolve_switches = false;
  std::vector<TrackingSummary> old_summaries, new_summaries;
  const TrackingFigures old_figures = RunScenes(cars, DetectorModel(), old_model, 5, 700, &old_summaries);
  const TrackingFigures new_figures = RunScenes(cars, DetectorModel(), TrackerOptions(), 5, 700, &new_summaries);
  EXPECT_GE(old_figures.TracksPerCar(), 3.0) << old_figures.Report();
  EXPECT_LE(new_figures.TracksPerCar(), 1.10) << new_figures.Report();
  EXPECT_GE(new_figures.MainShare(), 0.95) << new_figures.Report();
  for (const TrackingSummary& s : old_summaries) {
    EXPECT_LT(s.median_track_length, 5.0) << s.BriefReport();
    ASSERT_EQ(s.warnings.size(), 1u) << s.BriefReport();
    EXPECT_NE(s.warnings[0].find("median track length"), std::string::npos);
  }
  for (const TrackingSummary& s : new_summaries) {
    EXPECT_GE(s.median_track_length, 10.0) << s.BriefReport();
    EXPECT_TRUE(s.warnings.empty()) << s.BriefReport();
  }
}

TEST(TrackingStereoDetector, OptionsAreCheckedAndWrittenAsJson) {
  TrackerOptions o;
  EXPECT_NO_THROW(o.Check());
  o.along_sigma_a = 0;
  test::ExpectError([&] { o.Check(); }, {"along_sigma_a"});
  o = TrackerOptions();
  o.yaw_gate_deg = 120;
  test::ExpectError([&] { o.Check(); }, {"TrackerOptions.yaw_gate_deg"});
  o = TrackerOptions();
  o.fit_window = 0;
  test::ExpectError([&] { o.Check(); }, {"TrackerOptions.fit_window"});
  const std::string json = TrackerOptions().ToJson();
  for (const char* key : {"along_sigma_a", "across_sigma_b", "vertical_sigma_a", "size_sigma", "yaw_gate_deg",
                          "max_misses", "max_join_gap", "join_gate_chi2", "swap_margin"})
    EXPECT_NE(json.find(key), std::string::npos) << key;
}


// ---------------------------------------------------------------------------
// Robust association (issue 28): a detector three times noisier in box size
// than the tracker's default assumes (0.9 m against 0.3 m).

std::vector<SimCar> MixedTraffic() {
  std::vector<SimCar> cars = ParkedRow();
  for (const SimCar& c : StraightTraffic()) cars.push_back(c);
  return cars;
}

// Without robust cues every size cue gates and the cars split; robust cues
// alone (the default sigmas) mend part of it; self-calibration (below) all.
TEST(TrackingRobust, NoisySizesSplitLessWithRobustCues) {
  DetectorModel model;
  model.size = 0.9;
  const TrackingFigures plain = RunScenes(MixedTraffic(), model, TrackerOptions(), 5, 800);
  TrackerOptions options;
  options.robust_cues = true;
  const TrackingFigures robust = RunScenes(MixedTraffic(), model, options, 5, 800);
  EXPECT_GE(plain.TracksPerCar(), 1.3) << plain.Report();
  EXPECT_LE(robust.TracksPerCar(), plain.TracksPerCar() - 0.2) << robust.Report() << " against " << plain.Report();
  EXPECT_GE(robust.MainShare(), 0.95) << robust.Report();
}

// A single wrong box length, or a box turned by 90 degrees, in a car's
// otherwise steady track does not start a new track with robust cues.
TEST(TrackingRobust, OneWrongCueDoesNotSplitTheTrack) {
  for (int which = 0; which < 2; ++which) {
    std::vector<FrameDetections> frames;
    for (int t = 0; t < 12; ++t) {
      FrameDetections fd;
      fd.frame = t;
      fd.world_from_camera = EgoPose(t);
      ObjectLabel d = DetectionAt(Eigen::Vector3d(3.0, 0.9, 25.0 + 0.8 * t), t, 1.0);
      d.rotation_y = -M_PI / 2 - 0.02 * t;  // heading +z in the world
      if (t == 6 && which == 0) d.length = 9.0;       // a wrong box length
      if (t == 6 && which == 1) d.rotation_y += M_PI / 2;  // a box turned by 90 degrees
      fd.detections.push_back(d);
      frames.push_back(fd);
    }
    TrackerOptions options;
    options.join_fragments = false;  // the online stage alone
    TrackingSummary plain_summary, robust_summary;
    const std::vector<LinkedTrack> plain = LinkDetections(frames, options, &plain_summary);
    EXPECT_GT(plain_summary.num_online_tracks, 1) << which;
    options.robust_cues = true;
    const std::vector<LinkedTrack> robust = LinkDetections(frames, options, &robust_summary);
    EXPECT_EQ(robust_summary.num_online_tracks, 1) << which << ": " << robust_summary.BriefReport();
    ASSERT_EQ(robust.size(), 1u);
    EXPECT_EQ(robust[0].detections.size(), 12u);
    // Joining fragments with the robust link cost mends the split of the plain tracker too.
    TrackerOptions join = TrackerOptions();
    join.robust_cues = true;
    const std::vector<LinkedTrack> joined = LinkDetections(frames, join, nullptr);
    EXPECT_EQ(joined.size(), 1u) << which;
  }
}

// 1,000 identical detections in every frame: flagged and dropped, one track;
// the association is linear in the detections per frame (with the dense
// assignment of the previous version this took minutes: 300 duplicates, 42 s).
TEST(TrackingRobust, ThousandDuplicatesAreFlagged) {
  std::vector<FrameDetections> frames;
  for (int t = 0; t < 5; ++t) {
    FrameDetections fd;
    fd.frame = t;
    fd.world_from_camera = EgoPose(t);
    const ObjectLabel d = DetectionAt(Eigen::Vector3d(-3.0, 0.9, 20.0), t, 1.0);
    fd.detections.assign(1000, d);
    frames.push_back(fd);
  }
  TrackingSummary summary;
  const std::vector<LinkedTrack> tracks = LinkDetections(frames, TrackerOptions(), &summary);
  ASSERT_EQ(tracks.size(), 1u) << summary.BriefReport();
  EXPECT_EQ(tracks[0].detections.size(), 5u);
  EXPECT_EQ(summary.num_detections, 5000);
  EXPECT_EQ(summary.num_duplicates, 4995);
  ASSERT_EQ(summary.duplicates.size(), 5u);
  EXPECT_EQ(summary.duplicates[0], "frame 0: 999 duplicates");
  EXPECT_NE(summary.BriefReport().find("4995 duplicate"), std::string::npos);
  EXPECT_NE(summary.ToJson().find("\"duplicates\":4995"), std::string::npos);
}

// Many distinct cars in one frame (a 30 x 30 grid of parked cars, 900
// detections per frame): each stays one track; the spatial gate keeps the
// assignment groups small.
TEST(TrackingRobust, ManyCarsPerFrameOneTrackEach) {
  std::vector<FrameDetections> frames;
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (int t = 0; t < 4; ++t) {
    FrameDetections fd;
    fd.frame = t;
    for (int i = 0; i < 30; ++i)
      for (int j = 0; j < 30; ++j) {
        ObjectLabel d;
        d.height = 1.5, d.width = 1.7, d.length = 4.0;
        d.position = Eigen::Vector3d(-60 + 4.0 * i + noise(rng), 1.65, 5 + 7.0 * j + noise(rng));
        d.rotation_y = 0.0;
        d.alpha = 30 * i + j;
        fd.detections.push_back(d);
      }
    frames.push_back(fd);
  }
  TrackingSummary summary;
  const std::vector<LinkedTrack> tracks = LinkDetections(frames, TrackerOptions(), &summary);
  ASSERT_EQ(tracks.size(), 900u) << summary.BriefReport();
  for (const LinkedTrack& t : tracks) {
    ASSERT_EQ(t.detections.size(), 4u);
    for (const ObjectLabel& d : t.detections) EXPECT_EQ(d.alpha, t.detections.front().alpha);
  }
  EXPECT_EQ(summary.num_duplicates, 0);
}

TEST(TrackingRobust, RobustCuesInJsonOnlyWhenOn) {
  EXPECT_EQ(TrackerOptions().ToJson().find("robust_cues"), std::string::npos);
  TrackerOptions o;
  o.robust_cues = true;
  EXPECT_NE(o.ToJson().find("\"robust_cues\":true"), std::string::npos);
}

// Self-calibration (issue 28): link with robust cues, estimate the detector's
// noise from the tracks, re-link with it. Five sequences of the mixed traffic
// pooled, sizes three times noisier than the default assumes.
TEST(TrackingSelfCalibration, NoisySizesAreMeasuredAndStayOneTrackPerCar) {
  DetectorModel model;
  model.size = 0.9;
  std::vector<SimSequence> sims;
  std::vector<std::vector<FrameDetections>> frames;
  for (int s = 0; s < 5; ++s) {
    sims.push_back(Simulate(MixedTraffic(), SimEgo(), model, 900 + s));
    frames.push_back(sims.back().frames);
  }
  const CalibrationResult calibration = CalibrateTracker(frames, TrackerOptions(), CalibrationOptions());
  const DetectorNoiseModel& m = calibration.model;
  EXPECT_EQ(m.source, "self-calibration") << calibration.BriefReport();
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(m.size_sigma[i], 0.9, 0.25 * 0.9) << calibration.BriefReport();
  EXPECT_NEAR(m.yaw_sigma_deg, 5.0, 0.25 * 5.0) << calibration.BriefReport();
  // Flips 7 %, misses 5 % (interior gaps only, so at most that).
  EXPECT_NEAR(m.flip_rate, 0.07, 0.03) << calibration.BriefReport();
  EXPECT_LE(m.miss_rate, 0.07) << calibration.BriefReport();
  EXPECT_TRUE(calibration.tracker.robust_cues);
  EXPECT_GT(calibration.tracker.size_sigma, 0.7);
  TrackingFigures total;
  for (size_t s = 0; s < sims.size(); ++s)
    total.Add(Score(LinkDetections(sims[s].frames, calibration.tracker, nullptr), sims[s]));
  EXPECT_LE(total.TracksPerCar(), 1.10) << total.Report();
  EXPECT_LE(total.SwitchesPerCar(), 0.1) << total.Report();
  EXPECT_GE(total.MainShare(), 0.95) << total.Report();
}

}  // namespace
}  // namespace samp
