#include "libsamp/fit/fit_options.h"

#include <ceres/types.h>

#include <cctype>

#include "libsamp/core/error.h"

namespace samp {

ceres::LinearSolverType LinearSolverTypeOf(const std::string& name) {
  std::string upper = name;
  for (char& c : upper) c = char(std::toupper(static_cast<unsigned char>(c)));
  ceres::LinearSolverType type;
  SAMP_CHECK(ceres::StringToLinearSolverType(upper, &type))
      << "FitOptions.linear_solver: unknown solver '" << name << "'";
  SAMP_CHECK(type != ceres::DENSE_NORMAL_CHOLESKY && type != ceres::CGNR)
      << "FitOptions.linear_solver: use sparse_normal_cholesky, dense_schur, iterative_schur or "
         "dense_qr, not '"
      << name << "'";
  return type;
}

const char* DataWeightingName(DataWeighting weighting) {
  return weighting == DataWeighting::kMean ? "mean" : "effective";
}

DataWeighting ParseDataWeighting(const std::string& name) {
  if (name == "mean") return DataWeighting::kMean;
  if (name == "effective") return DataWeighting::kEffective;
  SAMP_THROW() << "unknown data weighting '" << name << "' (mean, effective)";
}

// FitOptions::Check() is driven by the option table (fit_option_table.cc).

}  // namespace samp
