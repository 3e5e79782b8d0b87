#include "rff_ceres/convert/plaza.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <string_view>

#include "rff_ceres/convert/raw_records.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"
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

// Header key of the heading offset in the raw files (gpslam's .mat variable
// of the same name): "# init_heading_offset[rad] = X".
constexpr std::string_view kHeadingOffsetKey = "init_heading_offset";

// Below this much DR travel the direction of the GT displacements is GPS
// noise: the heading offset cannot be measured and the DR distances not
// checked.
constexpr double kMinMeasuredTravel = 1.0;  // m

// The GT displacement must be this close to the DR distance (as a ratio);
// outside, the DR distance column is in other units or another convention.
constexpr double kMinDistanceRatio = 0.5;
constexpr double kMaxDistanceRatio = 2.0;

// Below this much GT turning (summed |heading change|) the heading
// increments cannot be compared; above it, DR and GT heading increments
// must agree with a normalised correlation of at least kMinTurnAgreement
// (1 on Plaza 1; a flipped sign gives -1, absolute headings ~0).
constexpr double kMinMeasuredTurning = 2.0 * M_PI;
constexpr double kMinTurnAgreement = 0.5;

// An angle this close to a multiple of pi/2 is that multiple exactly when
// rotating the odometry (see AxisExactCosSin).
constexpr double kAxisSnap = 1e-9;

struct RawRange {
  double t = 0.0;
  LandmarkId beacon = 0;
  double range = 0.0;
};

struct PlazaRaw {
  std::vector<TimedPose> ground_truth;  // Headings as in the file.
  std::vector<double> odometry_distance;
  std::vector<double> odometry_heading;
  // Comment lines before the first row (where the heading offset is
  // declared).
  std::vector<std::string> ground_truth_header;
  std::vector<std::string> odometry_header;
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
      error, &raw->ground_truth_header);
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
      error, &raw->odometry_header);
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

// Reads "init_heading_offset[rad] = X" (or ": X") from the header comments
// of `path` into `offset`; leaves it alone when the file declares none.
bool ReadDeclaredHeadingOffset(const std::string& path,
                               const std::vector<std::string>& header,
                               std::optional<double>* offset,
                               std::string* error) {
  for (const std::string& comment : header) {
    std::string_view text(comment);
    const std::size_t at = text.find(kHeadingOffsetKey);
    if (at == std::string_view::npos) continue;
    auto fail = [&](const std::string& problem) {
      *error = path + ": header '#" + comment + "': " + problem;
      return false;
    };
    auto skip_blanks = [&text]() {
      while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) {
        text.remove_prefix(1);
      }
    };
    text.remove_prefix(at + kHeadingOffsetKey.size());
    if (!text.empty() && text.front() == '[') {
      const std::size_t close = text.find(']');
      if (close == std::string_view::npos ||
          text.substr(1, close - 1) != "rad") {
        return fail("the heading offset must be given in [rad]");
      }
      text.remove_prefix(close + 1);
    }
    skip_blanks();
    if (text.empty() || (text.front() != '=' && text.front() != ':')) {
      return fail("expected '=' after " + std::string(kHeadingOffsetKey));
    }
    text.remove_prefix(1);
    skip_blanks();
    const std::string_view number = text.substr(0, text.find_first_of(" \t"));
    double value;
    if (!ParseFiniteDouble(number, &value)) {
      return fail("'" + std::string(number) + "' is not a finite number");
    }
    if (offset->has_value() && **offset != value) {
      return fail("declares " + FormatNumber(value) + " after " +
                  FormatNumber(**offset));
    }
    *offset = value;
  }
  return true;
}

// cos and sin of `angle`, exactly 0 and +-1 within kAxisSnap of a multiple
// of pi/2: axis-aligned frames (offset 0, pi/2, pi) then give ODOM records
// without 1e-17 residue, and offset 0 reproduces (d, 0) bit for bit.
void AxisExactCosSin(double angle, double* c, double* s) {
  const double quarters = std::round(angle / M_PI_2);
  if (std::abs(angle - quarters * M_PI_2) > kAxisSnap) {
    *c = std::cos(angle);
    *s = std::sin(angle);
    return;
  }
  static constexpr double kCos[] = {1.0, 0.0, -1.0, 0.0};
  static constexpr double kSin[] = {0.0, 1.0, 0.0, -1.0};
  const int quadrant = static_cast<int>(std::fmod(quarters, 4.0) + 4.0) % 4;
  *c = kCos[quadrant];
  *s = kSin[quadrant];
}

// a * b, but +0 when either is 0 (no "-0" in the written records).
double Product(double a, double b) {
  return a == 0.0 || b == 0.0 ? 0.0 : a * b;
}

// What the GT trajectory says about the DR rows, independent of any frame.
struct OdometryAgreement {
  // Direction of the GT displacement k -> k + 1 in the GT pose frame at k,
  // averaged with weight d_k^2 (arg of sum d_k * z_k): where the odometry
  // frame points relative to the GT heading. NaN below kMinMeasuredTravel.
  double heading_offset = std::numeric_limits<double>::quiet_NaN();
  // |sum d_k * z_k| / sum d_k^2: the GT displacement per DR metre.
  double distance_ratio = std::numeric_limits<double>::quiet_NaN();
  // Normalised correlation of the GT and DR heading increments; NaN below
  // kMinMeasuredTurning.
  double turn_agreement = std::numeric_limits<double>::quiet_NaN();
  // The sums overflowed: distances or coordinates no recording has.
  bool overflowed = false;
};

OdometryAgreement MeasureOdometryAgreement(const PlazaRaw& raw) {
  const std::vector<TimedPose>& gt = raw.ground_truth;
  OdometryAgreement result;
  double sum_x = 0.0, sum_y = 0.0, sum_d2 = 0.0, travel = 0.0;
  double sum_gh = 0.0, sum_gg = 0.0, sum_hh = 0.0, turning = 0.0;
  for (std::size_t k = 0; k < raw.odometry_distance.size(); ++k) {
    const double d = raw.odometry_distance[k];
    const double c = std::cos(gt[k].theta), s = std::sin(gt[k].theta);
    const double ex = gt[k + 1].x - gt[k].x, ey = gt[k + 1].y - gt[k].y;
    sum_x += d * (c * ex + s * ey);
    sum_y += d * (-s * ex + c * ey);
    sum_d2 += d * d;
    travel += std::abs(d);
    const double g = WrapAngle(gt[k + 1].theta - gt[k].theta);
    const double h = WrapAngle(raw.odometry_heading[k]);
    sum_gh += g * h;
    sum_gg += g * g;
    sum_hh += h * h;
    turning += std::abs(g);
  }
  result.overflowed = !std::isfinite(sum_x + sum_y + sum_d2 + travel);
  if (travel >= kMinMeasuredTravel && !result.overflowed) {
    result.heading_offset = std::atan2(sum_y, sum_x);
    result.distance_ratio = std::hypot(sum_x, sum_y) / sum_d2;
  }
  if (turning >= kMinMeasuredTurning && std::isfinite(sum_gh + sum_hh)) {
    result.turn_agreement =
        sum_hh > 0.0 ? sum_gh / std::sqrt(sum_gg * sum_hh) : 0.0;
  }
  return result;
}

// Rounds to 1e-4 for messages and metadata (+ 0.0: "0", never "-0").
std::string Short(double value) {
  return FormatNumber(std::round(value * 1e4) / 1e4 + 0.0);
}

// Chooses the heading offset of the odometry frame (option, declared,
// measured) and checks it and the DR columns against the ground truth, so
// that no frame or convention mismatch reaches the ODOM records silently.
bool ResolveHeadingOffset(const std::string& prefix,
                          const PlazaOptions& options, const PlazaRaw& raw,
                          PlazaSummary* summary, std::string* error) {
  const std::string dr_path = prefix + "_DR.txt";
  const OdometryAgreement agreement = MeasureOdometryAgreement(raw);
  summary->measured_heading_offset = agreement.heading_offset;
  if (agreement.overflowed) {
    *error = prefix + "_{GT,DR}.txt: the DR distances and the ground-truth " +
             "displacements overflow double precision when compared: " +
             "distances or coordinates no recording has";
    return false;
  }
  if (std::isfinite(agreement.distance_ratio) &&
      !(agreement.distance_ratio >= kMinDistanceRatio &&
        agreement.distance_ratio <= kMaxDistanceRatio)) {
    *error = dr_path + ": the DR distances do not match the ground truth " +
             "(GT moves " + Short(agreement.distance_ratio) +
             " m per DR metre): column 2 must be the distance travelled " +
             "since the previous row, in metres";
    return false;
  }
  if (std::isfinite(agreement.turn_agreement) &&
      !(agreement.turn_agreement >= kMinTurnAgreement)) {
    *error = dr_path + ": the DR heading column does not follow the " +
             "ground-truth heading (correlation of the increments " +
             Short(agreement.turn_agreement) +
             ", expected about 1): column 3 must be the heading change " +
             "since the previous row, counter-clockwise, in radians";
    return false;
  }

  std::optional<double> declared_gt, declared_dr;
  if (!ReadDeclaredHeadingOffset(prefix + "_GT.txt", raw.ground_truth_header,
                                 &declared_gt, error) ||
      !ReadDeclaredHeadingOffset(dr_path, raw.odometry_header, &declared_dr,
                                 error)) {
    return false;
  }
  if (declared_gt && declared_dr && *declared_gt != *declared_dr) {
    *error = prefix + "_{GT,DR}.txt: the headers declare different " +
             std::string(kHeadingOffsetKey) + " (" +
             FormatNumber(*declared_gt) + " and " + FormatNumber(*declared_dr) +
             ")";
    return false;
  }
  const double measured = agreement.heading_offset;
  const double tolerance = options.heading_offset_tolerance;
  if (options.heading_offset) {
    summary->heading_offset = *options.heading_offset;
    summary->heading_offset_source = "option";
  } else if (declared_gt || declared_dr) {
    summary->heading_offset = declared_gt ? *declared_gt : *declared_dr;
    const std::string name = options.name;
    summary->heading_offset_source =
        "declared in " + (declared_gt && declared_dr
                              ? name + "_GT.txt and " + name + "_DR.txt"
                              : name + (declared_gt ? "_GT.txt" : "_DR.txt"));
  } else if (std::isfinite(measured)) {
    summary->heading_offset = WrapAngle(std::round(measured / M_PI_2) * M_PI_2);
    summary->heading_offset_source =
        "measured, not declared (nearest multiple of pi/2)";
  } else {
    *error = dr_path + ": no " + std::string(kHeadingOffsetKey) +
             " declared in the headers, and the ground truth moves too " +
             "little to measure one; set --plaza_heading_offset";
    return false;
  }
  if (std::isfinite(measured) &&
      std::abs(WrapAngle(measured - summary->heading_offset)) > tolerance) {
    *error = dr_path + ": the odometry moves the robot along the " +
             "ground-truth heading + " + Short(measured) +
             " rad (measured from the GT displacements), but the heading " +
             "offset is " + Short(summary->heading_offset) + " rad (" +
             summary->heading_offset_source +
             "); set --plaza_heading_offset (or widen " +
             "--plaza_heading_offset_tolerance, now " +
             FormatNumber(tolerance) + " rad)";
    return false;
  }
  return true;
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
  const std::string heading_offset =
      o.heading_offset ? n(*o.heading_offset) : "auto";
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
         " --plaza_heading_offset=" + heading_offset +
         " --plaza_heading_offset_tolerance=" + n(o.heading_offset_tolerance) +
         " --prior_sigma_xy=" + n(o.first_pose_sigma_xy) +
         " --prior_sigma_theta=" + n(o.first_pose_sigma_theta);
}

}  // namespace

bool ParsePlazaCalibration(const std::string& text,
                           PlazaCalibration* calibration, std::string* error) {
  if (text == "linear") {
    *calibration = PlazaCalibration::kLinear;
  } else if (text == "none") {
    *calibration = PlazaCalibration::kNone;
  } else {
    *error = OptionError("plaza_calibration", text, "unknown calibration",
                         "linear or none");
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
  // A non-positive scale maps longer ranges to shorter distances: no sensor
  // does that, so the pairs do not describe one trajectory (wrong beacon
  // ids, time base, or a trajectory that is not the one ranged from).
  if (!(fit->a > 0.0)) {
    *error = "range calibration: the fitted scale a = " + FormatNumber(fit->a) +
             " (b = " + FormatNumber(fit->b) +
             " m) is not positive, which no range sensor produces: the " +
             "ranges do not match the ground truth";
    return false;
  }
  fit->inlier_sigma = std::sqrt(sum_squares / (fit->num_inliers - 2));
  return true;
}

bool CheckPlazaOptions(const PlazaOptions& o, std::string* error) {
  if (o.name.empty()) {
    *error = OptionError("plaza_name", o.name, "empty",
                         "a file prefix such as Plaza1");
    return false;
  }
  // A path here would read files outside --input, which the output check
  // does not see: it could overwrite one of them.
  if (o.name.find('/') != std::string::npos) {
    *error = OptionError("plaza_name", o.name, "holds a '/'",
                         "a file prefix such as Plaza1 (the directory goes "
                         "in --input)");
    return false;
  }
  if (o.heading_offset && !std::isfinite(*o.heading_offset)) {
    *error =
        OptionError("plaza_heading_offset", FormatNumber(*o.heading_offset), "",
                    "auto or a finite number [rad]");
    return false;
  }
  return CheckNumericOptions(
      {{o.outlier_threshold, "plaza_outlier_threshold", false},
       {o.range_sigma, "plaza_range_sigma", true},
       {o.odometry_sigma_xy_floor, "plaza_odom_sigma_xy_floor", false},
       {o.odometry_sigma_xy_per_metre, "plaza_odom_sigma_xy_per_m", true},
       {o.odometry_sigma_theta_floor, "plaza_odom_sigma_theta_floor", false},
       {o.odometry_sigma_theta_per_radian, "plaza_odom_sigma_theta_per_rad",
        true},
       {o.landmark_prior_sigma, "plaza_landmark_prior_sigma", true},
       {o.first_pose_sigma_xy, "prior_sigma_xy", false},
       {o.first_pose_sigma_theta, "prior_sigma_theta", false},
       {o.heading_offset_tolerance, "plaza_heading_offset_tolerance", false}},
      error);
}

bool ConvertPlaza(const std::string& directory, const PlazaOptions& options,
                  Dataset* dataset, PlazaSummary* summary, std::string* error) {
  *dataset = Dataset();
  *summary = PlazaSummary();
  if (!CheckPlazaOptions(options, error)) return false;
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
  if (!ResolveHeadingOffset(prefix, options, raw, summary, error)) {
    return false;
  }

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

  // Every pose the solver reads is in the GT heading frame: the prior is GT
  // row 0 as it is, never moved into the odometry frame.
  const TimedPose& first = gt.front();
  dataset->pose_priors.push_back(
      {{first.t, first.x, first.y, WrapAngle(first.theta)},
       options.first_pose_sigma_xy,
       options.first_pose_sigma_theta});
  // DR row k moves the odometry frame by Pose2(d, 0, dtheta); that frame is
  // the GT pose frame turned by the offset R, so in the GT pose frame the
  // motion is R * Pose2(d, 0, dtheta) * R^-1 = Pose2(R (d, 0), dtheta).
  double offset_cos, offset_sin;
  AxisExactCosSin(summary->heading_offset, &offset_cos, &offset_sin);
  for (std::size_t k = 0; k < raw.odometry_distance.size(); ++k) {
    const double d = raw.odometry_distance[k];
    const double dtheta = WrapAngle(raw.odometry_heading[k]);
    const double sigma_xy =
        std::max(options.odometry_sigma_xy_floor,
                 options.odometry_sigma_xy_per_metre * std::abs(d));
    const double sigma_theta =
        std::max(options.odometry_sigma_theta_floor,
                 options.odometry_sigma_theta_per_radian * std::abs(dtheta));
    dataset->odometry.push_back({gt[k].t, gt[k + 1].t, Product(d, offset_cos),
                                 Product(d, offset_sin), dtheta, sigma_xy,
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
  const std::string measured_offset =
      std::isfinite(summary->measured_heading_offset)
          ? Short(summary->measured_heading_offset) + " rad"
          : "not measurable";
  meta.emplace_back(
      "heading_offset",
      "odometry frame = GT heading + " + Short(summary->heading_offset) +
          " rad (" + summary->heading_offset_source +
          "; measured from the GT displacements: " + measured_offset +
          "); ODOM = Pose2(d cos(offset), d sin(offset), dtheta) in the GT "
          "pose frame, PRIOR_POSE and GT_POSE are GT as given");
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
