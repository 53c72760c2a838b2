// The clean preset (`samp synth --preset clean`, docs/synthetic.md): a flat
// textured road, building blocks and boxes beside it, cars with plain paint on
// stratified near/far distances, motion by car index (standing, straight,
// turning), no sway.
#include <algorithm>
#include <cmath>
#include <iterator>

#include "libsamp/core/log.h"
#include "libsamp/synth/procedural.h"
#include "libsamp/synth/scene.h"

namespace samp::synth {
namespace {

using procedural::Mix;

void AddBuildings(const SynthOptions& options, Random* rng, uint64_t seed, Scene* scene) {
  const double h = options.camera_height;
  static const Eigen::Vector3d kFacadeColors[] = {
      {0.55, 0.25, 0.18}, {0.75, 0.66, 0.50}, {0.55, 0.55, 0.55}, {0.80, 0.72, 0.45},
      {0.45, 0.30, 0.25}, {0.70, 0.70, 0.66}, {0.60, 0.45, 0.35}};
  int building = 0;
  for (int side : {-1, 1}) {
    double z = -40.0;
    while (z < 200.0) {
      const double length = rng->Uniform(8.0, 25.0);
      const double setback = rng->Uniform(kRoadHalfWidth + 2.0, kRoadHalfWidth + 4.5);
      const double depth = rng->Uniform(6.0, 12.0);
      const double height = rng->Uniform(5.0, 18.0);
      const double x0 = side * setback, x1 = side * (setback + depth);
      StaticMesh m;
      m.mesh = MakeBoxMesh(Eigen::Vector3d(std::min(x0, x1), h - height, z),
                           Eigen::Vector3d(std::max(x0, x1), h, z + length));
      m.material = MaterialKind::kFacade;
      m.color = kFacadeColors[rng->Index(int(std::size(kFacadeColors)))];
      m.seed = Mix(seed, uint64_t(100 + building++));
      scene->statics.push_back(std::move(m));
      z += length + (rng->Bernoulli(0.5) ? 0.0 : rng->Uniform(1.0, 6.0));
    }
  }
  // Backdrop across the far end of the street.
  StaticMesh backdrop;
  backdrop.mesh = MakeBoxMesh(Eigen::Vector3d(-70, h - 30.0, 200.0), Eigen::Vector3d(70, h, 206.0));
  backdrop.material = MaterialKind::kFacade;
  backdrop.color = Eigen::Vector3d(0.6, 0.6, 0.62);
  backdrop.seed = Mix(seed, 99);
  scene->statics.push_back(std::move(backdrop));
  // Small boxes and poles on the sidewalks.
  for (int i = 0; i < 14; ++i) {
    const double side = rng->Bernoulli(0.5) ? 1.0 : -1.0;
    const double x = side * rng->Uniform(kRoadHalfWidth + 0.4, kRoadHalfWidth + 1.6);
    const double z = rng->Uniform(-10.0, 130.0);
    Eigen::Vector3d size;
    if (rng->Bernoulli(0.5)) {
      const double s = rng->Uniform(0.4, 1.0);
      size = Eigen::Vector3d(s, rng->Uniform(0.5, 1.2), s);
    } else {
      size = Eigen::Vector3d(0.14, rng->Uniform(2.5, 4.0), 0.14);
    }
    StaticMesh m;
    m.mesh = MakeBoxMesh(Eigen::Vector3d(x - 0.5 * size.x(), h - size.y(), z - 0.5 * size.z()),
                         Eigen::Vector3d(x + 0.5 * size.x(), h, z + 0.5 * size.z()));
    m.material = MaterialKind::kBlotch;
    m.color = Eigen::Vector3d(rng->Uniform(0.2, 0.8), rng->Uniform(0.2, 0.8), rng->Uniform(0.2, 0.8));
    m.seed = Mix(seed, uint64_t(500 + i));
    scene->statics.push_back(std::move(m));
  }
}

struct Paint {
  const char* name;
  Eigen::Vector3d color;
};
const Paint kPaints[] = {{"white", {0.82, 0.82, 0.80}}, {"silver", {0.55, 0.57, 0.60}},
                         {"black", {0.05, 0.05, 0.06}}, {"red", {0.55, 0.05, 0.04}},
                         {"blue", {0.06, 0.13, 0.45}},  {"grey", {0.25, 0.25, 0.27}},
                         {"beige", {0.65, 0.58, 0.45}}, {"green", {0.08, 0.28, 0.15}}};

// Tries to place one car; returns false when no admissible trajectory was found.
bool PlaceCar(const SynthOptions& options, MotionType motion, double min_d, double max_d,
              const Scene& scene, Random* rng, SceneCar* car) {
  const int middle = options.num_frames / 2;
  const PinholeCamera camera = MakeCamera(options);
  const double tan_half_fov = std::min(camera.cx, camera.width - camera.cx) / camera.fx;
  const Eigen::Isometry3d& world_from_middle = scene.world_from_camera[middle];
  for (int attempt = 0; attempt < 400; ++attempt) {
    const double d = rng->Uniform(min_d, max_d);
    const double max_x = d * std::sin(0.85 * std::atan(tan_half_fov));
    const double x_c = rng->Uniform(-max_x, max_x);
    const double z_c = std::sqrt(std::max(d * d - x_c * x_c, 1e-6));
    PlanarState middle_state;
    middle_state.position =
        world_from_middle * Eigen::Vector3d(x_c, options.camera_height, z_c);
    middle_state.position.y() = options.camera_height;
    if (std::abs(middle_state.position.x()) > kMaxCarCentreX) continue;
    const double along = rng->Bernoulli(0.5) ? -0.5 * kPi : 0.5 * kPi;  // same way / oncoming
    double speed = 0.0, yaw_rate = 0.0;
    switch (motion) {
      case MotionType::kStanding:
        middle_state.heading = rng->Bernoulli(0.65) ? along + rng->Normal(6.0 * kPi / 180.0)
                                                    : rng->Uniform(-kPi, kPi);
        break;
      case MotionType::kStraight:
        speed = rng->Uniform(options.min_speed, options.max_speed);
        if (rng->Bernoulli(0.8)) {
          middle_state.heading = along + rng->Normal(3.0 * kPi / 180.0);
        } else {  // crossing, slower
          speed = std::min(speed, rng->Uniform(options.min_speed, options.min_speed + 2.0));
          middle_state.heading = (rng->Bernoulli(0.5) ? 0.0 : kPi) + rng->Normal(10.0 * kPi / 180.0);
        }
        break;
      case MotionType::kTurning:
        speed = rng->Uniform(options.min_turn_speed, options.max_turn_speed);
        yaw_rate = rng->Uniform(options.min_yaw_rate, options.max_yaw_rate) *
                   (rng->Bernoulli(0.5) ? 1.0 : -1.0);
        middle_state.heading = along + rng->Uniform(-25.0, 25.0) * kPi / 180.0;
        break;
    }
    middle_state.heading = WrapAngle(middle_state.heading);
    if (TakeTrajectory(options, scene, motion, d, middle_state, speed, yaw_rate, car)) return true;
  }
  return false;
}

}  // namespace

Scene MakeCleanScene(const SynthOptions& options, const std::vector<SynthCar>& cars, int sequence_index,
                     uint64_t seed, Random* rng, int* global_car_index) {
  Scene scene;
  const double dt = 1.0 / options.frame_rate_hz;
  scene.ego_speed = rng->Uniform(options.min_ego_speed, options.max_ego_speed);
  scene.ego_yaw_rate = rng->Uniform(-options.max_ego_yaw_rate, options.max_ego_yaw_rate);
  PlanarState ego;  // the camera's forward is the ego heading -pi/2 (world +z)
  ego.heading = -0.5 * kPi;
  for (int t = 0; t < options.num_frames; ++t) {
    const PlanarState s = Advance(ego, scene.ego_speed, scene.ego_yaw_rate, t * dt);
    // The camera looks along the ego heading: its z is the ego's forward.
    scene.world_from_camera.push_back(samp::WorldFromObject(s.position, s.heading + 0.5 * kPi));
  }
  StaticMesh road;
  road.mesh = MakeGroundMesh(options.camera_height, -80, 80, -60, 220);
  road.material = MaterialKind::kRoad;
  road.seed = Mix(seed, 1);
  scene.statics.push_back(std::move(road));
  AddBuildings(options, rng, seed, &scene);

  const std::vector<int> order = ShuffledCarOrder(cars.size(), rng);
  const double split = std::clamp(20.0, options.min_distance, options.max_distance);
  for (int k = 0; k < options.cars_per_sequence; ++k) {
    const int g = (*global_car_index)++;
    SceneCar car = NewSceneCar(&cars[order[k % order.size()]]);
    car.track_id = k;
    const Paint& paint = kPaints[rng->Index(int(std::size(kPaints)))];
    car.paint = paint.color;
    car.paint_name = paint.name;
    const MotionType motion = MotionType(g % 3);
    const bool near = ((g / 3) % 2) == 0;
    const double lo = near ? options.min_distance : split;
    const double hi = near ? split : options.max_distance;
    bool placed = PlaceCar(options, motion, lo, hi, scene, rng, &car);
    if (!placed) placed = PlaceCar(options, motion, options.min_distance, options.max_distance, scene, rng, &car);
    if (!placed) placed = PlaceCar(options, MotionType::kStanding, options.min_distance,
                                   options.max_distance, scene, rng, &car);
    if (!placed) {
      LogWarning() << "synth: sequence " << sequence_index << ": no free place for car " << k
                   << " (" << car.car->name << "); the sequence has fewer cars";
      continue;
    }
    car.track_id = int(scene.cars.size());
    scene.cars.push_back(std::move(car));
  }
  return scene;
}

}  // namespace samp::synth
