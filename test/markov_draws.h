// Helpers for tests of the Markov-state priors (WNOA, WNOJ): a mean easy to
// tell from the states' deviation, a known map beside a drawn path, and the
// consistency of a solve's covariances.
#ifndef RFF_TEST_MARKOV_DRAWS_H_
#define RFF_TEST_MARKOV_DRAWS_H_

#include <cmath>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "gtest/gtest.h"
#include "rff_ceres/consistency.h"
#include "rff_ceres/io/pose_covariance_io.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/slam_solver.h"
#include "rff_ceres/types.h"

namespace rff {
namespace testing {

// A mean linear in time (relative to `origin`, so epoch times keep their
// digits).
class LinearMean : public MeanFunction {
 public:
  explicit LinearMean(double origin) : origin_(origin) {}
  Eigen::Vector3d Evaluate(double t) const override {
    const double u = t - origin_;
    return Eigen::Vector3d(1.0 + 0.5 * u, -2.0 + 0.25 * u, 0.1 * u);
  }

 private:
  double origin_;
};

// `truth` with landmarks planted beside it at every third pose (4 m to the
// left and right in turn, priors at 1 cm), range-bearing sightings (0.05 m,
// 0.01 rad) of every landmark within 12 m from every `every`-th pose, their
// noise from `standard_normal` (the draw's own generator, so that its
// sequence goes on), and the first pose held at 1 cm and 0.01 rad.
inline Dataset SightedDraw(const std::vector<TimedPose>& truth, int every,
                           const std::function<double()>& standard_normal) {
  Dataset dataset;
  dataset.ground_truth = truth;
  for (std::size_t k = 0; k < truth.size(); k += 3) {
    const TimedPose& pose = truth[k];
    Landmark landmark;
    landmark.id = static_cast<LandmarkId>(k / 3);
    const double side = (landmark.id % 2 == 0) ? 4.0 : -4.0;
    landmark.x = pose.x - side * std::sin(pose.theta);
    landmark.y = pose.y + side * std::cos(pose.theta);
    dataset.ground_truth_landmarks.push_back(landmark);
    dataset.landmark_priors.push_back(
        {landmark.id, landmark.x, landmark.y, 0.01});
  }
  for (std::size_t k = 0; k < truth.size(); k += every) {
    const TimedPose& pose = truth[k];
    for (const Landmark& l : dataset.ground_truth_landmarks) {
      const double range = std::hypot(l.x - pose.x, l.y - pose.y);
      if (range > 12.0) continue;
      Observation o;
      o.type = ObservationType::kRangeBearing;
      o.t = pose.t;
      o.id = l.id;
      o.sigma_range = 0.05;
      o.sigma_bearing = 0.01;
      o.range = range + o.sigma_range * standard_normal();
      o.bearing = WrapAngle(std::atan2(l.y - pose.y, l.x - pose.x) -
                            pose.theta + o.sigma_bearing * standard_normal());
      dataset.observations.push_back(o);
    }
  }
  PosePrior start;
  start.pose = truth.front();
  start.sigma_xy = 0.01;
  start.sigma_theta = 0.01;
  dataset.pose_priors.push_back(start);
  return dataset;
}

// The mean position NEES of `prior`'s default solve of `dataset` (its pose
// covariances against the truth); a failure is recorded, and gives NaN.
inline double SolvedPositionNees(const Dataset& dataset,
                                 const std::string& prior, SlamResult* result) {
  SlamOptions options;
  options.prior = prior;
  options.output.covariance = true;
  std::string error;
  Evaluation evaluation;
  evaluation.consistency.mean_position_nees = NAN;
  if (!RunSlam(dataset, options, result, &error)) {
    ADD_FAILURE() << error;
    return NAN;
  }
  std::vector<PoseCovariance> covariances;
  for (std::size_t k = 0; k < result->trajectory.size(); ++k) {
    covariances.push_back(
        {result->trajectory[k].t, result->pose_covariances[k]});
  }
  if (!EvaluateConsistency(dataset.ground_truth, result->trajectory,
                           covariances, &evaluation, &error)) {
    ADD_FAILURE() << error;
  }
  return evaluation.consistency.mean_position_nees;
}

}  // namespace testing
}  // namespace rff

#endif  // RFF_TEST_MARKOV_DRAWS_H_
