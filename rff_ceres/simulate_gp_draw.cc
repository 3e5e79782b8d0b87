#include "rff_ceres/simulate_gp_draw.h"

#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"

namespace rff {

SimulationOptions GpDrawOptions(std::uint64_t seed) {
  SimulationOptions options;
  options.seed = seed;
  options.preset = "gp_draw";
  options.trajectory = TrajectoryShape::kGpDraw;
  options.num_steps = 600;
  options.dt = 1.0;
  options.gp_kernel = "matern52";
  options.gp_lengthscale = 8.0;
  options.gp_kernel_variance = 25.0;
  options.gp_heading_lengthscale = 12.0;
  options.gp_heading_kernel_variance = 0.25;
  options.num_landmarks = 25;
  // The draw wanders over about +-2 standard deviations (+-10 m for 25 m^2);
  // 5 m around it puts every landmark within a few metres of some pose.
  options.landmark_margin = 5.0;
  options.landmark_prior_sigma = 1.0;
  options.kind = ObservationType::kRangeBearing;
  options.sigma_range = 0.1;
  options.sigma_bearing = 2.0 * M_PI / 180.0;
  options.observations_per_step = 4;
  options.observe_nearest = true;
  options.min_range = 1.0;
  options.odometry = false;
  return options;
}

KernelOptions GpDrawPositionKernel(const SimulationOptions& options) {
  KernelOptions kernel;
  kernel.name = options.gp_kernel;
  kernel.lengthscale = options.gp_lengthscale;
  kernel.variance = options.gp_kernel_variance;
  return kernel;
}

KernelOptions GpDrawHeadingKernel(const SimulationOptions& options) {
  KernelOptions kernel;
  kernel.name = options.gp_kernel;
  kernel.lengthscale = options.gp_heading_lengthscale;
  kernel.variance = options.gp_heading_kernel_variance;
  return kernel;
}

bool ValidateGpDrawOptions(const SimulationOptions& options,
                           std::string* error) {
  if (options.num_steps > kMaxGpDrawSteps) {
    *error = OptionError(
        "num_steps", std::to_string(options.num_steps),
        "a GP draw factorises a dense N x N matrix, O(N^3)",
        "1 to " + std::to_string(kMaxGpDrawSteps) + " with --preset=gp_draw");
    return false;
  }
  constexpr double kMaxGpScale = 1e6;
  const struct {
    const char* name;
    double value;
  } positives[] = {
      {"gp_lengthscale", options.gp_lengthscale},
      {"gp_kernel_variance", options.gp_kernel_variance},
      {"gp_heading_lengthscale", options.gp_heading_lengthscale},
      {"gp_heading_kernel_variance", options.gp_heading_kernel_variance},
  };
  for (const auto& option : positives) {
    if (!CheckPositiveUpToOption(option.value, option.name, kMaxGpScale,
                                 error)) {
      return false;
    }
  }
  // The heading kernel shares --gp_kernel: its name is checked with x, y.
  return CreateKernel(GpDrawPositionKernel(options), error, "gp_") &&
         CreateKernel(GpDrawHeadingKernel(options), error, "gp_heading_");
}

bool DrawGaussianProcess(const Kernel& kernel, const std::vector<double>& times,
                         SimulationRandom* random, std::vector<double>* values,
                         std::string* error) {
  const std::size_t n = times.size();
  const double jitter = kGpDrawJitter * kernel.variance();
  // Lower triangle of K, row-major, overwritten by L (Cholesky-Crout, one
  // row at a time): L_ij = (K_ij - sum_{k<j} L_ik L_jk) / L_jj,
  // L_ii = sqrt(K_ii - sum_{k<i} L_ik^2).
  std::vector<double> factor(n * n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    double* row_i = &factor[i * n];
    for (std::size_t j = 0; j <= i; ++j) {
      const double* row_j = &factor[j * n];
      double sum = kernel.Evaluate(times[i] - times[j]);
      if (i == j) sum += jitter;
      for (std::size_t k = 0; k < j; ++k) sum -= row_i[k] * row_j[k];
      if (i == j) {
        if (!(sum > 0.0)) {
          *error = "the " + kernel.name() +
                   " kernel matrix is not positive definite at row " +
                   std::to_string(i) + " (lengthscale " +
                   FormatNumber(kernel.lengthscale()) + ")";
          return false;
        }
        row_i[i] = std::sqrt(sum);
      } else {
        row_i[j] = sum / row_j[j];
      }
    }
  }
  std::vector<double> z(n);
  for (double& value : z) value = random->Normal();
  values->assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    double sum = 0.0;
    for (std::size_t k = 0; k <= i; ++k) sum += factor[i * n + k] * z[k];
    (*values)[i] = sum;
  }
  return true;
}

bool DrawGpTrajectory(const SimulationOptions& options,
                      SimulationRandom* random, std::vector<TimedPose>* poses,
                      std::string* error) {
  if (!ValidateGpDrawOptions(options, error)) return false;
  std::vector<double> times(options.num_steps);
  for (int k = 0; k < options.num_steps; ++k) times[k] = k * options.dt;
  const std::unique_ptr<Kernel> position =
      CreateKernel(GpDrawPositionKernel(options), error);
  const std::unique_ptr<Kernel> heading =
      CreateKernel(GpDrawHeadingKernel(options), error);
  if (!position || !heading) return false;
  std::vector<double> x, y, theta;
  if (!DrawGaussianProcess(*position, times, random, &x, error) ||
      !DrawGaussianProcess(*position, times, random, &y, error) ||
      !DrawGaussianProcess(*heading, times, random, &theta, error)) {
    return false;
  }
  poses->resize(times.size());
  for (std::size_t k = 0; k < times.size(); ++k) {
    (*poses)[k] = {times[k], x[k], y[k], theta[k]};
  }
  return true;
}

std::string GpDrawTruth(const SimulationOptions& options) {
  return "kernel=" + options.gp_kernel +
         " lengthscale=" + FormatNumber(options.gp_lengthscale) +
         " kernel_variance=" + FormatNumber(options.gp_kernel_variance) +
         " heading_lengthscale=" +
         FormatNumber(options.gp_heading_lengthscale) +
         " heading_kernel_variance=" +
         FormatNumber(options.gp_heading_kernel_variance);
}

bool ParseGpDrawTruth(const std::string& value, KernelOptions* position,
                      KernelOptions* heading, std::string* error) {
  std::map<std::string, std::string> fields;
  std::istringstream tokens(value);
  std::string token;
  while (tokens >> token) {
    const std::size_t equals = token.find('=');
    if (equals == std::string::npos) {
      *error = "truth: expected key=value, got '" + token + "'";
      return false;
    }
    fields[token.substr(0, equals)] = token.substr(equals + 1);
  }
  double* numbers[] = {&position->lengthscale, &position->variance,
                       &heading->lengthscale, &heading->variance};
  const char* keys[] = {"lengthscale", "kernel_variance", "heading_lengthscale",
                        "heading_kernel_variance"};
  if (fields.count("kernel") == 0) {
    *error = "truth: no kernel=";
    return false;
  }
  position->name = heading->name = fields["kernel"];
  fields.erase("kernel");
  for (int i = 0; i < 4; ++i) {
    const auto it = fields.find(keys[i]);
    if (it == fields.end()) {
      *error = std::string("truth: no ") + keys[i] + "=";
      return false;
    }
    if (!ParseFiniteDouble(it->second, numbers[i])) {
      *error = std::string("truth: ") + keys[i] + "=" + it->second +
               " is not a number";
      return false;
    }
    fields.erase(it);
  }
  if (!fields.empty()) {
    *error = "truth: unknown key '" + fields.begin()->first + "'";
    return false;
  }
  return true;
}

}  // namespace rff
