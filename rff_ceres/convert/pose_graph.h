// What the pose-graph formats (PyFG, g2o; docs/converters.md) share. They
// keep poses as vertices and measurements as edges between vertices, with
// full covariance or information matrices; .rffd keeps timed records with
// independent sigmas. Helpers here map one onto the other.
#ifndef RFF_CERES_CONVERT_POSE_GRAPH_H_
#define RFF_CERES_CONVERT_POSE_GRAPH_H_

#include <Eigen/Core>
#include <cstddef>
#include <istream>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "rff_ceres/io/output_file.h"
#include "rff_ceres/types.h"

namespace rff {

// The distinct times of the PRIOR_POSE records, ODOM endpoints and
// observations, sorted: one pose vertex each.
std::vector<double> PoseVertexTimes(const Dataset& dataset);

// The ODOM chain composed from the earliest PRIOR_POSE (held through gaps),
// at `times`; where the chain does not reach, the earliest PRIOR_POSE.
// Starting values for vertices, never ground truth.
std::vector<TimedPose> DeadReckonedPoses(const Dataset& dataset,
                                         const std::vector<double>& times);

// A landmark in the robot frame, x = r cos(b), y = r sin(b), and the
// covariance of (x, y).
struct RelativePosition {
  double x = 0.0;
  double y = 0.0;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
};

// A RANGE_BEARING record as a relative position; the covariance is
// propagated to first order, J diag(sr^2, sb^2) J^T with J = d(x, y)/d(r, b).
// Fails, naming the record, when the range is not > 0 (no direction,
// singular J).
bool ToRelativePosition(const Observation& range_bearing,
                        RelativePosition* position, std::string* error);

// Largest |correlation| of range and bearing that ToRangeBearing drops:
// rounding of the transform, not a property of the data.
inline constexpr double kMaxRangeBearingCorrelation = 1e-6;

// The inverse of ToRelativePosition: range, bearing and sigmas from the
// covariance G C G^T, G = d(r, b)/d(x, y). .rffd range and bearing are
// independent, so a correlation above kMaxRangeBearingCorrelation fails, as
// does (0, 0) (no bearing).
bool ToRangeBearing(const RelativePosition& position, Observation* observation,
                    std::string* error);

// Standard deviations from the upper triangle, row by row (a11 a12 ... ann,
// the order of g2o and PyFG), of an n x n diagonal matrix of variances
// (`information` false) or of information. Fails, naming the entry (1-based
// within the matrix), when an off-diagonal entry is not 0 or a diagonal one
// is not > 0: .rffd sigmas are independent.
bool DiagonalSigmas(const double* upper_triangle, int n, bool information,
                    std::vector<double>* sigmas, std::string* error);

// The upper triangle, row by row, of diag(sigmas)^2 or of its inverse.
std::vector<double> DiagonalUpperTriangle(const std::vector<double>& sigmas,
                                          bool information);

// `values` separated by single blanks, each in the shortest form that reads
// back exactly.
std::string JoinNumbers(const std::vector<double>& values);

// Writes the text a format's stream writer `write` makes of `dataset` to
// `path`, whole or not at all (WriteOutputFile), and never a text the
// format's parser `parse` refuses with its default options (a sigma whose
// square overflows or whose information underflows): it names the refusal
// instead.
template <typename Summary, typename ReadOptions, typename ReadSummary>
bool WriteGraphFile(bool (*write)(const Dataset&, std::ostream*, Summary*,
                                  std::string*),
                    bool (*parse)(std::istream*, const std::string&,
                                  const ReadOptions&, Dataset*, ReadSummary*,
                                  std::string*),
                    const Dataset& dataset, const std::string& path,
                    Summary* summary, std::string* error) {
  std::ostringstream text;
  if (!write(dataset, &text, summary, error)) return false;
  std::istringstream written(text.str());
  Dataset back;
  ReadSummary read;
  std::string why;
  if (!parse(&written, path, ReadOptions(), &back, &read, &why)) {
    *error = path + ": not written: its reader would refuse it: " + why;
    return false;
  }
  return WriteOutputFile(
      path, [&](std::ostream* out) { *out << text.str(); }, error);
}

}  // namespace rff

#endif  // RFF_CERES_CONVERT_POSE_GRAPH_H_
