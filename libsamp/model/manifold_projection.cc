#include "libsamp/model/manifold_projection.h"

#include "libsamp/core/error.h"

namespace samp {

Eigen::VectorXd ProjectToManifold(const ShapeModel& model, const std::vector<float>& sdf,
                                  double prior_weight) {
  SAMP_CHECK(int64_t(sdf.size()) == model.NumVoxels())
      << "ProjectToManifold: " << sdf.size() << " values for a model of " << model.NumVoxels()
      << " voxels";
  SAMP_CHECK(prior_weight >= 0) << "ProjectToManifold: prior_weight must be >= 0";
  const Eigen::Map<const Eigen::VectorXf> x(sdf.data(), Eigen::Index(sdf.size()));
  const Eigen::VectorXf centred = x - model.mean;
  Eigen::VectorXd z = (model.components.transpose() * centred).cast<double>();
  if (prior_weight > 0) {
    for (int i = 0; i < z.size(); ++i) {
      const double variance = model.eigenvalues[i];
      z[i] = variance > 0 ? z[i] / (1.0 + prior_weight / variance) : 0.0;
    }
  }
  return z;
}

}  // namespace samp
