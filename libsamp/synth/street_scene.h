// The realistic street of `samp synth`'s default scenes (docs/synthetic.md,
// "Street"): a road with lanes, lane marks and asphalt texture, kerbs and
// sidewalks, facades 3-12 m beside the road with windows in several styles,
// poles, trees, bins and walls on the sidewalks, parking lanes for parked rows
// and an optional crossing street; the ego car's sway; and the clutter where a
// detector may fire falsely.
//
// Frame: the "road frame" (KITTI axes: x right, y down, z forward), the road
// surface at y = road_y; the ego car drives along +z in its lane. Everything is
// a function of the options and the seed. Pure functions, thread-safe.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "libsamp/core/mesh.h"

namespace samp {

struct StreetOptions {
  // Driving lanes per direction: 2 with this probability, else 1.
  double two_lane_probability = 0.35;
  // Lane width range, metres.
  double min_lane_width = 3.0, max_lane_width = 3.6;
  // Probability of a parking lane (2.2 m) on the right and on the left side.
  double right_parking_probability = 0.85, left_parking_probability = 0.6;
  // Kerb height, metres.
  double kerb_height = 0.13;
  // Sidewalk width range, metres (the rest up to the facade is a front yard).
  double min_sidewalk_width = 2.0, max_sidewalk_width = 4.0;
  // Facade distance from the kerb, metres (per side a base distance, per building
  // a jitter; every facade lies in [min, max]).
  double min_facade_distance = 3.0, max_facade_distance = 12.0;
  // Mean spacing (metres along the street, per side) of sidewalk clutter: poles,
  // trees, bins, bollards and signs, at 0.3-1.2 m from the kerb.
  double clutter_spacing = 6.0;
  // Probability of a crossing street ahead (15-45 m).
  double intersection_probability = 0.5;
  // Parked rows: gap between parked cars, metres.
  double min_parked_gap = 0.3, max_parked_gap = 0.9;

  void Check() const;  // throws samp::Error naming the field
};

// Materials of the street objects (textures in procedural.h).
enum class StreetMaterial {
  kAsphalt,   // ground plane: road, cross street (markings from the layout)
  kYard,      // ground plane outside the road: grass and soil
  kSidewalk,  // paving slabs
  kKerb,      // kerb stones
  kFacade,    // a building (style and colour per object)
  kRoof,      // building tops and side walls
  kPole,      // metal poles, sign posts, bollards
  kSign,      // sign plates
  kBark,      // tree trunks
  kFoliage,   // tree crowns, hedges
  kBin,       // waste bins
  kWall,      // low garden walls
};

struct StreetObject {
  Mesh mesh;                  // road frame
  StreetMaterial material = StreetMaterial::kSidewalk;
  Eigen::Vector3d color = Eigen::Vector3d::Constant(0.5);  // base albedo
  int style = 0;              // facade style (procedural::FacadeStyle), 0 otherwise
  int facade_axis = 2;        // kFacade: the in-plane horizontal axis of its street face (0 = x, 2 = z)
  uint64_t seed = 0;
};

// A painted line on the road: along z at x (dashed or solid), or across the road at z (stop lines, zebra).
struct LaneMarking {
  bool across = false;        // false: a line along z at `position` = x; true: a band across at z
  double position = 0.0;      // x (along) or z (across)
  double half_width = 0.06;
  double dash_on = 0.0, dash_period = 0.0;  // dashed when dash_period > 0
  double from = -1e9, to = 1e9;             // extent along the line (z for along, x for across)
};

// A place for one parked car: its centre line and direction.
struct ParkingLane {
  double centre_x = 0.0;      // x of the car centres
  double kerb_x = 0.0;        // x of the kerb face
  double heading = 0.0;       // KITTI yaw of the parked cars (world): -pi/2 = +z
  int side = 1;               // +1 right, -1 left
};

struct StreetLayout {
  double road_y = 1.65;
  double lane_width = 3.5;
  int lanes_per_direction = 1;
  double centre_x = 0.0;                    // centre line between the directions
  std::vector<double> same_lanes, oncoming_lanes;  // lane centres (x)
  double left_kerb_x = -5.0, right_kerb_x = 5.0;   // road edges (kerb faces)
  std::vector<ParkingLane> parking;
  bool has_intersection = false;
  double intersection_z = 0.0, intersection_half_width = 0.0;  // cross-street band (asphalt)
  std::vector<LaneMarking> markings;
  // Sidewalk clutter positions (road frame, on the sidewalk, bottom) for false positives.
  std::vector<Eigen::Vector3d> clutter;

  // True where a moving car's centre may be: on the driving lanes (not the
  // parking lanes) or on the cross street.
  bool Drivable(double x, double z) const;
  // True on the asphalt (road incl. parking lanes, cross street).
  bool OnAsphalt(double x, double z) const;
};

StreetLayout MakeStreetLayout(const StreetOptions& options, double road_y, double ego_x,
                              std::mt19937_64* engine);

// The static objects: ground, sidewalks and kerbs, buildings, clutter (z from z_min to z_max).
std::vector<StreetObject> MakeStreetObjects(const StreetOptions& options, StreetLayout* layout,
                                            double z_min, double z_max, uint64_t seed,
                                            std::mt19937_64* engine);

// Albedo (linear RGB) of a street object at a point (road frame) with the given
// unit normal and pixel footprint (metres per pixel there).
Eigen::Vector3d StreetAlbedo(const StreetObject& object, const StreetLayout& layout,
                             const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double footprint);

// Planned parked row of one parking lane: the centre z of each car (lengths
// given, in order), starting at z_start with gaps U(min_parked_gap, max_parked_gap).
std::vector<double> PlanParkedRow(const StreetOptions& options, const std::vector<double>& lengths,
                                  double z_start, std::mt19937_64* engine);

// The ego car's sway: pitch and roll (radians) and vertical bounce (metres) as
// smooth functions of time, amplitudes growing with speed.
struct EgoSway {
  double pitch_amplitude = 0.0, roll_amplitude = 0.0, bounce_amplitude = 0.0;
  double pitch_frequency_hz = 1.0, roll_frequency_hz = 0.7, bounce_frequency_hz = 1.5;
  double pitch_phase = 0.0, roll_phase = 0.0, bounce_phase = 0.0;
  double pitch_offset = 0.0;  // constant pitch of the mounting/load
  // road_from_camera's rotation correction: camera pitched about x, rolled about z.
  Eigen::Matrix3d Rotation(double time) const;
  double Bounce(double time) const;
};

}  // namespace samp
