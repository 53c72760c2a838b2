#include "libsamp/synth/street_scene.h"

#include <algorithm>
#include <cmath>

#include "libsamp/core/error.h"
#include "libsamp/core/pose.h"
#include "libsamp/synth/procedural.h"
#include "libsamp/synth/synth_option_table.h"

namespace samp {
namespace {

using procedural::Mix;
constexpr double kParkingLaneWidth = 2.2;
constexpr double kKerbStoneWidth = 0.15;

double Uniform(std::mt19937_64* engine, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(*engine);
}
bool Bernoulli(std::mt19937_64* engine, double p) { return Uniform(engine, 0.0, 1.0) < p; }

// Box from corner ranges (x0 may exceed x1).
Mesh Box(double x0, double x1, double y0, double y1, double z0, double z1) {
  return MakeBoxMesh(Eigen::Vector3d(std::min(x0, x1), std::min(y0, y1), std::min(z0, z1)),
                     Eigen::Vector3d(std::max(x0, x1), std::max(y0, y1), std::max(z0, z1)));
}

double DistanceToGrid(double x, double period) {
  const double r = x - period * std::floor(x / period);
  return std::min(r, period - r);
}

}  // namespace

void StreetOptions::Check() const { StreetOptionTable().Check(*this); }

bool StreetLayout::Drivable(double x, double z) const {
  const double half = lanes_per_direction * lane_width;
  if (x > centre_x - half + 0.8 && x < centre_x + half - 0.8) return true;
  return has_intersection && std::abs(z - intersection_z) < intersection_half_width - 0.8;
}

bool StreetLayout::OnAsphalt(double x, double z) const {
  if (x >= left_kerb_x && x <= right_kerb_x) return true;
  return has_intersection && std::abs(z - intersection_z) < intersection_half_width;
}

namespace {

// The lane marks: centre and lane lines (dashed between lanes of one
// direction), edge lines, and at a junction a stop line on the ego's side and
// zebra crossings on both sides.
void AddMarkings(StreetLayout* layout) {
  const double w = layout->lane_width;
  const int n = layout->lanes_per_direction;
  const double left = layout->left_kerb_x, right = layout->right_kerb_x;
  const double zi = layout->intersection_z, hw = layout->intersection_half_width;
  auto along = [&](double x, double half_width, double on, double period) {
    LaneMarking m;
    m.position = x;
    m.half_width = half_width;
    m.dash_on = on;
    m.dash_period = period;
    if (layout->has_intersection) {
      LaneMarking a = m, b = m;
      a.to = zi - hw;
      b.from = zi + hw;
      layout->markings.push_back(a);
      layout->markings.push_back(b);
    } else {
      layout->markings.push_back(m);
    }
  };
  if (n == 1) {
    along(layout->centre_x, 0.06, 3.0, 9.0);
  } else {
    along(layout->centre_x - 0.1, 0.06, 0.0, 0.0);
    along(layout->centre_x + 0.1, 0.06, 0.0, 0.0);
    along(layout->centre_x + w, 0.06, 3.0, 9.0);
    along(layout->centre_x - w, 0.06, 3.0, 9.0);
  }
  along(layout->centre_x + n * w, 0.06, 0.0, 0.0);  // edge lines / parking lane boundaries
  along(layout->centre_x - n * w, 0.06, 0.0, 0.0);
  if (layout->has_intersection) {
    LaneMarking stop;
    stop.across = true;
    stop.position = zi - hw - 4.5;
    stop.half_width = 0.2;
    stop.from = layout->centre_x;
    stop.to = layout->centre_x + n * w;
    layout->markings.push_back(stop);
    for (double zebra_z : {zi - hw - 2.0, zi + hw + 2.0}) {
      LaneMarking zebra;
      zebra.across = true;
      zebra.position = zebra_z;
      zebra.half_width = 1.5;
      zebra.dash_on = 0.5;
      zebra.dash_period = 1.0;
      zebra.from = left;
      zebra.to = right;
      layout->markings.push_back(zebra);
    }
  }
}

}  // namespace

StreetLayout MakeStreetLayout(const StreetOptions& options, double road_y, double ego_x,
                              std::mt19937_64* engine) {
  options.Check();
  StreetLayout layout;
  layout.road_y = road_y;
  layout.lane_width = Uniform(engine, options.min_lane_width, options.max_lane_width);
  layout.lanes_per_direction = Bernoulli(engine, options.two_lane_probability) ? 2 : 1;
  const double w = layout.lane_width;
  const int n = layout.lanes_per_direction;
  // The ego car drives in the rightmost lane of its direction (right-hand traffic).
  const double ego_lane_x = ego_x + Uniform(engine, -0.25, 0.25);
  layout.centre_x = ego_lane_x - (n - 0.5) * w;
  for (int k = 0; k < n; ++k) {
    layout.same_lanes.push_back(layout.centre_x + (k + 0.5) * w);
    layout.oncoming_lanes.push_back(layout.centre_x - (k + 0.5) * w);
  }
  double right = layout.centre_x + n * w, left = layout.centre_x - n * w;
  if (Bernoulli(engine, options.right_parking_probability)) {
    layout.parking.push_back({right + 0.5 * kParkingLaneWidth, right + kParkingLaneWidth, -0.5 * kPi, 1});
    right += kParkingLaneWidth;
  } else {
    right += 0.4;
  }
  if (Bernoulli(engine, options.left_parking_probability)) {
    layout.parking.push_back({left - 0.5 * kParkingLaneWidth, left - kParkingLaneWidth, 0.5 * kPi, -1});
    left -= kParkingLaneWidth;
  } else {
    left -= 0.4;
  }
  layout.right_kerb_x = right;
  layout.left_kerb_x = left;
  if (Bernoulli(engine, options.intersection_probability)) {
    layout.has_intersection = true;
    layout.intersection_z = Uniform(engine, 15.0, 45.0);
    layout.intersection_half_width = Uniform(engine, 3.2, 4.5);
  }
  AddMarkings(&layout);
  return layout;
}

namespace {

const Eigen::Vector3d kFacadeColors[] = {
    {0.55, 0.27, 0.20}, {0.78, 0.70, 0.55}, {0.58, 0.58, 0.58}, {0.82, 0.76, 0.52}, {0.47, 0.33, 0.27},
    {0.72, 0.72, 0.68}, {0.62, 0.48, 0.38}, {0.85, 0.83, 0.78}, {0.45, 0.47, 0.50}, {0.70, 0.55, 0.45}};

// The objects of a street, each with its own texture seed.
struct ObjectList {
  uint64_t seed = 0;
  int next_seed = 0;
  std::vector<StreetObject> objects;

  void Add(Mesh mesh, StreetMaterial material, const Eigen::Vector3d& color, int style = 0, int facade_axis = 2) {
    StreetObject o;
    o.mesh = std::move(mesh);
    o.material = material;
    o.color = color;
    o.style = style;
    o.facade_axis = facade_axis;
    o.seed = Mix(seed, uint64_t(1000 + next_seed++));
    objects.push_back(std::move(o));
  }
};

// The buildings of one side between z0 and z1: facades at kerb + [min, max]
// facade distance, with a low wall or hedge in some front yards.
void AddBuildings(const StreetOptions& options, int side, double kerb, double sidewalk, double base_distance, double z0,
                  double z1, StreetLayout* layout, ObjectList* objects, std::mt19937_64* engine) {
  const double y = layout->road_y;
  double z = z0;
  while (z < z1) {
    const double length = std::min(z1 - z, Uniform(engine, 7.0, 24.0));
    const double distance = std::clamp(base_distance + Uniform(engine, -1.5, 4.0), options.min_facade_distance,
                                       options.max_facade_distance);
    const double depth = Uniform(engine, 8.0, 14.0), height = Uniform(engine, 6.0, 20.0);
    const double x0 = kerb + side * distance;
    if (length > 2.0) {
      const int style = std::uniform_int_distribution<int>(0, procedural::kNumFacadeStyles - 1)(*engine);
      const Eigen::Vector3d color =
          kFacadeColors[std::uniform_int_distribution<int>(0, int(std::size(kFacadeColors)) - 1)(*engine)];
      objects->Add(Box(x0, x0 + side * depth, y - height, y + 0.05, z, z + length), StreetMaterial::kFacade, color,
                   style, 2);
      // Front yard between the sidewalk and the facade: a low wall or hedge along the sidewalk.
      if (distance - sidewalk > 1.0 && Bernoulli(engine, 0.6)) {
        const double xw = kerb + side * sidewalk;
        if (Bernoulli(engine, 0.5)) {
          objects->Add(Box(xw, xw + side * 0.25, y - Uniform(engine, 0.6, 1.4), y, z + 0.2, z + length - 0.2),
                       StreetMaterial::kWall, Eigen::Vector3d(0.55, 0.52, 0.48) * Uniform(engine, 0.7, 1.2));
        } else {
          objects->Add(Box(xw, xw + side * 0.7, y - Uniform(engine, 0.9, 1.8), y, z + 0.2, z + length - 0.2),
                       StreetMaterial::kFoliage, Eigen::Vector3d(0.15, 0.25, 0.1));
        }
        layout->clutter.push_back(Eigen::Vector3d(xw, y, z + 0.5 * length));
      }
    }
    z += length + (Bernoulli(engine, 0.6) ? 0.0 : Uniform(engine, 1.0, 5.0));
  }
}

// One piece of sidewalk clutter at (x, z) by `kind` in [0, 1): a tree, a
// street light, a sign post, a waste bin or bollards.
void AddClutterItem(double kind, double x, double z, double kerb_top, double sidewalk, int side, ObjectList* objects,
                    std::mt19937_64* engine) {
  if (kind < 0.25 && sidewalk >= 2.4) {  // tree: trunk and crown
    const double trunk = Uniform(engine, 2.0, 3.2), radius = Uniform(engine, 1.2, 2.3);
    objects->Add(Box(x - 0.15, x + 0.15, kerb_top - trunk - 0.3, kerb_top, z - 0.15, z + 0.15), StreetMaterial::kBark,
                 Eigen::Vector3d(0.28, 0.22, 0.16));
    Mesh crown = MakeSphereMesh(Eigen::Vector3d(x + side * 0.3, kerb_top - trunk - 0.8 * radius, z), radius, 8, 12);
    crown.Transform(
        Eigen::Affine3d(Eigen::Translation3d(x, kerb_top - trunk - 0.8 * radius, z) * Eigen::Scaling(1.0, 0.85, 1.0) *
                        Eigen::Translation3d(-x, -(kerb_top - trunk - 0.8 * radius), -z)));
    objects->Add(std::move(crown), StreetMaterial::kFoliage, Eigen::Vector3d(0.15, 0.25, 0.1));
  } else if (kind < 0.45) {  // street light / pole
    const double h = Uniform(engine, 4.0, 8.0);
    objects->Add(Box(x - 0.08, x + 0.08, kerb_top - h, kerb_top, z - 0.08, z + 0.08), StreetMaterial::kPole,
                 Eigen::Vector3d::Constant(Uniform(engine, 0.25, 0.6)));
  } else if (kind < 0.6) {  // sign post with a plate
    const double h = Uniform(engine, 2.2, 3.0);
    objects->Add(Box(x - 0.04, x + 0.04, kerb_top - h, kerb_top, z - 0.04, z + 0.04), StreetMaterial::kPole,
                 Eigen::Vector3d::Constant(0.55));
    const Eigen::Vector3d plate =
        Bernoulli(engine, 0.5) ? Eigen::Vector3d(0.75, 0.08, 0.06) : Eigen::Vector3d(0.08, 0.18, 0.6);
    objects->Add(Box(x - 0.3, x + 0.3, kerb_top - h - 0.6, kerb_top - h + 0.05, z - 0.06, z - 0.04),
                 StreetMaterial::kSign, plate);
  } else if (kind < 0.82) {  // waste bin
    const double s = Uniform(engine, 0.5, 0.75);
    const Eigen::Vector3d bin_colors[] = {{0.1, 0.25, 0.12}, {0.2, 0.2, 0.22}, {0.55, 0.45, 0.1}, {0.1, 0.2, 0.45}};
    objects->Add(
        Box(x - 0.5 * s, x + 0.5 * s, kerb_top - Uniform(engine, 0.9, 1.2), kerb_top, z - 0.5 * s, z + 0.5 * s),
        StreetMaterial::kBin, bin_colors[std::uniform_int_distribution<int>(0, 3)(*engine)]);
  } else {  // bollards
    for (int b = 0; b < 3; ++b) {
      const double zb = z + 1.2 * b;
      objects->Add(Box(x - 0.07, x + 0.07, kerb_top - 0.9, kerb_top, zb - 0.07, zb + 0.07), StreetMaterial::kPole,
                   Eigen::Vector3d::Constant(0.3));
    }
  }
}

// The sidewalk clutter of one side between z0 and z1, about clutter_spacing apart.
void AddSidewalkClutter(const StreetOptions& options, int side, double kerb, double sidewalk, double z0, double z1,
                        StreetLayout* layout, ObjectList* objects, std::mt19937_64* engine) {
  const double y = layout->road_y;
  const double kerb_top = y - options.kerb_height;
  double z = z0 + Uniform(engine, 0.0, options.clutter_spacing);
  while (z < z1 - 0.5) {
    const double x = kerb + side * Uniform(engine, 0.3, std::min(1.2, sidewalk - 0.3));
    const double kind = Uniform(engine, 0.0, 1.0);
    AddClutterItem(kind, x, z, kerb_top, sidewalk, side, objects, engine);
    layout->clutter.push_back(Eigen::Vector3d(x, y, z));
    z += options.clutter_spacing * Uniform(engine, 0.4, 1.6);
  }
}

// Buildings along the cross street (has_intersection).
void AddCrossStreetBuildings(const StreetLayout* layout, ObjectList* objects, std::mt19937_64* engine) {
  const double y = layout->road_y;
  const double zi = layout->intersection_z, hw = layout->intersection_half_width + 3.0;
  for (int side : {-1, 1}) {
    for (double x = side > 0 ? layout->right_kerb_x + 14.0 : layout->left_kerb_x - 14.0; std::abs(x) < 90.0;
         x += side * 20.0) {
      for (double zs : {zi - hw - 12.0, zi + hw}) {
        objects->Add(Box(x, x + side * 18.0, y - Uniform(engine, 6.0, 18.0), y + 0.05, zs, zs + 12.0),
                     StreetMaterial::kFacade,
                     kFacadeColors[std::uniform_int_distribution<int>(0, int(std::size(kFacadeColors)) - 1)(*engine)],
                     std::uniform_int_distribution<int>(0, procedural::kNumFacadeStyles - 1)(*engine), 0);
      }
    }
  }
}

}  // namespace

std::vector<StreetObject> MakeStreetObjects(const StreetOptions& options, StreetLayout* layout, double z_min,
                                            double z_max, uint64_t seed, std::mt19937_64* engine) {
  const double y = layout->road_y;
  const double kerb_top = y - options.kerb_height;
  ObjectList objects;
  objects.seed = seed;
  objects.Add(MakeGroundMesh(y, -120, 120, -80, 260), StreetMaterial::kAsphalt, Eigen::Vector3d::Constant(0.25));
  // z segments of the sidewalks, building rows and clutter (interrupted by the cross street).
  std::vector<std::pair<double, double>> segments;
  if (layout->has_intersection) {
    segments = {{z_min, layout->intersection_z - layout->intersection_half_width},
                {layout->intersection_z + layout->intersection_half_width, z_max}};
  } else {
    segments = {{z_min, z_max}};
  }
  for (int side : {-1, 1}) {
    const double kerb = side > 0 ? layout->right_kerb_x : layout->left_kerb_x;
    const double sidewalk = Uniform(engine, options.min_sidewalk_width, options.max_sidewalk_width);
    const double base_distance = Uniform(engine, options.min_facade_distance,
                                         std::max(options.min_facade_distance, options.max_facade_distance - 4.0));
    for (const auto& [z0, z1] : segments) {
      if (z1 - z0 < 1.0) continue;
      // Kerb stones and sidewalk (a raised slab reaching under the buildings).
      objects.Add(Box(kerb, kerb + side * kKerbStoneWidth, kerb_top, y + 0.05, z0, z1), StreetMaterial::kKerb,
                  Eigen::Vector3d(0.62, 0.61, 0.58));
      objects.Add(Box(kerb + side * kKerbStoneWidth, kerb + side * sidewalk, kerb_top, y + 0.05, z0, z1),
                  StreetMaterial::kSidewalk, Eigen::Vector3d::Constant(0.5));
      AddBuildings(options, side, kerb, sidewalk, base_distance, z0, z1, layout, &objects, engine);
      AddSidewalkClutter(options, side, kerb, sidewalk, z0, z1, layout, &objects, engine);
    }
  }
  if (layout->has_intersection) AddCrossStreetBuildings(layout, &objects, engine);
  // A far block closing the view.
  objects.Add(Box(-90, 90, y - 30.0, y + 0.05, z_max + 10.0, z_max + 16.0), StreetMaterial::kFacade,
              Eigen::Vector3d(0.6, 0.6, 0.62), 1, 0);
  return std::move(objects.objects);
}

Eigen::Vector3d StreetAlbedo(const StreetObject& object, const StreetLayout& layout, const Eigen::Vector3d& p,
                             const Eigen::Vector3d& normal, double footprint) {
  switch (object.material) {
    case StreetMaterial::kAsphalt: {
      if (!layout.OnAsphalt(p.x(), p.z())) return procedural::GrassAlbedo(p, footprint, object.seed);
      double mark = 0.0;
      for (const LaneMarking& m : layout.markings) {
        const double across = m.across ? p.z() : p.x();
        const double along = m.across ? p.x() : p.z();
        if (std::abs(across - m.position) > m.half_width || along < m.from || along > m.to) continue;
        if (m.dash_period > 0.0) {
          const double phase = along - m.dash_period * std::floor(along / m.dash_period);
          if (phase > m.dash_on) continue;
        }
        mark = 1.0;
      }
      const double min_feature = 2.0 * std::min(0.06, 0.5 * footprint + 0.06);
      mark *= 0.25 + 0.75 * procedural::FeatureVisibility(min_feature, footprint);
      return procedural::AsphaltAlbedo(p, mark, footprint, object.seed);
    }
    case StreetMaterial::kYard:
      return procedural::GrassAlbedo(p, footprint, object.seed);
    case StreetMaterial::kSidewalk:
      if (std::abs(normal.y()) > 0.7) return procedural::PavingAlbedo(p, 0.3 + 0.2 * double(object.seed % 3), footprint, object.seed);
      return procedural::ConcreteAlbedo(p, Eigen::Vector3d(0.55, 0.54, 0.52), footprint, object.seed);
    case StreetMaterial::kKerb: {
      Eigen::Vector3d a = procedural::ConcreteAlbedo(p, object.color, footprint, object.seed);
      if (DistanceToGrid(p.z(), 1.0) < 0.01) a *= 1.0 - 0.5 * procedural::FeatureVisibility(0.02, footprint);
      return a;
    }
    case StreetMaterial::kFacade: {
      const bool up_facing = std::abs(normal.y()) > 0.7;
      if (up_facing) return procedural::ConcreteAlbedo(p, Eigen::Vector3d(0.35, 0.33, 0.32), footprint, object.seed);
      const bool street_face = object.facade_axis == 2 ? std::abs(normal.x()) > std::abs(normal.z())
                                                       : std::abs(normal.z()) > std::abs(normal.x());
      const double along = street_face ? (object.facade_axis == 2 ? p.z() : p.x())
                                       : (object.facade_axis == 2 ? p.x() : p.z());
      const procedural::FacadeStyle style =
          street_face ? procedural::FacadeStyle(object.style) : procedural::FacadeStyle::kPlaster;
      return procedural::StyledFacadeAlbedo(style, along, layout.road_y - p.y(), object.color, footprint,
                                            object.seed);
    }
    case StreetMaterial::kRoof:
      return procedural::ConcreteAlbedo(p, object.color, footprint, object.seed);
    case StreetMaterial::kFoliage:
      return procedural::FoliageAlbedo(p, footprint, object.seed);
    case StreetMaterial::kBark:
    case StreetMaterial::kWall:
    case StreetMaterial::kBin:
      return procedural::ConcreteAlbedo(p, object.color, footprint, object.seed);
    case StreetMaterial::kPole:
    case StreetMaterial::kSign:
      return procedural::ConcreteAlbedo(p, object.color, footprint * 4.0, object.seed);
  }
  return object.color;
}

std::vector<double> PlanParkedRow(const StreetOptions& options, const std::vector<double>& lengths,
                                  double z_start, std::mt19937_64* engine) {
  std::vector<double> centres;
  double z = z_start;
  for (double length : lengths) {
    centres.push_back(z + 0.5 * length);
    z += length + Uniform(engine, options.min_parked_gap, options.max_parked_gap);
  }
  return centres;
}

Eigen::Matrix3d EgoSway::Rotation(double t) const {
  const double pitch = pitch_offset + pitch_amplitude * std::sin(2.0 * kPi * pitch_frequency_hz * t + pitch_phase);
  const double roll = roll_amplitude * std::sin(2.0 * kPi * roll_frequency_hz * t + roll_phase);
  return (Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

double EgoSway::Bounce(double t) const {
  return bounce_amplitude * std::sin(2.0 * kPi * bounce_frequency_hz * t + bounce_phase);
}

}  // namespace samp
