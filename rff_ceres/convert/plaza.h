// Converter of the CMU Plaza range-only datasets (Djugash, Hamner, Roth,
// "Navigating with ranging radios: five data sets with ground truth", JFR
// 26(9), 2009) from their text layout (NAME_GT.txt, NAME_DR.txt, NAME_TD.txt,
// NAME_TL.txt, see data/SOURCES.md) to a .rffd Dataset.
//
// The robot trajectory is sampled at the ground-truth times: DR row k is the
// motion Pose2(d, 0, dtheta) of the odometry frame from GT time k to k + 1
// and becomes one ODOM record. Some recordings carry odometry whose heading
// frame is the GT heading plus a constant offset (gpslam's
// init_heading_offset; pi in the recording that was reported): the robot then
// moves d along GT heading + offset, so the ODOM record, expressed in the frame
// of the GT pose as every pose the solver reads is (PRIOR_POSE, GT_POSE), is
// Pose2(d cos(offset), d sin(offset), dtheta). The offset is taken from
// the option, else from the files' "init_heading_offset[rad] = X" header,
// else measured from the data and rounded to a multiple of pi/2, and always
// checked against the one measured from the GT displacements.
// The raw UWB ranges are long by about 7% and carry outliers;
// the default calibration (after gpslam's range_measure_fit.m) fits
// r_true ~ a * r + b by least squares against ground truth and drops ranges
// whose residual exceeds a threshold (FitLinearRangeCalibration). That uses
// ground truth, like every published pipeline on these data;
// PlazaCalibration::kNone keeps the raw ranges instead, for runs with a robust
// loss.
#ifndef RFF_CERES_CONVERT_PLAZA_H_
#define RFF_CERES_CONVERT_PLAZA_H_

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "rff_ceres/types.h"

namespace rff {

enum class PlazaCalibration { kLinear, kNone };

// Parses "linear" or "none".
bool ParsePlazaCalibration(const std::string& text,
                           PlazaCalibration* calibration, std::string* error);

struct PlazaOptions {
  // File prefix inside the input directory ("Plaza1" reads Plaza1_GT.txt...).
  std::string name = "Plaza1";
  PlazaCalibration calibration = PlazaCalibration::kLinear;
  // A range is an outlier when |a * r + b - r_true| exceeds this (metres);
  // gpslam uses 2 m.
  double outlier_threshold = 2.0;
  // Sigma of the RANGE records; 0 means the fitted inlier sigma rounded to
  // the nearest 0.1 m (at least 0.1 m).
  double range_sigma = 0.0;
  // ODOM sigmas: sigma = max(floor, per_metre * |d|) for x and y, and
  // max(floor, per_radian * |dtheta|) for theta. See docs/converters.md for
  // the measurement behind the defaults.
  double odometry_sigma_xy_floor = 0.01;
  double odometry_sigma_xy_per_metre = 0.05;
  double odometry_sigma_theta_floor = 0.005;
  double odometry_sigma_theta_per_radian = 0.05;
  // PRIOR_LANDMARK sigma at the surveyed beacon positions (gpslam: 1 m);
  // 0 writes no landmark priors.
  double landmark_prior_sigma = 1.0;
  // PRIOR_POSE sigmas at GT row 0 (GPS ground truth is good to ~2 cm).
  double first_pose_sigma_xy = 0.02;
  double first_pose_sigma_theta = 0.01;
  // Heading of the odometry (DR) frame minus the ground-truth heading
  // [rad]. Unset: the "init_heading_offset" header of NAME_GT.txt or
  // NAME_DR.txt, or when neither declares one, the offset measured from the
  // data rounded to a multiple of pi/2 (frames differ by axis conventions;
  // the rest of the measured offset is a GPS/odometry bias, not a frame).
  std::optional<double> heading_offset;
  // The offset measured from the GT displacements must lie this close to the
  // offset used [rad] (Plaza 1 measures -0.018 rad against 0); a larger gap
  // means a wrong declaration or a DR file in another convention, which
  // would hand the solver odometry that drives away from the truth.
  double heading_offset_tolerance = 0.1;
};

// Result of the linear range calibration.
struct LinearRangeFit {
  double a = 1.0;
  double b = 0.0;
  // RMS residual of the inliers after the refit (n - 2 degrees of freedom).
  double inlier_sigma = 0.0;
  std::vector<bool> inlier;  // One flag per input range.
  std::size_t num_inliers = 0;
};

// Fits truth ~ a * measured + b: starts from Siegel's repeated-median line
// (robust to gross outliers), then repeats { inliers = pairs with
// |a * measured + b - truth| <= outlier_threshold; least-squares refit on
// the inliers } until the inlier set stops changing. range_measure_fit.m
// does one such round from the least-squares line of all pairs; on Plaza 1
// both give the same result. Fails when fewer than 3 pairs (or inliers)
// remain, the measured values are all equal, or the fitted scale a is not
// positive (a true distance that shrinks as the measured range grows is not
// a calibration but ranges that do not belong to the trajectory).
bool FitLinearRangeCalibration(const std::vector<double>& measured,
                               const std::vector<double>& truth,
                               double outlier_threshold, LinearRangeFit* fit,
                               std::string* error);

struct PlazaSummary {
  std::size_t ground_truth_rows = 0;
  std::size_t odometry_rows = 0;
  std::size_t range_rows = 0;           // Rows of NAME_TD.txt.
  std::size_t ranges_out_of_order = 0;  // Rows earlier than a row before.
  std::size_t ranges_outside_span = 0;  // Dropped: outside the GT times.
  std::size_t ranges_rejected = 0;      // Dropped: calibration outliers.
  std::size_t ranges_kept = 0;
  // The fit is computed in both modes (for the report); it is applied to the
  // ranges only with PlazaCalibration::kLinear.
  LinearRangeFit fit;
  double range_sigma = 0.0;  // Sigma written in the RANGE records.
  // Odometry frame against GT heading: the offset applied to the ODOM
  // records, where it came from ("option", "declared in ...", "measured"),
  // and the offset measured from the data (the direction of the GT
  // displacement in the GT pose frame, weighted by the DR distance; NaN when
  // the robot moves too little to tell or the sums overflow).
  double heading_offset = 0.0;
  std::string heading_offset_source;
  double measured_heading_offset = 0.0;
};

// Whether `options` are valid ("--flag=value: why" in `error`); ConvertPlaza
// checks them first, and tools may check them before any work.
bool CheckPlazaOptions(const PlazaOptions& options, std::string* error);

// Reads DIRECTORY/NAME_{GT,DR,TD,TL}.txt and fills `dataset` (metadata,
// priors, ODOM, RANGE, GT_POSE, GT_LANDMARK). Returns false with
// "path:line: problem" on malformed input or a missing file.
bool ConvertPlaza(const std::string& directory, const PlazaOptions& options,
                  Dataset* dataset, PlazaSummary* summary, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_CONVERT_PLAZA_H_
