// Initial states of a track (initialization.h): flips resolved, arcs and
// standing cars recognised from noisy detections.
#include "libsamp/fit/initialization.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/model/shape_model.h"
#include "tests/fit/fit_test_util.h"

namespace samp {
namespace {

const ShapeModel& Model() {
  static const ShapeModel model = testing::MakeSyntheticModel(5, 0.1);
  return model;
}

using testing::MakeTrack;
using testing::Synthetic;

TEST(Initialization, ResolvesFlipsAndArc) {
  const ShapeLookup lookup(Model());
  Synthetic s = MakeTrack(lookup, 11, 8.0, 0.3, 50, 5, /*flipped_frame=*/4);
  const InitialState init = InitializeTrack(s.track, FitOptions());
  EXPECT_FALSE(init.standing);
  for (int k = 0; k < 11; ++k) {
    EXPECT_LT(std::abs(WrapAngle(init.poses[k][3] - s.poses_true[k][3])), 0.2) << "frame " << k;
    EXPECT_NEAR(init.poses[k][1], 1.65, 1e-9);  // on the road plane
  }
  EXPECT_NEAR(init.velocities[0][0], 8.0, 2.0);

  // Standing car, detections flipped in some frames: yaw from the majority.
  Synthetic st = MakeTrack(lookup, 9, 0.0, 0.0, 50, 6, /*flipped_frame=*/2);
  const InitialState init_st = InitializeTrack(st.track, FitOptions());
  EXPECT_TRUE(init_st.standing);
  for (int k = 0; k < 9; ++k) {
    EXPECT_LT(std::abs(WrapAngle(init_st.poses[k][3] - 0.4)), 0.2) << "frame " << k;
    EXPECT_EQ(init_st.velocities[k][0], 0.0);
  }
}

TEST(Initialization, IgnoresOffAxisDrift) {
  // A standing car far away: its detections drift 4 m across the car's length
  // axis within a second (noise, 4 m/s > standing_speed). The drift must not
  // be taken as motion, or the car would get a heading 90 degrees off.
  const ShapeLookup lookup(Model());
  Synthetic st = MakeTrack(lookup, 9, 0.0, 0.0, 50, 6, /*flipped_frame=*/2);
  const Eigen::Vector3d across_in_world = Heading(0.4 + M_PI / 2);
  for (size_t k = 0; k < st.track.frames.size(); ++k) {
    TrackFrame& f = st.track.frames[k];
    f.detection.position += f.world_from_camera.linear().transpose() * (0.5 * double(k) * across_in_world);
  }
  const InitialState init = InitializeTrack(st.track, FitOptions());
  EXPECT_TRUE(init.standing);
  for (size_t k = 0; k < st.track.frames.size(); ++k) {
    EXPECT_LT(std::abs(WrapAngle(init.poses[k][3] - 0.4)), 0.2) << "frame " << k;
  }
  // The same drift along the length axis is motion.
  Synthetic along = MakeTrack(lookup, 9, 0.0, 0.0, 50, 6, /*flipped_frame=*/-1);
  for (size_t k = 0; k < along.track.frames.size(); ++k) {
    TrackFrame& f = along.track.frames[k];
    f.detection.position += f.world_from_camera.linear().transpose() * (0.5 * double(k) * Heading(0.4));
  }
  const InitialState moving = InitializeTrack(along.track, FitOptions());
  EXPECT_FALSE(moving.standing);
  EXPECT_LT(std::abs(WrapAngle(moving.poses[0][3] - 0.4)), 0.2);
  FitOptions bad;
  bad.max_motion_off_axis = 0.0;
  EXPECT_THROW(bad.Check(), Error);
}

TEST(Initialization, KeepsFarStandingCarsStanding) {
  // A standing car ~40 m away whose length axis is along the line of sight:
  // its detections scatter by 1.5 m (s.d.) along that axis, so their
  // displacements point along the car either way. Taking the noise as motion
  // would give the car the heading of the noise, flipped in half the cases.
  const ShapeLookup lookup(Model());
  std::mt19937 rng(17);
  std::normal_distribution<double> noise(0.0, 1.5);
  int num_standing = 0, num_right = 0;
  const int num_trials = 40;
  for (int trial = 0; trial < num_trials; ++trial) {
    Synthetic st = MakeTrack(lookup, 21, 0.0, 0.0, 50, 100 + trial);
    const Eigen::Vector3d along_in_world = Heading(0.4);
    for (TrackFrame& f : st.track.frames) {
      f.detection.position += f.world_from_camera.linear().transpose() * (noise(rng) * along_in_world);
    }
    const InitialState init = InitializeTrack(st.track, FitOptions());
    num_standing += init.standing;
    num_right += std::abs(WrapAngle(init.poses[0][3] - 0.4)) < 0.2;
  }
  EXPECT_EQ(num_standing, num_trials);
  EXPECT_EQ(num_right, num_trials);
  // The same noise on a car driving at 5 m/s along its axis: moving, right
  // way round (the noise is white, and so is the options' error model).
  FitOptions white;
  white.detection_correlation_frames = 0.0;
  int num_moving = 0;
  for (int trial = 0; trial < num_trials; ++trial) {
    Synthetic mv = MakeTrack(lookup, 21, 5.0, 0.0, 50, 200 + trial);
    const double yaw0 = mv.poses_true[0][3];
    for (TrackFrame& f : mv.track.frames) {
      f.detection.position += f.world_from_camera.linear().transpose() * (noise(rng) * Heading(yaw0));
    }
    const InitialState init = InitializeTrack(mv.track, white);
    num_moving += !init.standing && std::abs(WrapAngle(init.poses[0][3] - yaw0)) < 0.2 &&
                  std::abs(init.velocities[0][0] - 5.0) < 1.5;
  }
  EXPECT_EQ(num_moving, num_trials);
  FitOptions bad;
  bad.min_speed_significance = -1.0;
  EXPECT_THROW(bad.Check(), Error);
}

TEST(Initialization, CorrelatedDetectionErrorsAreNotTakenForMotion) {
  // A standing car whose detections err along its length axis as an AR(1)
  // process (rho = exp(-1/3) per frame, 1 m s.d.), as the position errors of
  // a real detector do: the errors drift together for several frames, which
  // white-noise significance mistakes for a speed, and the car would get the
  // drift's heading (backwards in half the cases).
  const ShapeLookup lookup(Model());
  const double rho = std::exp(-1.0 / 3.0);
  auto add_ar1 = [&](Synthetic* s, const Eigen::Vector3d& along_in_world, std::mt19937* rng) {
    std::normal_distribution<double> n(0.0, 1.0);
    double e = n(*rng);
    for (TrackFrame& f : s->track.frames) {
      f.detection.position += f.world_from_camera.linear().transpose() * (e * along_in_world);
      e = rho * e + std::sqrt(1.0 - rho * rho) * n(*rng);
    }
  };
  const int num_trials = 100;
  FitOptions white;
  white.detection_correlation_frames = 0.0;
  int standing_white = 0, standing = 0, right = 0;
  std::mt19937 rng(5);
  for (int trial = 0; trial < num_trials; ++trial) {
    Synthetic st = MakeTrack(lookup, 21, 0.0, 0.0, 50, 300 + trial);
    add_ar1(&st, Heading(0.4), &rng);
    standing_white += InitializeTrack(st.track, white).standing;
    const InitialState init = InitializeTrack(st.track, FitOptions());
    standing += init.standing;
    right += std::abs(WrapAngle(init.poses[0][3] - 0.4)) < 0.2;
  }
  // White-noise significance calls a share of them moving; the default
  // (errors correlated over 3 frames) at most one in a hundred.
  EXPECT_LE(standing_white, num_trials - 5);
  EXPECT_GE(standing, num_trials - 1);
  EXPECT_GE(right, num_trials - 1);
  // The same errors on a car driving at 5 m/s: moving, the right way round.
  int moving = 0;
  for (int trial = 0; trial < num_trials; ++trial) {
    Synthetic mv = MakeTrack(lookup, 21, 5.0, 0.0, 50, 400 + trial);
    const double yaw0 = mv.poses_true[0][3];
    add_ar1(&mv, Heading(yaw0), &rng);
    const InitialState init = InitializeTrack(mv.track, FitOptions());
    moving += !init.standing && std::abs(WrapAngle(init.poses[0][3] - yaw0)) < 0.2;
  }
  EXPECT_GE(moving, num_trials - 2);
}

}  // namespace
}  // namespace samp
