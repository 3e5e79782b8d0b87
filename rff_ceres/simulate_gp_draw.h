// Trajectories drawn from the SLAM prior itself (the "gp_draw" preset of the
// simulator): x(t), y(t) and theta(t) are independent zero-mean Gaussian
// processes, x and y with one kernel and theta with its own (same family,
// its own lengthscale and variance). On data drawn this way the exact-GP MAP
// with the true hyperparameters is the best any estimator can do on average,
// so it gives every approximation (features, segments, learned
// hyperparameters) a reference that nothing was tuned on.
//
// A draw at the times t_1..t_N is f = L z, z ~ N(0, I), with
// K = L L^T, K_ij = k(t_i - t_j) + jitter variance delta_ij (Rasmussen &
// Williams 2006, A.2). The Cholesky factor is computed here by plain loops
// in a fixed order, so that a seed gives the same trajectory with every
// compiler and vector width (see docs/simulator.md, Reproducibility). It is
// O(N^3): meant for N up to a few thousand.
#ifndef RFF_CERES_SIMULATE_GP_DRAW_H_
#define RFF_CERES_SIMULATE_GP_DRAW_H_

#include <cstdint>
#include <string>
#include <vector>

#include "rff_ceres/kernels/kernel.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/types.h"

namespace rff {

// Most poses a GP draw accepts: the dense factorisation is O(N^3) time and
// O(N^2) memory (5000 poses: 200 MB, tens of seconds).
inline constexpr int kMaxGpDrawSteps = 5000;

// Diagonal jitter of the kernel matrix, relative to the kernel's variance:
// keeps K numerically positive definite for smooth kernels (an RBF matrix
// with a lengthscale of many steps has eigenvalues far below machine
// precision) while changing the draw by about sqrt(1e-9) of its size.
inline constexpr double kGpDrawJitter = 1e-9;

// The preset: 600 poses at 1 Hz, no odometry, Matern 5/2 with lengthscale
// 8 s and variance 25 m^2 for x and y, 12 s and 0.25 rad^2 for theta;
// range-bearing (0.1 m, 2 deg) to the 4 nearest of 25 landmarks at least 1 m
// away, landmark priors of 1 m. The setting of
// shared/data/heldout/gp_draw_matern52_ell8.rffd.
SimulationOptions GpDrawOptions(std::uint64_t seed);

// The position and heading kernels of options.gp_* (KernelOptions for
// CreateKernel and for the solver's trajectory options).
KernelOptions GpDrawPositionKernel(const SimulationOptions& options);
KernelOptions GpDrawHeadingKernel(const SimulationOptions& options);

// Checks the gp_* options (known kernel, positive finite hyperparameters,
// at most kMaxGpDrawSteps poses); on failure `error` names the option.
bool ValidateGpDrawOptions(const SimulationOptions& options,
                           std::string* error);

// One draw of the zero-mean GP with `kernel` at `times`: L z with K = L L^T
// as above and z standard normal from `random`. Fails when K (with jitter)
// is not positive definite in floating point.
bool DrawGaussianProcess(const Kernel& kernel, const std::vector<double>& times,
                         SimulationRandom* random, std::vector<double>* values,
                         std::string* error);

// The true trajectory of the preset: poses at t = 0, dt, ..., with x, y and
// theta drawn in that order from `random`. Headings are the GP's values,
// not wrapped (the caller wraps what it writes).
bool DrawGpTrajectory(const SimulationOptions& options,
                      SimulationRandom* random, std::vector<TimedPose>* poses,
                      std::string* error);

// The value of the "# truth:" metadata line:
//   kernel=matern52 lengthscale=8 kernel_variance=25 heading_lengthscale=12
//   heading_kernel_variance=0.25
// (one line; the keys are rff_slam's flag names, so that the truth can be
// handed to the solver as it is).
std::string GpDrawTruth(const SimulationOptions& options);

// Reads a value written by GpDrawTruth into the two kernels. Fails, naming
// the token, on a missing key, an unknown key or a number that does not
// parse.
bool ParseGpDrawTruth(const std::string& value, KernelOptions* position,
                      KernelOptions* heading, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_SIMULATE_GP_DRAW_H_
