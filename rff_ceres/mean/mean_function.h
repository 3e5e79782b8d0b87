// Prior means mu(t) of the trajectory GP (paper section III-B): the GP models
// the deviation x(t) - mu(t), so a good mean lets a short lengthscale and few
// features do the rest.
#ifndef RFF_CERES_MEAN_MEAN_FUNCTION_H_
#define RFF_CERES_MEAN_MEAN_FUNCTION_H_

#include <memory>
#include <utility>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/types.h"

namespace rff {

class MeanFunction {
 public:
  virtual ~MeanFunction() = default;
  // (x, y, theta) at t; theta is continuous (unwrapped) along the run.
  virtual Eigen::Vector3d Evaluate(double t) const = 0;
};

// Linear interpolation between poses (headings unwrapped along the sequence
// so the mean turns continuously); held constant before the first and after
// the last pose.
class PiecewiseLinearMean : public MeanFunction {
 public:
  // `poses` sorted by strictly increasing time, at least one.
  explicit PiecewiseLinearMean(const std::vector<TimedPose>& poses);
  Eigen::Vector3d Evaluate(double t) const override;

  const std::vector<double>& times() const { return times_; }
  const std::vector<Eigen::Vector3d>& values() const { return values_; }

 private:
  std::vector<double> times_;
  std::vector<Eigen::Vector3d> values_;
};

// A mean moved by a constant: mu(t) + offset (the level of the data learned
// with the kernel's hyperparameters, hyperparameter_learning.h).
class ShiftedMean : public MeanFunction {
 public:
  ShiftedMean(std::shared_ptr<const MeanFunction> mean,
              const Eigen::Vector3d& offset)
      : mean_(std::move(mean)), offset_(offset) {}
  Eigen::Vector3d Evaluate(double t) const override {
    return mean_->Evaluate(t) + offset_;
  }

 private:
  std::shared_ptr<const MeanFunction> mean_;
  Eigen::Vector3d offset_;
};

}  // namespace rff

#endif  // RFF_CERES_MEAN_MEAN_FUNCTION_H_
