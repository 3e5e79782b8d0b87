#include "rff_ceres/io/dataset_io.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/measurement_types.h"

namespace rff {
namespace {

// Numbers of fields after the record name, per record type: an observation
// has t, id, and a value and a sigma per measured quantity.
const std::map<std::string_view, std::size_t>& RecordArity() {
  static const auto* const arity = [] {
    auto* counts = new std::map<std::string_view, std::size_t>{
        {"RFFD", 1}, {"PRIOR_POSE", 6}, {"PRIOR_LANDMARK", 4},
        {"ODOM", 8}, {"GT_POSE", 4},    {"GT_LANDMARK", 3}};
    for (const MeasurementType& m : MeasurementTypes()) {
      (*counts)[m.record] = 2 + 2 * (int{m.range} + int{m.bearing});
    }
    return counts;
  }();
  return *arity;
}

// Why a positive measurement sigma is finer than double precision resolves
// its value (m or rad, at least 1), where its weight only overflows the
// normal equations; empty when it is not.
std::string UnresolvedSigma(double sigma, double value, const char* what,
                            const char* quantity) {
  const double resolution =
      std::numeric_limits<double>::epsilon() * std::max(std::abs(value), 1.0);
  if (sigma >= resolution) return "";
  return std::string(what) + " " + FormatNumber(sigma) +
         " is finer than double precision resolves its " + quantity +
         "; allowed at least " + FormatNumber(resolution);
}

// The same for an ODOM interval, whose length its times must resolve.
std::string UnresolvedInterval(double t0, double t1) {
  const double resolution = std::numeric_limits<double>::epsilon() *
                            std::max({std::abs(t0), std::abs(t1), 1.0});
  if (t1 - t0 >= resolution) return "";
  return "t1 - t0 = " + FormatNumber(t1 - t0) +
         " s is finer than double precision resolves its times; allowed at "
         "least " +
         FormatNumber(resolution);
}

// Why a pose prior, a landmark prior, an odometry record or an observation
// is refused for a sigma (or an interval) finer than double precision
// resolves; empty when it is not. The reader and the writer both ask.
std::string UnresolvedPosePrior(const PosePrior& p) {
  std::string why = UnresolvedSigma(
      p.sigma_xy, std::max(std::abs(p.pose.x), std::abs(p.pose.y)), "sigma_xy",
      "position");
  if (why.empty()) {
    why =
        UnresolvedSigma(p.sigma_theta, p.pose.theta, "sigma_theta", "heading");
  }
  return why;
}
std::string UnresolvedLandmarkPrior(const LandmarkPrior& p) {
  return UnresolvedSigma(p.sigma, std::max(std::abs(p.x), std::abs(p.y)),
                         "sigma", "position");
}
std::string UnresolvedOdometry(const Odometry& o) {
  std::string why = UnresolvedInterval(o.t0, o.t1);
  if (why.empty()) why = UnresolvedSigma(o.sigma_x, o.dx, "sigma_x", "dx");
  if (why.empty()) why = UnresolvedSigma(o.sigma_y, o.dy, "sigma_y", "dy");
  if (why.empty()) {
    why = UnresolvedSigma(o.sigma_theta, o.dtheta, "sigma_theta", "dtheta");
  }
  return why;
}

std::string UnresolvedObservation(const Observation& o) {
  std::string why;
  if (o.HasRange()) {
    why = UnresolvedSigma(o.sigma_range, o.range, "sigma_range", "range");
  }
  if (why.empty() && o.HasBearing()) {
    why =
        UnresolvedSigma(o.sigma_bearing, o.bearing, "sigma_bearing", "bearing");
  }
  return why;
}

// How messages name a record: its keyword and its time, or its id.
std::string RecordName(const PosePrior& p) {
  return "PRIOR_POSE at t = " + FormatNumber(p.pose.t);
}
std::string RecordName(const LandmarkPrior& p) {
  return "PRIOR_LANDMARK " + std::to_string(p.id);
}
std::string RecordName(const Odometry& o) {
  return "ODOM at t = " + FormatNumber(o.t0);
}
std::string RecordName(const Observation& o) {
  return std::string(MeasurementTypeOf(o.type).record) +
         " at t = " + FormatNumber(o.t);
}
std::string RecordName(const TimedPose& p) {
  return "GT_POSE at t = " + FormatNumber(p.t);
}
std::string RecordName(const Landmark& l) {
  return "GT_LANDMARK " + std::to_string(l.id);
}

// The first record the reader would refuse for its sigmas, as
// "RECORD at t = T: why"; empty when there is none.
std::string FirstUnresolvedSigma(const Dataset& dataset) {
  for (const PosePrior& p : dataset.pose_priors) {
    const std::string why = UnresolvedPosePrior(p);
    if (!why.empty()) return RecordName(p) + ": " + why;
  }
  for (const LandmarkPrior& p : dataset.landmark_priors) {
    const std::string why = UnresolvedLandmarkPrior(p);
    if (!why.empty()) return RecordName(p) + ": " + why;
  }
  for (const Odometry& o : dataset.odometry) {
    const std::string why = UnresolvedOdometry(o);
    if (!why.empty()) return RecordName(o) + ": " + why;
  }
  for (const Observation& o : dataset.observations) {
    const std::string why = UnresolvedObservation(o);
    if (!why.empty()) return RecordName(o) + ": " + why;
  }
  return "";
}

// The first record holding a number that is not finite (a converter's sigma
// scaled past the largest double), as "RECORD at t = T"; empty when there is
// none. The reader refuses such a file.
std::string FirstNonFinite(const Dataset& dataset) {
  auto finite = [](std::initializer_list<double> values) {
    return std::all_of(values.begin(), values.end(),
                       [](double v) { return std::isfinite(v); });
  };
  for (const PosePrior& p : dataset.pose_priors) {
    if (!finite({p.pose.t, p.pose.x, p.pose.y, p.pose.theta, p.sigma_xy,
                 p.sigma_theta})) {
      return RecordName(p);
    }
  }
  for (const LandmarkPrior& p : dataset.landmark_priors) {
    if (!finite({p.x, p.y, p.sigma})) return RecordName(p);
  }
  for (const Odometry& o : dataset.odometry) {
    if (!finite({o.t0, o.t1, o.dx, o.dy, o.dtheta, o.sigma_x, o.sigma_y,
                 o.sigma_theta})) {
      return RecordName(o);
    }
  }
  for (const Observation& o : dataset.observations) {
    if (!finite({o.t, o.range, o.bearing, o.sigma_range, o.sigma_bearing})) {
      return RecordName(o);
    }
  }
  for (const TimedPose& p : dataset.ground_truth) {
    if (!finite({p.t, p.x, p.y, p.theta})) return RecordName(p);
  }
  for (const Landmark& l : dataset.ground_truth_landmarks) {
    if (!finite({l.x, l.y})) return RecordName(l);
  }
  return "";
}

// Parses one .rffd record at a time into a Dataset, with every check of the
// format: field counts, finite numbers, positive sigmas, t1 > t0, ids.
class DatasetParser {
 public:
  DatasetParser(LineReader* reader, Dataset* dataset)
      : reader_(*reader), dataset_(dataset) {}

  bool ParseRecord(const std::vector<std::string_view>& fields,
                   std::string* error) {
    error_ = error;
    const std::string_view name = fields[0];
    const auto it = RecordArity().find(name);
    if (it == RecordArity().end()) {
      return Fail("unknown record '" + std::string(name.substr(0, 64)) + "'");
    }
    if (fields.size() - 1 != it->second) {
      return Fail(std::string(name) + " needs " + std::to_string(it->second) +
                  " fields, got " + std::to_string(fields.size() - 1));
    }
    if (!seen_header_ && name != "RFFD") {
      return Fail("missing header: the first record must be 'RFFD 1', got '" +
                  std::string(name) + "'");
    }
    if (name == "RFFD") return ParseHeader(fields);
    // The id, where a record has one, is the field after the time (or the
    // first field for landmark records); everything else is a double.
    if (name == "PRIOR_LANDMARK" || name == "GT_LANDMARK") {
      LandmarkId id;
      if (!ParseId(fields[1], &id)) return false;
      double v[3];
      if (!Numbers(fields, 2, fields.size() - 2, v)) return false;
      return name == "PRIOR_LANDMARK" ? AddLandmarkPrior(id, v)
                                      : AddGroundTruthLandmark(id, v);
    }
    if (const MeasurementType* type = FindMeasurementRecord(name)) {
      double t;
      LandmarkId id;
      double v[4];
      if (!Numbers(fields, 1, 1, &t) || !ParseId(fields[2], &id) ||
          !Numbers(fields, 3, fields.size() - 3, v)) {
        return false;
      }
      return AddObservation(*type, t, id, v);
    }
    double v[8];
    if (!Numbers(fields, 1, fields.size() - 1, v)) return false;
    if (name == "PRIOR_POSE") return AddPosePrior(v);
    if (name == "ODOM") return AddOdometry(v);
    return AddGroundTruthPose(v);  // GT_POSE, the last one left.
  }

  bool seen_header() const { return seen_header_; }

 private:
  bool Fail(const std::string& message) {
    *error_ = reader_.Error(message);
    return false;
  }

  bool Numbers(const std::vector<std::string_view>& fields, std::size_t first,
               std::size_t count, double* values) {
    return ParseFiniteDoubles(reader_, fields, first, count, values, error_);
  }

  bool ParseId(std::string_view field, LandmarkId* id) {
    if (!ParseNonNegativeInt(field, id)) {
      return Fail("landmark id '" + std::string(field.substr(0, 64)) +
                  "' is not a non-negative 64-bit integer");
    }
    return true;
  }

  bool Positive(double sigma, const char* what) {
    if (!(sigma > 0.0)) {
      return Fail(std::string(what) + " must be > 0, got " +
                  FormatNumber(sigma));
    }
    return true;
  }

  bool ParseHeader(const std::vector<std::string_view>& fields) {
    if (seen_header_) return Fail("second RFFD header");
    if (fields[1] != "1") {
      return Fail("unsupported RFFD version '" +
                  std::string(fields[1].substr(0, 64)) + "' (expected 1)");
    }
    seen_header_ = true;
    return true;
  }

  bool AddPosePrior(const double* v) {
    if (!Positive(v[4], "sigma_xy") || !Positive(v[5], "sigma_theta")) {
      return false;
    }
    // Angles are judged as written, before wrapping: 1e300 rad has no
    // digits left for any sigma.
    PosePrior prior{{v[0], v[1], v[2], v[3]}, v[4], v[5]};
    const std::string why = UnresolvedPosePrior(prior);
    if (!why.empty()) return Fail(why);
    prior.pose.theta = WrapAngle(prior.pose.theta);
    dataset_->pose_priors.push_back(prior);
    return true;
  }

  bool AddLandmarkPrior(LandmarkId id, const double* v) {
    if (!Positive(v[2], "sigma")) return false;
    if (!prior_ids_.insert(id).second) {
      return Fail("duplicate PRIOR_LANDMARK for landmark " +
                  std::to_string(id));
    }
    const LandmarkPrior prior{id, v[0], v[1], v[2]};
    const std::string why = UnresolvedLandmarkPrior(prior);
    if (!why.empty()) return Fail(why);
    dataset_->landmark_priors.push_back(prior);
    return true;
  }

  bool AddGroundTruthLandmark(LandmarkId id, const double* v) {
    if (!truth_ids_.insert(id).second) {
      return Fail("duplicate GT_LANDMARK for landmark " + std::to_string(id));
    }
    Landmark landmark;
    landmark.id = id;
    landmark.x = v[0];
    landmark.y = v[1];
    dataset_->ground_truth_landmarks.push_back(landmark);
    return true;
  }

  bool AddOdometry(const double* v) {
    if (!(v[1] > v[0])) {
      return Fail("ODOM needs t1 > t0, got t0 = " + FormatNumber(v[0]) +
                  ", t1 = " + FormatNumber(v[1]));
    }
    if (!Positive(v[5], "sigma_x") || !Positive(v[6], "sigma_y") ||
        !Positive(v[7], "sigma_theta")) {
      return false;
    }
    Odometry odometry{v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]};
    const std::string why = UnresolvedOdometry(odometry);
    if (!why.empty()) return Fail(why);
    odometry.dtheta = WrapAngle(odometry.dtheta);
    dataset_->odometry.push_back(odometry);
    return true;
  }

  // `v`: the measured values, then their sigmas (MeasurementType::record).
  bool AddObservation(const MeasurementType& type, double t, LandmarkId id,
                      const double* v) {
    Observation obs;
    obs.type = type.type;
    obs.t = t;
    obs.id = id;
    const int measured = int{type.range} + int{type.bearing};
    int field = 0;
    if (type.range) {
      obs.range = v[field];
      obs.sigma_range = v[field + measured];
      ++field;
    }
    if (type.bearing) {
      obs.bearing = v[field];
      obs.sigma_bearing = v[field + measured];
    }
    // A noisy range may be negative (a Gaussian measurement of a short
    // distance): it is data, not an error.
    if (obs.HasRange() && !Positive(obs.sigma_range, "sigma_range")) {
      return false;
    }
    if (obs.HasBearing() && !Positive(obs.sigma_bearing, "sigma_bearing")) {
      return false;
    }
    const std::string why = UnresolvedObservation(obs);
    if (!why.empty()) return Fail(why);
    if (obs.HasBearing()) obs.bearing = WrapAngle(obs.bearing);
    dataset_->observations.push_back(obs);
    return true;
  }

  bool AddGroundTruthPose(const double* v) {
    dataset_->ground_truth.push_back({v[0], v[1], v[2], WrapAngle(v[3])});
    return true;
  }

  const LineReader& reader_;
  Dataset* dataset_;
  std::string* error_ = nullptr;
  bool seen_header_ = false;
  std::set<LandmarkId> prior_ids_;
  std::set<LandmarkId> truth_ids_;
};

}  // namespace

void ParseMetadata(const std::vector<std::string>& comments, Dataset* dataset) {
  for (const std::string& comment : comments) {
    const std::size_t colon = comment.find(':');
    if (colon == std::string::npos) continue;  // Prose, not metadata.
    // CR too: a line ending in "\r\r\n" keeps one CR after the reader
    // strips the last, and a value ending in CR would not survive a write.
    auto trim = [](std::string s) {
      const auto begin = s.find_first_not_of(" \t\r");
      if (begin == std::string::npos) return std::string();
      const auto end = s.find_last_not_of(" \t\r");
      return s.substr(begin, end - begin + 1);
    };
    std::string key = trim(comment.substr(0, colon));
    if (key.empty() || key.find_first_of(" \t") != std::string::npos) continue;
    dataset->metadata.emplace_back(key, trim(comment.substr(colon + 1)));
  }
}

void SortRecords(Dataset* dataset) {
  std::stable_sort(
      dataset->observations.begin(), dataset->observations.end(),
      [](const Observation& a, const Observation& b) { return a.t < b.t; });
  std::stable_sort(
      dataset->odometry.begin(), dataset->odometry.end(),
      [](const Odometry& a, const Odometry& b) { return a.t0 < b.t0; });
  std::stable_sort(
      dataset->ground_truth.begin(), dataset->ground_truth.end(),
      [](const TimedPose& a, const TimedPose& b) { return a.t < b.t; });
  std::sort(dataset->landmark_priors.begin(), dataset->landmark_priors.end(),
            [](const LandmarkPrior& a, const LandmarkPrior& b) {
              return a.id < b.id;
            });
  std::sort(dataset->ground_truth_landmarks.begin(),
            dataset->ground_truth_landmarks.end(),
            [](const Landmark& a, const Landmark& b) { return a.id < b.id; });
}

bool ParseDataset(std::istream* input, const std::string& source,
                  Dataset* dataset, std::string* error) {
  *dataset = Dataset();
  LineReader reader(input, source);
  DatasetParser parser(&reader, dataset);
  std::vector<std::string_view> fields;
  while (reader.Next(&fields)) {
    if (!parser.ParseRecord(fields, error)) return false;
  }
  if (!reader.ok()) {
    *error = reader.error();
    return false;
  }
  if (!parser.seen_header()) {
    *error = source + ": missing header: no 'RFFD 1' record (empty file?)";
    return false;
  }
  if (dataset->pose_priors.empty()) {
    *error = source +
             ": no PRIOR_POSE record (every dataset needs one to anchor the "
             "trajectory)";
    return false;
  }
  ParseMetadata(reader.leading_comments(), dataset);

  // Every time is finite, but the solver works with their differences.
  double first = dataset->pose_priors.front().pose.t, last = first;
  auto span = [&](double t) {
    first = std::min(first, t);
    last = std::max(last, t);
  };
  for (const PosePrior& p : dataset->pose_priors) span(p.pose.t);
  for (const Odometry& o : dataset->odometry) span(o.t0), span(o.t1);
  for (const Observation& o : dataset->observations) span(o.t);
  for (const TimedPose& p : dataset->ground_truth) span(p.t);
  if (!std::isfinite(last - first)) {
    *error = source + ": the records' times run from " + FormatNumber(first) +
             " to " + FormatNumber(last) +
             " s, a span beyond double range; allowed times whose "
             "differences are finite";
    return false;
  }

  // Records may come in any order: sort them once here.
  SortRecords(dataset);
  for (std::size_t i = 1; i < dataset->ground_truth.size(); ++i) {
    if (dataset->ground_truth[i].t == dataset->ground_truth[i - 1].t) {
      *error = source + ": two GT_POSE records at time " +
               FormatNumber(dataset->ground_truth[i].t);
      return false;
    }
  }
  return true;
}

bool ReadDataset(const std::string& path, Dataset* dataset,
                 std::string* error) {
  std::ifstream stream;
  if (!OpenForReading(path, &stream, error)) return false;
  return ParseDataset(&stream, path, dataset, error);
}

void WriteDataset(const Dataset& dataset, std::ostream* output) {
  std::ostream& out = *output;
  for (const auto& [key, value] : dataset.metadata) {
    out << "# " << key << ": " << value << "\n";
  }
  out << "RFFD 1\n";
  auto n = [](double v) { return FormatNumber(v); };
  for (const PosePrior& p : dataset.pose_priors) {
    out << "PRIOR_POSE " << n(p.pose.t) << " " << n(p.pose.x) << " "
        << n(p.pose.y) << " " << n(p.pose.theta) << " " << n(p.sigma_xy) << " "
        << n(p.sigma_theta) << "\n";
  }
  for (const LandmarkPrior& p : dataset.landmark_priors) {
    out << "PRIOR_LANDMARK " << p.id << " " << n(p.x) << " " << n(p.y) << " "
        << n(p.sigma) << "\n";
  }
  for (const Odometry& o : dataset.odometry) {
    out << "ODOM " << n(o.t0) << " " << n(o.t1) << " " << n(o.dx) << " "
        << n(o.dy) << " " << n(o.dtheta) << " " << n(o.sigma_x) << " "
        << n(o.sigma_y) << " " << n(o.sigma_theta) << "\n";
  }
  for (const Observation& o : dataset.observations) {
    const MeasurementType& type = MeasurementTypeOf(o.type);
    out << type.record << " " << n(o.t) << " " << o.id;
    if (type.range) out << " " << n(o.range);
    if (type.bearing) out << " " << n(o.bearing);
    if (type.range) out << " " << n(o.sigma_range);
    if (type.bearing) out << " " << n(o.sigma_bearing);
    out << "\n";
  }
  for (const TimedPose& p : dataset.ground_truth) {
    out << "GT_POSE " << n(p.t) << " " << n(p.x) << " " << n(p.y) << " "
        << n(p.theta) << "\n";
  }
  for (const Landmark& l : dataset.ground_truth_landmarks) {
    out << "GT_LANDMARK " << l.id << " " << n(l.x) << " " << n(l.y) << "\n";
  }
}

bool WriteDataset(const Dataset& dataset, const std::string& path,
                  std::string* error) {
  // Never a file the reader refuses: a number scaled past the largest
  // double, or a simulator's sigma given too fine.
  const std::string non_finite = FirstNonFinite(dataset);
  if (!non_finite.empty()) {
    *error = path + ": not written: " + non_finite +
             " holds a number that is not finite (the reader would refuse the "
             "file)";
    return false;
  }
  const std::string unresolved = FirstUnresolvedSigma(dataset);
  if (!unresolved.empty()) {
    *error = path + ": not written: " + unresolved +
             " (the reader would refuse the file)";
    return false;
  }
  return WriteOutputFile(
      path, [&](std::ostream* out) { WriteDataset(dataset, out); }, error);
}

}  // namespace rff
