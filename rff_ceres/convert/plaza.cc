#include "rff_ceres/convert/plaza.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <string_view>

#include "rff_ceres/convert/raw_records.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/se2.h"
#include "rff_ceres/statistics.h"

namespace rff {
namespace {

// DR row k must carry the time of GT row k + 1; the files were written from
// the same doubles, so anything beyond rounding noise is a mismatch.
constexpr double kTimeMatchTolerance = 1e-6;

// Threshold-and-refit rounds of the range calibration; the inlier set
// settles in a few.
constexpr int kMaxCalibrationRounds = 100;

struct RawRange {
  double t = 0.0;
  LandmarkId beacon = 0;
  double range = 0.0;
};

struct PlazaRaw {
  std::vector<TimedPose> ground_truth;  // Headings as in the file.
  std::vector<double> odometry_distance;
  std::vector<double> odometry_heading;
  std::map<LandmarkId, std::pair<double, double>> beacons;
  std::vector<RawRange> ranges;  // In file order.
};

bool ReadGroundTruth(const std::string& path, PlazaRaw* raw,
                     std::string* error) {
  return ReadRecords(
      path, 4,
      [&](const LineReader& reader, const std::vector<std::string_view>& f,
          std::string* err) {
        double v[4];
        if (!ParseFiniteDoubles(reader, f, 0, 4, v, err)) return false;
        if (!raw->ground_truth.empty() &&
            !(v[0] > raw->ground_truth.back().t)) {
          *err = reader.Error("time " + FormatNumber(v[0]) +
                              " does not increase (previous row " +
                              FormatNumber(raw->ground_truth.back().t) + ")");
          return false;
        }
        raw->ground_truth.push_back({v[0], v[1], v[2], v[3]});
        return true;
      },
      error);
}

bool ReadOdometry(const std::string& path, PlazaRaw* raw, std::string* error) {
  const std::vector<TimedPose>& gt = raw->ground_truth;
  return ReadRecords(
      path, 3,
      [&](const LineReader& reader, const std::vector<std::string_view>& f,
          std::string* err) {
        double v[3];
        if (!ParseFiniteDoubles(reader, f, 0, 3, v, err)) return false;
        const std::size_t k = raw->odometry_distance.size();
        if (k + 1 >= gt.size()) {
          *err =
              reader.Error("more odometry rows than ground-truth rows - 1 (" +
                           std::to_string(gt.size() - 1) + ")");
          return false;
        }
        if (std::abs(v[0] - gt[k + 1].t) > kTimeMatchTolerance) {
          *err = reader.Error("time " + FormatNumber(v[0]) +
                              " does not match ground-truth row " +
                              std::to_string(k + 2) + " time " +
                              FormatNumber(gt[k + 1].t) +
                              " (DR row k moves GT pose k to k + 1)");
          return false;
        }
        raw->odometry_distance.push_back(v[1]);
        raw->odometry_heading.push_back(v[2]);
        return true;
      },
      error);
}

bool ReadBeacons(const std::string& path, PlazaRaw* raw, std::string* error) {
  return ReadRecords(
      path, 3,
      [&](const LineReader& reader, const std::vector<std::string_view>& f,
          std::string* err) {
        LandmarkId id;
        double v[2];
        if (!ParseRawInteger(reader, f[0], 1, &id, err) ||
            !ParseFiniteDoubles(reader, f, 1, 2, v, err)) {
          return false;
        }
        if (!raw->beacons.emplace(id, std::make_pair(v[0], v[1])).second) {
          *err = reader.Error("duplicate beacon " + std::to_string(id));
          return false;
        }
        return true;
      },
      error);
}

bool ReadRanges(const std::string& path, PlazaRaw* raw, std::string* error) {
  return ReadRecords(
      path, 4,
      [&](const LineReader& reader, const std::vector<std::string_view>& f,
          std::string* err) {
        double t, range;
        LandmarkId sender, beacon;
        if (!ParseFiniteDoubles(reader, f, 0, 1, &t, err) ||
            !ParseRawInteger(reader, f[1], 2, &sender, err) ||
            !ParseRawInteger(reader, f[2], 3, &beacon, err) ||
            !ParseFiniteDoubles(reader, f, 3, 1, &range, err)) {
          return false;
        }
        if (raw->beacons.count(beacon) == 0) {
          *err = reader.Error("beacon " + std::to_string(beacon) +
                              " is not in the beacon list (TL file)");
          return false;
        }
        if (range < 0.0) {
          *err = reader.Error("range must be >= 0, got " + FormatNumber(range));
          return false;
        }
        raw->ranges.push_back({t, beacon, range});
        return true;
      },
      error);
}

// Least squares line truth ~ a * measured + b over the flagged pairs.
bool FitLine(const std::vector<double>& measured,
             const std::vector<double>& truth, const std::vector<bool>& use,
             double* a, double* b, std::string* error) {
  std::size_t n = 0;
  double mean_m = 0.0, mean_t = 0.0;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    if (!use[i]) continue;
    ++n;
    mean_m += measured[i];
    mean_t += truth[i];
  }
  if (n < 3) {
    *error =
        "range calibration needs at least 3 ranges, got " + std::to_string(n);
    return false;
  }
  mean_m /= n;
  mean_t /= n;
  double smm = 0.0, smt = 0.0;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    if (!use[i]) continue;
    smm += (measured[i] - mean_m) * (measured[i] - mean_m);
    smt += (measured[i] - mean_m) * (truth[i] - mean_t);
  }
  if (!(smm > 0.0)) {
    *error = "range calibration: all measured ranges are equal";
    return false;
  }
  *a = smt / smm;
  *b = mean_t - *a * mean_m;
  return true;
}

// Siegel's repeated-median line: the slope is the median over i of the
// median slope from pair i to every other pair; the intercept the median of
// truth - a * measured. Robust to up to half of the pairs being outliers.
bool RepeatedMedianLine(const std::vector<double>& measured,
                        const std::vector<double>& truth, double* a, double* b,
                        std::string* error) {
  std::vector<double> slopes_at, slopes;
  slopes_at.reserve(measured.size());
  slopes.reserve(measured.size());
  for (std::size_t i = 0; i < measured.size(); ++i) {
    slopes.clear();
    for (std::size_t j = 0; j < measured.size(); ++j) {
      if (measured[j] == measured[i]) continue;
      slopes.push_back((truth[j] - truth[i]) / (measured[j] - measured[i]));
    }
    if (!slopes.empty()) slopes_at.push_back(Median(slopes));
  }
  if (slopes_at.empty()) {
    *error = "range calibration: all measured ranges are equal";
    return false;
  }
  *a = Median(slopes_at);
  std::vector<double> intercepts;
  intercepts.reserve(measured.size());
  for (std::size_t i = 0; i < measured.size(); ++i) {
    intercepts.push_back(truth[i] - *a * measured[i]);
  }
  *b = Median(intercepts);
  return true;
}

double RoundedRangeSigma(double inlier_sigma) {
  return std::max(0.1, std::round(inlier_sigma * 10.0) / 10.0);
}

std::string ConverterDescription(const PlazaOptions& o) {
  auto n = [](double v) { return FormatNumber(v); };
  return "rff_convert --format=plaza --plaza_name=" + o.name +
         " --plaza_calibration=" +
         (o.calibration == PlazaCalibration::kLinear ? "linear" : "none") +
         " --plaza_outlier_threshold=" + n(o.outlier_threshold) +
         " --plaza_range_sigma=" + n(o.range_sigma) +
         " --plaza_odom_sigma_xy_floor=" + n(o.odometry_sigma_xy_floor) +
         " --plaza_odom_sigma_xy_per_m=" + n(o.odometry_sigma_xy_per_metre) +
         " --plaza_odom_sigma_theta_floor=" + n(o.odometry_sigma_theta_floor) +
         " --plaza_odom_sigma_theta_per_rad=" +
         n(o.odometry_sigma_theta_per_radian) +
         " --plaza_landmark_prior_sigma=" + n(o.landmark_prior_sigma) +
         " --prior_sigma_xy=" + n(o.first_pose_sigma_xy) +
         " --prior_sigma_theta=" + n(o.first_pose_sigma_theta);
}

bool CheckOptions(const PlazaOptions& o, std::string* error) {
  auto positive = [&](double v, const char* name) {
    return CheckPositiveOption(v, name, error);
  };
  auto non_negative = [&](double v, const char* name) {
    return CheckNonNegativeOption(v, name, error);
  };
  if (o.name.empty()) {
    *error = "the Plaza dataset name (file prefix) is empty";
    return false;
  }
  return positive(o.outlier_threshold, "plaza_outlier_threshold") &&
         non_negative(o.range_sigma, "plaza_range_sigma") &&
         positive(o.odometry_sigma_xy_floor, "plaza_odom_sigma_xy_floor") &&
         non_negative(o.odometry_sigma_xy_per_metre,
                      "plaza_odom_sigma_xy_per_m") &&
         positive(o.odometry_sigma_theta_floor,
                  "plaza_odom_sigma_theta_floor") &&
         non_negative(o.odometry_sigma_theta_per_radian,
                      "plaza_odom_sigma_theta_per_rad") &&
         non_negative(o.landmark_prior_sigma, "plaza_landmark_prior_sigma") &&
         positive(o.first_pose_sigma_xy, "prior_sigma_xy") &&
         positive(o.first_pose_sigma_theta, "prior_sigma_theta");
}

}  // namespace

bool ParsePlazaCalibration(const std::string& text,
                           PlazaCalibration* calibration, std::string* error) {
  if (text == "linear") {
    *calibration = PlazaCalibration::kLinear;
  } else if (text == "none") {
    *calibration = PlazaCalibration::kNone;
  } else {
    *error = "unknown Plaza calibration '" + text + "' (use linear or none)";
    return false;
  }
  return true;
}

bool FitLinearRangeCalibration(const std::vector<double>& measured,
                               const std::vector<double>& truth,
                               double outlier_threshold, LinearRangeFit* fit,
                               std::string* error) {
  if (measured.size() != truth.size()) {
    *error = "range calibration: measured and true ranges differ in number";
    return false;
  }
  *fit = LinearRangeFit();
  if (measured.size() < 3) {
    *error = "range calibration needs at least 3 ranges, got " +
             std::to_string(measured.size());
    return false;
  }
  // A robust start, so that gross outliers cannot drag the first line away
  // from the inliers; then threshold and least-squares refit until the
  // inlier set settles.
  if (!RepeatedMedianLine(measured, truth, &fit->a, &fit->b, error)) {
    return false;
  }
  std::vector<bool> inlier;
  for (int round = 0; round < kMaxCalibrationRounds; ++round) {
    inlier.assign(measured.size(), false);
    for (std::size_t i = 0; i < measured.size(); ++i) {
      inlier[i] = std::abs(fit->a * measured[i] + fit->b - truth[i]) <=
                  outlier_threshold;
    }
    if (inlier == fit->inlier) break;
    fit->inlier = inlier;
    if (!FitLine(measured, truth, fit->inlier, &fit->a, &fit->b, error)) {
      *error +=
          " (inliers: |residual| <= " + FormatNumber(outlier_threshold) + " m)";
      return false;
    }
  }
  double sum_squares = 0.0;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    if (!fit->inlier[i]) continue;
    ++fit->num_inliers;
    const double r = fit->a * measured[i] + fit->b - truth[i];
    sum_squares += r * r;
  }
  fit->inlier_sigma = std::sqrt(sum_squares / (fit->num_inliers - 2));
  return true;
}

bool ConvertPlaza(const std::string& directory, const PlazaOptions& options,
                  Dataset* dataset, PlazaSummary* summary, std::string* error) {
  *dataset = Dataset();
  *summary = PlazaSummary();
  if (!CheckOptions(options, error)) return false;
  const std::string prefix = directory + "/" + options.name;
  PlazaRaw raw;
  if (!ReadGroundTruth(prefix + "_GT.txt", &raw, error)) return false;
  if (raw.ground_truth.size() < 2) {
    *error = prefix + "_GT.txt: needs at least 2 rows";
    return false;
  }
  if (!ReadOdometry(prefix + "_DR.txt", &raw, error)) return false;
  if (raw.odometry_distance.size() + 1 != raw.ground_truth.size()) {
    *error = prefix +
             "_DR.txt: " + std::to_string(raw.odometry_distance.size()) +
             " rows, expected " + std::to_string(raw.ground_truth.size() - 1) +
             " (one per ground-truth row after the first)";
    return false;
  }
  if (!ReadBeacons(prefix + "_TL.txt", &raw, error)) return false;
  if (!ReadRanges(prefix + "_TD.txt", &raw, error)) return false;

  const std::vector<TimedPose>& gt = raw.ground_truth;
  summary->ground_truth_rows = gt.size();
  summary->odometry_rows = raw.odometry_distance.size();
  summary->range_rows = raw.ranges.size();
  double latest = raw.ranges.front().t;
  for (const RawRange& r : raw.ranges) {
    if (r.t < latest) ++summary->ranges_out_of_order;
    latest = std::max(latest, r.t);
  }
  // TD is not sorted by time (some rows arrive late).
  std::vector<RawRange> ranges = raw.ranges;
  std::stable_sort(
      ranges.begin(), ranges.end(),
      [](const RawRange& a, const RawRange& b) { return a.t < b.t; });

  // True range at each range time from interpolated ground truth and the
  // surveyed beacons; ranges outside the trajectory cannot be used.
  std::vector<RawRange> in_span;
  std::vector<double> measured, truth;
  for (const RawRange& r : ranges) {
    if (r.t < gt.front().t || r.t > gt.back().t) {
      ++summary->ranges_outside_span;
      continue;
    }
    const TimedPose pose = PoseAtTime(gt, r.t);
    const auto& beacon = raw.beacons.at(r.beacon);
    in_span.push_back(r);
    measured.push_back(r.range);
    truth.push_back(std::hypot(beacon.first - pose.x, beacon.second - pose.y));
  }
  if (!FitLinearRangeCalibration(measured, truth, options.outlier_threshold,
                                 &summary->fit, error)) {
    *error = prefix + "_TD.txt: " + *error;
    return false;
  }
  const LinearRangeFit& fit = summary->fit;
  const bool linear = options.calibration == PlazaCalibration::kLinear;
  summary->range_sigma = options.range_sigma > 0.0
                             ? options.range_sigma
                             : RoundedRangeSigma(fit.inlier_sigma);

  for (std::size_t i = 0; i < in_span.size(); ++i) {
    Observation obs;
    obs.type = ObservationType::kRange;
    obs.t = in_span[i].t;
    obs.id = in_span[i].beacon;
    obs.sigma_range = summary->range_sigma;
    if (linear) {
      obs.range = fit.a * in_span[i].range + fit.b;
      // A negative corrected range cannot be a distance: reject it too.
      if (!fit.inlier[i] || obs.range < 0.0) {
        ++summary->ranges_rejected;
        continue;
      }
    } else {
      obs.range = in_span[i].range;
    }
    dataset->observations.push_back(obs);
  }
  summary->ranges_kept = dataset->observations.size();

  const TimedPose& first = gt.front();
  dataset->pose_priors.push_back(
      {{first.t, first.x, first.y, WrapAngle(first.theta)},
       options.first_pose_sigma_xy,
       options.first_pose_sigma_theta});
  for (std::size_t k = 0; k < raw.odometry_distance.size(); ++k) {
    const double d = raw.odometry_distance[k];
    const double dtheta = WrapAngle(raw.odometry_heading[k]);
    const double sigma_xy =
        std::max(options.odometry_sigma_xy_floor,
                 options.odometry_sigma_xy_per_metre * std::abs(d));
    const double sigma_theta =
        std::max(options.odometry_sigma_theta_floor,
                 options.odometry_sigma_theta_per_radian * std::abs(dtheta));
    dataset->odometry.push_back({gt[k].t, gt[k + 1].t, d, 0.0, dtheta, sigma_xy,
                                 sigma_xy, sigma_theta});
  }
  for (const TimedPose& p : gt) {
    dataset->ground_truth.push_back({p.t, p.x, p.y, WrapAngle(p.theta)});
  }
  for (const auto& [id, xy] : raw.beacons) {
    if (options.landmark_prior_sigma > 0.0) {
      dataset->landmark_priors.push_back(
          {id, xy.first, xy.second, options.landmark_prior_sigma});
    }
    Landmark landmark;
    landmark.id = id;
    landmark.x = xy.first;
    landmark.y = xy.second;
    dataset->ground_truth_landmarks.push_back(landmark);
  }

  const std::string kept = std::to_string(summary->ranges_kept) + " of " +
                           std::to_string(summary->range_rows);
  auto& meta = dataset->metadata;
  meta.emplace_back("source", "CMU " + options.name +
                                  " range-only UWB + odometry (" +
                                  options.name + "_{GT,DR,TD,TL}.txt)");
  meta.emplace_back("citation",
                    "Djugash, Hamner, Roth, Navigating with ranging radios: "
                    "five data sets with ground truth, Journal of Field "
                    "Robotics 26(9), 2009");
  meta.emplace_back("license",
                    "BSD-3-Clause (gpslam copy, Copyright (c) 2016 Georgia "
                    "Tech Research Corporation); see "
                    "third_party_licenses/CMU_PLAZA.txt");
  meta.emplace_back("converter", ConverterDescription(options));
  if (linear) {
    meta.emplace_back(
        "calibration",
        "range = a * raw + b fitted against ground truth (interpolated GT "
        "position + surveyed beacons), a=" +
            FormatNumber(fit.a) + ", b=" + FormatNumber(fit.b) +
            ", inlier sigma=" + FormatNumber(fit.inlier_sigma) +
            " m, outliers |residual| > " +
            FormatNumber(options.outlier_threshold) + " m dropped, kept " +
            kept);
  } else {
    meta.emplace_back(
        "calibration",
        "none: raw ranges kept (" + kept +
            "); for reference the linear fit is a=" + FormatNumber(fit.a) +
            ", b=" + FormatNumber(fit.b) +
            ", inlier sigma=" + FormatNumber(fit.inlier_sigma) + " m");
  }
  meta.emplace_back("ranges", std::to_string(summary->range_rows) + " rows, " +
                                  std::to_string(summary->ranges_out_of_order) +
                                  " out of time order (sorted), " +
                                  std::to_string(summary->ranges_outside_span) +
                                  " outside the ground-truth times, " +
                                  std::to_string(summary->ranges_rejected) +
                                  " rejected, sigma " +
                                  FormatNumber(summary->range_sigma));
  return true;
}

}  // namespace rff
