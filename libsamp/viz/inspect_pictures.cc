// The pictures of `samp inspect --pictures`: eigen-shape grid and shape sheet.
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "libsamp/core/error.h"
#include "libsamp/core/log.h"
#include "libsamp/core/util.h"
#include "libsamp/model/trainer.h"
#include "libsamp/scan/mesh_io.h"
#include "libsamp/scan/renderer.h"
#include "libsamp/viz/inspect.h"
#include "libsamp/viz/inspect_option_table.h"
#include "libsamp/viz/opencv_image.h"
#include "libsamp/viz/plot.h"
#include "libsamp/sdf/surface.h"

namespace samp {
namespace {

namespace fs = std::filesystem;

constexpr Rgb kSubtleColor{110, 110, 110};
constexpr Rgb kSeparatorColor{225, 225, 225};

double Sigma(const ShapeModel& model, int i) { return std::sqrt(std::max(0.0, model.eigenvalues[i])); }

// "-2σ", "mean", "+1.5σ".
std::string SigmaLabel(double k) {
  if (k == 0.0) return "mean";
  char buffer[32];
  if (std::abs(k - std::round(k)) < 1e-9) {
    std::snprintf(buffer, sizeof(buffer), "%+d\u03c3", int(std::lround(k)));
  } else {
    std::snprintf(buffer, sizeof(buffer), "%+.1f\u03c3", k);
  }
  std::string s = buffer;
  if (s[0] == '-') s = "\u2212" + s.substr(1);  // a real minus sign
  return s;
}


// Shortens text with an ellipsis to fit `width` pixels.
std::string FitText(std::string text, double size, int width) {
  TextStyle style = MakeTextStyle(size);
  int w = 0;
  MeasureText(text, style, &w, nullptr);
  if (w <= width) return text;
  while (text.size() > 1) {
    text.pop_back();
    MeasureText(text + "\u2026", style, &w, nullptr);
    if (w <= width) break;
  }
  return text + "\u2026";
}

AlignedBox UnionBounds(const std::vector<const Mesh*>& meshes) {
  AlignedBox box;
  for (const Mesh* m : meshes) {
    if (m == nullptr || m->Empty()) continue;
    const AlignedBox b = m->Bounds();
    box.Extend(b.min);
    box.Extend(b.max);
  }
  return box;
}

// The pixel box holding everything that is not white, over all images (same size).
cv::Rect CommonContent(const std::vector<RgbImage>& images, int margin) {
  int x0 = INT32_MAX, y0 = INT32_MAX, x1 = -1, y1 = -1;
  for (const RgbImage& image : images) {
    for (int y = 0; y < image.height; ++y) {
      for (int x = 0; x < image.width; ++x) {
        if (image.At(x, y) != kWhite) {
          x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
        }
      }
    }
  }
  if (x1 < 0 || images.empty()) return cv::Rect(0, 0, images.empty() ? 0 : images[0].width,
                                                images.empty() ? 0 : images[0].height);
  x0 = std::max(0, x0 - margin), y0 = std::max(0, y0 - margin);
  x1 = std::min(images[0].width - 1, x1 + margin), y1 = std::min(images[0].height - 1, y1 + margin);
  return cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
}

RgbImage Crop(const RgbImage& image, const cv::Rect& rect) {
  RgbImage result(rect.width, rect.height);
  Paste(image, -rect.x, -rect.y, &result);
  return result;
}

// Pastes `image` scaled to fit and centred into the cell at (x, y).
void PasteFitted(const RgbImage& image, int x, int y, int width, int height, RgbImage* canvas) {
  if (image.Empty()) return;
  const RgbImage fitted = ResizeToFit(image, width, height);
  Paste(fitted, x + (width - fitted.width) / 2, y + (height - fitted.height) / 2, canvas);
}

// Renders every mesh with one camera framing all of them, then crops all
// renders to their common content so that sizes stay comparable.
std::vector<RgbImage> RenderComparable(const std::vector<const Mesh*>& meshes,
                                       const std::vector<Eigen::Vector3f>& colors, int cell_width,
                                       int cell_height) {
  std::vector<RgbImage> renders(meshes.size());
  const AlignedBox bounds = UnionBounds(meshes);
  if (bounds.IsEmpty()) return renders;
  ViewOptions view_options;
  view_options.width = cell_width;
  view_options.height = cell_height;
  const View view = ThreeQuarterView(bounds, view_options);
  for (size_t i = 0; i < meshes.size(); ++i) {
    renders[i] = meshes[i] != nullptr && !meshes[i]->Empty()
                     ? RenderMeshes({meshes[i]}, {colors[i]}, view)
                     : RgbImage(cell_width, cell_height, kWhite);
  }
  const cv::Rect content = CommonContent(renders, 4);
  for (auto& r : renders) r = Crop(r, content);
  return renders;
}

Eigen::Vector3f ColumnColor(double k, double k_max) {
  const Eigen::Vector3f neutral(0.72f, 0.72f, 0.74f);
  const Eigen::Vector3f negative(0.36f, 0.55f, 0.82f);  // blue
  const Eigen::Vector3f positive(0.90f, 0.55f, 0.32f);  // orange
  const float t = k_max > 0 ? float(std::min(1.0, std::abs(k) / k_max)) : 0.f;
  return (1.f - t) * neutral + t * (k < 0 ? negative : positive);
}

}  // namespace

// ---- Views and rendering ------------------------------------------------------

View ThreeQuarterView(const AlignedBox& bounds, const ViewOptions& options) {
  SAMP_CHECK(!bounds.IsEmpty()) << "ThreeQuarterView: empty bounds";
  SAMP_CHECK(options.width > 0 && options.height > 0) << "ThreeQuarterView: bad image size";
  const double azimuth = options.azimuth_deg * M_PI / 180.0;
  const double elevation = options.elevation_deg * M_PI / 180.0;
  // Object frame: x front, y down, z left. Direction from the centre to the eye.
  const Eigen::Vector3d to_eye(std::cos(elevation) * std::cos(azimuth), -std::sin(elevation),
                               std::cos(elevation) * std::sin(azimuth));
  const Eigen::Vector3d centre = bounds.Center();
  const double radius = std::max(1e-6, 0.5 * bounds.Size().norm());
  const Eigen::Vector3d eye = centre + 4.0 * radius * to_eye;
  const Eigen::Vector3d forward = (centre - eye).normalized();
  const Eigen::Vector3d up(0, -1, 0);
  const Eigen::Vector3d right = forward.cross(up).normalized();
  const Eigen::Vector3d down = forward.cross(right);
  Eigen::Matrix3d rotation;
  rotation.row(0) = right.transpose();
  rotation.row(1) = down.transpose();
  rotation.row(2) = forward.transpose();
  View view;
  view.camera_from_object.linear() = rotation;
  view.camera_from_object.translation() = -rotation * eye;
  // Frame the box's corners tightly: focal length and principal point.
  double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? bounds.max.x() : bounds.min.x(),
                                 (c & 2) ? bounds.max.y() : bounds.min.y(),
                                 (c & 4) ? bounds.max.z() : bounds.min.z());
    const Eigen::Vector3d p = view.camera_from_object * corner;
    u0 = std::min(u0, p.x() / p.z()), u1 = std::max(u1, p.x() / p.z());
    v0 = std::min(v0, p.y() / p.z()), v1 = std::max(v1, p.y() / p.z());
  }
  const double usable = 1.0 - 2.0 * options.margin;
  const double f = std::min(options.width * usable / (u1 - u0), options.height * usable / (v1 - v0));
  view.camera.fx = view.camera.fy = f;
  view.camera.cx = 0.5 * options.width - f * 0.5 * (u0 + u1);
  view.camera.cy = 0.5 * options.height - f * 0.5 * (v0 + v1);
  view.camera.width = options.width;
  view.camera.height = options.height;
  return view;
}

RgbImage RenderMeshes(const std::vector<const Mesh*>& meshes,
                      const std::vector<Eigen::Vector3f>& colors, const View& view) {
  SAMP_CHECK(colors.size() == meshes.size()) << "RenderMeshes: one colour per mesh";
  constexpr int kSupersample = 2;
  PinholeCamera camera = view.camera;
  camera.fx *= kSupersample, camera.fy *= kSupersample;
  camera.cx *= kSupersample, camera.cy *= kSupersample;
  camera.width *= kSupersample, camera.height *= kSupersample;
  std::vector<PlacedMesh> placed;
  std::vector<Eigen::Vector3f> placed_colors;
  for (size_t i = 0; i < meshes.size(); ++i) {
    if (meshes[i] == nullptr || meshes[i]->Empty()) continue;
    placed.push_back({meshes[i], view.camera_from_object});
    placed_colors.push_back(colors[i]);
  }
  if (placed.empty()) return RgbImage(view.camera.width, view.camera.height, kWhite);
  const RenderBuffers buffers = Render(camera, placed);
  const RgbImage large =
      RgbImage::FromBuffer(buffers.width, buffers.height, ShadeRender(buffers, placed_colors));
  return Resize(large, view.camera.width, view.camera.height);
}

RgbImage RenderSdfSlice(const GridSpec& grid, const std::vector<float>& sdf, int scale) {
  SAMP_CHECK(int64_t(sdf.size()) == grid.NumVoxels())
      << "RenderSdfSlice: " << sdf.size() << " values for " << grid.NumVoxels() << " voxels";
  SAMP_CHECK(scale >= 1) << "RenderSdfSlice: scale must be >= 1";
  const int k = std::clamp(int(std::lround(grid.ToVoxel(Eigen::Vector3d::Zero()).z())), 0,
                           grid.dims.z() - 1);
  const int nx = grid.dims.x(), ny = grid.dims.y();
  cv::Mat slice(ny, nx, CV_32F);
  std::vector<float> magnitudes;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const float v = sdf[grid.Index(i, j, k)];
      slice.at<float>(j, i) = v;
      magnitudes.push_back(std::abs(v));
    }
  }
  std::nth_element(magnitudes.begin(), magnitudes.begin() + magnitudes.size() * 98 / 100, magnitudes.end());
  const double max_abs = std::max(1e-3f, magnitudes[magnitudes.size() * 98 / 100]);
  // Bilinear upsampling with samples at pixel centres (image x = object x, image y = object y: down).
  cv::Mat large;
  cv::resize(slice, large, cv::Size(nx * scale, ny * scale), 0, 0, cv::INTER_LINEAR);
  std::vector<float> values(large.begin<float>(), large.end<float>());
  RgbImage image = ColorizeSigned(values, large.cols, large.rows, max_abs);
  // Zero level set as an anti-aliased black polyline.
  cv::Mat inside = large < 0.0f;
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(inside, contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
  cv::Mat mat = internal::AsMat(&image);
  cv::drawContours(mat, contours, -1, cv::Scalar(20, 20, 20), std::max(1, scale / 4), cv::LINE_AA);
  return image;
}

// ---- Eigen-shape grid ---------------------------------------------------------------

void PictureOptions::Check() const {
  PictureOptionTable().Check(*this);
}

RgbImage RenderEigenShapeGrid(const ShapeModel& model, const PictureOptions& options) {
  options.Check();
  model.Check();
  const int rows = options.max_components > 0
                       ? std::min(options.max_components, model.NumComponents())
                       : model.NumComponents();
  const int cols = int(options.sigmas.size());
  double k_max = 0.0;
  for (double k : options.sigmas) k_max = std::max(k_max, std::abs(k));
  std::vector<Mesh> meshes(size_t(rows) * cols);
  tbb::parallel_for(0, rows * cols, [&](int index) {
    const int i = index / cols, c = index % cols;
    Eigen::VectorXd z = Eigen::VectorXd::Zero(model.NumComponents());
    z[i] = options.sigmas[c] * Sigma(model, i);
    meshes[index] = ExtractSurface(model.grid, model.Shape(z));
  });
  std::vector<const Mesh*> pointers;
  std::vector<Eigen::Vector3f> colors;
  for (int index = 0; index < rows * cols; ++index) {
    pointers.push_back(&meshes[index]);
    colors.push_back(ColumnColor(options.sigmas[index % cols], k_max));
  }
  const std::vector<RgbImage> renders =
      RenderComparable(pointers, colors, options.cell_width, options.cell_height);

  // Layout: title, column headers, a label column, cells.
  const int cw = options.cell_width, ch = options.cell_height;
  const int label_w = 170, title_h = 44, header_h = 30, pad = 16, gap = 6;
  const int width = pad + label_w + cols * (cw + gap) - gap + pad;
  const int height = title_h + header_h + rows * (ch + gap) - gap + pad;
  RgbImage canvas(width, height, kWhite);
  DrawText(&canvas, "Eigen-shapes: zero level sets of \u03bc + k\u00b7\u03c3\u1d62\u00b7w\u1d62",
           width / 2, 12, MakeTextStyle(20, HAlign::kCenter, VAlign::kTop, true));
  const double total = model.total_variance > 0 ? model.total_variance : model.eigenvalues.sum();
  for (int c = 0; c < cols; ++c) {
    const int x = pad + label_w + c * (cw + gap);
    DrawText(&canvas, SigmaLabel(options.sigmas[c]), x + cw / 2, title_h + header_h / 2,
             MakeTextStyle(16, HAlign::kCenter, VAlign::kMiddle, true));
  }
  double cumulative = 0.0;
  for (int i = 0; i < rows; ++i) {
    const int y = title_h + header_h + i * (ch + gap);
    if (i > 0) DrawLine(&canvas, pad, y - gap / 2.0, width - pad, y - gap / 2.0, kSeparatorColor, 1);
    const double share = total > 0 ? model.eigenvalues[i] / total : 0.0;
    cumulative += share;
    DrawText(&canvas, "component " + std::to_string(i + 1), pad, y + ch / 2 - 22,
             MakeTextStyle(16, HAlign::kLeft, VAlign::kMiddle, true));
    const double rms_cm = 100.0 * Sigma(model, i) / std::sqrt(double(model.NumVoxels()));
    DrawText(&canvas, "\u03c3 = " + Fixed(Sigma(model, i), 2) + " m (" + Fixed(rms_cm, 1) + " cm/voxel)",
             pad, y + ch / 2,
             MakeTextStyle(13, HAlign::kLeft, VAlign::kMiddle, false, kSubtleColor));
    DrawText(&canvas,
             Fixed(100 * share, 1) + " % (cum. " + Fixed(100 * cumulative, 1) + " %)" +
                 (model.total_variance > 0 ? "" : "*"),
             pad, y + ch / 2 + 20, MakeTextStyle(13, HAlign::kLeft, VAlign::kMiddle, false, kSubtleColor));
    for (int c = 0; c < cols; ++c) {
      PasteFitted(renders[size_t(i) * cols + c], pad + label_w + c * (cw + gap), y, cw, ch, &canvas);
    }
  }
  if (model.total_variance <= 0) {
    DrawText(&canvas, "* share of the variance kept by the R components (no total variance stored)",
             pad, height - 4, MakeTextStyle(11, HAlign::kLeft, VAlign::kBottom, false, kSubtleColor));
  }
  return canvas;
}

// ---- Shape sheet ----------------------------------------------------------------------

RgbImage RenderShapeSheet(const ShapeModel& model, const std::vector<ShapeInput>& shapes,
                          const PictureOptions& options) {
  options.Check();
  model.Check();
  SAMP_CHECK(!shapes.empty()) << "RenderShapeSheet: no shapes";
  const int n = int(shapes.size());
  std::vector<Mesh> reconstructions(n);
  std::vector<Eigen::VectorXd> codes(n);
  std::vector<double> rms_near(n, 0.0);
  tbb::parallel_for(0, n, [&](int s) {
    codes[s] = ProjectToManifold(model, shapes[s].sdf);
    const Eigen::VectorXf phi = model.Shape(codes[s]);
    double sum = 0;
    int64_t count = 0;
    for (int64_t i = 0; i < model.NumVoxels(); ++i) {
      if (std::abs(shapes[s].sdf[i]) < 2 * model.grid.voxel_size) {
        const double e = phi[i] - shapes[s].sdf[i];
        sum += e * e, ++count;
      }
    }
    rms_near[s] = count > 0 ? std::sqrt(sum / count) : 0.0;
    reconstructions[s] = ExtractSurface(model.grid, phi);
  });
  std::vector<const Mesh*> pointers;
  std::vector<Eigen::Vector3f> colors;
  for (int s = 0; s < n; ++s) {
    pointers.push_back(&shapes[s].original);
    colors.push_back(Eigen::Vector3f(0.72f, 0.72f, 0.74f));
    pointers.push_back(&reconstructions[s]);
    colors.push_back(Eigen::Vector3f(0.36f, 0.55f, 0.82f));
  }
  const std::vector<RgbImage> renders =
      RenderComparable(pointers, colors, options.cell_width, options.cell_height);

  const int cw = options.cell_width, ch = options.cell_height;
  const int label_w = 150, title_h = 44, header_h = 30, pad = 16, gap = 8, foot_h = 18;
  const int cols = 4;
  const int width = pad + label_w + cols * (cw + gap) - gap + pad;
  const int row_h = ch + foot_h;
  const int height = title_h + header_h + n * (row_h + gap) - gap + pad;
  RgbImage canvas(width, height, kWhite);
  DrawText(&canvas, "Training shapes and their reconstruction from the manifold (R = " +
                        std::to_string(model.NumComponents()) + ")",
           width / 2, 12, MakeTextStyle(20, HAlign::kCenter, VAlign::kTop, true));
  bool all_cad = true;
  for (const auto& s : shapes) all_cad = all_cad && s.kind == "cad";
  const std::string headers[cols] = {all_cad ? "CAD model" : "original",
                                     "SDF slice z = 0 (blue inside)", "reconstruction",
                                     "code z\u1d62 / \u03c3\u1d62"};
  for (int c = 0; c < cols; ++c) {
    DrawText(&canvas, headers[c], pad + label_w + c * (cw + gap) + cw / 2, title_h + header_h / 2,
             MakeTextStyle(16, HAlign::kCenter, VAlign::kMiddle, true));
  }
  std::vector<std::string> categories;
  for (int i = 0; i < model.NumComponents(); ++i) categories.push_back(std::to_string(i + 1));
  // One code axis for all rows, symmetric, at least +-1.
  double code_max = 1.0;
  for (int s = 0; s < n; ++s) {
    for (int i = 0; i < codes[s].size(); ++i) {
      const double sigma = Sigma(model, i);
      if (sigma > 0) code_max = std::max(code_max, std::abs(codes[s][i] / sigma));
    }
  }
  code_max = NiceTicks(-code_max, code_max, 5).back();
  const int slice_scale = std::max(2, int(std::ceil(double(cw) / model.grid.dims.x())) * 2);
  for (int s = 0; s < n; ++s) {
    const int y = title_h + header_h + s * (row_h + gap);
    if (s > 0) DrawLine(&canvas, pad, y - gap / 2.0, width - pad, y - gap / 2.0, kSeparatorColor, 1);
    DrawText(&canvas, FitText(shapes[s].name, 15, label_w - 8), pad, y + ch / 2,
             MakeTextStyle(15, HAlign::kLeft, VAlign::kMiddle, true));
    DrawText(&canvas, shapes[s].kind == "cad" ? "CAD file" : "SDF file", pad, y + ch / 2 + 20,
             MakeTextStyle(12, HAlign::kLeft, VAlign::kMiddle, false, kSubtleColor));
    const int x0 = pad + label_w;
    PasteFitted(renders[2 * s], x0, y, cw, ch, &canvas);
    PasteFitted(RenderSdfSlice(model.grid, shapes[s].sdf, slice_scale), x0 + (cw + gap), y + 8, cw,
                ch - 16, &canvas);
    PasteFitted(renders[2 * s + 1], x0 + 2 * (cw + gap), y, cw, ch, &canvas);
    DrawText(&canvas, "RMS SDF error near the surface " + Fixed(100 * rms_near[s], 2) + " cm",
             x0 + 2 * (cw + gap) + cw / 2, y + ch + foot_h / 2,
             MakeTextStyle(12, HAlign::kCenter, VAlign::kMiddle, false, kSubtleColor));
    BarSeries code;
    for (int i = 0; i < codes[s].size(); ++i) {
      const double sigma = Sigma(model, i);
      code.values.push_back(sigma > 0 ? codes[s][i] / sigma : 0.0);
    }
    code.color = Rgb{92, 140, 209};
    BarPlotOptions plot;
    plot.width = cw;
    plot.height = ch + foot_h;
    plot.y_min = -code_max;
    plot.y_max = code_max;
    plot.reference_lines = {-1.0, 1.0};
    plot.font_px = 11;
    plot.max_ticks = 5;
    plot.x_label = "component";
    PasteFitted(DrawBarPlot(categories, {code}, plot), x0 + 3 * (cw + gap), y, cw, ch + foot_h,
                &canvas);
  }
  return canvas;
}

// ---- Writing the pictures ------------------------------------------------------------

std::string PictureSummary::BriefReport() const {
  std::ostringstream out;
  for (const auto& f : files) out << "wrote " << f << "\n";
  return out.str();
}

PictureSummary WritePictures(const ShapeModel& model, const PictureOptions& options) {
  options.Check();
  PictureSummary summary;
  const std::string grid_path = (fs::path(options.output_folder) / "eigen_shapes.png").string();
  WritePng(grid_path, RenderEigenShapeGrid(model, options));
  summary.files.push_back(grid_path);

  // Shapes for the sheet: training shapes first (in the model's order), then others.
  std::string folder = !options.sdf_folder.empty() ? options.sdf_folder : options.cad_folder;
  if (folder.empty()) return summary;
  std::error_code ec;
  SAMP_CHECK(fs::is_directory(folder, ec)) << "cannot read " << folder << ": not a folder";
  const bool use_sdf = !options.sdf_folder.empty();
  std::vector<std::string> files;
  for (auto it = fs::recursive_directory_iterator(folder, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (!it->is_regular_file()) continue;
    const std::string path = it->path().string();
    const bool is_vdb = it->path().extension() == ".vdb";
    if (use_sdf ? is_vdb : (!is_vdb && IsMeshFile(path))) files.push_back(path);
  }
  std::sort(files.begin(), files.end());
  std::map<std::string, int> rank;
  for (size_t i = 0; i < model.training_shapes.size(); ++i) rank[model.training_shapes[i]] = int(i);
  std::stable_sort(files.begin(), files.end(), [&](const std::string& a, const std::string& b) {
    auto r = [&](const std::string& f) {
      auto it = rank.find(fs::path(f).stem().string());
      return it == rank.end() ? INT32_MAX : it->second;
    };
    return r(a) < r(b);
  });
  std::vector<ShapeInput> shapes;
  for (const auto& file : files) {
    if (int(shapes.size()) >= options.num_sheet_shapes) break;
    try {
      ShapeInput input = LoadShapeInput(file, model, options.manifest_path);
      // With both folders, show the CAD model itself next to its stored SDF.
      if (use_sdf && !options.cad_folder.empty() && !input.source_file.empty()) {
        const fs::path cad = fs::path(options.cad_folder) / input.source_file;
        if (fs::exists(cad, ec)) {
          std::string name;
          CanonicalizeOptions canonicalize;
          if (!options.manifest_path.empty()) {
            const Manifest manifest = LoadManifest(options.manifest_path);
            const ManifestEntry* entry = manifest.Find(input.source_file);
            canonicalize = entry != nullptr ? entry->canonicalize : manifest.defaults;
          }
          input.original = CanonicalCad(cad.string(), canonicalize).mesh;
          input.kind = "cad";
        }
      }
      shapes.push_back(std::move(input));
    } catch (const std::exception& e) {
      LogWarning() << "sheet: skipping " << file << ": " << e.what();
    }
  }
  SAMP_CHECK(!shapes.empty()) << "no usable shape in " << folder << " for the sheet";
  const std::string sheet_path = (fs::path(options.output_folder) / "shapes.png").string();
  WritePng(sheet_path, RenderShapeSheet(model, shapes, options));
  summary.files.push_back(sheet_path);
  return summary;
}

}  // namespace samp
