#include "libsamp/eval/synth.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <tbb/parallel_for.h>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <set>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/camera.h"
#include "libsamp/core/error.h"
#include "libsamp/core/json_text.h"
#include "libsamp/core/log.h"
#include "libsamp/core/ply_io.h"
#include "libsamp/core/progress.h"
#include "libsamp/core/util.h"
#include "libsamp/eval/procedural.h"
#include "libsamp/eval/street_scene.h"
#include "libsamp/fit/motion_model.h"
#include "libsamp/data/kitti_io.h"
#include "libsamp/data/sequence_layout.h"
#include "libsamp/data/stereo.h"
#include "libsamp/scan/canonical.h"
#include "libsamp/scan/mesh_io.h"
#include "libsamp/scan/embree_scene.h"
#include "libsamp/scan/renderer.h"

namespace samp {
namespace {

namespace fs = std::filesystem;
using procedural::Mix;

constexpr double kPi = 3.14159265358979323846;
// Road layout in the world frame (= camera of frame 0): lanes of 3.5 m, road
// |x| < 7 m, sidewalk to the building line at |x| >= 9 m.
constexpr double kRoadHalfWidth = 7.0;
constexpr double kLaneWidth = 3.5;
constexpr double kMaxCarCentreX = 6.1;

// Pose conventions (WrapAngle, Heading, WorldFromObject) and the motion model: the
// fitter's, fit/motion_model.h.
struct PlanarState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double heading = 0.0;
};

// Motion for dt seconds (negative dt goes back in time), predicted by the
// fitter's circular-arc model (fit/motion_model.h PredictMotion; standing and
// straight are its exact limits v = 0 and omega = 0), so that the ground truth
// follows the model the fitter predicts with.
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

enum class MaterialKind { kRoad, kFacade, kBlotch, kCar, kStreet };

struct StaticMesh {
  Mesh mesh;
  MaterialKind material = MaterialKind::kBlotch;
  Eigen::Vector3d color = Eigen::Vector3d::Constant(0.5);
  uint64_t seed = 0;
  int street_index = -1;  // kStreet: index into Scene::street_objects (whose mesh is moved here)
};

enum class MotionType { kStanding = 0, kStraight = 1, kTurning = 2 };

const char* MotionName(MotionType type) {
  switch (type) {
    case MotionType::kStanding: return "standing";
    case MotionType::kStraight: return "straight";
    case MotionType::kTurning: return "turning";
  }
  return "?";
}

struct SceneCar {
  int track_id = 0;
  const SynthCar* car = nullptr;
  MotionType motion = MotionType::kStanding;
  double speed = 0.0, yaw_rate = 0.0;
  Eigen::Vector3d paint = Eigen::Vector3d::Constant(0.5);
  std::string paint_name;
  double length = 0, height = 0, width = 0;  // from the mesh bounds
  double target_distance = 0.0;              // at the middle frame
  std::vector<PlanarState> states;           // per frame, world frame
  bool parked = false;                       // kStreet: in a parking lane's row
  bool metallic = false;                     // silver/grey metallic paint (stronger, broader highlight)
};

struct Scene {
  std::vector<StaticMesh> statics;
  std::vector<SceneCar> cars;
  // Rendering frame ("world"; for kStreet the road frame, in which frame 0's
  // camera is pitched/rolled by the sway). Written poses are relative to frame 0.
  std::vector<Eigen::Isometry3d> world_from_camera;
  double ego_speed = 0.0, ego_yaw_rate = 0.0;
  // kStreet only.
  bool street = false;
  StreetLayout layout;
  std::vector<StreetObject> street_objects;  // materials (meshes moved into statics)
  OutdoorLighting lighting;
  double exposure = 1.0;
  EgoSway sway;
  std::vector<ClutterCandidate> clutter;     // false-positive candidates, world frame (position), id
  std::vector<double> clutter_heading;       // world heading of each candidate box
};

Eigen::Isometry3d WorldFromObject(const PlanarState& state) {
  return samp::WorldFromObject(state.position, state.heading);
}

class Random {
 public:
  explicit Random(uint64_t seed) : engine_(seed) {}
  double Uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine_); }
  double Normal(double sigma) { return sigma > 0 ? std::normal_distribution<double>(0.0, sigma)(engine_) : 0.0; }
  bool Bernoulli(double p) { return Uniform(0.0, 1.0) < p; }
  int Index(int n) { return std::uniform_int_distribution<int>(0, n - 1)(engine_); }
  std::mt19937_64& engine() { return engine_; }

 private:
  std::mt19937_64 engine_;
};

PinholeCamera MakeCamera(const SynthOptions& options) {
  PinholeCamera camera;
  camera.fx = camera.fy = options.focal_px;
  camera.cx = options.cx_px;
  camera.cy = options.cy_px;
  camera.width = options.width;
  camera.height = options.height;
  return camera;
}

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

// Integrates a car's trajectory from its middle-frame state and checks it:
// on the road (clean: |x| <= kMaxCarCentreX; street: drivable, unless parked),
// clear of the ego car and the other cars, centre in view in >= 70 % of the frames.
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
    // Clear of the ego car (its body from 2 m ahead to 2.6 m behind the camera).
    const Eigen::Isometry3d& wc = scene.world_from_camera[t];
    Eigen::Vector3d ego_forward = wc.linear() * Eigen::Vector3d::UnitZ();
    ego_forward.y() = 0.0;
    ego_forward.normalize();
    const double ego_heading = std::atan2(-ego_forward.z(), ego_forward.x());
    Eigen::Vector3d ego_centre = wc.translation() - 0.3 * ego_forward;
    ego_centre.y() = options.camera_height;
    const GroundBox ego = MakeGroundBox(ego_centre, ego_heading, 4.6, 1.9);
    const GroundBox self = MakeGroundBox(s.position, s.heading, car.length, car.width);
    if (Overlap(ego, self, 1.0)) return false;
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

// Gives `car` the trajectory through `middle_state` (the car at distance `d`
// from the middle frame's camera) when AcceptTrajectory admits it.
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

// Tries to place one car; returns false when no admissible trajectory was found.
bool PlaceCar(const SynthOptions& options, MotionType motion, double min_d, double max_d,
              const Scene& scene, Random* rng, SceneCar* car) {
  const int num_frames = options.num_frames;
  const int middle = num_frames / 2;
  const PinholeCamera camera = MakeCamera(options);
  const double tan_half_fov = std::min(camera.cx, camera.width - camera.cx) / camera.fx;
  const Eigen::Isometry3d& world_from_middle = scene.world_from_camera[middle];
  (void)num_frames;
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

Scene MakeCleanScene(const SynthOptions& options, const std::vector<SynthCar>& cars, int sequence_index,
                     int* global_car_index) {
  const uint64_t seed = Mix(options.seed, uint64_t(sequence_index));
  Random rng(seed);
  Scene scene;
  const double dt = 1.0 / options.frame_rate_hz;
  scene.ego_speed = rng.Uniform(options.min_ego_speed, options.max_ego_speed);
  scene.ego_yaw_rate = rng.Uniform(-options.max_ego_yaw_rate, options.max_ego_yaw_rate);
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
  AddBuildings(options, &rng, seed, &scene);

  std::vector<int> order(cars.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = int(i);
  std::shuffle(order.begin(), order.end(), rng.engine());
  const double split = std::clamp(20.0, options.min_distance, options.max_distance);
  for (int k = 0; k < options.cars_per_sequence; ++k) {
    const int g = (*global_car_index)++;
    SceneCar car;
    car.track_id = k;
    car.car = &cars[order[k % order.size()]];
    const AlignedBox bounds = car.car->mesh.Bounds();
    car.length = bounds.Size().x();
    car.height = bounds.Size().y();
    car.width = bounds.Size().z();
    const Paint& paint = kPaints[rng.Index(int(std::size(kPaints)))];
    car.paint = paint.color;
    car.paint_name = paint.name;
    const MotionType motion = MotionType(g % 3);
    const bool near = ((g / 3) % 2) == 0;
    const double lo = near ? options.min_distance : split;
    const double hi = near ? split : options.max_distance;
    bool placed = PlaceCar(options, motion, lo, hi, scene, &rng, &car);
    if (!placed) placed = PlaceCar(options, motion, options.min_distance, options.max_distance, scene, &rng, &car);
    if (!placed) placed = PlaceCar(options, MotionType::kStanding, options.min_distance,
                                   options.max_distance, scene, &rng, &car);
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

// Paint of real traffic (street scenes): white, black, grey and silver dominate.
struct WeightedPaint {
  const char* name;
  Eigen::Vector3d color;
  double weight;
  bool metallic;
};
const WeightedPaint kStreetPaints[] = {
    {"white", {0.78, 0.78, 0.76}, 0.24, false},  {"black", {0.025, 0.025, 0.03}, 0.20, false},
    {"grey", {0.20, 0.21, 0.22}, 0.16, true},    {"silver", {0.50, 0.52, 0.55}, 0.15, true},
    {"blue", {0.05, 0.10, 0.32}, 0.08, true},    {"red", {0.45, 0.04, 0.03}, 0.08, false},
    {"beige", {0.55, 0.48, 0.36}, 0.05, true},   {"green", {0.06, 0.20, 0.12}, 0.04, true}};

void PickStreetPaint(Random* rng, SceneCar* car) {
  double total = 0.0;
  for (const WeightedPaint& p : kStreetPaints) total += p.weight;
  double u = rng->Uniform(0.0, total);
  for (const WeightedPaint& p : kStreetPaints) {
    u -= p.weight;
    if (u <= 0.0 || &p == &kStreetPaints[std::size(kStreetPaints) - 1]) {
      car->paint = p.color;
      car->paint_name = p.name;
      car->metallic = p.metallic;
      return;
    }
  }
}

// The traffic car's middle-frame state in a street: a lane (same way or
// oncoming), the cross street (crossing), or the junction (turning); false when
// the target distance cannot be met there.
bool ProposeStreetState(const SynthOptions& options, const Scene& scene, MotionType motion, double d,
                        Random* rng, PlanarState* state, double* speed, double* yaw_rate) {
  const StreetLayout& layout = scene.layout;
  const Eigen::Vector3d camera = scene.world_from_camera[options.num_frames / 2].translation();
  *speed = 0.0;
  *yaw_rate = 0.0;
  const bool can_cross = layout.has_intersection;
  const double u = rng->Uniform(0.0, 1.0);
  enum { kSame, kOncoming, kCross } where = u < 0.5 ? kSame : (u < 0.8 || !can_cross ? kOncoming : kCross);
  if (motion == MotionType::kTurning && can_cross && rng->Bernoulli(0.6)) where = kCross;
  if (where == kCross) {
    const bool plus_x = rng->Bernoulli(0.5);
    // Right-hand traffic: a car driving +x keeps to z < intersection_z (its right side).
    const double z = layout.intersection_z + (plus_x ? -0.5 : 0.5) * layout.intersection_half_width;
    const double dz = z - camera.z();
    if (d <= std::abs(dz) + 0.5) return false;
    const double dx = std::sqrt(d * d - dz * dz) * (rng->Bernoulli(0.5) ? 1.0 : -1.0);
    state->position = Eigen::Vector3d(camera.x() + dx, options.camera_height, z);
    state->heading = (plus_x ? 0.0 : kPi) + rng->Normal(2.0 * kPi / 180.0);
  } else {
    const std::vector<double>& lanes = where == kSame ? layout.same_lanes : layout.oncoming_lanes;
    const double x = lanes[rng->Index(int(lanes.size()))] + rng->Normal(0.15);
    const double dx = x - camera.x();
    if (d <= std::abs(dx) + 0.5) return false;
    state->position = Eigen::Vector3d(x, options.camera_height, camera.z() + std::sqrt(d * d - dx * dx));
    state->heading = (where == kSame ? -0.5 * kPi : 0.5 * kPi) + rng->Normal(1.5 * kPi / 180.0);
  }
  switch (motion) {
    case MotionType::kStanding:
      break;
    case MotionType::kStraight:
      *speed = rng->Uniform(options.min_speed, options.max_speed);
      if (where == kCross) *speed = std::min(*speed, rng->Uniform(options.min_speed, options.min_speed + 4.0));
      break;
    case MotionType::kTurning:
      *speed = rng->Uniform(options.min_turn_speed, options.max_turn_speed);
      *yaw_rate = rng->Uniform(options.min_yaw_rate, options.max_yaw_rate) * (rng->Bernoulli(0.5) ? 1.0 : -1.0);
      state->heading += rng->Uniform(-20.0, 20.0) * kPi / 180.0;
      break;
  }
  state->heading = WrapAngle(state->heading);
  return true;
}

bool PlaceStreetCar(const SynthOptions& options, MotionType motion, double min_d, double max_d,
                    const Scene& scene, Random* rng, SceneCar* car) {
  for (int attempt = 0; attempt < 400; ++attempt) {
    const double d = rng->Uniform(min_d, max_d);
    PlanarState middle_state;
    double speed = 0.0, yaw_rate = 0.0;
    if (!ProposeStreetState(options, scene, motion, d, rng, &middle_state, &speed, &yaw_rate)) continue;
    if (TakeTrajectory(options, scene, motion, d, middle_state, speed, yaw_rate, car)) return true;
  }
  return false;
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

// The realistic street scene (docs/synthetic.md "Street").
Scene MakeStreetScene(const SynthOptions& options, const std::vector<SynthCar>& cars, int sequence_index,
                      int* global_car_index) {
  const uint64_t seed = Mix(options.seed, uint64_t(sequence_index));
  Random rng(seed);
  Scene scene;
  scene.street = true;
  const double dt = 1.0 / options.frame_rate_hz;
  const int middle = options.num_frames / 2;
  scene.ego_speed = rng.Uniform(options.min_ego_speed, options.max_ego_speed);
  scene.ego_yaw_rate = rng.Uniform(-options.max_ego_yaw_rate, options.max_ego_yaw_rate);
  // Sway grows with speed (at least 30 % of the amplitudes at max_ego_speed).
  const double speed_factor =
      std::max(0.3, options.max_ego_speed > 0 ? scene.ego_speed / options.max_ego_speed : 0.0);
  constexpr double kDeg = kPi / 180.0;
  scene.sway.pitch_amplitude = options.ego_pitch_sway_deg * kDeg * speed_factor * rng.Uniform(0.5, 1.0);
  scene.sway.roll_amplitude = options.ego_roll_sway_deg * kDeg * speed_factor * rng.Uniform(0.5, 1.0);
  scene.sway.bounce_amplitude = options.ego_bounce * speed_factor * rng.Uniform(0.5, 1.0);
  scene.sway.pitch_frequency_hz = rng.Uniform(0.8, 1.8);
  scene.sway.roll_frequency_hz = rng.Uniform(0.4, 1.2);
  scene.sway.bounce_frequency_hz = rng.Uniform(1.0, 2.5);
  scene.sway.pitch_phase = rng.Uniform(0.0, 2.0 * kPi);
  scene.sway.roll_phase = rng.Uniform(0.0, 2.0 * kPi);
  scene.sway.bounce_phase = rng.Uniform(0.0, 2.0 * kPi);
  scene.sway.pitch_offset = rng.Uniform(-1.0, 1.0) * options.ego_max_pitch_offset_deg * kDeg;
  PlanarState ego;  // the camera's forward is the ego heading -pi/2 (road +z)
  ego.heading = -0.5 * kPi;
  for (int t = 0; t < options.num_frames; ++t) {
    const PlanarState s = Advance(ego, scene.ego_speed, scene.ego_yaw_rate, t * dt);
    Eigen::Isometry3d road_from_camera = Eigen::Isometry3d::Identity();
    road_from_camera.linear() =
        samp::WorldFromObject(Eigen::Vector3d::Zero(), s.heading + 0.5 * kPi).linear() * scene.sway.Rotation(t * dt);
    road_from_camera.translation() = s.position + Eigen::Vector3d(0.0, -scene.sway.Bounce(t * dt), 0.0);
    scene.world_from_camera.push_back(road_from_camera);
  }
  // Lighting: sun elevation and azimuth, sun and sky strength, exposure.
  const double elevation = rng.Uniform(options.min_sun_elevation_deg, options.max_sun_elevation_deg) * kDeg;
  const double azimuth = rng.Uniform(-kPi, kPi);
  scene.lighting.to_sun = Eigen::Vector3d(std::cos(elevation) * std::sin(azimuth), -std::sin(elevation),
                                          std::cos(elevation) * std::cos(azimuth));
  const double sun = rng.Uniform(0.55, 0.95);
  scene.lighting.sun = Eigen::Vector3d(1.0, 0.96, 0.88) * sun;
  scene.lighting.ambient = Eigen::Vector3d(0.30, 0.33, 0.38) * rng.Uniform(0.8, 1.15);
  scene.exposure = rng.Uniform(0.85, 1.15);

  // Street: layout, statics.
  scene.layout = MakeStreetLayout(options.street, options.camera_height, 0.0, &rng.engine());
  scene.street_objects = MakeStreetObjects(options.street, &scene.layout, -40.0, 220.0, Mix(seed, 7), &rng.engine());
  for (size_t i = 0; i < scene.street_objects.size(); ++i) {
    StaticMesh m;
    m.mesh = std::move(scene.street_objects[i].mesh);
    scene.street_objects[i].mesh = Mesh();
    m.material = MaterialKind::kStreet;
    m.street_index = int(i);
    m.seed = scene.street_objects[i].seed;
    scene.statics.push_back(std::move(m));
  }
  // False-positive candidates: car-sized boxes on the road beside the sidewalk clutter.
  for (const Eigen::Vector3d& c : scene.layout.clutter) {
    ClutterCandidate candidate;
    candidate.id = int(scene.clutter.size());
    const double side = c.x() > scene.layout.centre_x ? 1.0 : -1.0;
    candidate.position = Eigen::Vector3d(c.x() - side * 1.0, options.camera_height, c.z());
    scene.clutter.push_back(candidate);
    scene.clutter_heading.push_back(side > 0 ? -0.5 * kPi : 0.5 * kPi);
  }

  std::vector<int> order(cars.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = int(i);
  std::shuffle(order.begin(), order.end(), rng.engine());
  int next_car = 0;
  const Eigen::Vector3d camera_middle = scene.world_from_camera[middle].translation();

  // Near (nearer than `split` at the middle frame) while the realised near share of
  // the sequence's cars, parked and traffic, would stay short of near_share with
  // `count` more cars.
  const double split = std::clamp(20.0, options.min_distance, options.max_distance);
  const auto draw_near = [&](int count) {
    int placed_near = 0;
    for (const SceneCar& other : scene.cars) placed_near += other.target_distance < split ? 1 : 0;
    return placed_near < options.near_share * double(scene.cars.size() + count) - 1e-9;
  };

  // Parked rows, split over the parking lanes, near or far by draw_near.
  const int num_lanes = int(scene.layout.parking.size());
  for (int lane_index = 0; lane_index < num_lanes; ++lane_index) {
    const ParkingLane& lane = scene.layout.parking[lane_index];
    const int count = options.parked_cars_per_sequence / num_lanes +
                      (lane_index < options.parked_cars_per_sequence % num_lanes ? 1 : 0);
    if (count == 0) continue;
    const bool near_row = draw_near(count);
    for (int attempt = 0; attempt < 30; ++attempt) {
      std::vector<SceneCar> row;
      std::vector<double> lengths;
      for (int k = 0; k < count; ++k) {
        row.push_back(NewSceneCar(&cars[order[(next_car + k) % order.size()]]));
        lengths.push_back(row.back().length);
      }
      // Row starts (ahead of the camera): a near row's first car lies beyond
      // min_distance and its last car, where the row is short enough, within
      // `split`; a far row's first car lies beyond `split`; the last car of any row
      // lies within max_distance.
      const double lateral = std::abs(lane.kerb_x - camera_middle.x());
      const auto ahead = [&](double distance) {
        return std::sqrt(std::max(0.0, distance * distance - lateral * lateral));
      };
      double row_length = 0.0;
      for (double length : lengths) row_length += length + options.street.max_parked_gap;
      const double last_centre = row_length - options.street.max_parked_gap - 0.5 * lengths.back();
      const double near_lo = std::max(-2.0, ahead(options.min_distance) - 0.5 * lengths.front());
      const double near_hi = std::max(near_lo, ahead(split) - last_centre);
      const double far_lo = std::max(-2.0, ahead(split) - 0.5 * lengths.front());
      const double far_hi = std::max(far_lo, ahead(options.max_distance) - last_centre);
      const double z_lo = attempt >= 15 ? -2.0 : near_row ? near_lo : far_lo;
      const double z_hi = attempt < 15 && near_row ? near_hi : far_hi;
      const double z_start = camera_middle.z() + rng.Uniform(z_lo, z_hi);
      const std::vector<double> centres = PlanParkedRow(options.street, lengths, z_start, &rng.engine());
      bool ok = true;
      std::vector<SceneCar> accepted;
      for (int k = 0; k < count && ok; ++k) {
        SceneCar& car = row[k];
        car.parked = true;
        PlanarState state;
        const double kerb_offset = 0.5 * car.width + rng.Uniform(0.15, 0.4);
        state.position = Eigen::Vector3d(lane.kerb_x - lane.side * kerb_offset, options.camera_height, centres[k]);
        state.heading = WrapAngle(lane.heading + rng.Normal(1.5 * kDeg));
        const double d = (state.position - Eigen::Vector3d(camera_middle.x(), options.camera_height,
                                                            camera_middle.z())).norm();
        if (d < options.min_distance || d > options.max_distance) {
          ok = false;
          break;
        }
        if (scene.layout.has_intersection &&
            std::abs(state.position.z() - scene.layout.intersection_z) <
                scene.layout.intersection_half_width + 0.5 * car.length + 2.5) {
          ok = false;
          break;
        }
        Scene probe;
        probe.street = true;
        probe.layout = scene.layout;
        probe.world_from_camera = scene.world_from_camera;
        probe.cars = scene.cars;
        probe.cars.insert(probe.cars.end(), accepted.begin(), accepted.end());
        std::vector<PlanarState> states;
        if (!AcceptTrajectory(options, probe, state, 0.0, 0.0, car, &states)) {
          ok = false;
          break;
        }
        car.motion = MotionType::kStanding;
        car.target_distance = d;
        car.states = std::move(states);
        PickStreetPaint(&rng, &car);
        accepted.push_back(car);
      }
      if (!ok) continue;
      for (size_t k = 0; k < accepted.size(); ++k) {
        SceneCar& car = accepted[k];
        car.track_id = int(scene.cars.size());
        // A duplicate-detection candidate in the gap behind each parked car but the first.
        if (k > 0) {
          ClutterCandidate candidate;
          candidate.id = int(scene.clutter.size());
          candidate.position = 0.5 * (car.states[0].position + accepted[k - 1].states[0].position);
          scene.clutter.push_back(candidate);
          scene.clutter_heading.push_back(car.states[0].heading);
        }
        scene.cars.push_back(car);
        ++(*global_car_index);
      }
      next_car += count;
      break;
    }
  }

  // Traffic: standing (waiting), straight, turning by the shares, near/far by the realised near share.
  for (int k = 0; k < options.cars_per_sequence; ++k) {
    const int g = (*global_car_index)++;
    SceneCar car = NewSceneCar(&cars[order[(next_car++) % order.size()]]);
    PickStreetPaint(&rng, &car);
    // Low-discrepancy motion choice: the shares hold over the whole set.
    const double u = std::fmod(0.6180339887498949 * (g + 1), 1.0);
    const MotionType motion = u < options.standing_share ? MotionType::kStanding
                              : u < options.standing_share + options.turning_share ? MotionType::kTurning
                                                                                   : MotionType::kStraight;
    const bool near = draw_near(1);
    const double lo = near ? options.min_distance : split;
    const double hi = near ? split : options.max_distance;
    bool placed = PlaceStreetCar(options, motion, lo, hi, scene, &rng, &car);
    if (!placed) placed = PlaceStreetCar(options, motion, options.min_distance, options.max_distance, scene, &rng, &car);
    if (!placed && motion == MotionType::kTurning) {
      placed = PlaceStreetCar(options, MotionType::kStraight, options.min_distance, options.max_distance, scene, &rng, &car);
    }
    if (!placed) placed = PlaceStreetCar(options, MotionType::kStanding, options.min_distance,
                                         options.max_distance, scene, &rng, &car);
    if (!placed) {
      LogWarning() << "synth: sequence " << sequence_index << ": no free place for traffic car " << k << " ("
                   << car.car->name << "); the sequence has fewer cars";
      continue;
    }
    car.track_id = int(scene.cars.size());
    scene.cars.push_back(std::move(car));
  }
  return scene;
}

Scene MakeScene(const SynthOptions& options, const std::vector<SynthCar>& cars, int sequence_index,
                int* global_car_index) {
  return options.scene == SynthScene::kStreet ? MakeStreetScene(options, cars, sequence_index, global_car_index)
                                              : MakeCleanScene(options, cars, sequence_index, global_car_index);
}

// Shading of one rendered view into an 8-bit BGR image (for cv::imwrite).
cv::Mat ShadeView(const SynthOptions& options, const Scene& scene, int frame,
                  const Eigen::Isometry3d& world_from_camera, const PinholeCamera& camera,
                  const RenderBuffers& buffers, uint64_t noise_seed) {
  const Eigen::Vector3d sun = Eigen::Vector3d(-0.35, -1.0, -0.5).normalized();  // towards the sun
  const Eigen::Matrix3d rotation = world_from_camera.linear();
  std::vector<Eigen::Isometry3d> object_from_world(scene.cars.size());
  for (size_t c = 0; c < scene.cars.size(); ++c) {
    object_from_world[c] = WorldFromObject(scene.cars[c].states[frame]).inverse();
  }
  const int num_statics = int(scene.statics.size());
  cv::Mat image(camera.height, camera.width, CV_8UC3);
  // Rows in parallel; each row has its own noise stream, so the result does not
  // depend on the scheduling.
  tbb::parallel_for(0, camera.height, [&](int v) {
    std::mt19937_64 noise_engine(Mix(noise_seed, uint64_t(v)));
    std::normal_distribution<double> noise(0.0, 1.0);
    for (int u = 0; u < camera.width; ++u) {
      const size_t pixel = size_t(v) * camera.width + u;
      const int index = buffers.mesh_index[pixel];
      Eigen::Vector3d radiance;
      if (index < 0) {
        radiance = Eigen::Vector3d(0.70, 0.80, 0.95) * (1.0 - 0.25 * double(v) / camera.height);
      } else {
        const Eigen::Vector3d ray = camera.Ray(u, v);
        const Eigen::Vector3d point_in_camera = ray * double(buffers.depth[pixel]);
        const Eigen::Vector3d point = world_from_camera * point_in_camera;
        const Eigen::Vector3d normal = rotation * buffers.normal[pixel].cast<double>();
        const Eigen::Vector3d view = -(rotation * ray.normalized());  // towards the camera
        const double cos_incidence = std::max(0.2, std::abs(normal.dot(view)));
        const double footprint = buffers.depth[pixel] * ray.norm() / camera.fx / cos_incidence;
        const double diffuse = std::max(0.0, normal.dot(sun));
        if (index >= num_statics) {
          const SceneCar& car = scene.cars[index - num_statics];
          const Eigen::Vector3d p_object = object_from_world[index - num_statics] * point;
          Eigen::Vector3d albedo = car.paint;
          double specular_strength = 0.35;
          if (p_object.y() > -0.30) {  // tyres, bumpers, underbody
            albedo = Eigen::Vector3d(0.04, 0.04, 0.045);
            specular_strength = 0.05;
          } else if (p_object.y() < -0.62 * car.height && normal.y() > -0.9) {  // windows
            albedo = Eigen::Vector3d(0.06, 0.07, 0.09);
            specular_strength = 0.6;
          }
          const Eigen::Vector3d half = (sun + view).normalized();
          const double specular = specular_strength * std::pow(std::max(0.0, normal.dot(half)), 40.0);
          radiance = albedo * (0.3 + 0.7 * diffuse) + Eigen::Vector3d::Constant(specular);
        } else {
          const StaticMesh& m = scene.statics[index];
          Eigen::Vector3d albedo;
          switch (m.material) {
            case MaterialKind::kRoad:
              albedo = procedural::RoadAlbedo(point, kRoadHalfWidth, kLaneWidth, footprint, m.seed);
              break;
            case MaterialKind::kFacade:
              if (std::abs(normal.y()) > 0.7) {
                albedo = procedural::BlotchAlbedo(point, m.color, footprint, m.seed);
              } else {
                const double along = std::abs(normal.x()) > std::abs(normal.z()) ? point.z() : point.x();
                albedo = procedural::FacadeAlbedo(along, options.camera_height - point.y(), m.color,
                                                  footprint, m.seed);
              }
              break;
            default:
              albedo = procedural::BlotchAlbedo(point, m.color, footprint, m.seed);
              break;
          }
          radiance = albedo * (0.4 + 0.7 * diffuse);
        }
      }
      cv::Vec3b& out = image.at<cv::Vec3b>(v, u);
      for (int c = 0; c < 3; ++c) {
        const double value = 255.0 * std::pow(std::clamp(radiance[c], 0.0, 1.0), 1.0 / 2.2) +
                             options.image_noise_sigma * noise(noise_engine);
        out[2 - c] = cv::saturate_cast<uint8_t>(std::lround(value));
      }
    }
  });
  return image;
}

// Shading of one street view (normals in the world frame, as RenderFromScene
// gives them) into an 8-bit BGR image: street textures, car paint with clear
// coat (sun highlight, Fresnel sky reflection), dark glass, tyres, sun shadows
// cast by everything, contact shadows under the cars, sky where nothing is hit.
cv::Mat ShadeStreetView(const SynthOptions& options, const Scene& scene, int frame,
                        const Eigen::Isometry3d& world_from_camera, const PinholeCamera& camera,
                        const RenderBuffers& buffers, const EmbreeScene& embree, uint64_t noise_seed) {
  const Eigen::Matrix3d rotation = world_from_camera.linear();
  const size_t num_pixels = size_t(camera.width) * camera.height;
  const int num_statics = int(scene.statics.size());
  std::vector<Eigen::Isometry3d> object_from_world(scene.cars.size());
  for (size_t c = 0; c < scene.cars.size(); ++c) {
    object_from_world[c] = WorldFromObject(scene.cars[c].states[frame]).inverse();
  }
  std::vector<Eigen::Vector3f> points(num_pixels), normals(num_pixels, Eigen::Vector3f::Zero());
  tbb::parallel_for(0, camera.height, [&](int v) {
    for (int u = 0; u < camera.width; ++u) {
      const size_t pixel = size_t(v) * camera.width + u;
      if (buffers.mesh_index[pixel] < 0) continue;
      points[pixel] = (world_from_camera * (camera.Ray(u, v) * double(buffers.depth[pixel]))).cast<float>();
      normals[pixel] = buffers.normal[pixel];
    }
  });
  std::vector<uint8_t> sun_visible;
  if (options.shadows) {
    sun_visible = LightVisibility(embree, points, normals, scene.lighting.to_sun.cast<float>(), 0.01f);
  } else {
    sun_visible.assign(num_pixels, 1);
  }
  const OutdoorLighting& lighting = scene.lighting;
  cv::Mat image(camera.height, camera.width, CV_8UC3);
  tbb::parallel_for(0, camera.height, [&](int v) {
    std::mt19937_64 noise_engine(Mix(noise_seed, uint64_t(v)));
    std::normal_distribution<double> noise(0.0, 1.0);
    for (int u = 0; u < camera.width; ++u) {
      const size_t pixel = size_t(v) * camera.width + u;
      const int index = buffers.mesh_index[pixel];
      const Eigen::Vector3d ray = camera.Ray(u, v);
      const Eigen::Vector3d view = -(rotation * ray.normalized());  // towards the camera
      Eigen::Vector3d radiance;
      if (index < 0) {
        radiance = lighting.Environment(-view);
      } else {
        const Eigen::Vector3d point = points[pixel].cast<double>();
        const Eigen::Vector3d normal = normals[pixel].cast<double>();
        const double cos_incidence = std::max(0.2, std::abs(normal.dot(view)));
        const double footprint = buffers.depth[pixel] * ray.norm() / camera.fx / cos_incidence;
        const double sun = sun_visible[pixel];
        SurfaceMaterial material;
        double occlusion = 1.0;
        if (index >= num_statics) {
          const int c = index - num_statics;
          const SceneCar& car = scene.cars[c];
          const Eigen::Vector3d p_object = object_from_world[c] * point;
          const Eigen::Vector3d n_object = object_from_world[c].linear() * normal;
          const int body_triangles = car.car->num_body_triangles;
          const bool wheel = body_triangles >= 0 && buffers.triangle[pixel] >= body_triangles;
          if (wheel) {
            // Tyre, with a grey rim towards the hub (the part facing sideways, away from the tread).
            const bool rim = std::abs(n_object.z()) > 0.8 && p_object.y() < -0.12 && p_object.y() > -0.55;
            material.albedo = rim ? Eigen::Vector3d(0.35, 0.35, 0.36) : Eigen::Vector3d(0.03, 0.03, 0.03);
            material.specular = rim ? 0.3 : 0.02;
            material.shininess = 20.0;
          } else if (p_object.y() > -0.28) {  // bumpers, sills, underbody, open wheel arches
            material.albedo = Eigen::Vector3d(0.035, 0.035, 0.04);
            material.specular = 0.05;
            material.shininess = 20.0;
          } else if (p_object.y() < -0.62 * car.height && std::abs(n_object.y()) < 0.85) {  // windows
            // Tinted glass; what lies behind it (seats, headrests, the far windows) is
            // drawn on the glass plane as a blotchy grey of mean window_interior_albedo.
            const double interior =
                procedural::Fractal(p_object, 5.0, 4, footprint, Mix(uint64_t(car.track_id), 91));
            material.albedo = Eigen::Vector3d(0.02, 0.025, 0.03) +
                              Eigen::Vector3d::Constant(options.window_interior_albedo *
                                                        std::max(0.0, 1.0 + 2.5 * interior));
            material.specular = 1.2;
            material.shininess = 250.0;
            material.fresnel_f0 = options.glass_fresnel_f0;
          } else {  // paint: weak texture (dirt, orange peel) under a clear coat
            const double grain = procedural::Fractal(p_object, 6.0, 4, footprint, Mix(uint64_t(car.track_id), 77));
            material.albedo = car.paint * (1.0 + 2.0 * options.paint_texture * grain);
            material.specular = options.paint_specular * (car.metallic ? 1.3 : 1.0);
            material.shininess = car.metallic ? 0.5 * options.paint_shininess : options.paint_shininess;
            material.fresnel_f0 = options.paint_fresnel_f0;
          }
        } else {
          const StaticMesh& m = scene.statics[index];
          const StreetObject& object = scene.street_objects[m.street_index];
          material.albedo = StreetAlbedo(object, scene.layout, point, normal, footprint);
          if (object.material == StreetMaterial::kPole || object.material == StreetMaterial::kSign) {
            material.specular = 0.3;
            material.shininess = 30.0;
          }
          if (object.material == StreetMaterial::kAsphalt) {
            // Contact shadow under the cars (sky light blocked), fading over 0.5 m outside the footprint.
            for (size_t c = 0; c < scene.cars.size(); ++c) {
              const Eigen::Vector3d q = object_from_world[c] * point;
              const double ox = std::abs(q.x()) - 0.5 * scene.cars[c].length;
              const double oz = std::abs(q.z()) - 0.5 * scene.cars[c].width;
              const double outside = std::max(ox, oz);
              if (outside < 0.5) occlusion = std::min(occlusion, 0.25 + 0.75 * std::clamp(outside / 0.5, 0.0, 1.0));
            }
          }
        }
        radiance = ShadeSurface(material, normal, view, lighting, sun, occlusion);
      }
      cv::Vec3b& out = image.at<cv::Vec3b>(v, u);
      for (int c = 0; c < 3; ++c) {
        const double value = 255.0 * std::pow(std::clamp(scene.exposure * radiance[c], 0.0, 1.0), 1.0 / 2.2) +
                             options.image_noise_sigma * noise(noise_engine);
        out[2 - c] = cv::saturate_cast<uint8_t>(std::lround(value));
      }
    }
  });
  return image;
}

void WriteImage(const std::string& path, const cv::Mat& image) {
  WriteFileAtomically(path, [&](const std::string& temporary) {
    SAMP_CHECK(cv::imwrite(temporary, image)) << "cannot write image " << path;
  });
}

// The 3D box label of a car in the camera of one frame, 2D box from its projected vertices.
// Returns false when no vertex lies in front of the camera or the box misses the image.
bool MakeLabel(const SceneCar& car, int frame, const Eigen::Isometry3d& camera_from_world,
               const PinholeCamera& camera, ObjectLabel* label) {
  const Eigen::Isometry3d camera_from_object =
      camera_from_world * WorldFromObject(car.states[frame]);
  AlignedBox box;
  for (const Eigen::Vector3f& vertex : car.car->mesh.vertices) {
    const Eigen::Vector3d p = camera_from_object * vertex.cast<double>();
    if (p.z() < 0.1) continue;
    const Eigen::Vector2d uv = camera.Project(p);
    box.Extend(Eigen::Vector3d(uv.x(), uv.y(), 0.0));
  }
  if (box.IsEmpty()) return false;
  const double x1 = std::clamp(box.min.x(), 0.0, camera.width - 1.0);
  const double y1 = std::clamp(box.min.y(), 0.0, camera.height - 1.0);
  const double x2 = std::clamp(box.max.x(), 0.0, camera.width - 1.0);
  const double y2 = std::clamp(box.max.y(), 0.0, camera.height - 1.0);
  if (x2 <= x1 || y2 <= y1) return false;
  const double full_area = std::max(1e-9, (box.max.x() - box.min.x()) * (box.max.y() - box.min.y()));
  label->frame = frame;
  label->track_id = car.track_id;
  label->type = "Car";
  label->truncation = std::clamp(1.0 - (x2 - x1) * (y2 - y1) / full_area, 0.0, 1.0);
  label->occlusion = 0;
  label->box_2d = Eigen::Vector4d(x1, y1, x2, y2);
  label->height = car.height;
  label->width = car.width;
  label->length = car.length;
  label->position = camera_from_object.translation();
  const Eigen::Vector3d x_axis = camera_from_object.linear().col(0);
  label->rotation_y = std::atan2(-x_axis.z(), x_axis.x());
  label->alpha = WrapAngle(label->rotation_y - std::atan2(label->position.x(), label->position.z()));
  label->score = 1.0;
  return true;
}

cv::Mat TrueDisparityWithNoise(const SynthOptions& options, const RenderBuffers& left,
                               int num_statics, uint64_t noise_seed) {
  Random rng(noise_seed);
  const double fb = options.focal_px * options.baseline;
  cv::Mat disparity(left.height, left.width, CV_32FC1, cv::Scalar(0.f));
  for (int v = 0; v < left.height; ++v) {
    for (int u = 0; u < left.width; ++u) {
      const size_t pixel = size_t(v) * left.width + u;
      const float z = left.depth[pixel];
      if (!std::isfinite(z) || z <= 0.f) continue;
      const double truth = fb / z;
      double value;
      const double draw = rng.Uniform(0.0, 1.0);
      if (draw < options.invalid_fraction) {
        value = 0.0;
      } else if (draw < options.invalid_fraction + options.outlier_fraction) {
        value = rng.Uniform(0.5, std::min(255.0, std::max(2.0, 2.0 * truth)));
      } else {
        const bool on_car = left.mesh_index[pixel] >= num_statics;
        value = truth + rng.Normal(on_car ? options.car_disparity_sigma_px : options.disparity_sigma_px);
      }
      if (value < 0.5 || value >= 255.9) value = 0.0;  // below 0.5 px: invalid (z > 770 m)
      disparity.at<float>(v, u) = float(value);
    }
  }
  return disparity;
}

SynthSequenceInfo WriteSequence(const SynthOptions& options, const Scene& scene, int sequence_index,
                                Progress* progress) {
  const PinholeCamera camera = MakeCamera(options);
  SynthSequenceInfo info;
  char name[16];
  std::snprintf(name, sizeof(name), "%06d", options.first_sequence + sequence_index);
  info.name = name;
  info.folder = (fs::path(options.output_folder) / info.name).string();
  info.num_cars = int(scene.cars.size());
  const std::string seq = info.name;
  const SequenceLayout layout(info.folder, seq);
  const uint64_t seed = Mix(options.seed, uint64_t(sequence_index));

  StereoCalibration calibration;
  calibration.camera = camera;
  calibration.baseline = options.baseline;
  WriteCalibration(layout.Calibration(), calibration);
  // Poses are written relative to frame 0 (KITTI: frame 0 = identity); the
  // rendering frame differs from it by the sway of frame 0 (kStreet).
  const Eigen::Isometry3d output_from_world = scene.world_from_camera[0].inverse();
  std::vector<Eigen::Isometry3d> output_poses;
  for (const Eigen::Isometry3d& pose : scene.world_from_camera) output_poses.push_back(output_from_world * pose);
  WritePoses(layout.Poses(), output_poses);

  // Ground-truth meshes (object frame) and car descriptions.
  nlohmann::json cars_json = nlohmann::json::array();
  for (const SceneCar& car : scene.cars) {
    WritePly(layout.GroundTruthMesh(car.track_id),
             car.car->mesh);
    nlohmann::json entry = {{"track_id", car.track_id},
                            {"car", car.car->name},
                            {"motion", MotionName(car.motion)},
                            {"speed", car.speed},
                            {"yaw_rate", car.yaw_rate},
                            {"paint", car.paint_name},
                            {"length", car.length},
                            {"height", car.height},
                            {"width", car.width},
                            {"distance_at_middle_frame", car.target_distance}};
    if (scene.street) entry["parked"] = car.parked;
    cars_json.push_back(entry);
  }

  std::vector<PlacedMesh> placed(scene.statics.size() + scene.cars.size());
  const int num_statics = int(scene.statics.size());
  std::vector<ObjectLabel> gt_labels;
  StereoOptions stereo_options;
  StereoDetectorModel detector(options.detector, Mix(seed, 5000));
  double disparity_error_sum = 0.0;
  int64_t disparity_valid = 0, car_pixels = 0;
  const double fb = options.focal_px * options.baseline;
  for (int t = 0; t < options.num_frames; ++t) {
    const Eigen::Isometry3d camera_from_world = scene.world_from_camera[t].inverse();
    Eigen::Isometry3d right_from_left = Eigen::Isometry3d::Identity();
    right_from_left.translation() = Eigen::Vector3d(-options.baseline, 0.0, 0.0);
    RenderBuffers left_buffers, right_buffers;
    cv::Mat left_image, right_image;
    if (scene.street) {
      // One world-frame scene per frame for both cameras and the shadow rays.
      std::vector<Mesh> car_meshes(scene.cars.size());
      std::vector<const Mesh*> meshes;
      for (const StaticMesh& m : scene.statics) meshes.push_back(&m.mesh);
      for (size_t c = 0; c < scene.cars.size(); ++c) {
        car_meshes[c] = scene.cars[c].car->mesh;
        car_meshes[c].Transform(Eigen::Affine3d(WorldFromObject(scene.cars[c].states[t])));
        meshes.push_back(&car_meshes[c]);
      }
      const EmbreeScene embree(meshes);
      const Eigen::Isometry3d world_from_right = scene.world_from_camera[t] * right_from_left.inverse();
      left_buffers = RenderFromScene(embree, camera, scene.world_from_camera[t]);
      right_buffers = RenderFromScene(embree, camera, world_from_right);
      left_image = ShadeStreetView(options, scene, t, scene.world_from_camera[t], camera, left_buffers, embree,
                                   Mix(seed, uint64_t(1000 + 2 * t)));
      right_image = ShadeStreetView(options, scene, t, world_from_right, camera, right_buffers, embree,
                                    Mix(seed, uint64_t(1001 + 2 * t)));
    } else {
      std::vector<PlacedMesh> right(placed.size());
      for (int i = 0; i < num_statics; ++i) {
        placed[i].mesh = &scene.statics[i].mesh;
        placed[i].camera_from_object = camera_from_world;
      }
      for (size_t c = 0; c < scene.cars.size(); ++c) {
        placed[num_statics + c].mesh = &scene.cars[c].car->mesh;
        placed[num_statics + c].camera_from_object =
            camera_from_world * WorldFromObject(scene.cars[c].states[t]);
      }
      for (size_t i = 0; i < placed.size(); ++i) {
        right[i].mesh = placed[i].mesh;
        right[i].camera_from_object = right_from_left * placed[i].camera_from_object;
      }
      left_buffers = Render(camera, placed);
      right_buffers = Render(camera, right);
      left_image = ShadeView(options, scene, t, scene.world_from_camera[t], camera, left_buffers,
                             Mix(seed, uint64_t(1000 + 2 * t)));
      right_image = ShadeView(options, scene, t, scene.world_from_camera[t] * right_from_left.inverse(), camera,
                              right_buffers, Mix(seed, uint64_t(1001 + 2 * t)));
    }
    WriteImage(layout.LeftImage(t), left_image);
    WriteImage(layout.RightImage(t), right_image);

    // Ground truth: depth (uint16, 1/256 m) and object map (uint8, track_id + 1).
    cv::Mat depth(camera.height, camera.width, CV_16UC1, cv::Scalar(0));
    cv::Mat object_map(camera.height, camera.width, CV_8UC1, cv::Scalar(0));
    std::vector<int> visible(scene.cars.size(), 0);
    for (int v = 0; v < camera.height; ++v) {
      for (int u = 0; u < camera.width; ++u) {
        const size_t pixel = size_t(v) * camera.width + u;
        const float z = left_buffers.depth[pixel];
        if (std::isfinite(z) && z > 0.f && z < 255.99f) {
          depth.at<uint16_t>(v, u) = uint16_t(std::lround(double(z) * 256.0));
        }
        const int index = left_buffers.mesh_index[pixel];
        if (index >= num_statics) {
          const int car = index - num_statics;
          object_map.at<uint8_t>(v, u) = uint8_t(scene.cars[car].track_id + 1);
          ++visible[car];
        }
      }
    }
    WriteImage(layout.GroundTruthDepth(t), depth);
    WriteImage(layout.GroundTruthObjectMap(t), object_map);

    cv::Mat disparity;
    if (options.disparity == DisparitySource::kStereoSgbm) {
      disparity = ComputeDisparity(left_image, right_image, stereo_options);
    } else {
      disparity = TrueDisparityWithNoise(options, left_buffers, num_statics,
                                         Mix(seed, uint64_t(3000 + t)));
    }
    // Disparity quality on the car pixels (what the stereo baseline and the fitter see).
    for (int v = 0; v < camera.height; ++v) {
      for (int u = 0; u < camera.width; ++u) {
        const size_t pixel = size_t(v) * camera.width + u;
        if (left_buffers.mesh_index[pixel] < num_statics) continue;
        ++car_pixels;
        const float d = disparity.at<float>(v, u);
        if (!(d > 0.f)) continue;
        ++disparity_valid;
        disparity_error_sum += std::abs(double(d) - fb / double(left_buffers.depth[pixel]));
      }
    }
    WriteDisparity(layout.Disparity(t), disparity);
    // The road plane n . x + d = 0 (n = (0, -1, 0), d = camera height in the
    // rendering frame) in this frame's camera.
    const Eigen::Vector3d n_world(0.0, -1.0, 0.0);
    const Eigen::Vector3d n_camera = scene.world_from_camera[t].linear().transpose() * n_world;
    const double d_camera = options.camera_height + n_world.dot(scene.world_from_camera[t].translation());
    WritePlane(layout.Plane(t),
               Eigen::Vector4d(n_camera.x(), n_camera.y(), n_camera.z(), d_camera));

    std::vector<ObjectLabel> detections;
    for (size_t c = 0; c < scene.cars.size(); ++c) {
      ObjectLabel truth;
      if (visible[c] == 0 || !MakeLabel(scene.cars[c], t, camera_from_world, camera, &truth)) continue;
      gt_labels.push_back(truth);
      ObjectLabel det;
      if (detector.Detect(scene.cars[c].track_id, t, truth, visible[c], camera, &det)) detections.push_back(det);
    }
    if (!scene.clutter.empty()) {
      std::vector<ClutterCandidate> candidates = scene.clutter;
      for (size_t i = 0; i < candidates.size(); ++i) {
        PlanarState state;
        state.position = scene.clutter[i].position;
        state.heading = scene.clutter_heading[i];
        const Eigen::Isometry3d camera_from_object = camera_from_world * WorldFromObject(state);
        candidates[i].position = camera_from_object.translation();
        const Eigen::Vector3d x_axis = camera_from_object.linear().col(0);
        candidates[i].rotation_y = std::atan2(-x_axis.z(), x_axis.x());
      }
      const std::vector<ObjectLabel> false_positives = detector.FalsePositives(t, candidates, camera);
      info.num_false_positives += int(false_positives.size());
      detections.insert(detections.end(), false_positives.begin(), false_positives.end());
    }
    info.num_detections += int(detections.size());
    WriteLabels(layout.Detections(t), detections);
    if (progress) progress->Tick();
  }
  info.num_gt_labels = int(gt_labels.size());
  info.car_pixels = car_pixels;
  info.car_disparity_mae_px = disparity_valid > 0 ? disparity_error_sum / double(disparity_valid) : 0.0;
  info.car_disparity_valid_fraction = car_pixels > 0 ? double(disparity_valid) / double(car_pixels) : 0.0;
  WriteTrackingLabels(layout.GroundTruthLabels(), gt_labels);
  nlohmann::json scene_json = {{"sequence", seq},
                               {"seed", options.seed},
                               {"scene", scene.street ? "street" : "clean"},
                               {"ego_speed", scene.ego_speed},
                               {"ego_yaw_rate", scene.ego_yaw_rate},
                               {"frame_rate_hz", options.frame_rate_hz},
                               {"num_frames", options.num_frames},
                               {"depth_png", "uint16, depth_m = value / 256, 0 = no surface"},
                               {"obj_map_png", "uint8, 0 = background, track_id + 1 = car"},
                               {"car_disparity_mae_px", info.car_disparity_mae_px},
                               {"car_disparity_valid_fraction", info.car_disparity_valid_fraction},
                               {"num_false_positives", info.num_false_positives},
                               {"cars", cars_json}};
  if (scene.street) {
    constexpr double kDeg = 180.0 / kPi;
    scene_json["street"] = {{"lanes_per_direction", scene.layout.lanes_per_direction},
                            {"lane_width", scene.layout.lane_width},
                            {"parking_lanes", scene.layout.parking.size()},
                            {"intersection", scene.layout.has_intersection},
                            {"intersection_z", scene.layout.intersection_z},
                            {"sun_elevation_deg", std::asin(-scene.lighting.to_sun.y()) * kDeg},
                            {"ego_pitch_sway_deg", scene.sway.pitch_amplitude * kDeg},
                            {"ego_roll_sway_deg", scene.sway.roll_amplitude * kDeg},
                            {"ego_pitch_offset_deg", scene.sway.pitch_offset * kDeg}};
  }
  WriteTextFileAtomically(layout.GroundTruthCars(), DumpJson(scene_json, 2) + "\n");
  return info;
}

}  // namespace

void SynthCarSource::Check() const {
  SAMP_CHECK(!cad_folder.empty() || !canonical_meshes.empty())
      << "synth: give a CAD folder or canonical meshes (cad_folder and canonical_meshes are both empty)";
  SAMP_CHECK(manifest_path.empty() || !cad_folder.empty())
      << "synth: manifest_path needs cad_folder";
}

std::vector<SynthCar> LoadSynthCars(const SynthCarSource& source) {
  source.Check();
  std::vector<SynthCar> cars;
  std::set<std::string> wanted;
  for (const std::string& name : source.only) wanted.insert(Lower(name));
  std::set<std::string> found;
  if (!source.cad_folder.empty()) {
    SAMP_CHECK(fs::is_directory(source.cad_folder)) << "synth: CAD folder " << source.cad_folder
                                                    << " does not exist";
    Manifest manifest;
    if (!source.manifest_path.empty()) manifest = LoadManifest(source.manifest_path);
    std::vector<CadFile> files = ListCadFiles(source.cad_folder, &manifest);
    std::sort(files.begin(), files.end(), [](const CadFile& a, const CadFile& b) {
      return fs::path(a.path) < fs::path(b.path);  // the order of fs::path, as before
    });
    for (const CadFile& file : files) {
      const std::string& relative = file.relative_path;
      const ManifestEntry* entry = file.entry;
      const std::string& name = file.name;
      const std::string stem = fs::path(file.path).stem().string();
      const bool selected = wanted.empty() || wanted.count(Lower(name)) || wanted.count(Lower(stem));
      if (!selected) continue;
      if (entry && entry->skip && !(source.ignore_skip_for_only && !wanted.empty())) {
        LogDebug() << "synth: skipping " << relative << " (manifest: " << entry->skip_reason << ")";
        continue;
      }
      const Mesh cad_mesh = LoadMesh(file.path);
      const CanonicalizeResult result = Canonicalize(cad_mesh, file.canonicalize);
      for (const std::string& warning : result.warnings) {
        LogWarning() << "synth: " << relative << ": " << warning;
      }
      // Canonicalize appends the synthesised tyres after the body's triangles.
      cars.push_back({name, result.mesh, result.wheels_added ? int(cad_mesh.triangles.size()) : -1});
      if (result.wheels_added) LogDebug() << "synth: " << name << ": " << result.wheels.BriefReport();
      found.insert(Lower(name));
      found.insert(Lower(stem));
    }
  }
  for (const std::string& path : source.canonical_meshes) {
    SynthCar car{fs::path(path).stem().string(), LoadMesh(path)};
    const Eigen::Vector3d size = car.mesh.Bounds().Size();
    SAMP_CHECK(size.x() > 1.0 && size.x() < 10.0 && size.y() > 0.5 && size.z() > 0.5)
        << "synth: " << path << " does not look like a canonical car (extent " << size.transpose()
        << " m; expected x = length, y = height, z = width in metres)";
    found.insert(Lower(car.name));
    cars.push_back(std::move(car));
  }
  for (const std::string& name : wanted) {
    SAMP_CHECK(found.count(name)) << "synth: car '" << name << "' was not found in "
                                  << source.cad_folder;
  }
  SAMP_CHECK(!cars.empty()) << "synth: no car to use (all skipped or none found)";
  std::sort(cars.begin(), cars.end(), [](const SynthCar& a, const SynthCar& b) { return a.name < b.name; });
  return cars;
}

SynthOptions SynthOptions::Clean() {
  SynthOptions o;
  o.scene = SynthScene::kClean;
  o.parked_cars_per_sequence = 0;
  o.max_ego_speed = 8.0;
  o.max_ego_yaw_rate = 0.04;
  o.ego_pitch_sway_deg = o.ego_roll_sway_deg = o.ego_bounce = o.ego_max_pitch_offset_deg = 0.0;
  o.image_noise_sigma = 2.0;  // the first benchmark's image noise (the street default is 0.7)
  // The first benchmark's detections: 3DOP-like, white, no false positives.
  DetectorModelOptions& d = o.detector;
  d.ray_sigma_a = 0.1;
  d.ray_sigma_b = 0.0;
  d.ray_sigma_c = 0.001;
  d.lateral_sigma_a = 0.05;
  d.lateral_sigma_b = 0.005;
  d.vertical_sigma = 0.05;
  d.size_sigma = 0.0;
  d.relative_size_sigma = 0.05;
  d.yaw_sigma_deg_a = 3.0;
  d.yaw_sigma_deg_b = 0.15;
  d.flip_probability = 0.08;
  d.flip_mean_run_frames = 0.0;
  d.miss_probability = 0.05;
  d.miss_mean_run_frames = 0.0;
  d.correlation_frames = 0.0;
  d.false_positives_per_frame = 0.0;
  return o;
}

void SynthOptions::Check() const {
  SAMP_CHECK(!output_folder.empty()) << "synth: output_folder is empty";
  SAMP_CHECK(num_sequences >= 1) << "synth: num_sequences must be >= 1";
  SAMP_CHECK(first_sequence >= 0 && first_sequence + num_sequences <= 1000000)
      << "synth: first_sequence must be in [0, 999999 - num_sequences]";
  SAMP_CHECK(cars_per_sequence >= 1 && cars_per_sequence <= 20) << "synth: cars_per_sequence must be in [1, 20]";
  SAMP_CHECK(num_frames >= 1 && num_frames <= 100) << "synth: num_frames must be in [1, 100]";
  SAMP_CHECK(frame_rate_hz > 0) << "synth: frame_rate_hz must be > 0";
  SAMP_CHECK(width >= 32 && height >= 32) << "synth: image size must be at least 32 x 32";
  SAMP_CHECK(focal_px > 0 && baseline > 0) << "synth: focal_px and baseline must be > 0";
  SAMP_CHECK(cx_px > 0 && cx_px < width && cy_px > 0 && cy_px < height)
      << "synth: the principal point must lie inside the image";
  SAMP_CHECK(camera_height > 0.5) << "synth: camera_height must be > 0.5 m";
  SAMP_CHECK(min_distance >= 4.0 && max_distance > min_distance && max_distance <= 150.0)
      << "synth: need 4 <= min_distance < max_distance <= 150";
  SAMP_CHECK(min_speed > 0 && max_speed >= min_speed) << "synth: need 0 < min_speed <= max_speed";
  SAMP_CHECK(min_turn_speed > 0 && max_turn_speed >= min_turn_speed)
      << "synth: need 0 < min_turn_speed <= max_turn_speed";
  SAMP_CHECK(min_yaw_rate > 0 && max_yaw_rate >= min_yaw_rate)
      << "synth: need 0 < min_yaw_rate <= max_yaw_rate";
  SAMP_CHECK(min_ego_speed >= 0 && max_ego_speed >= min_ego_speed)
      << "synth: need 0 <= min_ego_speed <= max_ego_speed";
  SAMP_CHECK(max_ego_yaw_rate >= 0) << "synth: max_ego_yaw_rate must be >= 0";
  SAMP_CHECK(image_noise_sigma >= 0) << "synth: image_noise_sigma must be >= 0";
  SAMP_CHECK(disparity_sigma_px >= 0 && car_disparity_sigma_px >= 0)
      << "synth: disparity noise must be >= 0";
  SAMP_CHECK(invalid_fraction >= 0 && outlier_fraction >= 0 && invalid_fraction + outlier_fraction <= 1)
      << "synth: invalid_fraction and outlier_fraction must be >= 0 with sum <= 1";
  SAMP_CHECK(parked_cars_per_sequence >= 0 && parked_cars_per_sequence <= 12)
      << "synth: parked_cars_per_sequence must be in [0, 12]";
  SAMP_CHECK(near_share >= 0 && near_share <= 1) << "synth: near_share must lie in [0, 1]";
  SAMP_CHECK(standing_share >= 0 && turning_share >= 0 && standing_share + turning_share <= 1)
      << "synth: standing_share and turning_share must be >= 0 with sum <= 1";
  SAMP_CHECK(ego_pitch_sway_deg >= 0 && ego_roll_sway_deg >= 0 && ego_bounce >= 0 && ego_max_pitch_offset_deg >= 0)
      << "synth: ego sway amplitudes must be >= 0";
  SAMP_CHECK(min_sun_elevation_deg > 0 && max_sun_elevation_deg >= min_sun_elevation_deg &&
             max_sun_elevation_deg <= 90)
      << "synth: need 0 < min_sun_elevation_deg <= max_sun_elevation_deg <= 90";
  SAMP_CHECK(paint_specular >= 0 && paint_shininess >= 1 && paint_fresnel_f0 >= 0 && paint_fresnel_f0 < 1 &&
             glass_fresnel_f0 >= 0 && glass_fresnel_f0 < 1 && paint_texture >= 0 && window_interior_albedo >= 0 &&
             window_interior_albedo <= 0.5)
      << "synth: need paint_specular >= 0, paint_shininess >= 1, 0 <= paint/glass F0 < 1, paint_texture >= 0, "
         "0 <= window_interior_albedo <= 0.5";
  street.Check();
  detector.Check();
}

std::string SynthOptions::ToJson() const {
  nlohmann::json j = {
      {"seed", seed},
      {"num_sequences", num_sequences},
      {"first_sequence", first_sequence},
      {"cars_per_sequence", cars_per_sequence},
      {"num_frames", num_frames},
      {"frame_rate_hz", frame_rate_hz},
      {"width", width},
      {"height", height},
      {"focal_px", focal_px},
      {"cx_px", cx_px},
      {"cy_px", cy_px},
      {"baseline", baseline},
      {"camera_height", camera_height},
      {"min_distance", min_distance},
      {"max_distance", max_distance},
      {"min_speed", min_speed},
      {"max_speed", max_speed},
      {"min_turn_speed", min_turn_speed},
      {"max_turn_speed", max_turn_speed},
      {"min_yaw_rate", min_yaw_rate},
      {"max_yaw_rate", max_yaw_rate},
      {"min_ego_speed", min_ego_speed},
      {"max_ego_speed", max_ego_speed},
      {"max_ego_yaw_rate", max_ego_yaw_rate},
      {"image_noise_sigma", image_noise_sigma},
      {"disparity", disparity == DisparitySource::kStereoSgbm ? "sgbm" : "true+noise"},
      {"disparity_sigma_px", disparity_sigma_px},
      {"car_disparity_sigma_px", car_disparity_sigma_px},
      {"invalid_fraction", invalid_fraction},
      {"outlier_fraction", outlier_fraction},
      {"scene", scene == SynthScene::kStreet ? "street" : "clean"},
      {"parked_cars_per_sequence", parked_cars_per_sequence},
      {"near_share", near_share},
      {"standing_share", standing_share},
      {"turning_share", turning_share},
      {"ego_pitch_sway_deg", ego_pitch_sway_deg},
      {"ego_roll_sway_deg", ego_roll_sway_deg},
      {"ego_bounce", ego_bounce},
      {"ego_max_pitch_offset_deg", ego_max_pitch_offset_deg},
      {"min_sun_elevation_deg", min_sun_elevation_deg},
      {"max_sun_elevation_deg", max_sun_elevation_deg},
      {"paint_specular", paint_specular},
      {"paint_shininess", paint_shininess},
      {"paint_fresnel_f0", paint_fresnel_f0},
      {"glass_fresnel_f0", glass_fresnel_f0},
      {"paint_texture", paint_texture},
      {"window_interior_albedo", window_interior_albedo},
      {"shadows", shadows},
      {"street",
       {{"two_lane_probability", street.two_lane_probability},
        {"min_lane_width", street.min_lane_width},
        {"max_lane_width", street.max_lane_width},
        {"right_parking_probability", street.right_parking_probability},
        {"left_parking_probability", street.left_parking_probability},
        {"kerb_height", street.kerb_height},
        {"min_sidewalk_width", street.min_sidewalk_width},
        {"max_sidewalk_width", street.max_sidewalk_width},
        {"min_facade_distance", street.min_facade_distance},
        {"max_facade_distance", street.max_facade_distance},
        {"clutter_spacing", street.clutter_spacing},
        {"intersection_probability", street.intersection_probability},
        {"min_parked_gap", street.min_parked_gap},
        {"max_parked_gap", street.max_parked_gap}}},
      {"detector",
       {{"ray_sigma_a", detector.ray_sigma_a},
        {"ray_sigma_b", detector.ray_sigma_b},
        {"ray_sigma_c", detector.ray_sigma_c},
        {"lateral_sigma_a", detector.lateral_sigma_a},
        {"lateral_sigma_b", detector.lateral_sigma_b},
        {"vertical_sigma", detector.vertical_sigma},
        {"size_sigma", detector.size_sigma},
        {"relative_size_sigma", detector.relative_size_sigma},
        {"yaw_sigma_deg_a", detector.yaw_sigma_deg_a},
        {"yaw_sigma_deg_b", detector.yaw_sigma_deg_b},
        {"flip_probability", detector.flip_probability},
        {"flip_mean_run_frames", detector.flip_mean_run_frames},
        {"miss_probability", detector.miss_probability},
        {"miss_mean_run_frames", detector.miss_mean_run_frames},
        {"correlation_frames", detector.correlation_frames},
        {"false_positives_per_frame", detector.false_positives_per_frame},
        {"false_positive_mean_run_frames", detector.false_positive_mean_run_frames},
        {"box_sigma_px", detector.box_sigma_px},
        {"min_pixels", detector.min_pixels}}}};
  return DumpJson(j, 2);
}

std::string SynthSummary::BriefReport() const {
  std::ostringstream out;
  out << "synth: " << sequences.size() << " sequences, " << num_tracks << " tracks (" << num_standing
      << " standing of which " << num_parked << " parked, " << num_straight << " straight, " << num_turning
      << " turning)";
  int detections = 0, labels = 0, false_positives = 0;
  for (const SynthSequenceInfo& s : sequences) {
    detections += s.num_detections;
    labels += s.num_gt_labels;
    false_positives += s.num_false_positives;
  }
  char disparity[160];
  std::snprintf(disparity, sizeof(disparity),
                "; disparity on car pixels: mean abs. error %.2f px, %.1f %% valid", car_disparity_mae_px,
                100.0 * car_disparity_valid_fraction);
  out << ", " << labels << " visible car-frames, " << detections << " detections (" << false_positives
      << " false positives)" << disparity << ", " << Progress::FormatDuration(seconds);
  return out.str();
}

std::vector<Eigen::Vector4d> SynthTrajectory(const Eigen::Vector4d& origin_pose, double speed, double yaw_rate,
                                             int num_frames, int origin_frame, double frame_rate_hz) {
  SAMP_CHECK(num_frames >= 1 && frame_rate_hz > 0) << "SynthTrajectory: num_frames " << num_frames
                                                   << ", frame_rate_hz " << frame_rate_hz;
  PlanarState origin;
  origin.position = origin_pose.head<3>();
  origin.heading = origin_pose[3];
  const double dt = 1.0 / frame_rate_hz;
  std::vector<Eigen::Vector4d> poses;
  for (int t = 0; t < num_frames; ++t) {
    const PlanarState s = Advance(origin, speed, yaw_rate, (t - origin_frame) * dt);
    poses.emplace_back(s.position.x(), s.position.y(), s.position.z(), WrapAngle(s.heading));
  }
  return poses;
}

SynthSummary SynthesizeSequences(const SynthOptions& options, const std::vector<SynthCar>& cars) {
  options.Check();
  SAMP_CHECK(!cars.empty()) << "synth: no cars given";
  for (const SynthCar& car : cars) {
    SAMP_CHECK(!car.mesh.Empty()) << "synth: car " << car.name << " has an empty mesh";
  }
  const auto start = std::chrono::steady_clock::now();
  LogInfo() << "synth: seed " << options.seed << ", " << options.num_sequences << " sequences of "
            << options.num_frames << " frames, " << cars.size() << " cars available, disparity "
            << (options.disparity == DisparitySource::kStereoSgbm ? "StereoSGBM" : "true + noise");
  nlohmann::json config = nlohmann::json::parse(options.ToJson());
  nlohmann::json names = nlohmann::json::array();
  for (const SynthCar& car : cars) names.push_back(car.name);
  config["cars"] = names;
  WriteTextFileAtomically((fs::path(options.output_folder) / "config.json").string(), DumpJson(config, 2) + "\n");

  SynthSummary summary;
  Progress progress("synth frames", int64_t(options.num_sequences) * options.num_frames,
                    options.show_progress);
  int global_car_index = 0;
  for (int i = 0; i < options.num_sequences; ++i) {
    const Scene scene = MakeScene(options, cars, i, &global_car_index);
    summary.sequences.push_back(WriteSequence(options, scene, i, &progress));
    for (const SceneCar& car : scene.cars) {
      ++summary.num_tracks;
      if (car.motion == MotionType::kStanding) ++summary.num_standing;
      if (car.motion == MotionType::kStraight) ++summary.num_straight;
      if (car.motion == MotionType::kTurning) ++summary.num_turning;
      if (car.parked) ++summary.num_parked;
    }
  }
  progress.Finish();
  double error_sum = 0.0, valid = 0.0, pixels = 0.0;
  for (const SynthSequenceInfo& s : summary.sequences) {
    const double v = s.car_disparity_valid_fraction * double(s.car_pixels);
    error_sum += s.car_disparity_mae_px * v;
    valid += v;
    pixels += double(s.car_pixels);
  }
  summary.car_disparity_mae_px = valid > 0 ? error_sum / valid : 0.0;
  summary.car_disparity_valid_fraction = pixels > 0 ? valid / pixels : 0.0;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace samp
