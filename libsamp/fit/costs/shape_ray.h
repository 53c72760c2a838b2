// Where a ray meets the shape's surface phi_z = 0 (samp addition: the paper's
// data term needs no ray). Shared by the ray terms (ray_depth.h, disparity.h);
// everything in the object frame, phi_z the lookup's dense grid of z
// (ShapeLookup::DenseCached), u a unit direction.
//   RayDistance:   from a point o, the distance d >= 0 along +u (phi(o) > 0)
//                  or -u (phi(o) < 0) to the first crossing, searched up to
//                  kMaxRayRatio |phi(o)|: sphere tracing (|phi| bounds the
//                  distance to the surface, steps >= half a voxel), then a
//                  secant and Newton steps in the bracket.
//   FirstCrossing: from the camera o_cam, the first crossing lambda_s of
//                  o_cam + lambda u from the grid box entry (the surface the
//                  camera sees on that pixel); when the ray misses the shape,
//                  its closest approach lambda* = argmin phi along the ray
//                  (sampled, refined by golden-section search).
// A crossing with grad phi . u > -kMinRaySlope grazes the surface: its
// distance moves fast with the parameters.
#pragma once

#include <limits>

#include "libsamp/model/shape_lookup.h"

namespace samp {

constexpr double kMinRaySlope = 0.05;

// Distance from o along u to the surface: towards the camera (-u) from inside
// (phi_o < 0), away from it from outside; the crossing c and grad phi there.
// False when none is found within kMaxRayRatio |phi_o| or the ray grazes the
// surface.
bool RayDistance(const ShapeLookup& lookup, const double* phi_z, const double* o, double phi_o, const double* u,
                 double* distance, double* c, double* g_c);

// The first crossing of the ray o_cam + lambda u with the surface, from the
// grid box entry. Hit: *lambda = lambda_s, c and grad phi at c, true (the
// caller clamps a grazing slope). Miss: *lambda = lambda* of the smallest phi
// along the ray (c, g_c there, *phi_min = phi(c)), false; without refine_miss
// a miss that needs the search returns false at once (c, g_c, *phi_min unset).
// max_lambda (finite: only without refine_miss): the caller needs a crossing
// at lambda < max_lambda only; the trace stops after its first sample beyond
// it (any later crossing would lie beyond it too) and returns false.
bool FirstCrossing(const ShapeLookup& lookup, const double* phi_z, const double* o_cam, const double* u,
                   double* lambda, double* c, double* g_c, double* phi_min, bool refine_miss = true,
                   double max_lambda = std::numeric_limits<double>::infinity());

// Batched forms for the ray-depth term: up to kRayBatch rays, marched a few
// at a time in lockstep, one sample of each per round, so that the rays'
// independent lookups overlap (a single ray's samples depend on each other),
// their samples evaluated four at a time in AVX lanes where the CPU has AVX,
// else two at a time (ShapeLookup::DenseValuePair). Each ray's result equals
// the single-ray function's.
constexpr int kRayBatch = 64;

// RayDistance for each ray: in o, phi_o, u; out found, distance, c, g_c,
// and c's cell when c lies inside the grid box (in_cell; d/dz at c by
// ShapeLookup::CodeGradientAt without locating c again).
struct RayDistanceQuery {
  double o[3], phi_o, u[3];
  bool found;
  double distance, c[3], g_c[3];
  ShapeLookup::DenseCell cell;
  bool in_cell;
};
void RayDistances(const ShapeLookup& lookup, const double* phi_z, RayDistanceQuery* rays, int n);

// FirstCrossing(.., refine_miss = false, max_lambda) for each ray from one
// camera centre: in u, max_lambda; out hit (lambda, c, g_c, cell and in_cell
// as RayDistanceQuery's, set only on a hit).
struct FirstCrossingQuery {
  double u[3], max_lambda;
  bool hit;
  double lambda, c[3], g_c[3];
  ShapeLookup::DenseCell cell;
  bool in_cell;
};
void FirstCrossings(const ShapeLookup& lookup, const double* phi_z, const double* o_cam, FirstCrossingQuery* rays,
                    int n);

}  // namespace samp
