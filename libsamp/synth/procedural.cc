#include "libsamp/synth/procedural.h"

#include <algorithm>
#include <cmath>

namespace samp::procedural {
namespace {

double Smooth(double t) { return t * t * (3.0 - 2.0 * t); }

double Clamp01(double x) { return std::clamp(x, 0.0, 1.0); }

// Distance of x to the nearest multiple of `period` (>= 0).
double DistanceToGrid(double x, double period) {
  const double r = x - period * std::floor(x / period);
  return std::min(r, period - r);
}

}  // namespace

double ValueNoise(const Eigen::Vector3d& p, uint64_t seed) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const int64_t ix = int64_t(fx), iy = int64_t(fy), iz = int64_t(fz);
  const double tx = Smooth(p.x() - fx), ty = Smooth(p.y() - fy), tz = Smooth(p.z() - fz);
  // HashToUnit(x, y, z, seed) of the 8 corners, sharing the (seed, x) and (seed, x, y) prefixes.
  double value = 0.0;
  for (int dx = 0; dx < 2; ++dx) {
    const uint64_t hx = Mix(seed, uint64_t(ix + dx));
    for (int dy = 0; dy < 2; ++dy) {
      const uint64_t hxy = Mix(hx, uint64_t(iy + dy));
      for (int dz = 0; dz < 2; ++dz) {
        const double w = (dx ? tx : 1.0 - tx) * (dy ? ty : 1.0 - ty) * (dz ? tz : 1.0 - tz);
        const uint64_t h = Mix(hxy, uint64_t(iz + dz));
        value += w * (double(h >> 11) * (1.0 / 9007199254740992.0));
      }
    }
  }
  return value;
}

double FeatureVisibility(double feature_size, double footprint) {
  // Full weight when the feature spans >= 2 pixels, none below 1 pixel.
  return Clamp01(feature_size / std::max(footprint, 1e-9) - 1.0);
}

double Fractal(const Eigen::Vector3d& p, double base_frequency, int octaves, double footprint,
               uint64_t seed) {
  double sum = 0.0, amplitude = 1.0, frequency = base_frequency;
  for (int o = 0; o < octaves; ++o) {
    const double weight = FeatureVisibility(0.5 / frequency, footprint);
    if (weight <= 0.0) break;
    sum += weight * amplitude * (ValueNoise(p * frequency, Mix(seed, uint64_t(o))) - 0.5);
    amplitude *= 0.5;
    frequency *= 2.0;
  }
  return sum;
}

Eigen::Vector3d RoadAlbedo(const Eigen::Vector3d& point_in_world, double road_half_width,
                           double lane_width, double footprint, uint64_t seed) {
  const double x = point_in_world.x(), z = point_in_world.z();
  const Eigen::Vector3d flat(x, 0.0, z);
  if (std::abs(x) < road_half_width) {
    // Asphalt: grainy fine noise over patchy large-scale variation.
    double grey = 0.26 + 0.22 * Fractal(flat, 4.0, 5, footprint, Mix(seed, 1)) +
                  0.10 * Fractal(flat, 0.35, 3, footprint, Mix(seed, 2));
    // Lane lines: 0.12 m wide, dashed 3 m on / 6 m off, at +-lane_width/2 + k * lane_width.
    const double line_half = 0.06;
    const double edge_distance = std::abs(std::abs(x) - (road_half_width - 0.25));
    double mark = 0.0;
    if (edge_distance < line_half) mark = 1.0;
    const double lane_distance = DistanceToGrid(x - 0.5 * lane_width, lane_width);
    if (lane_distance < line_half && std::abs(x) < road_half_width - 1.0) {
      const double phase = z - 9.0 * std::floor(z / 9.0);
      if (phase < 3.0) mark = 1.0;
    }
    mark *= FeatureVisibility(2.0 * line_half, footprint) * 0.8 + 0.2;
    grey = grey * (1.0 - mark) + 0.8 * mark;
    return Eigen::Vector3d(grey, grey, grey * 1.03).cwiseMax(0.0).cwiseMin(1.0);
  }
  // Paving: 0.5 m tiles, per-tile tone, dark joints, fine grain.
  const double tile = 0.5;
  const int64_t tx = int64_t(std::floor(x / tile)), tz = int64_t(std::floor(z / tile));
  double grey = 0.50 + 0.16 * (HashToUnit(tx, 0, tz, Mix(seed, 3)) - 0.5) +
                0.15 * Fractal(flat, 6.0, 4, footprint, Mix(seed, 4));
  const double joint = std::min(DistanceToGrid(x, tile), DistanceToGrid(z, tile));
  if (joint < 0.015) grey = grey * (1.0 - FeatureVisibility(0.03, footprint)) +
                            0.3 * FeatureVisibility(0.03, footprint);
  return Eigen::Vector3d(grey * 1.02, grey, grey * 0.96).cwiseMax(0.0).cwiseMin(1.0);
}

Eigen::Vector3d FacadeAlbedo(double along, double up, const Eigen::Vector3d& base, double footprint,
                             uint64_t seed) {
  // Windows: 1.3 m x 1.5 m on a 3.0 m x 3.2 m grid, from 1.0 m above the ground.
  const double wa = along - 3.0 * std::floor(along / 3.0);
  const double wu = up - 3.2 * std::floor(up / 3.2);
  if (up > 1.0 && wa > 0.85 && wa < 2.15 && wu > 0.9 && wu < 2.4) {
    const Eigen::Vector3d p(along, up, 0.0);
    const double shade =
        0.12 + 0.10 * HashToUnit(int64_t(std::floor(along / 3.0)), int64_t(std::floor(up / 3.2)), 0, seed) +
        0.08 * Fractal(p, 2.0, 3, footprint, Mix(seed, 5));
    return Eigen::Vector3d(shade, shade * 1.05, shade * 1.15).cwiseMax(0.0).cwiseMin(1.0);
  }
  // Bricks: 0.25 x 0.065 m, running bond.
  const double course = 0.075, brick = 0.25;
  const int64_t row = int64_t(std::floor(up / course));
  const double shifted = along + ((row & 1) ? 0.5 * brick : 0.0);
  const int64_t column = int64_t(std::floor(shifted / brick));
  const double tone = 0.75 + 0.5 * HashToUnit(column, row, 7, seed);
  const double vis = FeatureVisibility(course, footprint);
  const double mix_tone = vis * tone + (1.0 - vis) * 1.0;
  Eigen::Vector3d albedo = base * mix_tone;
  const double joint = std::min(DistanceToGrid(up, course), DistanceToGrid(shifted, brick));
  if (joint < 0.008) {
    const double w = FeatureVisibility(0.016, footprint);
    albedo = albedo * (1.0 - w) + Eigen::Vector3d(0.7, 0.7, 0.68) * w;
  }
  albedo *= 1.0 + 0.5 * Fractal(Eigen::Vector3d(along, up, 0.0), 0.8, 5, footprint, Mix(seed, 6));
  return albedo.cwiseMax(0.0).cwiseMin(1.0);
}

Eigen::Vector3d BlotchAlbedo(const Eigen::Vector3d& point_in_world, const Eigen::Vector3d& base,
                             double footprint, uint64_t seed) {
  Eigen::Vector3d albedo;
  for (int c = 0; c < 3; ++c) {
    albedo[c] = base[c] * (1.0 + 0.9 * Fractal(point_in_world, 1.5, 6, footprint,
                                                Mix(seed, uint64_t(10 + c))));
  }
  return albedo.cwiseMax(0.0).cwiseMin(1.0);
}

Eigen::Vector3d AsphaltAlbedo(const Eigen::Vector3d& p, double mark, double footprint, uint64_t seed) {
  const Eigen::Vector3d flat(p.x(), 0.0, p.z());
  double grey = 0.22 + 0.20 * Fractal(flat, 5.0, 5, footprint, Mix(seed, 1)) +
                0.12 * Fractal(flat, 0.3, 3, footprint, Mix(seed, 2));
  // Repair patches: darker, smoother rectangles of about 1-3 m on a 6 m lattice.
  const int64_t cx = int64_t(std::floor(p.x() / 6.0)), cz = int64_t(std::floor(p.z() / 6.0));
  if (HashToUnit(cx, 1, cz, Mix(seed, 3)) < 0.25) {
    const double ox = 6.0 * cx + 1.0 + 2.0 * HashToUnit(cx, 2, cz, seed);
    const double oz = 6.0 * cz + 1.0 + 2.0 * HashToUnit(cx, 3, cz, seed);
    if (p.x() > ox && p.x() < ox + 1.0 + 2.0 * HashToUnit(cx, 4, cz, seed) && p.z() > oz &&
        p.z() < oz + 1.0 + 2.0 * HashToUnit(cx, 5, cz, seed)) {
      grey = 0.14 + 0.5 * (grey - 0.22) * 0.5;
    }
  }
  // Tar seams: thin dark lines along z at a hashed x per 4 m band.
  const double seam_x = 4.0 * std::floor(p.x() / 4.0) + 4.0 * HashToUnit(int64_t(std::floor(p.x() / 4.0)), 6, 0, seed);
  if (std::abs(p.x() - seam_x) < 0.04) grey = grey * (1.0 - FeatureVisibility(0.08, footprint) * 0.6);
  mark = Clamp01(mark);
  grey = grey * (1.0 - mark) + (0.78 + 0.08 * Fractal(flat, 8.0, 3, footprint, Mix(seed, 7))) * mark;
  return Eigen::Vector3d(grey, grey, grey * 1.03).cwiseMax(0.0).cwiseMin(1.0);
}

namespace {

// Window grid of a facade: returns true inside a window and its glass shade.
bool Window(double along, double up, double spacing, double storey, double width, double height,
            double sill, uint64_t seed, double footprint, double* shade) {
  const double wa = along - spacing * std::floor(along / spacing);
  const double wu = up - storey * std::floor(up / storey);
  const double a0 = 0.5 * (spacing - width), u0 = sill;
  if (up < 0.8 || wa < a0 || wa > a0 + width || wu < u0 || wu > u0 + height) return false;
  const int64_t column = int64_t(std::floor(along / spacing)), row = int64_t(std::floor(up / storey));
  // Glass: dark with per-window tone (curtains, reflections), frame bars.
  double s = 0.08 + 0.18 * HashToUnit(column, row, 11, seed) +
             0.06 * Fractal(Eigen::Vector3d(along, up, 0.0), 1.5, 3, footprint, Mix(seed, 12));
  const double bar = std::min(std::abs(wa - (a0 + 0.5 * width)), std::min(wa - a0, a0 + width - wa));
  if (bar < 0.04) s = 0.75 * FeatureVisibility(0.08, footprint) + s * (1.0 - FeatureVisibility(0.08, footprint));
  *shade = s;
  return true;
}

}  // namespace

Eigen::Vector3d StyledFacadeAlbedo(FacadeStyle style, double along, double up, const Eigen::Vector3d& base,
                                   double footprint, uint64_t seed) {
  const double spacing = 2.4 + 1.4 * HashToUnit(0, 0, 1, seed);
  const double storey = 2.9 + 0.6 * HashToUnit(0, 0, 2, seed);
  const double width = (0.35 + 0.25 * HashToUnit(0, 0, 3, seed)) * spacing;
  const double height = (0.40 + 0.15 * HashToUnit(0, 0, 4, seed)) * storey;
  double shade = 0.0;
  switch (style) {
    case FacadeStyle::kBrick:
      return FacadeAlbedo(along, up, base, footprint, seed);
    case FacadeStyle::kStorefront:
      if (up < 3.2) {
        // Shop windows 0.6-3.0 m with frames every 2-4 m, a dark base band.
        if (up < 0.5) return ConcreteAlbedo(Eigen::Vector3d(along, up, 1.0), Eigen::Vector3d(0.3, 0.3, 0.3), footprint, seed);
        const double pane = 2.0 + 2.0 * HashToUnit(0, 0, 5, seed);
        const double wa = along - pane * std::floor(along / pane);
        if (up > 0.6 && up < 3.0 && wa > 0.12 && wa < pane - 0.12) {
          const double s = 0.05 + 0.25 * HashToUnit(int64_t(std::floor(along / pane)), 0, 13, seed) +
                           0.15 * Fractal(Eigen::Vector3d(along, up, 0.0), 0.7, 4, footprint, Mix(seed, 14));
          return Eigen::Vector3d(s, s * 1.03, s * 1.08).cwiseMax(0.0).cwiseMin(1.0);
        }
        return base * 0.5;
      }
      [[fallthrough]];
    case FacadeStyle::kPlaster: {
      if (Window(along, up, spacing, storey, width, height, 0.9, seed, footprint, &shade)) {
        return Eigen::Vector3d(shade, shade * 1.04, shade * 1.1).cwiseMax(0.0).cwiseMin(1.0);
      }
      Eigen::Vector3d a = base * (1.0 + 0.35 * Fractal(Eigen::Vector3d(along, up, 0.0), 0.5, 6, footprint, Mix(seed, 15)));
      // Cornices between storeys.
      if (DistanceToGrid(up, storey) < 0.08) a *= 1.0 - 0.25 * FeatureVisibility(0.16, footprint);
      return a.cwiseMax(0.0).cwiseMin(1.0);
    }
    case FacadeStyle::kPanels: {
      if (Window(along, up, spacing, storey, 0.7 * spacing, height, 0.8, seed, footprint, &shade)) {
        return Eigen::Vector3d(shade, shade * 1.05, shade * 1.12).cwiseMax(0.0).cwiseMin(1.0);
      }
      const int64_t pa = int64_t(std::floor(along / 1.5)), pu = int64_t(std::floor(up / 1.2));
      Eigen::Vector3d a = base * (0.9 + 0.2 * HashToUnit(pa, pu, 16, seed));
      a *= 1.0 + 0.25 * Fractal(Eigen::Vector3d(along, up, 0.0), 2.0, 5, footprint, Mix(seed, 17));
      if (std::min(DistanceToGrid(along, 1.5), DistanceToGrid(up, 1.2)) < 0.015) {
        a *= 1.0 - 0.5 * FeatureVisibility(0.03, footprint);
      }
      return a.cwiseMax(0.0).cwiseMin(1.0);
    }
  }
  return base;
}

Eigen::Vector3d PavingAlbedo(const Eigen::Vector3d& p, double slab, double footprint, uint64_t seed) {
  const double u = p.x(), w = p.z();
  const int64_t tx = int64_t(std::floor(u / slab)), tz = int64_t(std::floor(w / slab));
  double grey = 0.52 + 0.14 * (HashToUnit(tx, 0, tz, Mix(seed, 3)) - 0.5) +
                0.16 * Fractal(Eigen::Vector3d(u, 0.0, w), 5.0, 5, footprint, Mix(seed, 4)) +
                0.08 * Fractal(Eigen::Vector3d(u, 0.0, w), 0.4, 3, footprint, Mix(seed, 8));
  const double joint = std::min(DistanceToGrid(u, slab), DistanceToGrid(w, slab));
  if (joint < 0.012) grey = grey * (1.0 - 0.6 * FeatureVisibility(0.024, footprint));
  return Eigen::Vector3d(grey * 1.02, grey, grey * 0.95).cwiseMax(0.0).cwiseMin(1.0);
}

Eigen::Vector3d GrassAlbedo(const Eigen::Vector3d& p, double footprint, uint64_t seed) {
  const double soil = Clamp01(0.5 + 1.5 * Fractal(p, 0.4, 3, footprint, Mix(seed, 20)));
  const double fine = Fractal(p, 6.0, 5, footprint, Mix(seed, 21));
  const Eigen::Vector3d grass(0.16, 0.28, 0.09), dirt(0.30, 0.25, 0.18);
  return ((1.0 - soil) * grass + soil * dirt) * (1.0 + 0.9 * fine);
}

Eigen::Vector3d FoliageAlbedo(const Eigen::Vector3d& p, double footprint, uint64_t seed) {
  const double leaves = Fractal(p, 3.0, 6, footprint, Mix(seed, 22));
  const double tone = 0.5 + Fractal(p, 0.6, 2, footprint, Mix(seed, 23));
  const Eigen::Vector3d a = Eigen::Vector3d(0.10 + 0.05 * tone, 0.20 + 0.06 * tone, 0.06) * (1.0 + 1.6 * leaves);
  return a.cwiseMax(0.0).cwiseMin(1.0);
}

Eigen::Vector3d ConcreteAlbedo(const Eigen::Vector3d& p, const Eigen::Vector3d& base, double footprint,
                               uint64_t seed) {
  return (base * (1.0 + 0.45 * Fractal(p, 3.0, 6, footprint, Mix(seed, 24)))).cwiseMax(0.0).cwiseMin(1.0);
}

}  // namespace samp::procedural
