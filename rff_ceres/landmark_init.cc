#include "rff_ceres/landmark_init.h"

#include <cmath>
#include <map>
#include <vector>

#include "Eigen/Dense"
#include "costs/bearing_cost.h"

namespace rff {
namespace {

// Least-squares intersection of the bearing rays: each ray through p with
// direction angle a gives n^T l = n^T p, n = (-sin a, cos a). Returns false
// when the rays are (nearly) parallel.
bool Triangulate(const std::vector<Eigen::Vector3d>& poses,
                 const std::vector<double>& bearings, Eigen::Vector2d* l) {
  Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const double angle = poses[i].z() + bearings[i];
    const Eigen::Vector2d n(-std::sin(angle), std::cos(angle));
    a += n * n.transpose();
    b += n * n.dot(poses[i].head<2>());
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(a);
  // Rays spread by less than ~2 degrees give no depth.
  if (eigen.eigenvalues()(0) < 1e-3 * eigen.eigenvalues()(1) ||
      eigen.eigenvalues()(1) <= 0.0) {
    return false;
  }
  *l = a.ldlt().solve(b);
  // A point behind the robots (negative depth on average) is no solution.
  double depth = 0.0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const double angle = poses[i].z() + bearings[i];
    depth += (*l - poses[i].head<2>())
                 .dot(Eigen::Vector2d(std::cos(angle), std::sin(angle)));
  }
  return depth > 0.0;
}

// Multilateration: the linear solution of |l - p_i|^2 = r_i^2 (differences
// to the mean equation), refined by Gauss-Newton. Returns false when the
// positions are (nearly) collinear.
bool Multilaterate(const std::vector<Eigen::Vector3d>& poses,
                   const std::vector<double>& ranges, Eigen::Vector2d* l) {
  const std::size_t n = poses.size();
  if (n < 3) return false;
  Eigen::Vector2d mean_p = Eigen::Vector2d::Zero();
  double mean_c = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    mean_p += poses[i].head<2>();
    mean_c += poses[i].head<2>().squaredNorm() - ranges[i] * ranges[i];
  }
  mean_p /= n;
  mean_c /= n;
  Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    // 2 (p_i - mean_p)^T l = (|p_i|^2 - r_i^2) - mean_c
    const Eigen::Vector2d row = 2.0 * (poses[i].head<2>() - mean_p);
    const double rhs =
        poses[i].head<2>().squaredNorm() - ranges[i] * ranges[i] - mean_c;
    a += row * row.transpose();
    b += row * rhs;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(a);
  if (eigen.eigenvalues()(0) < 1e-6 * eigen.eigenvalues()(1) ||
      eigen.eigenvalues()(1) <= 0.0) {
    return false;
  }
  *l = a.ldlt().solve(b);
  for (int iteration = 0; iteration < 10; ++iteration) {
    Eigen::Matrix2d h = Eigen::Matrix2d::Zero();
    Eigen::Vector2d g = Eigen::Vector2d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector2d d = *l - poses[i].head<2>();
      const double distance = std::max(d.norm(), 1e-9);
      const Eigen::Vector2d j = d / distance;
      h += j * j.transpose();
      g += j * (distance - ranges[i]);
    }
    *l -= h.ldlt().solve(g);
  }
  return l->allFinite();
}

}  // namespace

bool InitializeLandmarks(const Dataset& dataset, const PoseFunction& pose,
                         std::map<LandmarkId, Eigen::Vector2d>* landmarks,
                         std::string* error,
                         std::vector<LandmarkId>* unlocated) {
  landmarks->clear();
  if (unlocated != nullptr) unlocated->clear();
  std::map<LandmarkId, double> prior_sigma;
  for (const LandmarkPrior& p : dataset.landmark_priors) {
    (*landmarks)[p.id] = Eigen::Vector2d(p.x, p.y);
    prior_sigma[p.id] = p.sigma;
  }
  // A prior mean on a pose that sees the landmark by a bearing leaves that
  // bearing undefined where the solve starts: it starts one prior sigma
  // along the bearing instead, where both allow it.
  for (const Observation& o : dataset.observations) {
    if (!o.HasBearing()) continue;
    const auto sigma = prior_sigma.find(o.id);
    if (sigma == prior_sigma.end()) continue;
    const Eigen::Vector3d p = pose(o.t);
    Eigen::Vector2d& l = (*landmarks)[o.id];
    if ((l - p.head<2>()).squaredNorm() > kMinBearingSquaredDistance) continue;
    const double angle = p.z() + o.bearing;
    l += sigma->second * Eigen::Vector2d(std::cos(angle), std::sin(angle));
  }
  // Observations of each landmark without a prior.
  struct Seen {
    std::vector<Eigen::Vector3d> rb_poses, bearing_poses, range_poses;
    std::vector<double> rb_ranges, rb_bearings, bearings, ranges;
  };
  std::map<LandmarkId, Seen> seen;
  for (const Observation& o : dataset.observations) {
    if (landmarks->count(o.id)) continue;
    Seen& s = seen[o.id];
    const Eigen::Vector3d p = pose(o.t);
    if (o.HasRange() && o.HasBearing()) {
      s.rb_poses.push_back(p);
      s.rb_ranges.push_back(o.range);
      s.rb_bearings.push_back(o.bearing);
    }
    if (o.HasBearing()) {
      s.bearing_poses.push_back(p);
      s.bearings.push_back(o.bearing);
    }
    if (o.HasRange()) {
      s.range_poses.push_back(p);
      s.ranges.push_back(o.range);
    }
  }
  for (const auto& [id, s] : seen) {
    Eigen::Vector2d l;
    if (!s.rb_poses.empty()) {
      // Mean of the inverted range-bearing measurements.
      l.setZero();
      for (std::size_t i = 0; i < s.rb_poses.size(); ++i) {
        const double angle = s.rb_poses[i].z() + s.rb_bearings[i];
        l += s.rb_poses[i].head<2>() +
             s.rb_ranges[i] * Eigen::Vector2d(std::cos(angle), std::sin(angle));
      }
      l /= static_cast<double>(s.rb_poses.size());
    } else if (!Triangulate(s.bearing_poses, s.bearings, &l) &&
               !Multilaterate(s.range_poses, s.ranges, &l)) {
      if (unlocated != nullptr) {
        unlocated->push_back(id);
        continue;
      }
      *error = "landmark " + std::to_string(id) +
               " has no PRIOR_LANDMARK and its " +
               std::to_string(s.bearings.size()) + " bearing(s) and " +
               std::to_string(s.ranges.size()) +
               " range(s) do not locate it (need crossing bearings or 3+ "
               "ranges from non-collinear places); give it a prior";
      return false;
    }
    (*landmarks)[id] = l;
  }
  return true;
}

}  // namespace rff
