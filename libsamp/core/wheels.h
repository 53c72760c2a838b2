// Wheels for car bodies in the canonical object frame (docs/canonical_frame.md:
// x to the front, y down, z to the car's left, origin at the centre of the
// bottom face of the bounding box, so the road is the plane y = 0).
//
// Most CAD bodies samp trains on (TORCS, Trigger Rally) have no wheels: once
// placed on the road their sills touch it and the car is lower than a real one
// by its ground clearance, while a stereo camera sees the tyres. AddWheels
// lifts the body by a ground clearance and synthesises four closed tyres
// (cylinders with capped sides) at axle positions derived from the body's
// bounding box, each touching y = 0. The one function is used by the trainer
// (every training shape) and by the synthetic benchmark (its rendered cars),
// so both see the same cars (docs/training.md, "Wheels").
//
// Usage:
//   samp::WheelOptions options;            // road-car defaults
//   const samp::WheeledCar car = samp::AddWheels(body_in_object, options);
//   car.body    // the body, lifted by car.placement.lift (y decreased)
//   car.wheels  // four closed tyre meshes (one Mesh), for a separate colour
//   car.Combined()  // body + wheels as one mesh (what the trainer scans)
// The result again has its origin at the centre of the bottom face of its
// bounding box: the tyres touch y = 0, nothing lies below it.
//
// Pure functions of their arguments: thread-safe, deterministic.
#pragma once

#include <array>
#include <string>

#include "libsamp/core/mesh.h"

namespace samp {

struct WheelOptions {
  // Tyre radius, metres; 0 = auto: radius_per_length * body length, clamped to
  // [min_radius, max_radius].
  double radius = 0.0;
  double radius_per_length = 0.078;  // road cars: 0.30-0.33 m at 3.9-4.3 m length
  double min_radius = 0.26;
  double max_radius = 0.42;
  // Tyre width, metres; 0 = auto: width_per_radius * radius.
  double width = 0.0;
  double width_per_radius = 0.65;
  // Wheelbase as a share of the body length (road cars 0.58-0.63) and the
  // axle midpoint's offset along x as a share of the length (+ = to the front).
  double wheelbase_per_length = 0.60;
  double axle_centre_offset_per_length = 0.0;
  // The outer face of each tyre lies this far inside the body's side (metres).
  double side_inset = 0.02;
  // Ground clearance added under the body, metres: the body is lifted by it.
  double ground_clearance = 0.14;
  // Facets around each tyre (>= 8).
  int segments = 24;

  void Check() const;  // throws samp::Error naming the field
};

// Where the wheels went (canonical frame, before the lift is undone: the
// final frame of AddWheels' result).
struct WheelPlacement {
  double radius = 0.0, width = 0.0;
  double lift = 0.0;  // metres the body moved up (its y decreased by this much)
  // Axle centres: front-left, front-right, rear-left, rear-right.
  std::array<Eigen::Vector3d, 4> centers{};
  std::string BriefReport() const;
};

struct WheeledCar {
  Mesh body;    // the input body, lifted
  Mesh wheels;  // four closed tyres, outward-facing triangles
  WheelPlacement placement;
  Mesh Combined() const;  // body followed by the wheels
};

// A closed cylinder (outward-facing) with its axis along z, centre `center`.
Mesh MakeWheelMesh(const Eigen::Vector3d& center, double radius, double width, int segments);

// Places the wheels under `body` (canonical frame; its bounding box decides
// length, width and the bottom) without building meshes.
// Throws samp::Error when the body is empty or too narrow for two tyres.
WheelPlacement PlaceWheels(const Mesh& body, const WheelOptions& options);

// Lifts `body` and adds four tyres touching y = 0 (see the header comment).
WheeledCar AddWheels(const Mesh& body, const WheelOptions& options);

}  // namespace samp
