// Projection of a signed distance field onto the shape manifold phi(z) = W z + mu
// of a model (docs/inspect.md "Encoding"). A pure function: thread-safe.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "libsamp/model/shape_model.h"

namespace samp {

// z = W^T (x - mu) for the dense SDF x on the model grid; with prior_weight
// lambda > 0 the minimiser of |W z + mu - x|^2 + lambda sum_i z_i^2 / sigma_i^2,
// i.e. z_i / (1 + lambda / sigma_i^2). Throws samp::Error when x has the wrong size.
Eigen::VectorXd ProjectToManifold(const ShapeModel& model, const std::vector<float>& sdf,
                                  double prior_weight = 0.0);

}  // namespace samp
