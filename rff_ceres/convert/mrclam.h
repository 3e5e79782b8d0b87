// Converter of the UTIAS Multi-Robot Cooperative Localization and Mapping
// dataset (Leung, Halpern, Barfoot, Liu, IJRR 30(8), 2011) from its .dat
// layout (RobotN_{Odometry,Measurement,Groundtruth}.dat, Barcodes.dat,
// Landmark_Groundtruth.dat, see data/SOURCES.md) to a .rffd Dataset for one
// robot.
//
// The trajectory is sampled at the distinct times of the kept measurements
// (plus, optionally, regularly between them). ODOM records integrate the
// commanded velocities, piecewise constant from one odometry row to the next,
// exactly along unicycle arcs. Measurements of other robots and of unknown
// barcodes are dropped and counted.
#ifndef RFF_CERES_CONVERT_MRCLAM_H_
#define RFF_CERES_CONVERT_MRCLAM_H_

#include <cstddef>
#include <string>
#include <vector>

#include "rff_ceres/types.h"

namespace rff {

struct MrclamOptions {
  int robot = 1;  // 1..5: reads RobotN_*.dat.
  // When > 0, every gap between consecutive measurement times longer than
  // this is split into equal steps no longer than it (seconds, >= 0.01);
  // the extra times are rounded to the millisecond of the dataset's clock.
  double odometry_interval = 0.0;
  // RANGE_BEARING sigmas; defaults from the agreement with Vicon truth on
  // Dataset 6 (1.4826 * MAD, rounded up; see docs/converters.md).
  double range_sigma = 0.1;
  double bearing_sigma = 0.02;
  // ODOM sigmas: max(floor, per_metre * path length) for x and y, and
  // max(floor, per_second * duration) for theta (the commanded heading rate
  // is biased, so its error grows with time, not with the angle turned).
  double odometry_sigma_xy_floor = 0.005;
  double odometry_sigma_xy_per_metre = 0.1;
  double odometry_sigma_theta_floor = 0.01;
  double odometry_sigma_theta_per_second = 0.05;
  // PRIOR_LANDMARK sigma at the Vicon landmark positions; 0 writes none.
  double landmark_prior_sigma = 0.1;
  // PRIOR_POSE sigmas at the first trajectory time (Vicon is good to ~mm).
  double first_pose_sigma_xy = 0.01;
  double first_pose_sigma_theta = 0.01;
  // GT_POSE rows are thinned to at most this rate (0 keeps every row).
  double gt_rate_hz = 10.0;
};

// Agreement of the kept measurements with Vicon truth (interpolated robot
// pose, landmark positions): median of the residuals (measured - true) and
// their median absolute deviation about that median.
struct MrclamAgreement {
  std::size_t count = 0;
  double range_median = 0.0;
  double range_mad = 0.0;
  double bearing_median = 0.0;
  double bearing_mad = 0.0;
};

struct MrclamSummary {
  std::size_t odometry_rows = 0;
  std::size_t ground_truth_rows = 0;
  std::size_t measurement_rows = 0;
  std::size_t dropped_robot = 0;         // Barcodes of robots (subjects 1-5).
  std::size_t dropped_unknown = 0;       // Barcodes not in Barcodes.dat or
                                         // subjects without landmark truth.
  std::size_t dropped_outside_span = 0;  // Outside odometry or GT times.
  std::size_t measurements_kept = 0;
  std::size_t trajectory_times = 0;  // Distinct pose times (ODOM + 1).
  std::size_t ground_truth_kept = 0;
  MrclamAgreement agreement;
};

// Whether `options` are valid ("--flag=value: why" in `error`);
// ConvertMrclam checks them first, and tools may check them before any work.
bool CheckMrclamOptions(const MrclamOptions& options, std::string* error);

// Reads DIRECTORY/RobotN_*.dat, Barcodes.dat, Landmark_Groundtruth.dat and
// fills `dataset`. Returns false with "path:line: problem" on malformed input
// or a missing file.
bool ConvertMrclam(const std::string& directory, const MrclamOptions& options,
                   Dataset* dataset, MrclamSummary* summary,
                   std::string* error);

}  // namespace rff

#endif  // RFF_CERES_CONVERT_MRCLAM_H_
