// rff_convert: converts a raw public dataset to .rffd, and .rffd to and from
// the pose-graph formats PyFG and g2o (docs/converters.md).
//
//   rff_convert --format=plaza --input=DIR --output=OUT.rffd
//       [--plaza_calibration=linear|none] [--plaza_heading_offset=auto|RAD]
//   rff_convert --format=mrclam --input=DIR --mrclam_robot=N --output=OUT.rffd
//       [--mrclam_odometry_interval=SECONDS]
//   rff_convert --format=pyfg|g2o --input=FILE --output=OUT.rffd
//       [--robot=A] [--rate=HZ]
//   rff_convert --to=pyfg|g2o --input=IN.rffd --output=OUT
#include <gflags/gflags.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "rff_ceres/convert/g2o.h"
#include "rff_ceres/convert/mrclam.h"
#include "rff_ceres/convert/plaza.h"
#include "rff_ceres/convert/pyfg.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/measurement_types.h"
#include "rff_ceres/option_error.h"
#include "tool_flags.h"

DEFINE_string(format, "",
              "Format of --input: plaza or mrclam (a directory of raw "
              "files), pyfg, g2o or rffd (a file); rffd when --to is pyfg or "
              "g2o");
DEFINE_string(to, "rffd", "Format of --output: rffd, pyfg or g2o");
DEFINE_string(input, "", "Raw dataset directory, or the file to convert");
DEFINE_string(output, "", "The file to write");
DEFINE_double(prior_sigma_xy, -1.0,
              "PRIOR_POSE position sigma [m] (-1: format default, plaza "
              "0.02, others 0.01); pyfg and g2o: only where the file has no "
              "pose prior");
DEFINE_string(robot, "",
              "pyfg: the robot to read (A, B, ...); required when the file "
              "has several");
DEFINE_double(rate, 0.0,
              "pyfg and g2o: pose k (PyFG pose number, g2o k-th pose vertex "
              "by id) is at k / rate seconds; 0: the file's timestamps "
              "(g2o: '# t=' comments, else 1 s apart)");
DEFINE_double(prior_sigma_theta, 0.01, "PRIOR_POSE heading sigma [rad]");

DEFINE_string(plaza_name, "Plaza1", "File prefix: reads NAME_GT.txt, ...");
DEFINE_string(plaza_calibration, "linear",
              "linear: fit r_true ~ a * r + b against ground truth and drop "
              "outliers; none: keep the raw ranges");
DEFINE_double(plaza_outlier_threshold, 2.0,
              "Drop ranges with |a * r + b - r_true| above this [m]");
DEFINE_double(plaza_range_sigma, 0.0,
              "RANGE sigma [m]; 0: fitted inlier sigma rounded to 0.1 m");
DEFINE_double(plaza_odom_sigma_xy_floor, 0.01, "ODOM x/y sigma floor [m]");
DEFINE_double(plaza_odom_sigma_xy_per_m, 0.05,
              "ODOM x/y sigma per metre travelled");
DEFINE_double(plaza_odom_sigma_theta_floor, 0.005,
              "ODOM heading sigma floor [rad]");
DEFINE_double(plaza_odom_sigma_theta_per_rad, 0.05,
              "ODOM heading sigma per radian turned");
DEFINE_double(plaza_landmark_prior_sigma, 1.0,
              "PRIOR_LANDMARK sigma at the surveyed beacons [m]; 0: none");
DEFINE_string(plaza_heading_offset, "auto",
              "Odometry (DR) heading frame minus the GT heading [rad]; auto: "
              "the init_heading_offset header of NAME_GT.txt / NAME_DR.txt, "
              "else measured from the data (nearest multiple of pi/2)");
DEFINE_double(plaza_heading_offset_tolerance, 0.1,
              "Largest gap [rad] between the heading offset used and the one "
              "measured from the GT displacements");

DEFINE_int32(mrclam_robot, 0, "Robot number 1..5");
DEFINE_double(mrclam_odometry_interval, 0.0,
              "Longest ODOM step between measurement times [s]; 0: poses "
              "only at measurement times; else at least 0.01, and at most "
              "1e7 poses in all");
DEFINE_double(mrclam_range_sigma, 0.1, "RANGE_BEARING range sigma [m]");
DEFINE_double(mrclam_bearing_sigma, 0.02, "RANGE_BEARING bearing sigma [rad]");
DEFINE_double(mrclam_odom_sigma_xy_floor, 0.005, "ODOM x/y sigma floor [m]");
DEFINE_double(mrclam_odom_sigma_xy_per_m, 0.1,
              "ODOM x/y sigma per metre travelled");
DEFINE_double(mrclam_odom_sigma_theta_floor, 0.01,
              "ODOM heading sigma floor [rad]");
DEFINE_double(mrclam_odom_sigma_theta_per_s, 0.05,
              "ODOM heading sigma per second of the step [rad/s]");
DEFINE_double(mrclam_landmark_prior_sigma, 0.1,
              "PRIOR_LANDMARK sigma at the Vicon landmarks [m]; 0: none");
DEFINE_double(gt_rate_hz, 10.0,
              "mrclam: thin GT_POSE to at most this rate; 0 keeps all rows");

namespace {

int Fail(const std::string& message) {
  std::fprintf(stderr, "rff_convert: error: %s\n", message.c_str());
  return 1;
}

void PrintRecordCounts(const rff::Dataset& d) {
  std::map<std::string, std::size_t> observations;
  for (const rff::Observation& o : d.observations) {
    ++observations[rff::MeasurementTypeOf(o.type).record];
  }
  std::printf("records: PRIOR_POSE %zu, PRIOR_LANDMARK %zu, ODOM %zu",
              d.pose_priors.size(), d.landmark_priors.size(),
              d.odometry.size());
  for (const auto& [name, count] : observations) {
    std::printf(", %s %zu", name.c_str(), count);
  }
  std::printf(", GT_POSE %zu, GT_LANDMARK %zu\n", d.ground_truth.size(),
              d.ground_truth_landmarks.size());
}

bool PlazaOptionsFromFlags(rff::PlazaOptions* plaza, std::string* error) {
  rff::PlazaOptions& options = *plaza;
  options.name = FLAGS_plaza_name;
  if (!rff::ParsePlazaCalibration(FLAGS_plaza_calibration, &options.calibration,
                                  error)) {
    return false;
  }
  options.outlier_threshold = FLAGS_plaza_outlier_threshold;
  options.range_sigma = FLAGS_plaza_range_sigma;
  options.odometry_sigma_xy_floor = FLAGS_plaza_odom_sigma_xy_floor;
  options.odometry_sigma_xy_per_metre = FLAGS_plaza_odom_sigma_xy_per_m;
  options.odometry_sigma_theta_floor = FLAGS_plaza_odom_sigma_theta_floor;
  options.odometry_sigma_theta_per_radian =
      FLAGS_plaza_odom_sigma_theta_per_rad;
  options.landmark_prior_sigma = FLAGS_plaza_landmark_prior_sigma;
  if (FLAGS_plaza_heading_offset != "auto") {
    double offset;
    if (!rff::ParseFiniteDouble(FLAGS_plaza_heading_offset, &offset)) {
      *error =
          rff::OptionError("plaza_heading_offset", FLAGS_plaza_heading_offset,
                           "", "auto or a finite number [rad]");
      return false;
    }
    options.heading_offset = offset;
  }
  options.heading_offset_tolerance = FLAGS_plaza_heading_offset_tolerance;
  if (FLAGS_prior_sigma_xy != -1.0) {  // -1: the format's default.
    options.first_pose_sigma_xy = FLAGS_prior_sigma_xy;
  }
  options.first_pose_sigma_theta = FLAGS_prior_sigma_theta;
  return true;
}

bool ConvertPlaza(const rff::PlazaOptions& options, rff::Dataset* dataset,
                  std::string* error) {
  rff::PlazaSummary s;
  if (!rff::ConvertPlaza(FLAGS_input, options, dataset, &s, error)) {
    return false;
  }
  std::printf(
      "plaza: %zu ground-truth rows, %zu odometry rows, %zu range rows "
      "(%zu out of time order, sorted)\n",
      s.ground_truth_rows, s.odometry_rows, s.range_rows,
      s.ranges_out_of_order);
  char measured[64] = "not measurable";
  if (std::isfinite(s.measured_heading_offset)) {
    std::snprintf(measured, sizeof(measured), "%.4f rad",
                  s.measured_heading_offset);
  }
  std::printf(
      "heading offset: odometry frame = GT heading + %.4f rad (%s; "
      "measured: %s)\n",
      s.heading_offset, s.heading_offset_source.c_str(), measured);
  std::printf(
      "calibration fit r_true ~ a * r + b: a = %.6f, b = %.6f m, inlier "
      "sigma = %.4f m, %zu inliers of %zu (threshold %g m)\n",
      s.fit.a, s.fit.b, s.fit.inlier_sigma, s.fit.num_inliers,
      s.fit.inlier.size(), options.outlier_threshold);
  std::printf(
      "ranges: calibration %s, kept %zu of %zu, rejected %zu, outside the "
      "ground-truth times %zu, sigma %g m\n",
      FLAGS_plaza_calibration.c_str(), s.ranges_kept, s.range_rows,
      s.ranges_rejected, s.ranges_outside_span, s.range_sigma);
  return true;
}

rff::MrclamOptions MrclamOptionsFromFlags() {
  rff::MrclamOptions options;
  options.robot = FLAGS_mrclam_robot;
  options.odometry_interval = FLAGS_mrclam_odometry_interval;
  options.range_sigma = FLAGS_mrclam_range_sigma;
  options.bearing_sigma = FLAGS_mrclam_bearing_sigma;
  options.odometry_sigma_xy_floor = FLAGS_mrclam_odom_sigma_xy_floor;
  options.odometry_sigma_xy_per_metre = FLAGS_mrclam_odom_sigma_xy_per_m;
  options.odometry_sigma_theta_floor = FLAGS_mrclam_odom_sigma_theta_floor;
  options.odometry_sigma_theta_per_second = FLAGS_mrclam_odom_sigma_theta_per_s;
  options.landmark_prior_sigma = FLAGS_mrclam_landmark_prior_sigma;
  if (FLAGS_prior_sigma_xy != -1.0) {  // -1: the format's default.
    options.first_pose_sigma_xy = FLAGS_prior_sigma_xy;
  }
  options.first_pose_sigma_theta = FLAGS_prior_sigma_theta;
  options.gt_rate_hz = FLAGS_gt_rate_hz;
  return options;
}

bool ConvertMrclam(const rff::MrclamOptions& options, rff::Dataset* dataset,
                   std::string* error) {
  rff::MrclamSummary s;
  if (!rff::ConvertMrclam(FLAGS_input, options, dataset, &s, error)) {
    return false;
  }
  std::printf(
      "mrclam robot %d: %zu odometry rows, %zu ground-truth rows, %zu "
      "measurement rows\n",
      options.robot, s.odometry_rows, s.ground_truth_rows, s.measurement_rows);
  std::printf(
      "measurements: kept %zu, dropped %zu of robots, %zu of unknown "
      "barcodes, %zu outside the odometry/ground-truth times\n",
      s.measurements_kept, s.dropped_robot, s.dropped_unknown,
      s.dropped_outside_span);
  std::printf(
      "agreement with Vicon: range residual median %.4f m, MAD %.4f m; "
      "bearing residual median %.4f rad, MAD %.4f rad\n",
      s.agreement.range_median, s.agreement.range_mad,
      s.agreement.bearing_median, s.agreement.bearing_mad);
  std::printf("trajectory: %zu pose times, %zu GT_POSE kept\n",
              s.trajectory_times, s.ground_truth_kept);
  return true;
}

double PriorSigmaXy() {
  return FLAGS_prior_sigma_xy != -1.0 ? FLAGS_prior_sigma_xy : 0.01;
}

bool ReadPyfgFile(rff::Dataset* dataset, std::string* error) {
  rff::PyfgReadOptions options;
  options.robot = FLAGS_robot;
  options.rate = FLAGS_rate;
  options.prior_sigma_xy = PriorSigmaXy();
  options.prior_sigma_theta = FLAGS_prior_sigma_theta;
  rff::PyfgReadSummary s;
  if (!rff::ReadPyfg(FLAGS_input, options, dataset, &s, error)) return false;
  std::printf(
      "pyfg: %zu records; robot %s of %s; %zu records of other "
      "robots only\n",
      s.records, s.robot.c_str(), s.robots.c_str(), s.other_robot_records);
  if (s.num_robots > 1) {
    std::fprintf(stderr,
                 "rff_convert: note: --robot=%s: left out %zu inter-robot "
                 "edges (.rffd holds one robot)\n",
                 s.robot.c_str(), s.inter_robot_edges);
  }
  if (s.prior_added) {
    std::printf(
        "no VERTEX_SE2:PRIOR for robot %s: PRIOR_POSE at its first "
        "pose (sigma %g m, %g rad)\n",
        s.robot.c_str(), options.prior_sigma_xy, options.prior_sigma_theta);
  }
  return true;
}

bool ReadG2oFile(rff::Dataset* dataset, std::string* error) {
  rff::G2oReadOptions options;
  options.rate = FLAGS_rate;
  options.prior_sigma_xy = PriorSigmaXy();
  options.prior_sigma_theta = FLAGS_prior_sigma_theta;
  rff::G2oReadSummary s;
  if (!rff::ReadG2o(FLAGS_input, options, dataset, &s, error)) return false;
  std::printf("g2o: %zu pose vertices, %zu landmark vertices; times from %s\n",
              s.pose_vertices, s.landmark_vertices, s.times.c_str());
  if (s.priors_added > 0) {
    std::printf(
        "no EDGE_PRIOR_SE2: PRIOR_POSE at %zu fixed or first pose "
        "vertices (sigma %g m, %g rad)\n",
        s.priors_added, options.prior_sigma_xy, options.prior_sigma_theta);
  }
  return true;
}

void LeftOut(std::size_t count, const char* what) {
  if (count == 0) return;
  std::fprintf(stderr, "rff_convert: note: left out %zu %s\n", count, what);
}

bool WritePyfgFile(const rff::Dataset& dataset, std::string* error) {
  rff::PyfgWriteSummary s;
  if (!rff::WritePyfg(dataset, FLAGS_output, &s, error)) return false;
  std::printf(
      "pyfg: %zu pose vertices (values: %zu GT_POSE, %zu "
      "interpolated GT_POSE, %zu dead reckoning), %zu landmark "
      "vertices (%zu without GT_LANDMARK)\n",
      s.pose_vertices, s.poses_from_truth, s.poses_interpolated,
      s.poses_dead_reckoned, s.landmark_vertices, s.landmarks_without_truth);
  LeftOut(s.bearings_left_out, "BEARING records (PyFG has no bearing edge)");
  if (s.poses_without_odometry > 0) {
    std::printf(
        "%zu pose vertices at observation times between ODOM "
        "endpoints have no EDGE_SE2\n",
        s.poses_without_odometry);
  }
  return true;
}

bool WriteG2oFile(const rff::Dataset& dataset, std::string* error) {
  rff::G2oWriteSummary s;
  if (!rff::WriteG2o(dataset, FLAGS_output, &s, error)) return false;
  std::printf(
      "g2o: %zu pose vertices (dead reckoning), %zu landmark "
      "vertices\n",
      s.pose_vertices, s.landmark_vertices);
  LeftOut(s.ranges_left_out, "RANGE records (g2o 2D has no range edge)");
  LeftOut(s.landmark_priors_left_out,
          "PRIOR_LANDMARK records (g2o 2D has no landmark prior)");
  LeftOut(s.ground_truth_left_out,
          "GT_POSE and GT_LANDMARK records (g2o has no ground truth)");
  return true;
}

// The input formats a flag applies to (by name, or by its prefix ending in
// '_'); given for another format it would change nothing.
bool CheckFlagsApply(const std::string& format, std::string* error) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> scopes = {
      {"plaza_", {"plaza"}},
      {"mrclam_", {"mrclam"}},
      {"gt_rate_hz", {"mrclam"}},
      {"robot", {"pyfg"}},
      {"rate", {"pyfg", "g2o"}},
      {"prior_sigma_xy", {"plaza", "mrclam", "pyfg", "g2o"}},
      {"prior_sigma_theta", {"plaza", "mrclam", "pyfg", "g2o"}}};
  std::vector<gflags::CommandLineFlagInfo> flags;
  gflags::GetAllFlags(&flags);
  for (const auto& [name, formats] : scopes) {
    for (const gflags::CommandLineFlagInfo& flag : flags) {
      const bool named = name.back() == '_' ? flag.name.rfind(name, 0) == 0
                                            : flag.name == name;
      if (!named || flag.is_default ||
          std::find(formats.begin(), formats.end(), format) != formats.end()) {
        continue;
      }
      // A double as given (gflags prints 17 digits).
      const std::string value = flag.type == "double"
                                    ? rff::FormatNumber(std::strtod(
                                          flag.current_value.c_str(), nullptr))
                                    : flag.current_value;
      *error = rff::OptionError(
          flag.name, value,
          "applies to --format=" + rff::JoinAlternatives(formats) + " only");
      return false;
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  gflags::SetUsageMessage(
      "converts a raw dataset to .rffd, and .rffd to and from PyFG and g2o\n"
      "  rff_convert --format=plaza --input=DIR --output=OUT.rffd "
      "[--plaza_calibration=linear|none]\n"
      "  rff_convert --format=mrclam --input=DIR --mrclam_robot=N "
      "--output=OUT.rffd [--mrclam_odometry_interval=SECONDS]\n"
      "  rff_convert --format=pyfg|g2o --input=FILE --output=OUT.rffd "
      "[--robot=A] [--rate=HZ]\n"
      "  rff_convert --to=pyfg|g2o --input=IN.rffd --output=OUT");
  std::string error;
  if (!rff::ParseToolFlags(&argc, &argv, &error)) return Fail(error);
  if (FLAGS_to != "rffd" && FLAGS_to != "pyfg" && FLAGS_to != "g2o") {
    return Fail(rff::OptionError("to", FLAGS_to, "unknown output format",
                                 "rffd, pyfg or g2o"));
  }
  const std::string format =
      FLAGS_format.empty() && FLAGS_to != "rffd" ? "rffd" : FLAGS_format;
  const bool raw = format == "plaza" || format == "mrclam";
  if (!raw && format != "pyfg" && format != "g2o" && format != "rffd") {
    return Fail(rff::OptionError("format", FLAGS_format, "unknown format",
                                 "plaza, mrclam, pyfg, g2o or rffd"));
  }
  if (FLAGS_input.empty()) {
    return Fail(std::string("--input=") + (raw ? "DIR" : "FILE") +
                " is required");
  }
  if (FLAGS_output.empty()) {
    return Fail("--output=OUT." + FLAGS_to + " is required");
  }
  if (!rff::CheckOutputPaths(rff::WithFlagfiles({{"--input", FLAGS_input}}),
                             {{"--output", FLAGS_output}}, &error)) {
    return Fail(error);
  }
  // Every converter's options are checked, used or not, before any work.
  rff::PlazaOptions plaza;
  rff::MrclamOptions mrclam = MrclamOptionsFromFlags();
  // Robot 0 is "not given", which only --format=mrclam refuses.
  if (format != "mrclam" && mrclam.robot == 0) mrclam.robot = 1;
  if (!PlazaOptionsFromFlags(&plaza, &error) ||
      !rff::CheckPlazaOptions(plaza, &error) ||
      !rff::CheckMrclamOptions(mrclam, &error)) {
    return Fail(error);
  }
  if (!CheckFlagsApply(format, &error)) return Fail(error);
  rff::Dataset dataset;
  bool ok;
  if (format == "plaza") {
    ok = ConvertPlaza(plaza, &dataset, &error);
  } else if (format == "mrclam") {
    ok = ConvertMrclam(mrclam, &dataset, &error);
  } else if (format == "pyfg") {
    ok = ReadPyfgFile(&dataset, &error);
  } else if (format == "g2o") {
    ok = ReadG2oFile(&dataset, &error);
  } else {
    ok = rff::ReadDataset(FLAGS_input, &dataset, &error);
  }
  if (!ok) return Fail(error);
  PrintRecordCounts(dataset);
  if (FLAGS_to == "pyfg") {
    ok = WritePyfgFile(dataset, &error);
  } else if (FLAGS_to == "g2o") {
    ok = WriteG2oFile(dataset, &error);
  } else {
    ok = rff::WriteDataset(dataset, FLAGS_output, &error);
  }
  if (!ok) return Fail(error);
  std::printf("wrote %s\n", FLAGS_output.c_str());
  return 0;
}
