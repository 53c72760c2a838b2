#include "libsamp/viz/fit_pictures.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <sstream>

#include "libsamp/core/atomic_file.h"
#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/core/util.h"
#include "libsamp/scan/renderer.h"
#include "libsamp/viz/inspect.h"
#include "libsamp/viz/plot.h"
#include "libsamp/viz/view_option_table.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

constexpr Rgb kDetectionColor{230, 60, 40};
constexpr Rgb kFitColor{20, 110, 220};
constexpr Rgb kGridColor{232, 232, 232};
constexpr Rgb kAboveTauColor{200, 30, 30};

Eigen::Vector3f ToUnit(Rgb c) { return Eigen::Vector3f(c.r, c.g, c.b) / 255.f; }

Rgb Mix(Rgb a, Rgb b, double t) {
  auto m = [t](uint8_t x, uint8_t y) { return uint8_t(std::lround(x + (y - x) * t)); };
  return {m(a.r, b.r), m(a.g, b.g), m(a.b, b.b)};
}

Rgb FrameColor(size_t k, size_t n) { return Viridis(n > 1 ? double(k) / double(n - 1) : 0.0); }
Rgb TrackColor(size_t index) { return PaletteColor(int(index)); }

// Colour of an error e against τ: viridis over [0, τ], red above.
Rgb ErrorColor(double e, double tau) { return e > tau ? kAboveTauColor : Viridis(e / tau); }

void BlendPixel(RgbImage* image, int x, int y, Rgb c, double alpha) {
  if (x < 0 || y < 0 || x >= image->width || y >= image->height) return;
  image->Set(x, y, Mix(image->At(x, y), c, alpha));
}

// A square dot of `size` pixels centred at (x, y).
void Dot(RgbImage* image, double x, double y, int size, Rgb c, double alpha) {
  const int x0 = int(std::floor(x - 0.5 * size + 0.5)), y0 = int(std::floor(y - 0.5 * size + 0.5));
  for (int dy = 0; dy < size; ++dy)
    for (int dx = 0; dx < size; ++dx) BlendPixel(image, x0 + dx, y0 + dy, c, alpha);
}

// Frames shown in the overlay: `count` spread evenly over the track's frames.
std::vector<size_t> SpreadFrames(size_t num_frames, int count) {
  std::vector<size_t> picks;
  if (num_frames == 0) return picks;
  const size_t n = std::min(num_frames, size_t(std::max(1, count)));
  for (size_t i = 0; i < n; ++i) {
    const size_t k = n == 1 ? num_frames / 2 : (i * (num_frames - 1) + (n - 1) / 2) / (n - 1);
    if (picks.empty() || picks.back() != k) picks.push_back(k);
  }
  return picks;
}

// A title bar above `body`.
RgbImage WithTitle(const RgbImage& body, const std::string& title, const std::string& subtitle = "") {
  const int title_height = subtitle.empty() ? 30 : 50;
  RgbImage out(body.width, body.height + title_height, kWhite);
  DrawText(&out, title, 10, 6, MakeTextStyle(16, HAlign::kLeft, VAlign::kTop, true));
  if (!subtitle.empty()) DrawText(&out, subtitle, 10, 28, MakeTextStyle(13));
  Paste(body, 0, title_height, &out);
  return out;
}

RgbImage HConcat(const std::vector<RgbImage>& parts, int gap) {
  int width = 0, height = 0;
  for (const RgbImage& p : parts) width += p.width + gap, height = std::max(height, p.height);
  RgbImage out(std::max(1, width - gap), std::max(1, height), kWhite);
  int x = 0;
  for (const RgbImage& p : parts) {
    Paste(p, x, 0, &out);
    x += p.width + gap;
  }
  return out;
}

RgbImage VConcat(const std::vector<RgbImage>& parts, int gap) {
  int width = 0, height = 0;
  for (const RgbImage& p : parts) height += p.height + gap, width = std::max(width, p.width);
  RgbImage out(std::max(1, width), std::max(1, height - gap), kWhite);
  int y = 0;
  for (const RgbImage& p : parts) {
    Paste(p, 0, y, &out);
    y += p.height + gap;
  }
  return out;
}

// A horizontal colour bar with end labels.
RgbImage ColorBar(int width, const std::string& left, const std::string& right,
                  const std::function<Rgb(double)>& color_of, const std::string& caption) {
  RgbImage bar(width, 40, kWhite);
  const int x0 = 10, x1 = width - 10;
  for (int x = x0; x <= x1; ++x) {
    const Rgb c = color_of(double(x - x0) / std::max(1, x1 - x0));
    DrawLine(&bar, x, 4, x, 16, c, 1);
  }
  DrawText(&bar, left, x0, 20, MakeTextStyle(12));
  DrawText(&bar, right, x1, 20, MakeTextStyle(12, HAlign::kRight));
  DrawText(&bar, caption, width / 2, 20, MakeTextStyle(12, HAlign::kCenter));
  return bar;
}

// ---- Top views ----------------------------------------------------------------
// Maps the plane coordinates (a, b) of a top view to pixels: a to the right,
// b upwards, one scale for both, the box [a0, a1] x [b0, b1] centred.
class TopView {
 public:
  TopView(double a0, double a1, double b0, double b1, int width, int height, int margin = 14)
      : width_(width), height_(height) {
    const double span_a = std::max(1e-3, a1 - a0), span_b = std::max(1e-3, b1 - b0);
    scale_ = std::min((width - 2.0 * margin) / span_a, (height - 2.0 * margin) / span_b);
    ca_ = 0.5 * (a0 + a1), cb_ = 0.5 * (b0 + b1);
  }
  Eigen::Vector2d Pixel(double a, double b) const {
    return {0.5 * width_ + (a - ca_) * scale_, 0.5 * height_ - (b - cb_) * scale_};
  }
  double scale() const { return scale_; }
  double AMin() const { return ca_ - 0.5 * width_ / scale_; }
  double AMax() const { return ca_ + 0.5 * width_ / scale_; }
  double BMin() const { return cb_ - 0.5 * height_ / scale_; }
  double BMax() const { return cb_ + 0.5 * height_ / scale_; }

  // Light grid lines every `step` metres and a scale bar of `step` in the corner.
  void DrawGrid(RgbImage* image, double step) const {
    for (double a = std::ceil(AMin() / step) * step; a <= AMax(); a += step) {
      const double u = Pixel(a, 0).x();
      DrawLine(image, u, 0, u, height_ - 1, kGridColor, 1);
    }
    for (double b = std::ceil(BMin() / step) * step; b <= BMax(); b += step) {
      const double v = Pixel(0, b).y();
      DrawLine(image, 0, v, width_ - 1, v, kGridColor, 1);
    }
    const double length = step * scale_;
    const double x0 = width_ - 12 - length, y0 = height_ - 12;
    DrawLine(image, x0, y0, x0 + length, y0, kDarkGray, 2);
    DrawText(image, (step >= 1 ? Fixed(step, 0) : Fixed(step, 1)) + " m", int(x0 + length / 2), int(y0 - 3),
             MakeTextStyle(11, HAlign::kCenter, VAlign::kBottom));
  }

 private:
  int width_, height_;
  double scale_ = 1.0, ca_ = 0.0, cb_ = 0.0;
};

// Grid spacing for a view of `span` metres: 1, 2, 5, 10, ... m, about 4-10 lines.
double GridStep(double span) {
  const double raw = span / 6.0;
  const double p = std::pow(10.0, std::floor(std::log10(std::max(1e-6, raw))));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (raw <= m * p) return m * p;
  }
  return 10 * p;
}

// World top view: a = x (right), b = z (forward); object top view: a = -z
// (the car's left to the left), b = x (front up).
Eigen::Vector2d WorldPlane(const Eigen::Vector3d& p) { return {p.x(), p.z()}; }
Eigen::Vector2d ObjectPlane(const Eigen::Vector3d& p) { return {-p.z(), p.x()}; }

// The footprint of a box (object frame, x and z extent) under `world_from_object`, world plane.
std::vector<Eigen::Vector2d> Footprint(const AlignedBox& box, const Eigen::Isometry3d& world_from_object) {
  std::vector<Eigen::Vector2d> corners;
  const double xs[4] = {box.min.x(), box.max.x(), box.max.x(), box.min.x()};
  const double zs[4] = {box.min.z(), box.min.z(), box.max.z(), box.max.z()};
  for (int i = 0; i < 4; ++i) corners.push_back(WorldPlane(world_from_object * Eigen::Vector3d(xs[i], 0, zs[i])));
  return corners;
}

void DrawPolygon(RgbImage* image, const TopView& view, const std::vector<Eigen::Vector2d>& corners, Rgb c,
                 int thickness) {
  for (size_t i = 0; i < corners.size(); ++i) {
    const Eigen::Vector2d p = view.Pixel(corners[i].x(), corners[i].y());
    const Eigen::Vector2d q = view.Pixel(corners[(i + 1) % corners.size()].x(), corners[(i + 1) % corners.size()].y());
    DrawLine(image, p.x(), p.y(), q.x(), q.y(), c, thickness);
  }
}

// A box of the detection's size centred like KITTI's (bottom centre at the origin).
AlignedBox DetectionBox(const TrackFrameView& f) {
  AlignedBox box;
  box.min = Eigen::Vector3d(-0.5 * f.detection_size.x(), -f.detection_size.y(), -0.5 * f.detection_size.z());
  box.max = Eigen::Vector3d(0.5 * f.detection_size.x(), 0.0, 0.5 * f.detection_size.z());
  return box;
}

AlignedBox TrackBox(const TrackView& track) {
  if (!track.box.IsEmpty()) return track.box;
  if (!track.mesh.Empty()) return track.mesh.Bounds();
  AlignedBox box;  // a typical car when nothing is known
  box.min = Eigen::Vector3d(-2.0, -1.5, -0.9);
  box.max = Eigen::Vector3d(2.0, 0.0, 0.9);
  return box;
}

// The points of every frame in the object frame of that frame's detection or fitted pose.
RgbImage ObjectFramePanel(const TrackView& track, bool by_detection, int size) {
  const AlignedBox box = TrackBox(track);
  const double half = 0.5 * std::max(box.Size().x(), box.Size().z()) + 1.5;
  const Eigen::Vector2d centre = ObjectPlane(box.Center());
  TopView view(centre.x() - half, centre.x() + half, centre.y() - half, centre.y() + half, size, size);
  RgbImage image(size, size, kWhite);
  view.DrawGrid(&image, 1.0);
  // The fitted box (and the mesh's outline, by its vertices) for reference.
  std::vector<Eigen::Vector2d> corners;
  for (const Eigen::Vector3d& c : {Eigen::Vector3d(box.min.x(), 0, box.min.z()), Eigen::Vector3d(box.max.x(), 0, box.min.z()),
                                   Eigen::Vector3d(box.max.x(), 0, box.max.z()), Eigen::Vector3d(box.min.x(), 0, box.max.z())}) {
    corners.push_back(ObjectPlane(c));
  }
  for (const Eigen::Vector3f& v : track.mesh.vertices) {
    const Eigen::Vector2d p = ObjectPlane(v.cast<double>());
    const Eigen::Vector2d px = view.Pixel(p.x(), p.y());
    BlendPixel(&image, int(px.x()), int(px.y()), kLightGray, 0.6);
  }
  DrawPolygon(&image, view, corners, kGray, 1);
  const size_t n = track.frames.size();
  const double alpha = 0.55;
  for (size_t k = 0; k < n; ++k) {
    const TrackFrameView& f = track.frames[k];
    if (by_detection && !f.has_detection) continue;
    const Eigen::Isometry3d object_from_world =
        (by_detection ? f.world_from_detection : f.world_from_object).inverse();
    const Rgb c = FrameColor(k, n);
    for (const Eigen::Vector3f& p : f.points_in_world) {
      const Eigen::Vector2d q = ObjectPlane(object_from_world * p.cast<double>());
      const Eigen::Vector2d px = view.Pixel(q.x(), q.y());
      Dot(&image, px.x(), px.y(), 2, c, alpha);
    }
  }
  // Heading arrow of the object frame.
  const Eigen::Vector2d tail = view.Pixel(0, box.max.x() + 0.2), head = view.Pixel(0, box.max.x() + 0.9);
  DrawLine(&image, tail.x(), tail.y(), head.x(), head.y(), kDarkGray, 2);
  DrawLine(&image, head.x(), head.y(), head.x() - 5, head.y() + 7, kDarkGray, 2);
  DrawLine(&image, head.x(), head.y(), head.x() + 5, head.y() + 7, kDarkGray, 2);
  return image;
}

// How well the frames' points agree in the object frame: the mean distance of
// the per-frame point centroids from their common mean (metres).
double CentroidSpread(const TrackView& track, bool by_detection) {
  std::vector<Eigen::Vector3d> centroids;
  for (const TrackFrameView& f : track.frames) {
    if (f.points_in_world.empty() || (by_detection && !f.has_detection)) continue;
    const Eigen::Isometry3d object_from_world = (by_detection ? f.world_from_detection : f.world_from_object).inverse();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& p : f.points_in_world) sum += object_from_world * p.cast<double>();
    centroids.push_back(sum / double(f.points_in_world.size()));
  }
  if (centroids.size() < 2) return 0.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& c : centroids) mean += c;
  mean /= double(centroids.size());
  double spread = 0.0;
  for (const auto& c : centroids) spread += (c - mean).norm();
  return spread / double(centroids.size());
}

// Bounds of the world plane coordinates of a sequence's (or one track's) content.
struct PlaneBounds {
  double a0 = 1e300, a1 = -1e300, b0 = 1e300, b1 = -1e300;
  void Add(const Eigen::Vector2d& p) {
    a0 = std::min(a0, p.x()), a1 = std::max(a1, p.x()), b0 = std::min(b0, p.y()), b1 = std::max(b1, p.y());
  }
  bool Empty() const { return a0 > a1; }
  void Grow(double m) { a0 -= m, a1 += m, b0 -= m, b1 += m; }
};

void AddTrackBounds(const TrackView& track, bool with_points, PlaneBounds* bounds) {
  const AlignedBox box = TrackBox(track);
  for (const TrackFrameView& f : track.frames) {
    for (const auto& c : Footprint(box, f.world_from_object)) bounds->Add(c);
    if (f.has_detection) bounds->Add(WorldPlane(f.world_from_detection.translation()));
    if (with_points) {
      for (const auto& p : f.points_in_world) bounds->Add(WorldPlane(p.cast<double>()));
    }
  }
}

// The track in the world from above: points, fitted and detected footprints, the path.
RgbImage TrajectoryPanel(const TrackView& track, int size) {
  PlaneBounds bounds;
  AddTrackBounds(track, false, &bounds);
  bounds.Grow(2.0);
  TopView view(bounds.a0, bounds.a1, bounds.b0, bounds.b1, size, size);
  RgbImage image(size, size, kWhite);
  view.DrawGrid(&image, GridStep(std::max(bounds.a1 - bounds.a0, bounds.b1 - bounds.b0)));
  const size_t n = track.frames.size();
  const AlignedBox box = TrackBox(track);
  for (size_t k = 0; k < n; ++k) {
    const Rgb c = FrameColor(k, n);
    for (const auto& p : track.frames[k].points_in_world) {
      const Eigen::Vector2d q = WorldPlane(p.cast<double>());
      const Eigen::Vector2d px = view.Pixel(q.x(), q.y());
      Dot(&image, px.x(), px.y(), 1, c, 0.35);
    }
  }
  for (size_t k = 0; k < n; ++k) {
    const TrackFrameView& f = track.frames[k];
    DrawPolygon(&image, view, Footprint(box, f.world_from_object), FrameColor(k, n), 1);
    if (f.has_detection) {
      DrawPolygon(&image, view, Footprint(DetectionBox(f), f.world_from_detection), Mix(kDetectionColor, kWhite, 0.6), 1);
      const Eigen::Vector2d d = WorldPlane(f.world_from_detection.translation());
      const Eigen::Vector2d px = view.Pixel(d.x(), d.y());
      DrawLine(&image, px.x() - 4, px.y() - 4, px.x() + 4, px.y() + 4, kDetectionColor, 1);
      DrawLine(&image, px.x() - 4, px.y() + 4, px.x() + 4, px.y() - 4, kDetectionColor, 1);
    }
  }
  for (size_t k = 1; k < n; ++k) {
    const Eigen::Vector2d p = WorldPlane(track.frames[k - 1].world_from_object.translation());
    const Eigen::Vector2d q = WorldPlane(track.frames[k].world_from_object.translation());
    const Eigen::Vector2d pp = view.Pixel(p.x(), p.y()), qq = view.Pixel(q.x(), q.y());
    DrawLine(&image, pp.x(), pp.y(), qq.x(), qq.y(), kFitColor, 2);
  }
  return image;
}

std::string TrackFigures(const TrackView& track) {
  double mean_speed = 0.0;
  int points = 0;
  for (const auto& f : track.frames) mean_speed += f.speed, points += f.num_points;
  if (!track.frames.empty()) mean_speed /= double(track.frames.size());
  const Eigen::Vector3d size = TrackBox(track).Size();
  std::ostringstream s;
  s << track.frames.size() << " frames, " << points << " points, cost " << Fixed(track.initial_cost, 3) << " -> "
    << Fixed(track.final_cost, 3) << ", speed " << Fixed(mean_speed, 1) << " m/s, l\u00d7h\u00d7w "
    << Fixed(size.x(), 2) << "\u00d7" << Fixed(size.y(), 2) << "\u00d7" << Fixed(size.z(), 2) << " m";
  return s.str();
}

std::string TrackTitle(const SequenceView& sequence, const TrackView& track) {
  return sequence.name + " \u00b7 track " + std::to_string(track.id) + " (" + track.mode + ")";
}

// Renders a mesh coloured per triangle: the renderer's shading of a white
// mesh gives the light, multiplied by each triangle's colour; 2x2 supersampled.
RgbImage RenderColoredMesh(const Mesh& mesh, const std::vector<Rgb>& triangle_colors, const View& view) {
  constexpr int kSupersample = 2;
  PinholeCamera camera = view.camera;
  camera.fx *= kSupersample, camera.fy *= kSupersample;
  camera.cx *= kSupersample, camera.cy *= kSupersample;
  camera.width *= kSupersample, camera.height *= kSupersample;
  const RenderBuffers buffers = Render(camera, {PlacedMesh{&mesh, view.camera_from_object}});
  std::vector<uint8_t> light = ShadeRender(buffers, {Eigen::Vector3f(1.f, 1.f, 1.f)});
  for (size_t i = 0; i < buffers.triangle.size(); ++i) {
    const int t = buffers.triangle[i];
    if (buffers.mesh_index[i] < 0 || t < 0 || size_t(t) >= triangle_colors.size()) continue;
    const Rgb c = triangle_colors[size_t(t)];
    const uint8_t base[3] = {c.r, c.g, c.b};
    for (int ch = 0; ch < 3; ++ch) light[3 * i + ch] = uint8_t((int(light[3 * i + ch]) * base[ch]) / 255);
  }
  return Resize(RgbImage::FromBuffer(buffers.width, buffers.height, std::move(light)), view.camera.width,
                view.camera.height);
}

}  // namespace

void FitPictureOptions::Check() const {
  SAMP_CHECK(overlay_frames >= 1) << "FitPictureOptions.overlay_frames must be >= 1";
  SAMP_CHECK(overlay_cell_width >= 32 && overlay_cell_height >= 32)
      << "FitPictureOptions.overlay_cell_width/height must be >= 32 pixels";
  SAMP_CHECK(birdseye_size >= 64) << "FitPictureOptions.birdseye_size must be >= 64 pixels";
  SAMP_CHECK(sequence_sheet_width >= 200) << "FitPictureOptions.sequence_sheet_width must be >= 200 pixels";
  SAMP_CHECK(shape_cell_width >= 32 && shape_cell_height >= 32)
      << "FitPictureOptions.shape_cell_width/height must be >= 32 pixels";
}

std::string FitPictureSummary::BriefReport() const {
  std::ostringstream s;
  s << files.size() << " picture(s)";
  for (const auto& f : files) s << "\n  " << f;
  return s.str();
}

RgbImage RenderTrackOverlay(const SequenceView& sequence, const TrackView& track,
                            const FitPictureOptions& options) {
  options.Check();
  const int cw = options.overlay_cell_width, ch = options.overlay_cell_height;
  const std::vector<size_t> picks = SpreadFrames(track.frames.size(), options.overlay_frames);
  SAMP_CHECK(!picks.empty()) << "track " << track.id << " has no frames";
  const PinholeCamera& camera = sequence.camera;
  const Rgb track_color = kFitColor;
  std::vector<RgbImage> top, bottom;
  for (size_t k : picks) {
    const TrackFrameView& f = track.frames[k];
    RgbImage image(camera.width, camera.height, kLightGray);
    auto image_path = sequence.left_images.find(f.frame);
    if (image_path != sequence.left_images.end()) {
      const RgbImage read = ReadPng(image_path->second);
      if (read.width == camera.width && read.height == camera.height) {
        image = read;
      } else {
        image = Resize(read, camera.width, camera.height);
      }
    }
    // The mesh at the fitted pose in the camera of this frame.
    auto wfc = sequence.world_from_camera.find(f.frame);
    const Eigen::Isometry3d world_from_camera =
        wfc != sequence.world_from_camera.end() ? wfc->second : Eigen::Isometry3d::Identity();
    const Eigen::Isometry3d camera_from_object = world_from_camera.inverse() * f.world_from_object;
    RgbImage fitted = image;
    int mx0 = camera.width, my0 = camera.height, mx1 = -1, my1 = -1;
    if (!track.mesh.Empty()) {
      const RenderBuffers buffers = Render(camera, {PlacedMesh{&track.mesh, camera_from_object}});
      const std::vector<uint8_t> shaded = ShadeRender(buffers, {ToUnit(Mix(track_color, kWhite, 0.35))});
      const int w = buffers.width, h = buffers.height;
      auto inside = [&](int x, int y) {
        return x >= 0 && y >= 0 && x < w && y < h && buffers.mesh_index[size_t(y) * w + x] >= 0;
      };
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          if (!inside(x, y)) continue;
          const size_t i = size_t(y) * w + x;
          mx0 = std::min(mx0, x), my0 = std::min(my0, y), mx1 = std::max(mx1, x), my1 = std::max(my1, y);
          const Rgb s{shaded[3 * i], shaded[3 * i + 1], shaded[3 * i + 2]};
          const bool edge = !inside(x - 1, y) || !inside(x + 1, y) || !inside(x, y - 1) || !inside(x, y + 1);
          fitted.Set(x, y, edge ? track_color : Mix(fitted.At(x, y), s, 0.6));
        }
      }
    }
    // The region shown: the detection box and the mesh, enlarged, at the cell's aspect.
    double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
    if (f.has_detection) {
      x0 = f.detection_box_2d[0], y0 = f.detection_box_2d[1], x1 = f.detection_box_2d[2], y1 = f.detection_box_2d[3];
    }
    if (mx1 >= 0) x0 = std::min(x0, double(mx0)), y0 = std::min(y0, double(my0)), x1 = std::max(x1, double(mx1)),
                  y1 = std::max(y1, double(my1));
    if (x1 < x0) {  // nothing to frame: the projection of the object origin
      const Eigen::Vector3d o = camera_from_object.translation();
      const Eigen::Vector2d uv = o.z() > 0.1 ? camera.Project(o) : Eigen::Vector2d(camera.cx, camera.cy);
      x0 = uv.x() - 40, x1 = uv.x() + 40, y0 = uv.y() - 30, y1 = uv.y() + 30;
    }
    double rw = (x1 - x0) * 1.35 + 16, rh = (y1 - y0) * 1.35 + 16;
    const double aspect = double(cw) / ch;
    if (rw / rh < aspect) rw = rh * aspect; else rh = rw / aspect;
    const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
    const double s = cw / rw;  // output pixels per image pixel
    auto crop = [&](const RgbImage& source, bool with_detection) {
      // Nearest/bilinear resampling through Resize of the clipped region.
      const int ix0 = int(std::floor(cx - rw / 2)), iy0 = int(std::floor(cy - rh / 2));
      const int iw = std::max(1, int(std::ceil(rw))), ih = std::max(1, int(std::ceil(rh)));
      RgbImage region(iw, ih, kLightGray);
      Paste(source, -ix0, -iy0, &region);
      RgbImage cell = Resize(region, cw, ch);
      if (with_detection && f.has_detection) {
        const Eigen::Vector4d& b = f.detection_box_2d;
        DrawRectangle(&cell, int((b[0] - ix0) * s), int((b[1] - iy0) * s), int((b[2] - ix0) * s),
                      int((b[3] - iy0) * s), kDetectionColor, 2);
      }
      return cell;
    };
    RgbImage detection = crop(image, true);
    RgbImage fit = crop(fitted, false);
    const std::string label = "frame " + std::to_string(f.frame) + " \u00b7 " + std::to_string(f.num_points) + " pts";
    DrawRectangle(&detection, 0, 0, cw - 1, 20, kWhite);
    DrawText(&detection, label, 4, 3, MakeTextStyle(12));
    DrawRectangle(&fit, 0, 0, cw - 1, 20, kWhite);
    DrawText(&fit, "fit · " + f.motion_model + ", " + Fixed(f.speed, 1) + " m/s", 4, 3, MakeTextStyle(12));
    top.push_back(detection);
    bottom.push_back(fit);
  }
  RgbImage grid = VConcat({HConcat(top, 6), HConcat(bottom, 6)}, 6);
  RgbImage labelled(grid.width + 26, grid.height, kWhite);
  Paste(grid, 26, 0, &labelled);
  TextStyle side = MakeTextStyle(13, HAlign::kCenter, VAlign::kMiddle, true);
  side.vertical = true;
  DrawText(&labelled, "detection", 12, ch / 2, side);
  DrawText(&labelled, "fitted mesh", 12, ch + 6 + ch / 2, side);
  return WithTitle(labelled, TrackTitle(sequence, track) + ": the fit in the left image", TrackFigures(track));
}

RgbImage RenderTrackBirdsEye(const SequenceView& sequence, const TrackView& track,
                             const FitPictureOptions& options) {
  options.Check();
  const int size = options.birdseye_size;
  auto captioned = [&](const RgbImage& panel, const std::string& caption, const std::string& figure) {
    RgbImage out(panel.width, panel.height + 40, kWhite);
    DrawText(&out, caption, panel.width / 2, 2, MakeTextStyle(13, HAlign::kCenter, VAlign::kTop, true));
    DrawText(&out, figure, panel.width / 2, 20, MakeTextStyle(12, HAlign::kCenter));
    Paste(panel, 0, 40, &out);
    DrawRectangle(&out, 0, 40, panel.width - 1, out.height - 1, kLightGray, 1);
    return out;
  };
  const bool any_detection =
      std::any_of(track.frames.begin(), track.frames.end(), [](const TrackFrameView& f) { return f.has_detection; });
  std::vector<RgbImage> panels;
  if (any_detection) {
    panels.push_back(captioned(ObjectFramePanel(track, true, size), "before: aligned by the detections",
                               "frame centroids spread " + Fixed(CentroidSpread(track, true), 2) + " m"));
  }
  panels.push_back(captioned(ObjectFramePanel(track, false, size), "after: aligned by the fitted poses",
                             "frame centroids spread " + Fixed(CentroidSpread(track, false), 2) + " m"));
  panels.push_back(captioned(TrajectoryPanel(track, size), "trajectory (world, from above)",
                             "fitted footprints, path in blue, detections in red (\u00d7)"));
  RgbImage body = HConcat(panels, 10);
  const size_t n = track.frames.size();
  const std::string first = n ? std::to_string(track.frames.front().frame) : "";
  const std::string last = n ? std::to_string(track.frames.back().frame) : "";
  const RgbImage bar = ColorBar(std::min(body.width, 420), "frame " + first, "frame " + last,
                                [](double t) { return Viridis(t); }, "points coloured by frame");
  RgbImage out = VConcat({body, bar}, 4);
  return WithTitle(out, TrackTitle(sequence, track) + ": stereo points of all frames from above",
                   TrackFigures(track));
}

RgbImage RenderTrackShapeStrip(const TrackView& track, const FitPictureOptions& options) {
  options.Check();
  const int w = options.shape_cell_width, h = options.shape_cell_height;
  std::vector<RgbImage> views;
  const std::vector<std::pair<std::string, std::pair<double, double>>> angles = {
      {"three-quarter", {40.0, 22.0}}, {"side", {90.0, 0.0}}, {"top", {0.0, 89.0}}};
  const Eigen::Vector3f color = ToUnit(Mix(kFitColor, kWhite, 0.35));
  for (const auto& [name, angle] : angles) {
    RgbImage cell(w, h + 20, kWhite);
    if (!track.mesh.Empty()) {
      ViewOptions view_options;
      view_options.width = w, view_options.height = h;
      view_options.azimuth_deg = angle.first, view_options.elevation_deg = angle.second;
      const View view = ThreeQuarterView(track.mesh.Bounds(), view_options);
      Paste(RenderMeshes({&track.mesh}, {color}, view), 0, 20, &cell);
    } else {
      DrawText(&cell, "(no surface)", w / 2, h / 2, MakeTextStyle(13, HAlign::kCenter, VAlign::kMiddle));
    }
    DrawText(&cell, name, w / 2, 2, MakeTextStyle(13, HAlign::kCenter));
    views.push_back(cell);
  }
  const bool sigmas = track.code_in_sigmas.size() == track.shape_code.size() && track.shape_code.size() > 0;
  const Eigen::VectorXd& code = sigmas ? track.code_in_sigmas : track.shape_code;
  if (code.size() > 0) {
    std::vector<std::string> categories;
    std::vector<double> values;
    for (int i = 0; i < code.size(); ++i) categories.push_back("z" + std::to_string(i + 1)), values.push_back(code[i]);
    BarPlotOptions bar;
    bar.width = std::max(260, 40 * int(code.size()) + 120);
    bar.height = h + 20;
    bar.title = sigmas ? "shape code (\u03c3)" : "shape code";
    bar.symmetric = true;
    if (sigmas) bar.reference_lines = {-1.0, 1.0};
    bar.show_values = code.size() <= 10;
    bar.font_px = 12;
    bar.legend = LegendPosition::kNone;
    BarSeries series;
    series.values = values;
    series.color = kFitColor;
    views.push_back(DrawBarPlot(categories, {series}, bar));
  }
  const Eigen::Vector3d size = TrackBox(track).Size();
  return WithTitle(HConcat(views, 8), "track " + std::to_string(track.id) + ": fitted shape",
                   "l\u00d7h\u00d7w " + Fixed(size.x(), 2) + " \u00d7 " + Fixed(size.y(), 2) + " \u00d7 " +
                       Fixed(size.z(), 2) + " m" + (track.mode == "single_frame" ? " (shape of the mean code)" : ""));
}

RgbImage RenderTrackErrorSurface(const SequenceView& sequence, const TrackView& track,
                                 const FitPictureOptions& options) {
  options.Check();
  SAMP_CHECK(!track.mesh.Empty() && track.vertex_errors.size() == track.mesh.vertices.size())
      << "track " << track.id << " has no per-vertex errors (no ground truth matched)";
  const double tau = sequence.error_tau;
  std::vector<Rgb> colors(track.mesh.triangles.size());
  for (size_t t = 0; t < colors.size(); ++t) {
    const Eigen::Vector3i& tri = track.mesh.triangles[t];
    const double e = (track.vertex_errors[tri[0]] + track.vertex_errors[tri[1]] + track.vertex_errors[tri[2]]) / 3.0;
    colors[t] = ErrorColor(e, tau);
  }
  std::vector<RgbImage> views;
  for (const auto& angle : {std::pair<double, double>{40.0, 22.0}, std::pair<double, double>{220.0, 22.0}}) {
    ViewOptions view_options;
    view_options.width = options.shape_cell_width, view_options.height = options.shape_cell_height;
    view_options.azimuth_deg = angle.first, view_options.elevation_deg = angle.second;
    views.push_back(RenderColoredMesh(track.mesh, colors, ThreeQuarterView(track.mesh.Bounds(), view_options)));
  }
  std::vector<float> sorted = track.vertex_errors;
  std::sort(sorted.begin(), sorted.end());
  const double within = double(std::upper_bound(sorted.begin(), sorted.end(), float(tau)) - sorted.begin()) /
                        double(sorted.size());
  const double median = sorted[sorted.size() / 2];
  RgbImage body = HConcat(views, 8);
  const RgbImage bar = ColorBar(body.width, "0 m", Fixed(tau, 2) + " m (red: above)",
                                [tau](double t) { return ErrorColor(t * tau, tau); }, "distance to the true surface");
  return WithTitle(VConcat({body, bar}, 4),
                   TrackTitle(sequence, track) + ": error against ground-truth car " + std::to_string(track.gt_track_id),
                   Fixed(100.0 * within, 1) + " % of the vertices within \u03c4 = " + Fixed(tau, 2) + " m, median " +
                       Fixed(median, 3) + " m (frame " + std::to_string(track.error_frame) + ")");
}

RgbImage RenderSequenceBirdsEye(const SequenceView& sequence, const FitPictureOptions& options) {
  options.Check();
  PlaneBounds bounds;
  for (const TrackView& track : sequence.tracks) AddTrackBounds(track, false, &bounds);
  for (int frame : sequence.frames) {
    auto it = sequence.world_from_camera.find(frame);
    if (it != sequence.world_from_camera.end()) bounds.Add(WorldPlane(it->second.translation()));
  }
  if (bounds.Empty()) bounds.Add({0, 0});
  bounds.Grow(3.0);
  const double span_a = bounds.a1 - bounds.a0, span_b = bounds.b1 - bounds.b0;
  const int width = options.sequence_sheet_width;
  const int height = std::clamp(int(width * span_b / span_a), 240, 2 * width);
  TopView view(bounds.a0, bounds.a1, bounds.b0, bounds.b1, width, height);
  RgbImage image(width, height, kWhite);
  view.DrawGrid(&image, GridStep(std::max(view.AMax() - view.AMin(), view.BMax() - view.BMin())));
  // Ego path: the camera centres.
  std::vector<Eigen::Vector2d> ego;
  for (int frame : sequence.frames) {
    auto it = sequence.world_from_camera.find(frame);
    if (it != sequence.world_from_camera.end()) ego.push_back(WorldPlane(it->second.translation()));
  }
  for (size_t i = 1; i < ego.size(); ++i) {
    const Eigen::Vector2d p = view.Pixel(ego[i - 1].x(), ego[i - 1].y()), q = view.Pixel(ego[i].x(), ego[i].y());
    DrawLine(&image, p.x(), p.y(), q.x(), q.y(), kDarkGray, 2);
  }
  if (!ego.empty()) {
    const Eigen::Vector2d p = view.Pixel(ego.front().x(), ego.front().y());
    DrawLine(&image, p.x(), p.y(), p.x() - 7, p.y() + 12, kDarkGray, 2);
    DrawLine(&image, p.x(), p.y(), p.x() + 7, p.y() + 12, kDarkGray, 2);
    DrawText(&image, "camera", int(p.x()) + 10, int(p.y()) + 2, MakeTextStyle(12));
  }
  for (const GroundTruthCarView& gt : sequence.ground_truth) {
    AlignedBox box;
    box.min = Eigen::Vector3d(-0.5 * gt.size.x(), -gt.size.y(), -0.5 * gt.size.z());
    box.max = Eigen::Vector3d(0.5 * gt.size.x(), 0.0, 0.5 * gt.size.z());
    if (!gt.world_from_object.empty()) {
      DrawPolygon(&image, view, Footprint(box, gt.world_from_object.rbegin()->second), kGray, 1);
    }
  }
  for (size_t t = 0; t < sequence.tracks.size(); ++t) {
    const TrackView& track = sequence.tracks[t];
    const Rgb c = TrackColor(t);
    for (const TrackFrameView& f : track.frames) {
      for (const auto& p : f.points_in_world) {
        const Eigen::Vector2d q = WorldPlane(p.cast<double>());
        const Eigen::Vector2d px = view.Pixel(q.x(), q.y());
        Dot(&image, px.x(), px.y(), 1, c, 0.25);
      }
    }
  }
  for (size_t t = 0; t < sequence.tracks.size(); ++t) {
    const TrackView& track = sequence.tracks[t];
    const Rgb c = TrackColor(t);
    const AlignedBox box = TrackBox(track);
    const size_t n = track.frames.size();
    for (size_t k = 0; k < n; ++k) {
      if (k % 5 != 0 && k + 1 != n) continue;
      DrawPolygon(&image, view, Footprint(box, track.frames[k].world_from_object), Mix(c, kWhite, k + 1 == n ? 0 : 0.5),
                  k + 1 == n ? 2 : 1);
    }
    for (size_t k = 1; k < n; ++k) {
      const Eigen::Vector2d p = WorldPlane(track.frames[k - 1].world_from_object.translation());
      const Eigen::Vector2d q = WorldPlane(track.frames[k].world_from_object.translation());
      const Eigen::Vector2d pp = view.Pixel(p.x(), p.y()), qq = view.Pixel(q.x(), q.y());
      DrawLine(&image, pp.x(), pp.y(), qq.x(), qq.y(), c, 2);
    }
    if (n > 0) {
      const Eigen::Vector2d p = WorldPlane(track.frames.back().world_from_object.translation());
      const Eigen::Vector2d px = view.Pixel(p.x(), p.y());
      DrawText(&image, std::to_string(track.id), int(px.x()) + 8, int(px.y()) - 8,
               MakeTextStyle(13, HAlign::kLeft, VAlign::kBottom, true, c));
    }
  }
  std::ostringstream subtitle;
  subtitle << sequence.tracks.size() << " tracks over " << sequence.frames.size()
           << " frames; trajectories, footprints every 5th frame and the last (bold), points by track"
           << (sequence.ground_truth.empty() ? "" : ", true boxes (last frame) in grey");
  return WithTitle(image, sequence.name + ": all tracks from above (world x right, z forward)", subtitle.str());
}

namespace {

std::string TrackFile(const std::string& folder, int id, const std::string& kind) {
  return (fs::path(folder) / ("track_" + std::to_string(id) + "_" + kind + ".png")).string();
}

void WriteOne(const std::string& path, const std::function<RgbImage()>& draw, FitPictureSummary* summary) {
  try {
    WritePng(path, draw());
    summary->files.push_back(path);
  } catch (const std::exception& e) {
    LogWarning() << "picture " << path << " skipped: " << e.what();
  }
}

}  // namespace

FitPictureSummary WriteFitPictures(const FitRunView& run, const FitPictureOptions& options) {
  options.Check();
  SAMP_CHECK(!options.output_folder.empty()) << "FitPictureOptions.output_folder is empty";
  FitPictureSummary summary;
  for (const SequenceView& sequence : run.sequences) {
    const std::string folder = (fs::path(options.output_folder) / sequence.name).string();
    WriteOne((fs::path(folder) / "birdseye.png").string(), [&] { return RenderSequenceBirdsEye(sequence, options); },
             &summary);
    for (const TrackView& track : sequence.tracks) {
      WriteOne(TrackFile(folder, track.id, "overlay"), [&] { return RenderTrackOverlay(sequence, track, options); },
               &summary);
      WriteOne(TrackFile(folder, track.id, "birdseye"), [&] { return RenderTrackBirdsEye(sequence, track, options); },
               &summary);
      WriteOne(TrackFile(folder, track.id, "shape"), [&] { return RenderTrackShapeStrip(track, options); }, &summary);
      if (options.error_surfaces && !track.vertex_errors.empty()) {
        WriteOne(TrackFile(folder, track.id, "error"),
                 [&] { return RenderTrackErrorSurface(sequence, track, options); }, &summary);
      }
    }
  }
  return summary;
}

FitPictureSummary WriteErrorSurfacePictures(const FitRunView& run, const FitPictureOptions& options) {
  options.Check();
  SAMP_CHECK(!options.output_folder.empty()) << "FitPictureOptions.output_folder is empty";
  FitPictureSummary summary;
  for (const SequenceView& sequence : run.sequences) {
    const std::string folder = (fs::path(options.output_folder) / sequence.name).string();
    for (const TrackView& track : sequence.tracks) {
      if (track.vertex_errors.empty()) continue;
      WriteOne(TrackFile(folder, track.id, "error"), [&] { return RenderTrackErrorSurface(sequence, track, options); },
               &summary);
    }
  }
  return summary;
}

void FitVisualsOptions::Check() const {
  FitVisualsOptionTable().Check(*this);  // with load and page
  picture.Check();
}

std::string FitVisualsSummary::BriefReport() const {
  std::ostringstream s;
  s << num_tracks << " track(s) in " << num_sequences << " sequence(s): " << pictures.size() << " picture(s)";
  if (!html.empty()) s << ", viewer " << html << " (" << Fixed(html_bytes / 1e6, 1) << " MB)";
  s << ", " << Fixed(seconds, 1) << " s";
  return s.str();
}

FitVisualsSummary WriteFitVisuals(const FitVisualsOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  options.Check();
  LoadFitRunOptions load = options.load;
  load.read_images = options.pictures && !options.only_error_surfaces;
  const FitRunView run = LoadFitRun(options.output_dir, load);
  FitVisualsSummary summary;
  summary.num_sequences = int(run.sequences.size());
  summary.num_tracks = run.NumTracks();
  if (options.pictures) {
    FitPictureOptions picture = options.picture;
    picture.output_folder = options.pictures_folder.empty()
                                ? (fs::path(options.output_dir) / "pictures").string()
                                : options.pictures_folder;
    summary.pictures = (options.only_error_surfaces ? WriteErrorSurfacePictures(run, picture)
                                                    : WriteFitPictures(run, picture))
                           .files;
  }
  if (options.html) {
    summary.html = options.html_path.empty() ? (fs::path(options.output_dir) / "index.html").string()
                                             : options.html_path;
    const std::string page = FitViewerHtml(run, options.page);
    WriteTextFileAtomically(summary.html, page);
    summary.html_bytes = page.size();
  }
  // Files added to an earlier samp output folder are samp's: its marker lists
  // them, so the next `samp fit` into it may still replace it.
  std::vector<std::string> written = summary.pictures;
  if (!summary.html.empty()) written.push_back(summary.html);
  RecordInOutputFolder(options.output_dir, written);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace samp
