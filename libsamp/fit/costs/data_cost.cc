#include "libsamp/fit/costs/data_cost.h"

#include <algorithm>
#include <cmath>

#include "libsamp/core/error.h"
#include "libsamp/fit/costs/disparity.h"
#include "libsamp/fit/costs/point_sdf.h"
#include "libsamp/fit/costs/ray_depth.h"

#if defined(SAMP_HAVE_LIBMVEC) && defined(__x86_64__)
#include <immintrin.h>
#define SAMP_MIXTURE_AVX2 1
// glibc's vector math (libmvec), the x86-64 vector ABI's AVX2 variants: four
// doubles per call, at most 4 ulp from the correctly rounded result.
extern "C" {
__attribute__((target("avx2"))) __m256d _ZGVdN4v_exp(__m256d x);
__attribute__((target("avx2"))) __m256d _ZGVdN4v_expm1(__m256d x);
__attribute__((target("avx2"))) __m256d _ZGVdN4v_log1p(__m256d x);
}
#endif

namespace samp {

void CameraInObject(const Eigen::Vector3d& camera, const double* pose, double c, double s, double* o_cam) {
  const double dx = camera[0] - pose[0], dy = camera[1] - pose[1], dz = camera[2] - pose[2];
  o_cam[0] = c * dx - s * dz;
  o_cam[1] = dy;
  o_cam[2] = s * dx + c * dz;
}

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

double HuberPsi(double s, double k, double* d_psi) {
  const double a = std::abs(s);
  if (a <= k) {
    if (d_psi) *d_psi = 1.0;
    return s;
  }
  const double root = std::sqrt(2.0 * k * a - k * k);
  if (d_psi) *d_psi = k / root;
  return s > 0.0 ? root : -root;
}

double MixturePsi(double s, double s0, double* d_psi) { return MixturePsiWithC(s, std::exp(-0.5 * s0 * s0), d_psi); }

double MixturePsiWithC(double s, double c, double* d_psi) {
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

#ifdef SAMP_MIXTURE_AVX2
namespace {

const bool kCpuHasAvx2 = [] {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") != 0;
}();

// MixturePsiWithC's arithmetic in four lanes (n a multiple of 4).
__attribute__((target("avx2"))) void MixturePsi4Lanes(const double* s, int n, double c, double* psi, double* d_psi) {
  const __m256d vc = _mm256_set1_pd(c), minus_half = _mm256_set1_pd(-0.5), two = _mm256_set1_pd(2.0);
  const __m256d zero = _mm256_setzero_pd(), sign_bit = _mm256_set1_pd(-0.0);
  const __m256d d_at_zero = _mm256_set1_pd(1.0 / std::sqrt(1.0 + c));
  for (int k = 0; k < n; k += 4) {
    const __m256d vs = _mm256_loadu_pd(s + k);
    const __m256d x = _mm256_mul_pd(_mm256_mul_pd(minus_half, vs), vs);  // -s^2 / 2
    const __m256d e = _ZGVdN4v_exp(x), e_c = _mm256_add_pd(e, vc);
    // rho = 2 log1p((1 - e) / (e + c)), 1 - e = -expm1(-s^2 / 2).
    const __m256d y = _mm256_div_pd(_mm256_sub_pd(zero, _ZGVdN4v_expm1(x)), e_c);
    const __m256d root = _mm256_sqrt_pd(_mm256_mul_pd(two, _ZGVdN4v_log1p(y)));
    // d psi / ds = |s| e / ((e + c) root), its limit 1 / sqrt(1 + c) where root is 0.
    const __m256d d = _mm256_div_pd(_mm256_mul_pd(_mm256_andnot_pd(sign_bit, vs), e), _mm256_mul_pd(e_c, root));
    _mm256_storeu_pd(d_psi + k, _mm256_blendv_pd(d_at_zero, d, _mm256_cmp_pd(root, zero, _CMP_GT_OQ)));
    // psi = sign(s) root.
    _mm256_storeu_pd(psi + k, _mm256_or_pd(root, _mm256_and_pd(sign_bit, vs)));
  }
}

}  // namespace
#endif

bool MixturePsiRowsVectorised() {
#ifdef SAMP_MIXTURE_AVX2
  return kCpuHasAvx2;
#else
  return false;
#endif
}

void MixturePsiRows(const double* s, int n, double c, double* psi, double* d_psi) {
  int k = 0;
#ifdef SAMP_MIXTURE_AVX2
  if (kCpuHasAvx2) {
    k = n / 4 * 4;
    MixturePsi4Lanes(s, k, c, psi, d_psi);
    if (k < n) {  // the last one to three in a padded group of four
      double s4[4] = {0.0, 0.0, 0.0, 0.0}, psi4[4], d4[4];
      std::copy(s + k, s + n, s4);
      MixturePsi4Lanes(s4, 4, c, psi4, d4);
      std::copy(psi4, psi4 + (n - k), psi + k);
      std::copy(d4, d4 + (n - k), d_psi + k);
      return;
    }
  }
#endif
  for (; k < n; ++k) psi[k] = MixturePsiWithC(s[k], c, &d_psi[k]);
}

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

DataCost::DataCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                   const std::vector<double>& sigmas, const DataCostOptions& options, bool with_rays)
    : lookup_(lookup), huber_(options.huber_threshold), mixture_(options.mixture_loss) {
  SAMP_CHECK(lookup != nullptr) << "DataCost: null shape lookup";
  SAMP_CHECK(!points_in_world.empty()) << "DataCost: no points";
  SAMP_CHECK(points_in_world.size() == sigmas.size())
      << "DataCost: " << points_in_world.size() << " points but " << sigmas.size() << " sigmas";
  SAMP_CHECK(options.huber_threshold > 0.0) << "DataCost: Huber threshold must be > 0";
  SAMP_CHECK(options.weight > 0.0) << "DataCost: weight must be > 0";
  SAMP_CHECK(options.camera_in_world.allFinite()) << "DataCost: camera centre is not finite";
  const size_t n = points_in_world.size();
  sqrt_weight_ = std::sqrt(options.weight / double(n));
  points_.resize(3 * n);
  inv_sigmas_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    SAMP_CHECK(points_in_world[i].allFinite()) << "DataCost: point " << i << " is not finite";
    SAMP_CHECK(sigmas[i] > 0.0 && std::isfinite(sigmas[i]))
        << "DataCost: sigma of point " << i << " must be > 0, got " << sigmas[i];
    for (int a = 0; a < 3; ++a) points_[3 * i + a] = points_in_world[i][a];
    inv_sigmas_[i] = 1.0 / sigmas[i];
  }
  camera_ = options.camera_in_world;
  outlier_threshold_ = options.outlier_threshold;
  SAMP_CHECK(!mixture_ || outlier_threshold_ > 0.0) << "DataCost: outlier_threshold must be > 0";
  mixture_c_ = std::exp(-0.5 * outlier_threshold_ * outlier_threshold_);
  if (with_rays) {
    rays_.resize(3 * n);
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d ray = points_in_world[i] - options.camera_in_world;
      SAMP_CHECK(ray.norm() > 0.0) << "DataCost: point " << i << " is at the camera centre";
      for (int a = 0; a < 3; ++a) rays_[3 * i + a] = ray[a] / ray.norm();
    }
  }
  set_num_residuals(int(n));
  mutable_parameter_block_sizes()->push_back(lookup->num_components());
  mutable_parameter_block_sizes()->push_back(4);
}

bool DataCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const int nr = lookup_->num_components();
  double* jz = jacobians ? jacobians[0] : nullptr;
  double* jp = jacobians ? jacobians[1] : nullptr;
  return EvaluateRows(parameters[0], parameters[1], 0, num_residuals(), residuals, jz, nr, jp, 4);
}

void DataCost::WriteDistanceRows(int first, int n, const double* phi, const double (*g)[3], const double (*o)[3],
                                 double c, double s, int nr, double* residuals, double* jz, int jz_stride,
                                 double* jp, int jp_stride) const {
  SAMP_CHECK(n >= 0 && n <= kRowChunk) << "WriteDistanceRows: " << n << " rows, at most " << kRowChunk;
  double scaled[kRowChunk] = {}, psi[kRowChunk], d_psi[kRowChunk];
  for (int k = 0; k < n; ++k) scaled[k] = phi[k] * inv_sigmas_[first + k];  // s_i = phi / sigma_i
  if (mixture_) {
    MixturePsiRows(scaled, n, mixture_c_, psi, d_psi);
  } else {
    for (int k = 0; k < n; ++k) psi[k] = HuberPsi(scaled[k], huber_, &d_psi[k]);
  }
  for (int k = 0; k < n; ++k) {
    residuals[k] = sqrt_weight_ * psi[k];
    const double f = sqrt_weight_ * d_psi[k] * inv_sigmas_[first + k];
    WriteJacobianRow(f, c, s, g[k], o[k], nr, jz ? jz + size_t(k) * jz_stride : nullptr,
                     jp ? jp + size_t(k) * jp_stride : nullptr);
  }
}

bool DataCost::DistanceRows(const double* z, const double* pose, int begin, int end, double* residuals, double* jz,
                            int jz_stride, double* jp, int jp_stride) const {
  const PoseFrame at = AtPose(z, pose);
  for (int first = begin; first < end; first += kRowChunk) {
    const int n = std::min(kRowChunk, end - first), row0 = first - begin;
    double phi[kRowChunk], o[kRowChunk][3], g[kRowChunk][3];
    for (int k = 0; k < n; ++k) {
      PointInObject(first + k, pose, at.c, at.s, o[k]);
      double* dz_row = jz ? jz + size_t(row0 + k) * jz_stride : nullptr;
      phi[k] = lookup_->EvaluateDense(at.phi_z, o[k], jp ? g[k] : nullptr, dz_row);
      if (!std::isfinite(phi[k])) return false;
    }
    WriteDistanceRows(first, n, phi, g, o, at.c, at.s, at.nr, residuals + row0,
                      jz ? jz + size_t(row0) * jz_stride : nullptr, jz_stride,
                      jp ? jp + size_t(row0) * jp_stride : nullptr, jp_stride);
  }
  return true;
}

std::unique_ptr<DataCost> MakeDataCost(const ShapeLookup* lookup, const std::vector<Eigen::Vector3d>& points_in_world,
                                       const std::vector<double>& sigmas, const DataCostOptions& options) {
  switch (options.term) {
    case DataTerm::kPaper: return std::make_unique<PointSdfCost>(lookup, points_in_world, sigmas, options);
    case DataTerm::kRayDepth: return std::make_unique<RayDepthCost>(lookup, points_in_world, sigmas, options);
    case DataTerm::kDisparity: return std::make_unique<DisparityCost>(lookup, points_in_world, sigmas, options);
  }
  SAMP_THROW() << "MakeDataCost: unknown data term";
}

}  // namespace samp
