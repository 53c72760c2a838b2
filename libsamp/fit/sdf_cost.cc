#include "libsamp/fit/sdf_cost.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "libsamp/core/error.h"

namespace samp {

namespace {

// Ray distance: at most this many sphere-tracing steps, each at least half a
// voxel; Newton steps on the bracketed crossing; at most kMaxRayRatio |phi|;
// crossings with |grad phi . u| below kMinRaySlope (grazing) count as misses.
constexpr int kMaxMarchSteps = 24;
constexpr int kNewtonSteps = 3;
constexpr double kMaxRayRatio = 5.0;
constexpr double kMinRaySlope = 0.05;
// First crossing (kDisparity): at most this many sphere-tracing steps from
// the grid box entry; golden-section steps refining a miss's closest approach.
constexpr int kMaxTraceSteps = 64;
constexpr int kGoldenSteps = 16;

}  // namespace

const char* DataTermName(DataTerm term) {
  switch (term) {
    case DataTerm::kPaper: return "paper";
    case DataTerm::kRayDepth: return "ray-depth";
    case DataTerm::kDisparity: return "disparity";
  }
  return "?";
}

DataTerm ParseDataTerm(const std::string& name) {
  for (DataTerm t : {DataTerm::kPaper, DataTerm::kRayDepth, DataTerm::kDisparity}) {
    if (name == DataTermName(t)) return t;
  }
  SAMP_THROW() << "unknown data term '" << name << "' (paper, ray-depth, disparity)";
}

namespace {

// One point's Jacobian rows from phi's derivatives: d/dz row (already
// d phi / dz) scaled by f, and the pose row from the spatial gradient g at the
// object-frame point o with R_y(theta) = (c, s): R grad = (c g0 + s g2, g1,
// -s g0 + c g2), d/dtheta = g . (-o_z, 0, o_x).
void WriteJacobianRow(double f, double c, double s, const double* g, const double* o, int nr, double* dz_row,
                      double* pose_row) {
  if (dz_row) {
    for (int r = 0; r < nr; ++r) dz_row[r] *= f;
  }
  if (pose_row) {
    pose_row[0] = -f * (c * g[0] + s * g[2]);
    pose_row[1] = -f * g[1];
    pose_row[2] = -f * (-s * g[0] + c * g[2]);
    pose_row[3] = f * (-g[0] * o[2] + g[2] * o[0]);
  }
}

}  // namespace

double SdfCost::MixturePsi(double s, double s0, double* d_psi) {
  const double c = std::exp(-0.5 * s0 * s0);
  const double e = std::exp(-0.5 * s * s);
  if (s == 0.0) {
    if (d_psi) *d_psi = 1.0 / std::sqrt(1.0 + c);
    return 0.0;
  }
  // rho = -2 log((e + c) / (1 + c)) = 2 log1p((1 - e) / (e + c)), stable for small s.
  const double rho = 2.0 * std::log1p(-std::expm1(-0.5 * s * s) / (e + c));
  const double root = std::sqrt(rho);
  if (d_psi) *d_psi = root > 0.0 ? std::abs(s) * e / ((e + c) * root) : 1.0 / std::sqrt(1.0 + c);
  return s > 0.0 ? root : -root;
}

SdfCost::SdfCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                 const std::vector<double>& sigmas, const SdfCostOptions& options)
    : lookup_(lookup), term_(options.term), huber_(options.huber_threshold), mixture_(options.mixture_loss) {
  SAMP_CHECK(lookup != nullptr) << "SdfCost: null shape lookup";
  SAMP_CHECK(!points_in_world.empty()) << "SdfCost: no points";
  SAMP_CHECK(points_in_world.size() == sigmas.size())
      << "SdfCost: " << points_in_world.size() << " points but " << sigmas.size() << " sigmas";
  SAMP_CHECK(options.huber_threshold > 0.0) << "SdfCost: Huber threshold must be > 0";
  SAMP_CHECK(options.weight > 0.0) << "SdfCost: weight must be > 0";
  SAMP_CHECK(options.camera_in_world.allFinite()) << "SdfCost: camera centre is not finite";
  const size_t n = points_in_world.size();
  sqrt_weight_ = std::sqrt(options.weight / double(n));
  points_.resize(3 * n);
  inv_sigmas_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    SAMP_CHECK(points_in_world[i].allFinite()) << "SdfCost: point " << i << " is not finite";
    SAMP_CHECK(sigmas[i] > 0.0 && std::isfinite(sigmas[i]))
        << "SdfCost: sigma of point " << i << " must be > 0, got " << sigmas[i];
    for (int a = 0; a < 3; ++a) points_[3 * i + a] = points_in_world[i][a];
    inv_sigmas_[i] = 1.0 / sigmas[i];
  }
  camera_ = options.camera_in_world;
  outlier_threshold_ = options.outlier_threshold;
  SAMP_CHECK(!mixture_ || outlier_threshold_ > 0.0) << "SdfCost: outlier_threshold must be > 0";
  if (term_ != DataTerm::kPaper) {
    rays_.resize(3 * n);
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d ray = points_in_world[i] - options.camera_in_world;
      SAMP_CHECK(ray.norm() > 0.0) << "SdfCost: point " << i << " is at the camera centre";
      for (int a = 0; a < 3; ++a) rays_[3 * i + a] = ray[a] / ray.norm();
    }
  }
  if (term_ == DataTerm::kDisparity) {
    SAMP_CHECK(options.focal_px > 0.0 && std::isfinite(options.focal_px))
        << "SdfCost: focal_px must be > 0 for the disparity term, got " << options.focal_px;
    SAMP_CHECK(options.silhouette_sigma_px > 0.0) << "SdfCost: silhouette_sigma_px must be > 0";
    SAMP_CHECK(options.outlier_threshold > 0.0) << "SdfCost: outlier_threshold must be > 0";
    SAMP_CHECK(std::abs(options.camera_axis_in_world.norm() - 1.0) < 1e-6)
        << "SdfCost: camera_axis_in_world must be a unit vector";
    ray_lengths_.resize(n);
    axis_cosines_.resize(n);
    inv_silhouette_sigmas_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d ray = points_in_world[i] - options.camera_in_world;
      ray_lengths_[i] = ray.norm();
      axis_cosines_[i] = ray.dot(options.camera_axis_in_world) / ray_lengths_[i];
      SAMP_CHECK(axis_cosines_[i] > 1e-3) << "SdfCost: point " << i << " is not in front of the camera";
      const double depth = axis_cosines_[i] * ray_lengths_[i];
      inv_silhouette_sigmas_[i] = options.focal_px / (depth * options.silhouette_sigma_px);
    }
  }
  set_num_residuals(int(n));
  mutable_parameter_block_sizes()->push_back(lookup->num_components());
  mutable_parameter_block_sizes()->push_back(4);
}

bool SdfCost::Evaluate(double const* const* parameters, double* residuals,
                       double** jacobians) const {
  const int nr = lookup_->num_components();
  double* jz = jacobians ? jacobians[0] : nullptr;
  double* jp = jacobians ? jacobians[1] : nullptr;
  return EvaluateRows(parameters[0], parameters[1], 0, num_residuals(), residuals, jz, nr, jp, 4);
}

bool SdfCost::EvaluateRows(const double* z, const double* pose, int begin, int end, double* residuals,
                           double* jz, int jz_stride, double* jp, int jp_stride) const {
  const int nr = lookup_->num_components();
  const double c = std::cos(pose[3]), s = std::sin(pose[3]);
  const double* phi_z = lookup_->DenseCached(z);
  if (term_ == DataTerm::kDisparity) {
    // The camera centre in the object frame.
    const double dx = camera_[0] - pose[0], dy = camera_[1] - pose[1], dz = camera_[2] - pose[2];
    const double o_cam[3] = {c * dx - s * dz, dy, s * dx + c * dz};
    for (int row = 0; row < end - begin; ++row) {
      const int i = begin + row;
      const double* w = &rays_[3 * i];
      const double u[3] = {c * w[0] - s * w[2], w[1], s * w[0] + c * w[2]};
      double* dz_row = jz ? jz + size_t(row) * jz_stride : nullptr;
      double m, o[3], g[3];
      const RayResidual ray = DisparityResidual(i, phi_z, o_cam, u, &m, o, jp ? g : nullptr, dz_row);
      if (!std::isfinite(ray.value)) return false;
      double d_psi = 1.0;
      residuals[row] = sqrt_weight_ * MixturePsi(ray.value, outlier_threshold_, &d_psi);
      const double f = sqrt_weight_ * d_psi * m;
      WriteJacobianRow(f, c, s, g, o, nr, dz_row, jp ? jp + size_t(row) * jp_stride : nullptr);
    }
    return true;
  }
  // The camera centre in the object frame (kRayDepth: points behind the far side).
  const double cx = camera_[0] - pose[0], cy = camera_[1] - pose[1], cz = camera_[2] - pose[2];
  const double o_cam[3] = {c * cx - s * cz, cy, s * cx + c * cz};
  for (int row = 0; row < end - begin; ++row) {
    const int i = begin + row;
    const double dx = points_[3 * i] - pose[0];
    const double dy = points_[3 * i + 1] - pose[1];
    const double dz = points_[3 * i + 2] - pose[2];
    double o[3] = {c * dx - s * dz, dy, s * dx + c * dz};
    double g[3];
    double* dz_row = jz ? jz + size_t(row) * jz_stride : nullptr;
    double phi = lookup_->EvaluateDense(phi_z, o, jp ? g : nullptr, dz_row);
    if (!std::isfinite(phi)) return false;
    if (!rays_.empty() && phi != 0.0) {
      // Distance along the viewing ray (searched up to kMaxRayRatio |phi|).
      // An outside point without a crossing there either lies behind the
      // far side (its ray meets the shape before it): minus its depth behind
      // that first crossing, like a point inside; or its ray passes the shape
      // (beside the silhouette): the Euclidean phi of the paper's term (m = 1).
      const double* w = &rays_[3 * i];
      const double u[3] = {c * w[0] - s * w[2], w[1], s * w[0] + c * w[2]};
      double distance, crossing[3];
      double m = 1.0;
      double g_crossing[3];
      bool found = RayDistance(phi_z, o, phi, u, &distance, crossing, g_crossing);
      if (!found && phi > 0.0) {
        double lambda, phi_min;
        const double li = std::sqrt((o[0] - o_cam[0]) * (o[0] - o_cam[0]) + (o[1] - o_cam[1]) * (o[1] - o_cam[1]) +
                                    (o[2] - o_cam[2]) * (o[2] - o_cam[2]));
        if (FirstCrossing(phi_z, o_cam, u, &lambda, crossing, g_crossing, &phi_min, /*refine_miss=*/false) &&
            lambda < li &&
            g_crossing[0] * u[0] + g_crossing[1] * u[1] + g_crossing[2] * u[2] < -kMinRaySlope) {
          found = true;
          distance = li - lambda;
          phi = -phi;  // behind the visible surface: signed like a point inside
        }
      }
      if (found) {
        // phi_eff = sign(phi) distance; by implicit differentiation of
        // phi(crossing) = 0 its derivatives are those of phi at the crossing
        // times m = -1 / (grad phi . u) (RayDistance ensures grad phi . u < 0).
        m = -1.0 / (g_crossing[0] * u[0] + g_crossing[1] * u[1] + g_crossing[2] * u[2]);
        for (int a = 0; a < 3; ++a) {
          o[a] = crossing[a];
          g[a] = g_crossing[a];
        }
        if (dz_row) lookup_->EvaluateDense(phi_z, crossing, nullptr, dz_row);
        phi = phi < 0.0 ? -distance : distance;
        for (int a = 0; a < 3; ++a) g[a] *= m;
        if (dz_row) {
          for (int r = 0; r < nr; ++r) dz_row[r] *= m;
        }
      }  // else: phi, g (when needed) and dz_row stay phi's at o
    }
    double d_psi = 1.0;
    const double scaled = phi * inv_sigmas_[i];  // s_i = phi / sigma_i
    residuals[row] = sqrt_weight_ * (mixture_ ? MixturePsi(scaled, outlier_threshold_, &d_psi)
                                              : Psi(scaled, huber_, &d_psi));
    const double f = sqrt_weight_ * d_psi * inv_sigmas_[i];
    WriteJacobianRow(f, c, s, g, o, nr, dz_row, jp ? jp + size_t(row) * jp_stride : nullptr);
  }
  return true;
}

bool SdfCost::RayDistance(const double* phi_z, const double* o, double phi_o, const double* u,
                          double* distance, double* c, double* g_c) const {
  const double min_step = 0.5 * lookup_->grid().voxel_size;
  const double sign = phi_o < 0.0 ? -1.0 : 1.0;  // inside: towards the camera
  auto at = [&](double d, double* p) {
    for (int a = 0; a < 3; ++a) p[a] = o[a] + sign * d * u[a];
  };
  auto same_side = [&](double v) { return sign < 0.0 ? v < 0.0 : v > 0.0; };
  // Sphere tracing: |phi| bounds the distance to the surface.
  double lo = 0.0, phi_lo = phi_o, hi = 0.0, phi_hi = phi_o;
  const double limit = kMaxRayRatio * std::abs(phi_o);
  for (int k = 0; k < kMaxMarchSteps && same_side(phi_hi) && hi <= limit; ++k) {
    lo = hi;
    phi_lo = phi_hi;
    hi = lo + std::max(std::abs(phi_lo), min_step);
    at(hi, c);
    phi_hi = lookup_->EvaluateDense(phi_z, c, nullptr, nullptr);
    if (!std::isfinite(phi_hi)) return false;
  }
  if (same_side(phi_hi)) return false;
  // Secant in the bracket [lo, hi], then Newton steps kept inside it until
  // |phi| is negligible; c and g_c are those of the final distance.
  double d = lo + (hi - lo) * phi_lo / (phi_lo - phi_hi);
  const double tolerance = 1e-9 * lookup_->grid().voxel_size;
  for (int k = 0;; ++k) {
    at(d, c);
    const double v = lookup_->EvaluateDense(phi_z, c, g_c, nullptr);
    const double slope = sign * (g_c[0] * u[0] + g_c[1] * u[1] + g_c[2] * u[2]);  // d phi / d distance
    if (k == kNewtonSteps || std::abs(v) <= tolerance || slope == 0.0 || !std::isfinite(slope)) break;
    d = std::min(std::max(d - v / slope, lo), hi);
  }
  if (d > limit) return false;
  // A crossing at a grazing angle (or none after all) counts as a miss.
  if (!(g_c[0] * u[0] + g_c[1] * u[1] + g_c[2] * u[2] < -kMinRaySlope)) return false;
  *distance = d;
  return true;
}

bool SdfCost::FirstCrossing(const double* phi_z, const double* o_cam, const double* u, double* lambda, double* c,
                            double* g_c, double* phi_min, bool refine_miss) const {
  const GridSpec& grid = lookup_->grid();
  const Eigen::Vector3d lo = grid.MinCorner(), hi = grid.MaxCorner();
  auto at = [&](double l, double* p) {
    for (int a = 0; a < 3; ++a) p[a] = o_cam[a] + l * u[a];
  };
  auto phi_at = [&](double l) {
    double p[3];
    at(l, p);
    return lookup_->EvaluateDense(phi_z, p, nullptr, nullptr);
  };
  auto finish_miss = [&](double l) {
    *lambda = l;
    at(l, c);
    *phi_min = lookup_->EvaluateDense(phi_z, c, g_c, nullptr);
    return false;
  };
  // Slab intersection with the grid box.
  double enter = 0.0, leave = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(u[a]) < 1e-12) {
      if (o_cam[a] < lo[a] || o_cam[a] > hi[a]) enter = leave + 1.0;
      continue;
    }
    double t0 = (lo[a] - o_cam[a]) / u[a], t1 = (hi[a] - o_cam[a]) / u[a];
    if (t0 > t1) std::swap(t0, t1);
    enter = std::max(enter, t0);
    leave = std::min(leave, t1);
  }
  if (!(enter <= leave)) {
    // The ray passes the grid box: its closest approach to the box centre.
    const Eigen::Vector3d centre = 0.5 * (lo + hi);
    double l = 0.0;
    for (int a = 0; a < 3; ++a) l += (centre[a] - o_cam[a]) * u[a];
    return finish_miss(std::max(l, 0.0));
  }
  // Sphere tracing from the entry: |phi| bounds the distance to the surface.
  const double min_step = 0.5 * grid.voxel_size;
  double ls[kMaxTraceSteps + 1], vs[kMaxTraceSteps + 1];
  int count = 0;
  double l = enter;
  for (;;) {
    const double v = phi_at(l);
    if (!std::isfinite(v)) {
      *phi_min = v;
      return false;
    }
    ls[count] = l;
    vs[count] = v;
    ++count;
    if (v < 0.0) break;
    if (l >= leave || count > kMaxTraceSteps) break;
    l = std::min(l + std::max(v, min_step), leave);
  }
  if (vs[count - 1] < 0.0 && count >= 2) {
    // Crossing bracketed in [ls[count-2], ls[count-1]]: secant, then Newton
    // steps kept inside the bracket.
    const double a_lo = ls[count - 2], a_hi = ls[count - 1];
    const double v_lo = vs[count - 2], v_hi = vs[count - 1];
    double d = a_lo + (a_hi - a_lo) * v_lo / (v_lo - v_hi);
    const double tolerance = 1e-9 * grid.voxel_size;
    double v = 0.0, slope = 0.0;
    for (int k = 0;; ++k) {
      at(d, c);
      v = lookup_->EvaluateDense(phi_z, c, g_c, nullptr);
      slope = g_c[0] * u[0] + g_c[1] * u[1] + g_c[2] * u[2];
      if (k == kNewtonSteps || std::abs(v) <= tolerance || slope == 0.0 || !std::isfinite(slope)) break;
      d = std::min(std::max(d - v / slope, a_lo), a_hi);
    }
    *lambda = d;
    *phi_min = v;
    return true;  // the caller clamps a grazing slope
  }
  if (vs[count - 1] < 0.0) return finish_miss(ls[0]);  // inside at the box entry (a shape touching the box)
  if (!refine_miss) return false;
  // Miss: the smallest sampled phi, refined by golden-section search in the
  // neighbouring samples' interval.
  int best = 0;
  for (int k = 1; k < count; ++k) {
    if (vs[k] < vs[best]) best = k;
  }
  double a = ls[std::max(best - 1, 0)], b = ls[std::min(best + 1, count - 1)];
  if (b > a) {
    constexpr double kInvPhi = 0.6180339887498949;
    double x1 = b - kInvPhi * (b - a), x2 = a + kInvPhi * (b - a);
    double f1 = phi_at(x1), f2 = phi_at(x2);
    for (int k = 0; k < kGoldenSteps; ++k) {
      if (f1 < f2) {
        b = x2;
        x2 = x1;
        f2 = f1;
        x1 = b - kInvPhi * (b - a);
        f1 = phi_at(x1);
      } else {
        a = x1;
        x1 = x2;
        f1 = f2;
        x2 = a + kInvPhi * (b - a);
        f2 = phi_at(x2);
      }
    }
    const double x = f1 < f2 ? x1 : x2;
    if (std::min(f1, f2) < vs[best]) return finish_miss(x);
  }
  return finish_miss(ls[best]);
}

RayResidual SdfCost::DisparityResidual(int i, const double* phi_z, const double* o_cam, const double* u, double* m,
                                       double* c, double* g, double* dz_row) const {
  RayResidual out;
  double lambda = 0.0, g_c[3], phi_min = 0.0;
  out.hit = FirstCrossing(phi_z, o_cam, u, &lambda, c, g_c, &phi_min);
  if (out.hit) {
    const double li = ray_lengths_[i], a = axis_cosines_[i], inv_sigma = inv_sigmas_[i];
    double slope = g_c[0] * u[0] + g_c[1] * u[1] + g_c[2] * u[2];
    if (!(slope < -kMinRaySlope)) {
      // Grazing: the crossing moves fast with the parameters; its derivative
      // is taken with the slope clamped (a Gauss-Newton approximation).
      out.grazing = true;
      slope = -kMinRaySlope;
    }
    out.value = a * li * (lambda - li) / lambda * inv_sigma;
    *m = -a * li * li / (lambda * lambda) * inv_sigma / slope;
  } else {
    out.value = phi_min * inv_silhouette_sigmas_[i];
    *m = inv_silhouette_sigmas_[i];
  }
  if (g) {
    for (int k = 0; k < 3; ++k) g[k] = g_c[k];
  }
  if (dz_row) lookup_->EvaluateDense(phi_z, c, nullptr, dz_row);
  return out;
}

std::vector<RayResidual> SdfCost::RayResiduals(const double* z, const double* pose) const {
  SAMP_CHECK(term_ == DataTerm::kDisparity) << "SdfCost::RayResiduals needs the disparity term";
  const double c = std::cos(pose[3]), s = std::sin(pose[3]);
  const double* phi_z = lookup_->DenseCached(z);
  const double dx = camera_[0] - pose[0], dy = camera_[1] - pose[1], dz = camera_[2] - pose[2];
  const double o_cam[3] = {c * dx - s * dz, dy, s * dx + c * dz};
  std::vector<RayResidual> out(static_cast<size_t>(num_residuals()));
  for (int i = 0; i < num_residuals(); ++i) {
    const double* w = &rays_[3 * i];
    const double u[3] = {c * w[0] - s * w[2], w[1], s * w[0] + c * w[2]};
    double m, o[3];
    out[size_t(i)] = DisparityResidual(i, phi_z, o_cam, u, &m, o, nullptr, nullptr);
  }
  return out;
}

CompressedSdfCost::CompressedSdfCost(const ShapeLookup* lookup,
                                     const std::vector<Eigen::Vector3d>& points_in_world,
                                     const std::vector<double>& sigmas, const SdfCostOptions& options)
    : full_(lookup, points_in_world, sigmas, options),
      num_components_(lookup->num_components()) {
  set_num_residuals(num_components_ + 4 + 1);
  mutable_parameter_block_sizes()->push_back(num_components_);
  mutable_parameter_block_sizes()->push_back(4);
}

bool CompressedSdfCost::Evaluate(double const* const* parameters, double* residuals,
                                 double** jacobians) const {
  const int nr = num_components_, m = nr + 4;
  std::lock_guard<std::mutex> lock(cache_mutex_);
  const bool hit = cache_valid_ && std::equal(parameters[0], parameters[0] + nr, cache_parameters_.begin()) &&
                   std::equal(parameters[1], parameters[1] + 4, cache_parameters_.begin() + nr);
  if (!hit) {
    cache_valid_ = false;
    cache_parameters_.assign(parameters[0], parameters[0] + nr);
    cache_parameters_.insert(cache_parameters_.end(), parameters[1], parameters[1] + 4);
    cache_residuals_.resize(size_t(m) + 1);
    cache_jz_.resize(size_t(m + 1) * nr);
    cache_jp_.resize(size_t(m + 1) * 4);
    if (!Linearize(parameters[0], parameters[1])) return false;
    cache_valid_ = true;
  }
  std::copy(cache_residuals_.begin(), cache_residuals_.end(), residuals);
  if (jacobians && jacobians[0]) std::copy(cache_jz_.begin(), cache_jz_.end(), jacobians[0]);
  if (jacobians && jacobians[1]) std::copy(cache_jp_.begin(), cache_jp_.end(), jacobians[1]);
  return true;
}

bool CompressedSdfCost::Linearize(const double* z, const double* pose) const {
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const int n = full_.num_residuals();
  const int nr = num_components_, m = nr + 4;
  // The points in chunks whose rows stay in the L1/L2 cache: J^T J, J^T r
  // and |r|^2 are accumulated chunk by chunk (per-thread scratch).
  // J = [d/dz | d/dpose], one row per point.
  constexpr int kChunk = 256;
  thread_local std::vector<double> r_buffer, j_buffer;
  r_buffer.resize(kChunk);
  j_buffer.resize(size_t(kChunk) * m);
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(m);
  double squared_norm = 0.0;
  for (int begin = 0; begin < n; begin += kChunk) {
    const int end = std::min(n, begin + kChunk), rows = end - begin;
    if (!full_.EvaluateRows(z, pose, begin, end, r_buffer.data(), j_buffer.data(), m, j_buffer.data() + nr, m)) {
      return false;
    }
    const Eigen::Map<const Eigen::VectorXd> r(r_buffer.data(), rows);
    const Eigen::Map<const RowMatrix> j(j_buffer.data(), rows, m);
    h.selfadjointView<Eigen::Lower>().rankUpdate(j.transpose());
    g.noalias() += j.transpose() * r;
    squared_norm += r.squaredNorm();
  }
  const double eps = 1e-12 * std::max(h.trace(), 1e-300);
  h.diagonal().array() += eps;
  Eigen::LLT<Eigen::MatrixXd, Eigen::Lower> llt(h);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::VectorXd rc = llt.matrixL().solve(g);
  for (int k = 0; k < m; ++k) cache_residuals_[size_t(k)] = rc[k];
  cache_residuals_[size_t(m)] = std::sqrt(std::max(0.0, squared_norm - rc.squaredNorm()));
  // Row k of the compressed Jacobian = row k of L^T; last row zero.
  const RowMatrix lt = llt.matrixL().transpose();  // m x m, upper
  Eigen::Map<RowMatrix> jz(cache_jz_.data(), m + 1, nr), jp(cache_jp_.data(), m + 1, 4);
  jz.topRows(m) = lt.leftCols(nr);
  jz.row(m).setZero();
  jp.topRows(m) = lt.rightCols(4);
  jp.row(m).setZero();
  return true;
}

}  // namespace samp
