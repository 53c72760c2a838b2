// The street preset, `samp synth`'s default (docs/synthetic.md "Street"): the
// ego car with sway, the sun and sky, the street's layout and objects
// (street_scene.h), parked rows in the parking lanes and traffic in the lanes,
// the cross street and the junction, near/far by the realised near share.
#include <algorithm>
#include <cmath>
#include <iterator>

#include "libsamp/core/log.h"
#include "libsamp/synth/procedural.h"
#include "libsamp/synth/scene.h"

namespace samp::synth {
namespace {

using procedural::Mix;

constexpr double kDeg = kPi / 180.0;

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

// The ego car: speed, yaw rate and sway (growing with speed, at least 30 % of
// the amplitudes at max_ego_speed), and the camera's pose per frame in the road
// frame (the camera's forward is the ego heading -pi/2, road +z).
void MakeStreetEgo(const SynthOptions& options, Random* rng, Scene* scene) {
  const double dt = 1.0 / options.frame_rate_hz;
  scene->ego_speed = rng->Uniform(options.min_ego_speed, options.max_ego_speed);
  scene->ego_yaw_rate = rng->Uniform(-options.max_ego_yaw_rate, options.max_ego_yaw_rate);
  const double speed_factor =
      std::max(0.3, options.max_ego_speed > 0 ? scene->ego_speed / options.max_ego_speed : 0.0);
  EgoSway& sway = scene->sway;
  sway.pitch_amplitude = options.ego_pitch_sway_deg * kDeg * speed_factor * rng->Uniform(0.5, 1.0);
  sway.roll_amplitude = options.ego_roll_sway_deg * kDeg * speed_factor * rng->Uniform(0.5, 1.0);
  sway.bounce_amplitude = options.ego_bounce * speed_factor * rng->Uniform(0.5, 1.0);
  sway.pitch_frequency_hz = rng->Uniform(0.8, 1.8);
  sway.roll_frequency_hz = rng->Uniform(0.4, 1.2);
  sway.bounce_frequency_hz = rng->Uniform(1.0, 2.5);
  sway.pitch_phase = rng->Uniform(0.0, 2.0 * kPi);
  sway.roll_phase = rng->Uniform(0.0, 2.0 * kPi);
  sway.bounce_phase = rng->Uniform(0.0, 2.0 * kPi);
  sway.pitch_offset = rng->Uniform(-1.0, 1.0) * options.ego_max_pitch_offset_deg * kDeg;
  PlanarState ego;
  ego.heading = -0.5 * kPi;
  for (int t = 0; t < options.num_frames; ++t) {
    const PlanarState s = Advance(ego, scene->ego_speed, scene->ego_yaw_rate, t * dt);
    Eigen::Isometry3d road_from_camera = Eigen::Isometry3d::Identity();
    road_from_camera.linear() =
        samp::WorldFromObject(Eigen::Vector3d::Zero(), s.heading + 0.5 * kPi).linear() * sway.Rotation(t * dt);
    road_from_camera.translation() = s.position + Eigen::Vector3d(0.0, -sway.Bounce(t * dt), 0.0);
    scene->world_from_camera.push_back(road_from_camera);
  }
}

// Lighting: sun elevation and azimuth, sun and sky strength, exposure.
void MakeStreetLighting(const SynthOptions& options, Random* rng, Scene* scene) {
  const double elevation = rng->Uniform(options.min_sun_elevation_deg, options.max_sun_elevation_deg) * kDeg;
  const double azimuth = rng->Uniform(-kPi, kPi);
  scene->lighting.to_sun = Eigen::Vector3d(std::cos(elevation) * std::sin(azimuth), -std::sin(elevation),
                                           std::cos(elevation) * std::cos(azimuth));
  const double sun = rng->Uniform(0.55, 0.95);
  scene->lighting.sun = Eigen::Vector3d(1.0, 0.96, 0.88) * sun;
  scene->lighting.ambient = Eigen::Vector3d(0.30, 0.33, 0.38) * rng->Uniform(0.8, 1.15);
  scene->exposure = rng->Uniform(0.85, 1.15);
}

// The street's layout and static objects (their meshes moved into the
// statics), and the false-positive candidates: car-sized boxes on the road
// beside the sidewalk clutter.
void AddStreetStatics(const SynthOptions& options, uint64_t seed, Random* rng, Scene* scene) {
  scene->layout = MakeStreetLayout(options.street, options.camera_height, 0.0, &rng->engine());
  scene->street_objects =
      MakeStreetObjects(options.street, &scene->layout, -40.0, 220.0, Mix(seed, 7), &rng->engine());
  for (size_t i = 0; i < scene->street_objects.size(); ++i) {
    StaticMesh m;
    m.mesh = std::move(scene->street_objects[i].mesh);
    scene->street_objects[i].mesh = Mesh();
    m.material = MaterialKind::kStreet;
    m.street_index = int(i);
    m.seed = scene->street_objects[i].seed;
    scene->statics.push_back(std::move(m));
  }
  for (const Eigen::Vector3d& c : scene->layout.clutter) {
    ClutterCandidate candidate;
    candidate.id = int(scene->clutter.size());
    const double side = c.x() > scene->layout.centre_x ? 1.0 : -1.0;
    candidate.position = Eigen::Vector3d(c.x() - side * 1.0, options.camera_height, c.z());
    scene->clutter.push_back(candidate);
    scene->clutter_heading.push_back(side > 0 ? -0.5 * kPi : 0.5 * kPi);
  }
}

// The cars of a scene are taken in `order`; near/far by the realised near share.
struct CarDraw {
  const std::vector<SynthCar>* cars = nullptr;
  std::vector<int> order;
  int next = 0;
  // Middle-frame distance that separates near from far.
  double split = 20.0;

  const SynthCar* Car(int k) const { return &(*cars)[order[(next + k) % order.size()]]; }
};

// Near (nearer than `split` at the middle frame) while the realised near share
// of the sequence's cars, parked and traffic, would stay short of near_share
// with `count` more cars.
bool DrawNear(const SynthOptions& options, const Scene& scene, double split, int count) {
  int placed_near = 0;
  for (const SceneCar& other : scene.cars) placed_near += other.target_distance < split ? 1 : 0;
  return placed_near < options.near_share * double(scene.cars.size() + count) - 1e-9;
}

// Where a parked row starts (z of its first car's rear, road frame) in
// attempt `attempt`: a near row's first car lies beyond min_distance and its
// last car, where the row is short enough, within `split`; a far row's first
// car lies beyond `split`; the last car of any row lies within max_distance.
// After 15 attempts any start from 2 m behind the camera is tried.
double ParkedRowStart(const SynthOptions& options, const ParkingLane& lane, const Eigen::Vector3d& camera_middle,
                      const std::vector<double>& lengths, double split, bool near_row, int attempt, Random* rng) {
  const double lateral = std::abs(lane.kerb_x - camera_middle.x());
  const auto ahead = [&](double distance) { return std::sqrt(std::max(0.0, distance * distance - lateral * lateral)); };
  double row_length = 0.0;
  for (double length : lengths) row_length += length + options.street.max_parked_gap;
  const double last_centre = row_length - options.street.max_parked_gap - 0.5 * lengths.back();
  const double near_lo = std::max(-2.0, ahead(options.min_distance) - 0.5 * lengths.front());
  const double near_hi = std::max(near_lo, ahead(split) - last_centre);
  const double far_lo = std::max(-2.0, ahead(split) - 0.5 * lengths.front());
  const double far_hi = std::max(far_lo, ahead(options.max_distance) - last_centre);
  const double z_lo = attempt >= 15 ? -2.0 : near_row ? near_lo : far_lo;
  const double z_hi = attempt < 15 && near_row ? near_hi : far_hi;
  return camera_middle.z() + rng->Uniform(z_lo, z_hi);
}

// Stands the cars of `row` at `centres` along the lane's kerb; false when one
// of them lies outside [min_distance, max_distance], in the crossing or on
// another car. The accepted cars (standing, painted) go to *accepted.
bool StandParkedRow(const SynthOptions& options, const Scene& scene, const ParkingLane& lane,
                    const std::vector<double>& centres, std::vector<SceneCar> row, Random* rng,
                    std::vector<SceneCar>* accepted) {
  const Eigen::Vector3d camera_middle = scene.world_from_camera[options.num_frames / 2].translation();
  for (size_t k = 0; k < row.size(); ++k) {
    SceneCar& car = row[k];
    car.parked = true;
    PlanarState state;
    const double kerb_offset = 0.5 * car.width + rng->Uniform(0.15, 0.4);
    state.position = Eigen::Vector3d(lane.kerb_x - lane.side * kerb_offset, options.camera_height, centres[k]);
    state.heading = WrapAngle(lane.heading + rng->Normal(1.5 * kDeg));
    const double d =
        (state.position - Eigen::Vector3d(camera_middle.x(), options.camera_height, camera_middle.z())).norm();
    if (d < options.min_distance || d > options.max_distance) return false;
    if (scene.layout.has_intersection && std::abs(state.position.z() - scene.layout.intersection_z) <
                                             scene.layout.intersection_half_width + 0.5 * car.length + 2.5) {
      return false;
    }
    Scene probe;
    probe.street = true;
    probe.layout = scene.layout;
    probe.world_from_camera = scene.world_from_camera;
    probe.cars = scene.cars;
    probe.cars.insert(probe.cars.end(), accepted->begin(), accepted->end());
    std::vector<PlanarState> states;
    if (!AcceptTrajectory(options, probe, state, 0.0, 0.0, car, &states)) return false;
    car.motion = MotionType::kStanding;
    car.target_distance = d;
    car.states = std::move(states);
    PickStreetPaint(rng, &car);
    accepted->push_back(car);
  }
  return true;
}

// Adds a parked row to the scene, with a duplicate-detection candidate in the
// gap behind each parked car but the first.
void AddParkedRow(std::vector<SceneCar> row, Scene* scene, int* global_car_index) {
  for (size_t k = 0; k < row.size(); ++k) {
    SceneCar& car = row[k];
    car.track_id = int(scene->cars.size());
    if (k > 0) {
      ClutterCandidate candidate;
      candidate.id = int(scene->clutter.size());
      candidate.position = 0.5 * (car.states[0].position + row[k - 1].states[0].position);
      scene->clutter.push_back(candidate);
      scene->clutter_heading.push_back(car.states[0].heading);
    }
    scene->cars.push_back(car);
    ++(*global_car_index);
  }
}

// Parked rows, parked_cars_per_sequence split over the parking lanes, each
// near or far by DrawNear, in up to 30 attempts.
void PlaceParkedRows(const SynthOptions& options, Random* rng, CarDraw* draw, Scene* scene,
                     int* global_car_index) {
  const Eigen::Vector3d camera_middle = scene->world_from_camera[options.num_frames / 2].translation();
  const int num_lanes = int(scene->layout.parking.size());
  for (int lane_index = 0; lane_index < num_lanes; ++lane_index) {
    const ParkingLane& lane = scene->layout.parking[lane_index];
    const int count = options.parked_cars_per_sequence / num_lanes +
                      (lane_index < options.parked_cars_per_sequence % num_lanes ? 1 : 0);
    if (count == 0) continue;
    const bool near_row = DrawNear(options, *scene, draw->split, count);
    for (int attempt = 0; attempt < 30; ++attempt) {
      std::vector<SceneCar> row;
      std::vector<double> lengths;
      for (int k = 0; k < count; ++k) {
        row.push_back(NewSceneCar(draw->Car(k)));
        lengths.push_back(row.back().length);
      }
      const double z_start =
          ParkedRowStart(options, lane, camera_middle, lengths, draw->split, near_row, attempt, rng);
      const std::vector<double> centres = PlanParkedRow(options.street, lengths, z_start, &rng->engine());
      std::vector<SceneCar> accepted;
      if (!StandParkedRow(options, *scene, lane, centres, std::move(row), rng, &accepted)) continue;
      AddParkedRow(std::move(accepted), scene, global_car_index);
      draw->next += count;
      break;
    }
  }
}

// Traffic: standing (waiting), straight and turning by the shares (a
// low-discrepancy choice over the global car index, so that the shares hold
// over the whole set), near/far by the realised near share; a car that finds
// no place near/far is tried anywhere, then straight instead of turning, then
// standing.
void PlaceTraffic(const SynthOptions& options, int sequence_index, Random* rng, CarDraw* draw, Scene* scene,
                  int* global_car_index) {
  for (int k = 0; k < options.cars_per_sequence; ++k) {
    const int g = (*global_car_index)++;
    SceneCar car = NewSceneCar(draw->Car(0));
    ++draw->next;
    PickStreetPaint(rng, &car);
    const double u = std::fmod(0.6180339887498949 * (g + 1), 1.0);
    const MotionType motion = u < options.standing_share ? MotionType::kStanding
                              : u < options.standing_share + options.turning_share ? MotionType::kTurning
                                                                                   : MotionType::kStraight;
    const bool near = DrawNear(options, *scene, draw->split, 1);
    const double lo = near ? options.min_distance : draw->split;
    const double hi = near ? draw->split : options.max_distance;
    const double min_d = options.min_distance, max_d = options.max_distance;
    bool placed = PlaceStreetCar(options, motion, lo, hi, *scene, rng, &car);
    if (!placed) placed = PlaceStreetCar(options, motion, min_d, max_d, *scene, rng, &car);
    if (!placed && motion == MotionType::kTurning) {
      placed = PlaceStreetCar(options, MotionType::kStraight, min_d, max_d, *scene, rng, &car);
    }
    if (!placed) placed = PlaceStreetCar(options, MotionType::kStanding, min_d, max_d, *scene, rng, &car);
    if (!placed) {
      LogWarning() << "synth: sequence " << sequence_index << ": no free place for traffic car " << k << " ("
                   << car.car->name << "); the sequence has fewer cars";
      continue;
    }
    car.track_id = int(scene->cars.size());
    scene->cars.push_back(std::move(car));
  }
}

}  // namespace

Scene MakeStreetScene(const SynthOptions& options, const std::vector<SynthCar>& cars, int sequence_index,
                      uint64_t seed, Random* rng, int* global_car_index) {
  Scene scene;
  scene.street = true;
  MakeStreetEgo(options, rng, &scene);
  MakeStreetLighting(options, rng, &scene);
  AddStreetStatics(options, seed, rng, &scene);
  CarDraw draw;
  draw.cars = &cars;
  draw.order = ShuffledCarOrder(cars.size(), rng);
  draw.split = std::clamp(20.0, options.min_distance, options.max_distance);
  PlaceParkedRows(options, rng, &draw, &scene, global_car_index);
  PlaceTraffic(options, sequence_index, rng, &draw, &scene, global_car_index);
  return scene;
}

}  // namespace samp::synth
