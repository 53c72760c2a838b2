#include "libsamp/synth/scene.h"

#include <algorithm>
#include <cmath>

#include "libsamp/fit/motion_model.h"
#include "libsamp/synth/procedural.h"

namespace samp::synth {
namespace {

// Oriented rectangle on the ground (x, z) for overlap tests.
struct GroundBox {
  Eigen::Vector2d centre;
  Eigen::Vector2d axis_forward, axis_side;
  double half_length = 0.0, half_width = 0.0;
};

GroundBox MakeGroundBox(const Eigen::Vector3d& centre, double heading, double length, double width) {
  GroundBox box;
  box.centre = Eigen::Vector2d(centre.x(), centre.z());
  const Eigen::Vector3d f = Heading(heading);
  box.axis_forward = Eigen::Vector2d(f.x(), f.z());
  box.axis_side = Eigen::Vector2d(-box.axis_forward.y(), box.axis_forward.x());
  box.half_length = 0.5 * length;
  box.half_width = 0.5 * width;
  return box;
}

// Separating-axis test with a margin (metres) added to both boxes.
bool Overlap(const GroundBox& a, const GroundBox& b, double margin) {
  const Eigen::Vector2d d = b.centre - a.centre;
  for (const Eigen::Vector2d& axis : {a.axis_forward, a.axis_side, b.axis_forward, b.axis_side}) {
    const double ra = (a.half_length + margin) * std::abs(axis.dot(a.axis_forward)) +
                      (a.half_width + margin) * std::abs(axis.dot(a.axis_side));
    const double rb = (b.half_length + margin) * std::abs(axis.dot(b.axis_forward)) +
                      (b.half_width + margin) * std::abs(axis.dot(b.axis_side));
    if (std::abs(d.dot(axis)) > ra + rb) return false;
  }
  return true;
}

// The ego car's body at frame t: from 2 m ahead to 2.6 m behind the camera.
GroundBox EgoBox(const SynthOptions& options, const Eigen::Isometry3d& world_from_camera) {
  Eigen::Vector3d ego_forward = world_from_camera.linear() * Eigen::Vector3d::UnitZ();
  ego_forward.y() = 0.0;
  ego_forward.normalize();
  Eigen::Vector3d ego_centre = world_from_camera.translation() - 0.3 * ego_forward;
  ego_centre.y() = options.camera_height;
  return MakeGroundBox(ego_centre, YawOfDirection(ego_forward), 4.6, 1.9);
}

}  // namespace

PlanarState Advance(const PlanarState& start, double speed, double yaw_rate, double dt) {
  const double pose[4] = {start.position.x(), start.position.y(), start.position.z(), start.heading};
  const double velocity[2] = {speed, yaw_rate};
  double predicted[6];
  PredictMotion(MotionModel::kArc, pose, velocity, dt, predicted, nullptr, nullptr);
  PlanarState end;
  end.position = Eigen::Vector3d(predicted[0], predicted[1], predicted[2]);
  end.heading = predicted[3];
  return end;
}

const char* MotionName(MotionType type) {
  switch (type) {
    case MotionType::kStanding: return "standing";
    case MotionType::kStraight: return "straight";
    case MotionType::kTurning: return "turning";
  }
  return "?";
}

SceneCar NewSceneCar(const SynthCar* synth_car) {
  SceneCar car;
  car.car = synth_car;
  const AlignedBox bounds = synth_car->mesh.Bounds();
  car.length = bounds.Size().x();
  car.height = bounds.Size().y();
  car.width = bounds.Size().z();
  return car;
}

PinholeCamera MakeCamera(const SynthOptions& options) {
  PinholeCamera camera;
  camera.fx = camera.fy = options.focal_px;
  camera.cx = options.cx_px;
  camera.cy = options.cy_px;
  camera.width = options.width;
  camera.height = options.height;
  return camera;
}

std::vector<int> ShuffledCarOrder(size_t num_cars, Random* rng) {
  std::vector<int> order(num_cars);
  for (size_t i = 0; i < order.size(); ++i) order[i] = int(i);
  std::shuffle(order.begin(), order.end(), rng->engine());
  return order;
}

bool AcceptTrajectory(const SynthOptions& options, const Scene& scene, const PlanarState& middle_state,
                      double speed, double yaw_rate, const SceneCar& car, std::vector<PlanarState>* out) {
  const int num_frames = options.num_frames;
  const int middle = num_frames / 2;
  const double dt = 1.0 / options.frame_rate_hz;
  const PinholeCamera camera = MakeCamera(options);
  std::vector<PlanarState> states(num_frames);
  int frames_in_view = 0;
  for (int t = 0; t < num_frames; ++t) {
    states[t] = Advance(middle_state, speed, yaw_rate, (t - middle) * dt);
    states[t].heading = WrapAngle(states[t].heading);
    const PlanarState& s = states[t];
    if (scene.street) {
      if (!car.parked && !scene.layout.Drivable(s.position.x(), s.position.z())) return false;
    } else if (std::abs(s.position.x()) > kMaxCarCentreX) {
      return false;
    }
    const Eigen::Isometry3d& wc = scene.world_from_camera[t];
    const GroundBox self = MakeGroundBox(s.position, s.heading, car.length, car.width);
    if (Overlap(EgoBox(options, wc), self, 1.0)) return false;
    for (const SceneCar& other : scene.cars) {
      const PlanarState& o = other.states[t];
      const double margin = car.parked && other.parked ? 0.1 : 0.4;
      if (Overlap(MakeGroundBox(o.position, o.heading, other.length, other.width), self, margin)) return false;
    }
    const Eigen::Vector3d centre_in_camera =
        wc.inverse() * (s.position - Eigen::Vector3d(0, 0.5 * car.height, 0));
    if (centre_in_camera.z() > 2.0 && camera.Contains(camera.Project(centre_in_camera))) ++frames_in_view;
  }
  if (frames_in_view < (7 * num_frames + 9) / 10) return false;
  *out = std::move(states);
  return true;
}

bool TakeTrajectory(const SynthOptions& options, const Scene& scene, MotionType motion, double d,
                    const PlanarState& middle_state, double speed, double yaw_rate, SceneCar* car) {
  std::vector<PlanarState> states;
  if (!AcceptTrajectory(options, scene, middle_state, speed, yaw_rate, *car, &states)) return false;
  car->motion = motion;
  car->speed = speed;
  car->yaw_rate = yaw_rate;
  car->target_distance = d;
  car->states = std::move(states);
  return true;
}

Scene MakeScene(const SynthOptions& options, const std::vector<SynthCar>& cars, int sequence_index,
                int* global_car_index) {
  const uint64_t seed = procedural::Mix(options.seed, uint64_t(sequence_index));
  Random rng(seed);
  return options.scene == SynthScene::kStreet
             ? MakeStreetScene(options, cars, sequence_index, seed, &rng, global_car_index)
             : MakeCleanScene(options, cars, sequence_index, seed, &rng, global_car_index);
}

}  // namespace samp::synth
