// The scene of one synthetic sequence (internal to libsamp/synth): the static
// meshes, the cars with their per-frame states, the ego camera's poses, and for
// the street preset its layout, lighting, sway and false-positive clutter.
// MakeScene builds it from the options and the sequence index alone (seeded);
// WriteSequence (sequence_writer.h) renders and writes it.
//
// Frames: the world frame of a scene is the rendering frame (KITTI axes: x
// right, y down, z forward; the road at y = camera_height); for the street
// preset it is the road frame, in which frame 0's camera is pitched and rolled
// by the sway. Poses follow libsamp/core/pose.h.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "libsamp/core/camera.h"
#include "libsamp/core/mesh.h"
#include "libsamp/core/pose.h"
#include "libsamp/scan/renderer.h"
#include "libsamp/synth/detector_model.h"
#include "libsamp/synth/street_scene.h"
#include "libsamp/synth/synth_options.h"

namespace samp::synth {

// Road layout of the clean preset in the world frame (= camera of frame 0):
// lanes of 3.5 m, road |x| < 7 m, sidewalk to the building line at |x| >= 9 m.
constexpr double kRoadHalfWidth = 7.0;
constexpr double kLaneWidth = 3.5;
constexpr double kMaxCarCentreX = 6.1;

// A car (or the ego car) on the road plane: position and heading (yaw).
struct PlanarState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double heading = 0.0;
};

// Motion for dt seconds (negative dt goes back in time), predicted by the
// fitter's circular-arc model (fit/motion_model.h PredictMotion; standing and
// straight are its exact limits v = 0 and omega = 0), so that the ground truth
// follows the model the fitter predicts with. The heading is not wrapped.
PlanarState Advance(const PlanarState& start, double speed, double yaw_rate, double dt);

inline Eigen::Isometry3d WorldFromObject(const PlanarState& state) {
  return samp::WorldFromObject(state.position, state.heading);
}

// How a static mesh is textured: the clean preset's road, facades and blotchy
// boxes, or a street object (its material in Scene::street_objects).
enum class MaterialKind { kRoad, kFacade, kBlotch, kStreet };

struct StaticMesh {
  Mesh mesh;
  MaterialKind material = MaterialKind::kBlotch;
  Eigen::Vector3d color = Eigen::Vector3d::Constant(0.5);
  uint64_t seed = 0;
  int street_index = -1;  // kStreet: index into Scene::street_objects (whose mesh is moved here)
};

enum class MotionType { kStanding = 0, kStraight = 1, kTurning = 2 };
const char* MotionName(MotionType type);

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
  bool parked = false;                       // street: in a parking lane's row
  bool metallic = false;                     // silver/grey metallic paint (stronger, broader highlight)
};

// A scene car of `synth_car` with its size from the mesh bounds, not yet placed.
SceneCar NewSceneCar(const SynthCar* synth_car);

struct Scene {
  std::vector<StaticMesh> statics;
  std::vector<SceneCar> cars;
  // Rendering frame ("world"; for the street the road frame, in which frame 0's
  // camera is pitched/rolled by the sway). Written poses are relative to frame 0.
  std::vector<Eigen::Isometry3d> world_from_camera;
  double ego_speed = 0.0, ego_yaw_rate = 0.0;
  // Street preset only.
  bool street = false;
  StreetLayout layout;
  std::vector<StreetObject> street_objects;  // materials (meshes moved into statics)
  OutdoorLighting lighting;                  // the clean preset: the default sun direction
  double exposure = 1.0;
  EgoSway sway;
  std::vector<ClutterCandidate> clutter;     // false-positive candidates, world frame (position), id
  std::vector<double> clutter_heading;       // world heading of each candidate box
};

// The random draws of one scene, from one seeded engine.
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

// The left camera of the options (KITTI's P2 by default).
PinholeCamera MakeCamera(const SynthOptions& options);

// The indices 0..num_cars-1 shuffled by the scene's engine: the order in which a
// scene takes the cars.
std::vector<int> ShuffledCarOrder(size_t num_cars, Random* rng);

// Integrates a car's trajectory from its middle-frame state and checks it:
// on the road (clean: |x| <= kMaxCarCentreX; street: drivable, unless parked),
// clear of the ego car and the other cars, centre in view in >= 70 % of the
// frames. On success the per-frame states go to *out.
bool AcceptTrajectory(const SynthOptions& options, const Scene& scene, const PlanarState& middle_state,
                      double speed, double yaw_rate, const SceneCar& car, std::vector<PlanarState>* out);

// Gives `car` the trajectory through `middle_state` (the car at distance `d`
// from the middle frame's camera) when AcceptTrajectory admits it.
bool TakeTrajectory(const SynthOptions& options, const Scene& scene, MotionType motion, double d,
                    const PlanarState& middle_state, double speed, double yaw_rate, SceneCar* car);

// The scene of sequence `sequence_index` (seeded by Mix(options.seed,
// sequence_index)) of the preset options.scene: MakeStreetScene or
// MakeCleanScene (street_preset.cc, clean_preset.cc), which draw from `rng`
// (seeded by `seed`) and derive their textures' seeds from `seed`.
// *global_car_index counts the cars over the sequences (it drives the motion
// and near/far choices).
Scene MakeScene(const SynthOptions& options, const std::vector<SynthCar>& cars, int sequence_index,
                int* global_car_index);
Scene MakeCleanScene(const SynthOptions& options, const std::vector<SynthCar>& cars, int sequence_index,
                     uint64_t seed, Random* rng, int* global_car_index);
Scene MakeStreetScene(const SynthOptions& options, const std::vector<SynthCar>& cars, int sequence_index,
                      uint64_t seed, Random* rng, int* global_car_index);

}  // namespace samp::synth
