// Pose covariance files: one line per time, `t sxx sxy sxtheta syy sytheta
// sthetatheta` (the upper triangle of the covariance of (x, y, theta)),
// sorted by time, at the times of the matching TUM trajectory file.
#ifndef RFF_CERES_IO_POSE_COVARIANCE_IO_H_
#define RFF_CERES_IO_POSE_COVARIANCE_IO_H_

#include <istream>
#include <ostream>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "rff_ceres/types.h"

namespace rff {

struct PoseCovariance {
  double t = 0.0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // Of (x, y, theta).
};

// Writes one line per entry in the caller's order (it must be sorted by
// time); the upper triangle of each covariance.
void WritePoseCovariances(const std::vector<PoseCovariance>& covariances,
                          std::ostream* output);
bool WritePoseCovariances(const std::vector<PoseCovariance>& covariances,
                          const std::string& path, std::string* error);
// The covariances of RunSlam (SlamResult::pose_covariances) at the times of
// its trajectory; fails when the two lengths differ.
bool WritePoseCovariances(const std::vector<TimedPose>& trajectory,
                          const std::vector<Eigen::Matrix3d>& covariances,
                          std::ostream* output, std::string* error);

// Reads a pose covariance file. Times must strictly increase; each
// covariance must be symmetric positive semi-definite: variances >= 0,
// |s_ij| <= sqrt(s_ii s_jj), and the correlation matrix without eigenvalues
// below -1e-9 (rounding in the writer's source is tolerated, nothing more).
bool ParsePoseCovariances(std::istream* input, const std::string& source,
                          std::vector<PoseCovariance>* covariances,
                          std::string* error);
bool ReadPoseCovariances(const std::string& path,
                         std::vector<PoseCovariance>* covariances,
                         std::string* error);

}  // namespace rff

#endif  // RFF_CERES_IO_POSE_COVARIANCE_IO_H_
