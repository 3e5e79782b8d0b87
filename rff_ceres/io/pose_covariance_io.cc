#include "rff_ceres/io/pose_covariance_io.h"

#include <cmath>
#include <fstream>

#include "Eigen/Eigenvalues"
#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"

namespace rff {
namespace {

constexpr const char* kNames[3] = {"x", "y", "theta"};

// Empty when `c` is symmetric positive semi-definite, else the problem.
std::string PsdProblem(const Eigen::Matrix3d& c) {
  for (int i = 0; i < 3; ++i) {
    if (c(i, i) < 0.0) {
      return std::string("negative variance s") + kNames[i] + kNames[i] +
             " = " + FormatNumber(c(i, i));
    }
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = i + 1; j < 3; ++j) {
      // A small relative slack for rounding of a (near-)singular pair.
      if (std::abs(c(i, j)) > std::sqrt(c(i, i) * c(j, j)) * (1.0 + 1e-9)) {
        return std::string("covariance is not positive semi-definite: |s") +
               kNames[i] + kNames[j] + "| > sqrt(s" + kNames[i] + kNames[i] +
               " s" + kNames[j] + kNames[j] + ")";
      }
    }
  }
  // Scale-free test on the correlation matrix: variances of x (m^2) and
  // theta (rad^2) may differ by orders of magnitude.
  Eigen::Vector3d scale;
  for (int i = 0; i < 3; ++i) {
    scale[i] = c(i, i) > 0.0 ? 1.0 / std::sqrt(c(i, i)) : 0.0;
  }
  const Eigen::Matrix3d correlation =
      scale.asDiagonal() * c * scale.asDiagonal();
  const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(
                              correlation, Eigen::EigenvaluesOnly)
                              .eigenvalues()[0];
  if (smallest < -1e-9) {
    return "covariance is not positive semi-definite (smallest eigenvalue "
           "of the correlation matrix " +
           FormatNumber(smallest) + ")";
  }
  return "";
}

}  // namespace

void WritePoseCovariances(const std::vector<PoseCovariance>& covariances,
                          std::ostream* output) {
  for (const PoseCovariance& p : covariances) {
    const Eigen::Matrix3d& c = p.covariance;
    *output << FormatNumber(p.t) << " " << FormatNumber(c(0, 0)) << " "
            << FormatNumber(c(0, 1)) << " " << FormatNumber(c(0, 2)) << " "
            << FormatNumber(c(1, 1)) << " " << FormatNumber(c(1, 2)) << " "
            << FormatNumber(c(2, 2)) << "\n";
  }
}

bool WritePoseCovariances(const std::vector<PoseCovariance>& covariances,
                          const std::string& path, std::string* error) {
  return WriteOutputFile(
      path, [&](std::ostream* out) { WritePoseCovariances(covariances, out); },
      error);
}

bool WritePoseCovariances(const std::vector<TimedPose>& trajectory,
                          const std::vector<Eigen::Matrix3d>& covariances,
                          std::ostream* output, std::string* error) {
  if (trajectory.size() != covariances.size()) {
    *error = std::to_string(covariances.size()) + " covariances for " +
             std::to_string(trajectory.size()) + " poses";
    return false;
  }
  std::vector<PoseCovariance> timed(trajectory.size());
  for (std::size_t k = 0; k < trajectory.size(); ++k) {
    timed[k].t = trajectory[k].t;
    timed[k].covariance = covariances[k];
  }
  WritePoseCovariances(timed, output);
  return true;
}

bool ParsePoseCovariances(std::istream* input, const std::string& source,
                          std::vector<PoseCovariance>* covariances,
                          std::string* error) {
  covariances->clear();
  LineReader reader(input, source);
  std::vector<std::string_view> fields;
  while (reader.Next(&fields)) {
    if (fields.size() != 7) {
      *error = reader.Error(
          "a pose covariance needs 7 fields (t sxx sxy sxtheta syy sytheta "
          "sthetatheta), got " +
          std::to_string(fields.size()));
      return false;
    }
    double v[7];
    if (!ParseFiniteDoubles(reader, fields, 0, 7, v, error)) return false;
    PoseCovariance p;
    p.t = v[0];
    p.covariance << v[1], v[2], v[3],  //
        v[2], v[4], v[5],              //
        v[3], v[5], v[6];
    if (!covariances->empty() && !(p.t > covariances->back().t)) {
      *error = reader.Error("time " + FormatNumber(p.t) +
                            " does not increase (previous " +
                            FormatNumber(covariances->back().t) + ")");
      return false;
    }
    const std::string problem = PsdProblem(p.covariance);
    if (!problem.empty()) {
      *error = reader.Error(problem);
      return false;
    }
    covariances->push_back(p);
  }
  if (!reader.ok()) {
    *error = reader.error();
    return false;
  }
  return true;
}

bool ReadPoseCovariances(const std::string& path,
                         std::vector<PoseCovariance>* covariances,
                         std::string* error) {
  std::ifstream stream;
  if (!OpenForReading(path, &stream, error)) return false;
  return ParsePoseCovariances(&stream, path, covariances, error);
}

}  // namespace rff
