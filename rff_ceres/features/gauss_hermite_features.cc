#include "rff_ceres/features/gauss_hermite_features.h"

#include <Eigen/Eigenvalues>
#include <cmath>

#include "rff_ceres/features/spectral_pair_features.h"
#include "rff_ceres/option_error.h"

namespace rff {

void GaussHermiteRule(int n, std::vector<double>* nodes,
                      std::vector<double>* weights) {
  // Jacobi matrix of the monic Hermite recurrence: zero diagonal,
  // off-diagonal sqrt(k / 2).
  Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd off_diagonal(std::max(n - 1, 0));
  for (int k = 1; k < n; ++k) off_diagonal[k - 1] = std::sqrt(0.5 * k);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver;
  solver.computeFromTridiagonal(diagonal, off_diagonal,
                                Eigen::ComputeEigenvectors);
  nodes->resize(n);
  weights->resize(n);
  for (int i = 0; i < n; ++i) {
    (*nodes)[i] = solver.eigenvalues()[i];
    const double v0 = solver.eigenvectors()(0, i);
    (*weights)[i] = std::sqrt(M_PI) * v0 * v0;
  }
}

std::unique_ptr<FeatureMap> CreateGaussHermiteFeatures(
    const Kernel& kernel, const FeatureMapOptions& options,
    std::string* error) {
  if (!kernel.has_gaussian_spectrum()) {
    const std::string why =
        "needs a kernel with a Gaussian spectral density, got " + kernel.name();
    *error =
        OptionError("features", "gauss_hermite", why, "with rbf kernels only");
    return nullptr;
  }
  if (!CheckEvenNumFeatures(options, error)) return nullptr;
  if (options.num_features > kMaxGaussHermiteFeatures) {
    *error = OptionError(options.num_features_flag,
                         std::to_string(options.num_features),
                         "gauss_hermite nodes come from a dense eigenproblem",
                         "at most " + std::to_string(kMaxGaussHermiteFeatures));
    return nullptr;
  }
  const int n = options.num_features;
  std::vector<double> nodes;
  std::vector<double> weights;
  GaussHermiteRule(n, &nodes, &weights);
  const int num_pairs = n / 2;
  std::vector<double> frequencies(num_pairs);
  std::vector<double> amplitudes(num_pairs);
  for (int i = 0; i < num_pairs; ++i) {
    // Pair node i of the upper half with its mirror; average away the
    // eigensolver's asymmetry.
    const int upper = num_pairs + i;
    const int lower = num_pairs - 1 - i;
    const double x = 0.5 * (nodes[upper] - nodes[lower]);
    const double w = weights[upper] + weights[lower];
    frequencies[i] = std::sqrt(2.0) * x / kernel.lengthscale();
    amplitudes[i] = std::sqrt(kernel.variance() * w / std::sqrt(M_PI));
  }
  return std::make_unique<SpectralPairFeatures>(WindowCentre(options), -1.0,
                                                std::move(frequencies),
                                                std::move(amplitudes));
}

}  // namespace rff
