#include "rff_ceres/convert/g2o.h"

#include <Eigen/LU>
#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include "rff_ceres/convert/pose_graph.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"

namespace rff {
namespace {

// Vertex ids, then numbers, after the record name (FIX: any ids).
struct Layout {
  int ids;
  int numbers;
};

const std::map<std::string_view, Layout>& Layouts() {
  static const auto* const layouts =
      new std::map<std::string_view, Layout>{{"VERTEX_SE2", {1, 3}},
                                             {"VERTEX_XY", {1, 2}},
                                             {"EDGE_SE2", {2, 9}},
                                             {"EDGE_SE2_XY", {2, 5}},
                                             {"EDGE_BEARING_SE2_XY", {2, 2}},
                                             {"EDGE_PRIOR_SE2", {1, 9}}};
  return *layouts;
}

struct Record {
  int line = 0;
  std::string type;
  std::vector<std::int64_t> ids;
  std::vector<double> numbers;
  bool has_time = false;  // VERTEX_SE2 with a "# t=" comment.
  double t = 0.0;
};

// The time in a VERTEX_SE2 comment "t=SECONDS"; other comments are prose.
bool ParseTimeComment(const LineReader& reader, Record* record,
                      std::string* error) {
  std::string_view comment = reader.comment();
  const std::size_t begin = comment.find_first_not_of(" \t\r");
  if (begin == std::string_view::npos) return true;
  comment =
      comment.substr(begin, comment.find_last_not_of(" \t\r") + 1 - begin);
  if (comment.substr(0, 2) != "t=") return true;
  if (!ParseFiniteDouble(comment.substr(2), &record->t)) {
    *error =
        reader.Error("time comment '" + std::string(comment.substr(0, 64)) +
                     "' is not t=SECONDS with a finite number");
    return false;
  }
  record->has_time = true;
  return true;
}

bool ParseRecord(const LineReader& reader,
                 const std::vector<std::string_view>& fields, Record* record,
                 std::string* error) {
  record->line = reader.line_number();
  record->type = std::string(fields[0]);
  Layout layout{static_cast<int>(fields.size()) - 1, 0};
  if (fields[0] != "FIX") {
    const auto it = Layouts().find(fields[0]);
    if (it == Layouts().end()) {
      *error = reader.Error(
          "unknown record '" + std::string(fields[0].substr(0, 64)) +
          "' (g2o 2D here: VERTEX_SE2, VERTEX_XY, EDGE_SE2, EDGE_SE2_XY, "
          "EDGE_BEARING_SE2_XY, EDGE_PRIOR_SE2 and FIX)");
      return false;
    }
    layout = it->second;
  }
  const std::size_t expected = layout.ids + layout.numbers;
  if (fields.size() - 1 != expected || expected == 0) {
    *error =
        reader.Error(record->type + " needs " +
                     (expected == 0 ? "at least 1" : std::to_string(expected)) +
                     " fields, got " + std::to_string(fields.size() - 1));
    return false;
  }
  for (int k = 1; k <= layout.ids; ++k) {
    std::int64_t id;
    if (!ParseNonNegativeInt(fields[k], &id)) {
      *error = reader.Error("field " + std::to_string(k + 1) + " '" +
                            std::string(fields[k].substr(0, 64)) +
                            "' is not a vertex id (a non-negative integer)");
      return false;
    }
    record->ids.push_back(id);
  }
  record->numbers.resize(layout.numbers);
  if (!ParseFiniteDoubles(reader, fields, 1 + layout.ids, layout.numbers,
                          record->numbers.data(), error)) {
    return false;
  }
  return record->type != "VERTEX_SE2" ||
         ParseTimeComment(reader, record, error);
}

// Turns the parsed records into a Dataset.
class G2oReader {
 public:
  G2oReader(const std::string& source, const G2oReadOptions& options,
            Dataset* dataset, G2oReadSummary* summary, std::string* error)
      : source_(source),
        options_(options),
        dataset_(dataset),
        summary_(summary),
        error_(error) {}

  bool Read(const std::vector<Record>& records) {
    for (const Record& r : records) {
      if ((r.type == "VERTEX_SE2" || r.type == "VERTEX_XY") && !AddVertex(r)) {
        return false;
      }
    }
    if (poses_.empty()) {
      *error_ = source_ + ": no VERTEX_SE2 record (no pose)";
      return false;
    }
    if (!TimePoses()) return false;
    std::vector<std::int64_t> fixed;
    for (const Record& r : records) {
      if (r.type == "FIX") {
        for (const std::int64_t id : r.ids) {
          if (!Vertex(r, id, kPose)) return false;
          fixed.push_back(id);
        }
      } else if (r.type != "VERTEX_SE2" && r.type != "VERTEX_XY" &&
                 !ConvertEdge(r)) {
        return false;
      }
    }
    if (dataset_->pose_priors.empty()) {
      if (fixed.empty()) fixed.push_back(poses_.begin()->first);
      for (const std::int64_t id : fixed) {
        const Pose& p = poses_.at(id);
        dataset_->pose_priors.push_back({{p.t, p.x, p.y, WrapAngle(p.theta)},
                                         options_.prior_sigma_xy,
                                         options_.prior_sigma_theta});
      }
      summary_->priors_added = fixed.size();
    }
    summary_->pose_vertices = poses_.size();
    summary_->landmark_vertices = landmarks_.size();
    return true;
  }

 private:
  enum Kind { kPose, kLandmark };
  struct Pose {
    int line;
    double x, y, theta;
    bool has_time;
    double t;
  };

  bool Fail(int line, const std::string& message) {
    *error_ = source_ + ":" + std::to_string(line) + ": " + message;
    return false;
  }

  bool AddVertex(const Record& r) {
    const std::int64_t id = r.ids[0];
    const auto pose = poses_.find(id);
    const auto landmark = landmarks_.find(id);
    if (pose != poses_.end() || landmark != landmarks_.end()) {
      const int first =
          pose != poses_.end() ? pose->second.line : landmark->second;
      return Fail(r.line, "second vertex " + std::to_string(id) +
                              " (first on line " + std::to_string(first) + ")");
    }
    if (r.type == "VERTEX_XY") {
      landmarks_[id] = r.line;
    } else {
      const std::vector<double>& v = r.numbers;
      poses_[id] = {r.line, v[0], v[1], v[2], r.has_time, r.t};
    }
    return true;
  }

  // Gives every pose its time (option, comments or order) and checks that
  // no two share one.
  bool TimePoses() {
    const Pose* timed = nullptr;
    for (const auto& [id, p] : poses_) {
      if (p.has_time) timed = &p;
    }
    const bool from_comments = options_.rate == 0.0 && timed != nullptr;
    summary_->times =
        options_.rate > 0.0
            ? "--rate=" + FormatNumber(options_.rate) + " in vertex id order"
        : from_comments ? "the '# t=' comments"
                        : "the vertex id order, 1 s apart";
    std::map<double, std::int64_t> id_at_time;
    std::size_t k = 0;
    for (auto& [id, p] : poses_) {
      if (from_comments && !p.has_time) {
        return Fail(p.line, "VERTEX_SE2 " + std::to_string(id) +
                                " has no '# t=SECONDS' comment while line " +
                                std::to_string(timed->line) +
                                " has one (--rate=HZ times every vertex by "
                                "its order)");
      }
      if (!from_comments) {
        p.t = options_.rate > 0.0 ? k / options_.rate : k;
      }
      ++k;
      const auto [it, added] = id_at_time.emplace(p.t, id);
      if (!added) {
        return Fail(p.line, "VERTEX_SE2 " + std::to_string(id) +
                                " has the time " + FormatNumber(p.t) +
                                " of VERTEX_SE2 " + std::to_string(it->second));
      }
    }
    return true;
  }

  bool Vertex(const Record& r, std::int64_t id, Kind kind) {
    const bool is_pose = poses_.count(id) > 0;
    const bool is_landmark = landmarks_.count(id) > 0;
    if (!is_pose && !is_landmark) {
      return Fail(r.line, r.type + " refers to vertex " + std::to_string(id) +
                              ", which no VERTEX_SE2 or VERTEX_XY defines");
    }
    if (is_pose != (kind == kPose)) {
      return Fail(r.line, r.type + ": vertex " + std::to_string(id) + " is a " +
                              (is_pose ? "pose" : "landmark") +
                              ", expected a " +
                              (kind == kPose ? "pose" : "landmark"));
    }
    return true;
  }

  bool Sigmas(const Record& r, std::size_t first, int n,
              std::vector<double>* sigmas) {
    std::string why;
    if (!DiagonalSigmas(&r.numbers[first], n, true, sigmas, &why)) {
      return Fail(r.line, r.type + " " + why);
    }
    return true;
  }

  bool ConvertEdge(const Record& r) {
    const std::vector<double>& v = r.numbers;
    if (!Vertex(r, r.ids[0], kPose)) return false;
    const double t0 = poses_.at(r.ids[0]).t;
    std::vector<double> s;
    if (r.type == "EDGE_PRIOR_SE2") {
      if (!Sigmas(r, 3, 3, &s)) return false;
      if (s[0] != s[1]) {
        return Fail(r.line, "EDGE_PRIOR_SE2 x and y information differ (" +
                                FormatNumber(v[3]) + ", " + FormatNumber(v[6]) +
                                "; .rffd PRIOR_POSE has one position sigma)");
      }
      dataset_->pose_priors.push_back(
          {{t0, v[0], v[1], WrapAngle(v[2])}, s[0], s[2]});
      return true;
    }
    if (r.type == "EDGE_SE2") {
      if (!Vertex(r, r.ids[1], kPose) || !Sigmas(r, 3, 3, &s)) return false;
      const double t1 = poses_.at(r.ids[1]).t;
      if (!(t1 > t0)) {
        return Fail(r.line, "EDGE_SE2 " + std::to_string(r.ids[0]) + " -> " +
                                std::to_string(r.ids[1]) +
                                " does not go forward in time (" +
                                FormatNumber(t0) + " -> " + FormatNumber(t1) +
                                "; .rffd ODOM needs t1 > t0)");
      }
      dataset_->odometry.push_back(
          {t0, t1, v[0], v[1], WrapAngle(v[2]), s[0], s[1], s[2]});
      return true;
    }
    if (!Vertex(r, r.ids[1], kLandmark)) return false;
    Observation obs;
    obs.t = t0;
    obs.id = r.ids[1];
    if (r.type == "EDGE_BEARING_SE2_XY") {
      if (!Sigmas(r, 1, 1, &s)) return false;
      obs.type = ObservationType::kBearing;
      obs.bearing = WrapAngle(v[0]);
      obs.sigma_bearing = s[0];
    } else {  // EDGE_SE2_XY.
      Eigen::Matrix2d information;
      information << v[2], v[3], v[3], v[4];
      if (!(v[2] > 0.0 && v[4] > 0.0 && information.determinant() > 0.0)) {
        return Fail(r.line,
                    "EDGE_SE2_XY information is not positive "
                    "definite");
      }
      RelativePosition position;
      position.x = v[0];
      position.y = v[1];
      position.covariance = information.inverse();
      std::string why;
      if (!ToRangeBearing(position, &obs, &why)) {
        return Fail(r.line, "EDGE_SE2_XY " + why);
      }
    }
    dataset_->observations.push_back(obs);
    return true;
  }

  const std::string& source_;
  const G2oReadOptions& options_;
  Dataset* dataset_;
  G2oReadSummary* summary_;
  std::string* error_;
  std::map<std::int64_t, Pose> poses_;     // By id: the time order.
  std::map<std::int64_t, int> landmarks_;  // Id -> line.
};

}  // namespace

bool ParseG2o(std::istream* input, const std::string& source,
              const G2oReadOptions& options, Dataset* dataset,
              G2oReadSummary* summary, std::string* error) {
  *dataset = Dataset();
  *summary = G2oReadSummary();
  if (!CheckNonNegativeOption(options.rate, "rate", error) ||
      !CheckPositiveOption(options.prior_sigma_xy, "prior_sigma_xy", error) ||
      !CheckPositiveOption(options.prior_sigma_theta, "prior_sigma_theta",
                           error)) {
    return false;
  }
  LineReader reader(input, source);
  std::vector<std::string_view> fields;
  std::vector<Record> records;
  while (reader.Next(&fields)) {
    records.emplace_back();
    if (!ParseRecord(reader, fields, &records.back(), error)) return false;
  }
  if (!reader.ok()) {
    *error = reader.error();
    return false;
  }
  G2oReader converter(source, options, dataset, summary, error);
  if (!converter.Read(records)) return false;
  ParseMetadata(reader.leading_comments(), dataset);
  dataset->metadata.emplace_back(
      "g2o", "'" + std::filesystem::path(source).filename().string() +
                 "' read by rff_convert --format=g2o, times from " +
                 summary->times);
  SortRecords(dataset);
  return true;
}

bool ReadG2o(const std::string& path, const G2oReadOptions& options,
             Dataset* dataset, G2oReadSummary* summary, std::string* error) {
  std::ifstream stream;
  if (!OpenForReading(path, &stream, error)) return false;
  return ParseG2o(&stream, path, options, dataset, summary, error);
}

bool WriteG2o(const Dataset& input, std::ostream* output,
              G2oWriteSummary* summary, std::string* error) {
  *summary = G2oWriteSummary();
  // Without the ranges, so that no vertex is written for them alone.
  Dataset dataset = input;
  const auto ranges = std::remove_if(
      dataset.observations.begin(), dataset.observations.end(),
      [](const Observation& o) { return o.type == ObservationType::kRange; });
  summary->ranges_left_out = dataset.observations.end() - ranges;
  dataset.observations.erase(ranges, dataset.observations.end());
  // Starting values: dead reckoning for poses; for landmarks the prior mean,
  // else the first relative position seen, else (0, 0).
  const std::vector<double> times = PoseVertexTimes(dataset);
  const std::vector<TimedPose> poses = DeadReckonedPoses(dataset, times);
  auto index = [&](double t) {
    return std::lower_bound(times.begin(), times.end(), t) - times.begin();
  };
  std::map<LandmarkId, std::pair<double, double>> landmarks;
  for (const Observation& o : dataset.observations) {
    landmarks.emplace(o.id, std::make_pair(0.0, 0.0));
  }
  std::set<LandmarkId> placed;
  for (const LandmarkPrior& p : dataset.landmark_priors) {
    ++summary->landmark_priors_left_out;
    if (landmarks.count(p.id) && placed.insert(p.id).second) {
      landmarks[p.id] = {p.x, p.y};
    }
  }
  // The largest id is compared before the + 1 that would overflow it.
  if (!landmarks.empty() && landmarks.rbegin()->first > INT_MAX) {
    *error = "landmark id " + std::to_string(landmarks.rbegin()->first) +
             " does not fit g2o's vertex ids (int)";
    return false;
  }
  const LandmarkId pose_base =
      landmarks.empty() ? 0 : landmarks.rbegin()->first + 1;
  if (pose_base > INT_MAX - static_cast<LandmarkId>(times.size())) {
    *error = "landmark id " + std::to_string(pose_base - 1) + " and " +
             std::to_string(times.size()) +
             " poses do not fit g2o's vertex ids (int)";
    return false;
  }
  auto n = [](double v) { return FormatNumber(v); };
  auto pose_id = [&](double t) { return pose_base + index(t); };
  std::ostringstream edges;
  for (const PosePrior& p : dataset.pose_priors) {
    edges << "EDGE_PRIOR_SE2 " << pose_id(p.pose.t) << " "
          << JoinNumbers({p.pose.x, p.pose.y, p.pose.theta}) << " "
          << JoinNumbers(DiagonalUpperTriangle(
                 {p.sigma_xy, p.sigma_xy, p.sigma_theta}, true))
          << "\n";
  }
  for (const Odometry& o : dataset.odometry) {
    edges << "EDGE_SE2 " << pose_id(o.t0) << " " << pose_id(o.t1) << " "
          << JoinNumbers({o.dx, o.dy, o.dtheta}) << " "
          << JoinNumbers(DiagonalUpperTriangle(
                 {o.sigma_x, o.sigma_y, o.sigma_theta}, true))
          << "\n";
  }
  for (const Observation& o : dataset.observations) {
    const std::string ids =
        std::to_string(pose_id(o.t)) + " " + std::to_string(o.id) + " ";
    if (o.type == ObservationType::kBearing) {
      edges << "EDGE_BEARING_SE2_XY " << ids
            << JoinNumbers(
                   {o.bearing, 1.0 / (o.sigma_bearing * o.sigma_bearing)})
            << "\n";
    } else if (o.type == ObservationType::kRangeBearing) {
      RelativePosition p;
      if (!ToRelativePosition(o, &p, error)) return false;
      const Eigen::Matrix2d information = p.covariance.inverse();
      edges << "EDGE_SE2_XY " << ids
            << JoinNumbers({p.x, p.y, information(0, 0),
                            information(0, 1) + 0.0,  // Never "-0".
                            information(1, 1)})
            << "\n";
      if (placed.insert(o.id).second) {
        const TimedPose& from = poses[index(o.t)];
        const double c = std::cos(from.theta), s = std::sin(from.theta);
        landmarks[o.id] = {from.x + c * p.x - s * p.y,
                           from.y + s * p.x + c * p.y};
      }
    }
  }
  summary->ground_truth_left_out =
      dataset.ground_truth.size() + dataset.ground_truth_landmarks.size();

  std::ostringstream out;
  for (const auto& [key, value] : dataset.metadata) {
    out << "# " << key << ": " << value << "\n";
  }
  out << "# g2o 2D written by rff_convert; '# t=' after a VERTEX_SE2 is the "
         "pose's time in seconds\n";
  for (std::size_t k = 0; k < times.size(); ++k) {
    out << "VERTEX_SE2 " << pose_base + k << " "
        << JoinNumbers({poses[k].x, poses[k].y, poses[k].theta})
        << " # t=" << n(times[k]) << "\n";
  }
  for (const auto& [id, xy] : landmarks) {
    out << "VERTEX_XY " << id << " " << JoinNumbers({xy.first, xy.second})
        << "\n";
  }
  out << edges.str();
  summary->pose_vertices = times.size();
  summary->landmark_vertices = landmarks.size();
  *output << out.str();
  return true;
}

bool WriteG2o(const Dataset& dataset, const std::string& path,
              G2oWriteSummary* summary, std::string* error) {
  return WriteGraphFile<G2oWriteSummary>(&WriteG2o, &ParseG2o, dataset, path,
                                         summary, error);
}

}  // namespace rff
