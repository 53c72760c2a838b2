// Procedural textures for the synthetic scenes (docs/synthetic.md): hashed
// value noise, band-limited fractal noise and the albedo of road, sidewalk,
// building facades and boxes as functions of the world position. Pure
// functions of their arguments (deterministic, thread-safe).
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "libsamp/core/util.h"

namespace samp::procedural {

// 64-bit mixing (core/util.h SplitMix64). Inline: the textures call it per pixel.
inline uint64_t Mix(uint64_t x) { return SplitMix64(x); }
inline uint64_t Mix(uint64_t a, uint64_t b) { return Mix(Mix(a) ^ (b + 0x632be59bd9b4e019ULL)); }
// Uniform in [0, 1) from integer lattice coordinates and a seed.
inline double HashToUnit(int64_t x, int64_t y, int64_t z, uint64_t seed) {
  const uint64_t h = Mix(Mix(Mix(seed, uint64_t(x)), uint64_t(y)), uint64_t(z));
  return double(h >> 11) * (1.0 / 9007199254740992.0);
}

// Value noise in [0, 1): trilinear interpolation (smoothstep weights) of hashed
// lattice values at integer points.
double ValueNoise(const Eigen::Vector3d& p, uint64_t seed);

// Sum over `octaves` of (ValueNoise(p * f_o) - 0.5) * 0.5^o with f_o = base_frequency * 2^o,
// each octave faded out when its wavelength falls below about two pixel
// footprints (`footprint` = metres covered by one pixel at that point), which
// keeps the textures free of aliasing at a distance. Range about [-0.5, 0.5].
double Fractal(const Eigen::Vector3d& p, double base_frequency, int octaves, double footprint,
               uint64_t seed);

// Weight in [0, 1] of a feature of size `feature_size` metres seen with pixel
// footprint `footprint` (1 when it spans several pixels, fading to 0 below ~1 px).
double FeatureVisibility(double feature_size, double footprint);

// Albedos (linear RGB in [0, 1]).
// Road: asphalt inside |x| < road_half_width (dashed lane lines every
// lane_width from x = +-lane_width / 2, solid edge lines), paving tiles outside.
Eigen::Vector3d RoadAlbedo(const Eigen::Vector3d& point_in_world, double road_half_width,
                           double lane_width, double footprint, uint64_t seed);
// Brick facade with a window grid. `along` and `up` are the in-plane
// coordinates of the face (metres), `base` the building colour.
Eigen::Vector3d FacadeAlbedo(double along, double up, const Eigen::Vector3d& base, double footprint,
                             uint64_t seed);
// Blotchy multi-colour noise (boxes, bins, backdrop).
Eigen::Vector3d BlotchAlbedo(const Eigen::Vector3d& point_in_world, const Eigen::Vector3d& base,
                             double footprint, uint64_t seed);

// Street scenes (street_scene.h).
// Asphalt: grain, large-scale patches, darker repair patches and tar seams.
// `mark` in [0, 1] blends in white paint (lane marks), computed by the caller.
Eigen::Vector3d AsphaltAlbedo(const Eigen::Vector3d& point_in_world, double mark, double footprint,
                              uint64_t seed);
// Facade styles: brick, plaster, concrete panels, storefront (glass ground floor over plaster).
enum class FacadeStyle { kBrick = 0, kPlaster = 1, kPanels = 2, kStorefront = 3 };
constexpr int kNumFacadeStyles = 4;
// `along`, `up` in-plane coordinates (metres), `window_seed` varies the window grid per building.
Eigen::Vector3d StyledFacadeAlbedo(FacadeStyle style, double along, double up, const Eigen::Vector3d& base,
                                   double footprint, uint64_t seed);
// Paving slabs of `slab` metres with joints; grass/soil; foliage; generic fine-grain concrete.
Eigen::Vector3d PavingAlbedo(const Eigen::Vector3d& p, double slab, double footprint, uint64_t seed);
Eigen::Vector3d GrassAlbedo(const Eigen::Vector3d& p, double footprint, uint64_t seed);
Eigen::Vector3d FoliageAlbedo(const Eigen::Vector3d& p, double footprint, uint64_t seed);
Eigen::Vector3d ConcreteAlbedo(const Eigen::Vector3d& p, const Eigen::Vector3d& base, double footprint,
                               uint64_t seed);

}  // namespace samp::procedural
