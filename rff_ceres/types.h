// Plain data types shared by every part of rff-slam. The records mirror the
// dataset contract (docs/FORMAT.md) one to one; units are seconds, metres and
// radians, angles wrapped to (-pi, pi].
#ifndef RFF_CERES_TYPES_H_
#define RFF_CERES_TYPES_H_

#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace rff {

using LandmarkId = std::int64_t;

// A planar pose at time t.
struct TimedPose {
  double t = 0.0;
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
};

// PRIOR_POSE t x y theta sigma_xy sigma_theta
struct PosePrior {
  TimedPose pose;
  double sigma_xy = 0.0;
  double sigma_theta = 0.0;
};

// PRIOR_LANDMARK id x y sigma
struct LandmarkPrior {
  LandmarkId id = 0;
  double x = 0.0;
  double y = 0.0;
  double sigma = 0.0;
};

// ODOM t0 t1 dx dy dtheta sigma_x sigma_y sigma_theta: the motion from the
// pose at t0 to the pose at t1, expressed in the frame of the pose at t0.
struct Odometry {
  double t0 = 0.0;
  double t1 = 0.0;
  double dx = 0.0;
  double dy = 0.0;
  double dtheta = 0.0;
  double sigma_x = 0.0;
  double sigma_y = 0.0;
  double sigma_theta = 0.0;
};

enum class ObservationType { kRange, kBearing, kRangeBearing };

// RANGE, BEARING and RANGE_BEARING records in one type; the fields that the
// type does not carry are zero.
struct Observation {
  ObservationType type = ObservationType::kRange;
  double t = 0.0;
  LandmarkId id = 0;
  double range = 0.0;
  double bearing = 0.0;
  double sigma_range = 0.0;
  double sigma_bearing = 0.0;

  // What the type measures (its entry in measurement_types.cc).
  bool HasRange() const;
  bool HasBearing() const;
};

// GT_LANDMARK id x y, and the rows of a .landmarks file (with an optional
// covariance sxx sxy syy).
struct Landmark {
  LandmarkId id = 0;
  double x = 0.0;
  double y = 0.0;
  bool has_covariance = false;
  double sxx = 0.0;
  double sxy = 0.0;
  double syy = 0.0;
};

// Everything a .rffd file holds. Observations, odometry and ground truth are
// sorted by time by the reader; landmark lists are sorted by id.
struct Dataset {
  std::vector<std::pair<std::string, std::string>> metadata;
  std::vector<PosePrior> pose_priors;
  std::vector<LandmarkPrior> landmark_priors;
  std::vector<Odometry> odometry;
  std::vector<Observation> observations;
  std::vector<TimedPose> ground_truth;
  std::vector<Landmark> ground_truth_landmarks;
};

// The earliest PRIOR_POSE (the first of equal times): where the run starts.
// The dataset must have one (the reader guarantees it).
inline const PosePrior& EarliestPosePrior(const Dataset& dataset) {
  return *std::min_element(dataset.pose_priors.begin(),
                           dataset.pose_priors.end(),
                           [](const PosePrior& a, const PosePrior& b) {
                             return a.pose.t < b.pose.t;
                           });
}
inline PosePrior& EarliestPosePrior(Dataset* dataset) {
  return const_cast<PosePrior&>(
      EarliestPosePrior(static_cast<const Dataset&>(*dataset)));
}

// The dataset moved by (dx, dy) in the plane: every position it holds (the
// priors and the ground truth; measurements are relative).
inline Dataset Translated(const Dataset& dataset, double dx, double dy) {
  Dataset moved = dataset;
  auto move = [&](double* x, double* y) {
    *x += dx;
    *y += dy;
  };
  for (PosePrior& p : moved.pose_priors) move(&p.pose.x, &p.pose.y);
  for (LandmarkPrior& p : moved.landmark_priors) move(&p.x, &p.y);
  for (TimedPose& p : moved.ground_truth) move(&p.x, &p.y);
  for (Landmark& l : moved.ground_truth_landmarks) move(&l.x, &l.y);
  return moved;
}

}  // namespace rff

#endif  // RFF_CERES_TYPES_H_
