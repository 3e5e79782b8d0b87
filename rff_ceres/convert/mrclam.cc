#include "rff_ceres/convert/mrclam.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string_view>

#include "rff_ceres/convert/raw_records.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"
#include "rff_ceres/se2.h"
#include "rff_ceres/statistics.h"

namespace rff {
namespace {

// Subjects 1..5 are the robots of the dataset; 6..20 are landmarks.
constexpr LandmarkId kLastRobotSubject = 5;

// Checks that row times do not decrease (strictly increase if `strict`).
bool CheckTimeOrder(const LineReader& reader, bool have_previous,
                    double previous, double t, bool strict,
                    std::string* error) {
  if (!have_previous) return true;
  if (t > previous || (!strict && t == previous)) return true;
  *error = reader.Error("time " + FormatNumber(t) +
                        (strict ? " does not increase" : " decreases") +
                        " (previous row " + FormatNumber(previous) + ")");
  return false;
}

struct VelocityRow {
  double t = 0.0;
  double v = 0.0;
  double omega = 0.0;
};

struct RawMeasurement {
  double t = 0.0;
  LandmarkId barcode = 0;
  double range = 0.0;
  double bearing = 0.0;
};

struct MrclamRaw {
  std::map<LandmarkId, LandmarkId> subject_of_barcode;
  std::map<LandmarkId, std::pair<double, double>> landmarks;
  std::vector<VelocityRow> odometry;
  std::vector<TimedPose> ground_truth;
  std::vector<RawMeasurement> measurements;
};

bool ReadBarcodes(const std::string& path, MrclamRaw* raw, std::string* error) {
  return ReadRecords(
      path, 2,
      [&](const LineReader& reader, const std::vector<std::string_view>& f,
          std::string* err) {
        LandmarkId subject, barcode;
        if (!ParseRawInteger(reader, f[0], 1, &subject, err) ||
            !ParseRawInteger(reader, f[1], 2, &barcode, err)) {
          return false;
        }
        if (!raw->subject_of_barcode.emplace(barcode, subject).second) {
          *err = reader.Error("duplicate barcode " + std::to_string(barcode));
          return false;
        }
        return true;
      },
      error);
}

bool ReadLandmarks(const std::string& path, MrclamRaw* raw,
                   std::string* error) {
  return ReadRecords(
      path, 5,
      [&](const LineReader& reader, const std::vector<std::string_view>& f,
          std::string* err) {
        LandmarkId subject;
        double v[4];  // x y sx sy; the standard deviations are not used.
        if (!ParseRawInteger(reader, f[0], 1, &subject, err) ||
            !ParseFiniteDoubles(reader, f, 1, 4, v, err)) {
          return false;
        }
        if (subject <= kLastRobotSubject) {
          *err = reader.Error(
              "subject " + std::to_string(subject) + " is a robot (1-" +
              std::to_string(kLastRobotSubject) + "), not a landmark");
          return false;
        }
        if (!raw->landmarks.emplace(subject, std::make_pair(v[0], v[1]))
                 .second) {
          *err = reader.Error("duplicate landmark " + std::to_string(subject));
          return false;
        }
        return true;
      },
      error);
}

bool ReadOdometry(const std::string& path, MrclamRaw* raw, std::string* error) {
  return ReadRecords(
      path, 3,
      [&](const LineReader& reader, const std::vector<std::string_view>& f,
          std::string* err) {
        double v[3];
        if (!ParseFiniteDoubles(reader, f, 0, 3, v, err)) return false;
        // Equal times occur in the data (a zero-length command); the later
        // row then governs.
        if (!CheckTimeOrder(
                reader, !raw->odometry.empty(),
                raw->odometry.empty() ? 0.0 : raw->odometry.back().t, v[0],
                /*strict=*/false, err)) {
          return false;
        }
        raw->odometry.push_back({v[0], v[1], v[2]});
        return true;
      },
      error);
}

bool ReadGroundTruth(const std::string& path, MrclamRaw* raw,
                     std::string* error) {
  return ReadRecords(
      path, 4,
      [&](const LineReader& reader, const std::vector<std::string_view>& f,
          std::string* err) {
        double v[4];
        if (!ParseFiniteDoubles(reader, f, 0, 4, v, err)) return false;
        if (!CheckTimeOrder(
                reader, !raw->ground_truth.empty(),
                raw->ground_truth.empty() ? 0.0 : raw->ground_truth.back().t,
                v[0], /*strict=*/true, err)) {
          return false;
        }
        raw->ground_truth.push_back({v[0], v[1], v[2], v[3]});
        return true;
      },
      error);
}

bool ReadMeasurements(const std::string& path, MrclamRaw* raw,
                      std::string* error) {
  return ReadRecords(
      path, 4,
      [&](const LineReader& reader, const std::vector<std::string_view>& f,
          std::string* err) {
        double t, rb[2];
        LandmarkId barcode;
        if (!ParseFiniteDoubles(reader, f, 0, 1, &t, err) ||
            !ParseRawInteger(reader, f[1], 2, &barcode, err) ||
            !ParseFiniteDoubles(reader, f, 2, 2, rb, err)) {
          return false;
        }
        if (rb[0] < 0.0) {
          *err = reader.Error("range must be >= 0, got " + FormatNumber(rb[0]));
          return false;
        }
        raw->measurements.push_back({t, barcode, rb[0], rb[1]});
        return true;
      },
      error);
}

// More pose times than this is a hostile input (or a wrong interval), not
// a trajectory: 1e7 poses already need gigabytes in the solver.
constexpr double kMaxTrajectoryTimes = 1e7;

// The pose times: the distinct measurement times, with each gap longer
// than `interval` (when > 0) split into equal steps rounded to the
// millisecond. Fails when that gives more than kMaxTrajectoryTimes.
bool TrajectoryTimes(const std::vector<double>& sorted_times, double interval,
                     std::vector<double>* out) {
  std::vector<double>& times = *out;
  times.clear();
  if (interval > 0.0 && !sorted_times.empty()) {
    // Counted in double first: the step count of one gap may overflow int.
    double total = 1.0;
    for (std::size_t i = 1; i < sorted_times.size(); ++i) {
      const double gap = sorted_times[i] - sorted_times[i - 1];
      total += std::max(1.0, std::ceil(gap / interval - 1e-9));
      if (!(total <= kMaxTrajectoryTimes)) return false;
    }
  }
  for (const double t : sorted_times) {
    if (!times.empty() && t == times.back()) continue;
    if (!times.empty() && interval > 0.0) {
      const double start = times.back();
      const double gap = t - start;
      const int steps = static_cast<int>(std::ceil(gap / interval - 1e-9));
      for (int k = 1; k < steps; ++k) {
        const double inner =
            std::round((start + gap * k / steps) * 1000.0) / 1000.0;
        if (inner > times.back() && inner < t) times.push_back(inner);
      }
    }
    times.push_back(t);
  }
  return true;
}

// Integrates the piecewise-constant velocities of `rows` over [t0, t1],
// starting from the identity. `row` is the index of a row with time <= t0;
// it is advanced so that successive calls over increasing times are linear.
void IntegrateBetween(const std::vector<VelocityRow>& rows, double t0,
                      double t1, std::size_t* row, double* dx, double* dy,
                      double* dtheta, double* path_length) {
  while (*row + 1 < rows.size() && rows[*row + 1].t <= t0) ++*row;
  *dx = *dy = *dtheta = *path_length = 0.0;
  double now = t0;
  std::size_t i = *row;
  while (now < t1) {
    const double end = i + 1 < rows.size() ? std::min(t1, rows[i + 1].t) : t1;
    if (end > now) {
      IntegrateUnicycle(rows[i].v, rows[i].omega, end - now, dx, dy, dtheta);
      *path_length += std::abs(rows[i].v) * (end - now);
      now = end;
    }
    if (i + 1 < rows.size() && rows[i + 1].t <= now) ++i;
  }
}

// Median and median absolute deviation about the median.
void MedianAndMad(const std::vector<double>& values, double* median,
                  double* mad) {
  *median = Median(values);
  std::vector<double> deviations;
  deviations.reserve(values.size());
  for (const double v : values) deviations.push_back(std::abs(v - *median));
  *mad = Median(deviations);
}

// The last component of `directory` ("mrclam6" for "data/mrclam6/"), which
// names the dataset in the metadata.
std::string DirectoryName(const std::string& directory) {
  std::filesystem::path path = std::filesystem::path(directory);
  if (path.filename().empty()) path = path.parent_path();
  return path.filename().string();
}

std::string ConverterDescription(const MrclamOptions& o) {
  auto n = [](double v) { return FormatNumber(v); };
  return "rff_convert --format=mrclam --mrclam_robot=" +
         std::to_string(o.robot) +
         " --mrclam_odometry_interval=" + n(o.odometry_interval) +
         " --mrclam_range_sigma=" + n(o.range_sigma) +
         " --mrclam_bearing_sigma=" + n(o.bearing_sigma) +
         " --mrclam_odom_sigma_xy_floor=" + n(o.odometry_sigma_xy_floor) +
         " --mrclam_odom_sigma_xy_per_m=" + n(o.odometry_sigma_xy_per_metre) +
         " --mrclam_odom_sigma_theta_floor=" + n(o.odometry_sigma_theta_floor) +
         " --mrclam_odom_sigma_theta_per_s=" +
         n(o.odometry_sigma_theta_per_second) +
         " --mrclam_landmark_prior_sigma=" + n(o.landmark_prior_sigma) +
         " --prior_sigma_xy=" + n(o.first_pose_sigma_xy) +
         " --prior_sigma_theta=" + n(o.first_pose_sigma_theta) +
         " --gt_rate_hz=" + n(o.gt_rate_hz);
}

}  // namespace

bool CheckMrclamOptions(const MrclamOptions& o, std::string* error) {
  if (o.robot < 1 || o.robot > kLastRobotSubject) {
    *error = OptionError("mrclam_robot", std::to_string(o.robot),
                         o.robot == 0 ? "no robot given (the default)" : "",
                         "1 to " + std::to_string(kLastRobotSubject));
    return false;
  }
  if (!CheckNonNegativeOption(o.odometry_interval, "mrclam_odometry_interval",
                              error)) {
    return false;
  }
  if (o.odometry_interval > 0.0 && o.odometry_interval < 0.01) {
    *error = OptionError("mrclam_odometry_interval",
                         FormatNumber(o.odometry_interval), "",
                         "0 (poses at measurement times only) or 0.01 s or "
                         "more");
    return false;
  }
  return CheckNumericOptions(
      {{o.range_sigma, "mrclam_range_sigma", false},
       {o.bearing_sigma, "mrclam_bearing_sigma", false},
       {o.odometry_sigma_xy_floor, "mrclam_odom_sigma_xy_floor", false},
       {o.odometry_sigma_xy_per_metre, "mrclam_odom_sigma_xy_per_m", true},
       {o.odometry_sigma_theta_floor, "mrclam_odom_sigma_theta_floor", false},
       {o.odometry_sigma_theta_per_second, "mrclam_odom_sigma_theta_per_s",
        true},
       {o.landmark_prior_sigma, "mrclam_landmark_prior_sigma", true},
       {o.first_pose_sigma_xy, "prior_sigma_xy", false},
       {o.first_pose_sigma_theta, "prior_sigma_theta", false},
       {o.gt_rate_hz, "gt_rate_hz", true}},
      error);
}

bool ConvertMrclam(const std::string& directory, const MrclamOptions& options,
                   Dataset* dataset, MrclamSummary* summary,
                   std::string* error) {
  *dataset = Dataset();
  *summary = MrclamSummary();
  if (!CheckMrclamOptions(options, error)) return false;
  const std::string robot =
      directory + "/Robot" + std::to_string(options.robot);
  MrclamRaw raw;
  if (!ReadBarcodes(directory + "/Barcodes.dat", &raw, error) ||
      !ReadLandmarks(directory + "/Landmark_Groundtruth.dat", &raw, error) ||
      !ReadOdometry(robot + "_Odometry.dat", &raw, error) ||
      !ReadGroundTruth(robot + "_Groundtruth.dat", &raw, error) ||
      !ReadMeasurements(robot + "_Measurement.dat", &raw, error)) {
    return false;
  }
  if (raw.ground_truth.size() < 2) {
    *error = robot + "_Groundtruth.dat: needs at least 2 rows";
    return false;
  }
  summary->odometry_rows = raw.odometry.size();
  summary->ground_truth_rows = raw.ground_truth.size();
  summary->measurement_rows = raw.measurements.size();

  // Poses need velocities before and after them and truth for the prior and
  // the evaluation: keep measurements inside both time spans.
  const double span_begin =
      std::max(raw.odometry.front().t, raw.ground_truth.front().t);
  const double span_end =
      std::min(raw.odometry.back().t, raw.ground_truth.back().t);
  std::vector<RawMeasurement> measurements = raw.measurements;
  std::stable_sort(measurements.begin(), measurements.end(),
                   [](const RawMeasurement& a, const RawMeasurement& b) {
                     return a.t < b.t;
                   });
  std::vector<double> measurement_times;
  std::set<LandmarkId> observed;
  for (const RawMeasurement& m : measurements) {
    const auto subject = raw.subject_of_barcode.find(m.barcode);
    if (subject != raw.subject_of_barcode.end() && subject->second >= 1 &&
        subject->second <= kLastRobotSubject) {
      ++summary->dropped_robot;
      continue;
    }
    if (subject == raw.subject_of_barcode.end() ||
        raw.landmarks.count(subject->second) == 0) {
      ++summary->dropped_unknown;
      continue;
    }
    if (m.t < span_begin || m.t > span_end) {
      ++summary->dropped_outside_span;
      continue;
    }
    Observation obs;
    obs.type = ObservationType::kRangeBearing;
    obs.t = m.t;
    obs.id = subject->second;
    obs.range = m.range;
    obs.bearing = WrapAngle(m.bearing);
    obs.sigma_range = options.range_sigma;
    obs.sigma_bearing = options.bearing_sigma;
    dataset->observations.push_back(obs);
    measurement_times.push_back(m.t);
    observed.insert(obs.id);
  }
  summary->measurements_kept = dataset->observations.size();
  if (dataset->observations.empty()) {
    *error = robot +
             "_Measurement.dat: no landmark measurement inside the "
             "odometry and ground-truth times";
    return false;
  }

  std::vector<double> times;
  if (!TrajectoryTimes(measurement_times, options.odometry_interval, &times)) {
    *error = OptionError(
        "mrclam_odometry_interval", FormatNumber(options.odometry_interval),
        "gives more than " + FormatNumber(kMaxTrajectoryTimes) +
            " poses over the measurement times " +
            FormatNumber(measurement_times.front()) + " to " +
            FormatNumber(measurement_times.back()) + " of " + robot +
            "_Measurement.dat",
        "0 or a longer interval");
    return false;
  }
  summary->trajectory_times = times.size();
  std::size_t row = 0;
  for (std::size_t k = 0; k + 1 < times.size(); ++k) {
    Odometry odom;
    odom.t0 = times[k];
    odom.t1 = times[k + 1];
    double path_length;
    IntegrateBetween(raw.odometry, odom.t0, odom.t1, &row, &odom.dx, &odom.dy,
                     &odom.dtheta, &path_length);
    if (!std::isfinite(odom.dx) || !std::isfinite(odom.dy) ||
        !std::isfinite(odom.dtheta) || !std::isfinite(path_length)) {
      *error = robot + "_Odometry.dat: the velocities integrate to a " +
               "non-finite motion from " + FormatNumber(odom.t0) + " to " +
               FormatNumber(odom.t1) + " s";
      return false;
    }
    odom.dtheta = WrapAngle(odom.dtheta);
    odom.sigma_x = odom.sigma_y =
        std::max(options.odometry_sigma_xy_floor,
                 options.odometry_sigma_xy_per_metre * path_length);
    odom.sigma_theta =
        std::max(options.odometry_sigma_theta_floor,
                 options.odometry_sigma_theta_per_second * (odom.t1 - odom.t0));
    dataset->odometry.push_back(odom);
  }

  dataset->pose_priors.push_back({PoseAtTime(raw.ground_truth, times[0]),
                                  options.first_pose_sigma_xy,
                                  options.first_pose_sigma_theta});
  // Priors only on landmarks this robot sees: an unobserved landmark would
  // just copy its prior through and flatter the landmark error.
  for (const auto& [id, xy] : raw.landmarks) {
    if (options.landmark_prior_sigma > 0.0 && observed.count(id) > 0) {
      dataset->landmark_priors.push_back(
          {id, xy.first, xy.second, options.landmark_prior_sigma});
    }
    Landmark landmark;
    landmark.id = id;
    landmark.x = xy.first;
    landmark.y = xy.second;
    dataset->ground_truth_landmarks.push_back(landmark);
  }
  const double min_gap =
      options.gt_rate_hz > 0.0 ? 1.0 / options.gt_rate_hz : 0.0;
  for (const TimedPose& p : raw.ground_truth) {
    if (p.t < times.front() || p.t > times.back()) continue;
    if (!dataset->ground_truth.empty() &&
        p.t - dataset->ground_truth.back().t < min_gap - 1e-9) {
      continue;
    }
    dataset->ground_truth.push_back({p.t, p.x, p.y, WrapAngle(p.theta)});
  }
  summary->ground_truth_kept = dataset->ground_truth.size();

  std::vector<double> range_residuals, bearing_residuals;
  for (const Observation& obs : dataset->observations) {
    const TimedPose pose = PoseAtTime(raw.ground_truth, obs.t);
    const auto& l = raw.landmarks.at(obs.id);
    range_residuals.push_back(obs.range -
                              std::hypot(l.first - pose.x, l.second - pose.y));
    bearing_residuals.push_back(WrapAngle(
        obs.bearing -
        (std::atan2(l.second - pose.y, l.first - pose.x) - pose.theta)));
  }
  MrclamAgreement& agreement = summary->agreement;
  agreement.count = range_residuals.size();
  MedianAndMad(range_residuals, &agreement.range_median, &agreement.range_mad);
  MedianAndMad(bearing_residuals, &agreement.bearing_median,
               &agreement.bearing_mad);

  auto n = [](double v) { return FormatNumber(v); };
  auto& meta = dataset->metadata;
  meta.emplace_back("source", "UTIAS MRCLAM, directory '" +
                                  DirectoryName(directory) + "', robot " +
                                  std::to_string(options.robot) + " (Robot" +
                                  std::to_string(options.robot) +
                                  "_*.dat, Barcodes.dat, "
                                  "Landmark_Groundtruth.dat)");
  meta.emplace_back("citation",
                    "Leung, Halpern, Barfoot, Liu, The UTIAS Multi-Robot "
                    "Cooperative Localization and Mapping Dataset, IJRR "
                    "30(8), 2011");
  meta.emplace_back("license",
                    "no licence file given by the authors; published for "
                    "research use with the citation; see "
                    "third_party_licenses/UTIAS_MRCLAM.txt");
  meta.emplace_back("converter", ConverterDescription(options));
  meta.emplace_back(
      "measurements",
      std::to_string(summary->measurement_rows) + " rows, kept " +
          std::to_string(summary->measurements_kept) + ", dropped " +
          std::to_string(summary->dropped_robot) + " of robots, " +
          std::to_string(summary->dropped_unknown) + " of unknown barcodes, " +
          std::to_string(summary->dropped_outside_span) +
          " outside the odometry/ground-truth times");
  meta.emplace_back(
      "trajectory",
      std::to_string(summary->trajectory_times) +
          " pose times (the distinct measurement times" +
          (options.odometry_interval > 0.0
               ? ", and steps of <= " + n(options.odometry_interval) +
                     " s between them)"
               : ")") +
          ", from " + n(times.front()) + " to " + n(times.back()) +
          " (Unix time); ODOM integrates the commanded velocities exactly");
  meta.emplace_back(
      "agreement", "vs Vicon truth over " + std::to_string(agreement.count) +
                       " measurements: range residual median " +
                       n(agreement.range_median) + " m, MAD " +
                       n(agreement.range_mad) + " m; bearing residual median " +
                       n(agreement.bearing_median) + " rad, MAD " +
                       n(agreement.bearing_mad) + " rad");
  return true;
}

}  // namespace rff
