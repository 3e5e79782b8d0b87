#include "rff_ceres/convert/pyfg.h"

#include <algorithm>
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
#include "rff_ceres/se2.h"

namespace rff {
namespace {

// Fields after the record name: a timestamp or not, vertex names, numbers.
struct Layout {
  bool timestamp;
  int names;
  int numbers;
};

const std::map<std::string_view, Layout>& Layouts() {
  static const auto* const layouts = new std::map<std::string_view, Layout>{
      {"VERTEX_SE2", {true, 1, 3}},       {"VERTEX_XY", {false, 1, 2}},
      {"VERTEX_SE2:PRIOR", {true, 1, 9}}, {"VERTEX_XY:PRIOR", {true, 1, 5}},
      {"EDGE_SE2", {true, 2, 9}},         {"EDGE_SE2_XY", {true, 2, 5}},
      {"EDGE_RANGE", {true, 2, 2}}};
  return *layouts;
}

// "A12": robot 'A', number 12; "L3": landmark 3.
struct VertexName {
  char letter = 0;
  std::int64_t number = 0;
  std::string text;
  bool landmark() const { return letter == 'L'; }
};

bool ParseVertexName(std::string_view text, VertexName* name) {
  if (text.size() < 2 || text[0] < 'A' || text[0] > 'Z') return false;
  name->letter = text[0];
  name->text = std::string(text);
  return ParseNonNegativeInt(text.substr(1), &name->number);
}

struct Record {
  int line = 0;
  std::string type;
  double t = 0.0;
  std::vector<VertexName> names;
  std::vector<double> numbers;
};

bool ParseRecords(std::istream* input, const std::string& source,
                  std::vector<Record>* records, std::string* error) {
  LineReader reader(input, source);
  std::vector<std::string_view> fields;
  while (reader.Next(&fields)) {
    const auto it = Layouts().find(fields[0]);
    if (it == Layouts().end()) {
      *error = reader.Error("unknown record '" +
                            std::string(fields[0].substr(0, 64)) +
                            "' (2D PyFG has VERTEX_SE2, VERTEX_XY, their "
                            ":PRIOR, EDGE_SE2, EDGE_SE2_XY and EDGE_RANGE)");
      return false;
    }
    const Layout& layout = it->second;
    const std::size_t expected =
        layout.timestamp + layout.names + layout.numbers;
    if (fields.size() - 1 != expected) {
      *error = reader.Error(std::string(fields[0]) + " needs " +
                            std::to_string(expected) + " fields, got " +
                            std::to_string(fields.size() - 1));
      return false;
    }
    Record record;
    record.line = reader.line_number();
    record.type = std::string(fields[0]);
    std::size_t next = 1;
    if (layout.timestamp &&
        !ParseFiniteDoubles(reader, fields, next++, 1, &record.t, error)) {
      return false;
    }
    for (int k = 0; k < layout.names; ++k, ++next) {
      VertexName name;
      if (!ParseVertexName(fields[next], &name)) {
        *error = reader.Error(
            "field " + std::to_string(next + 1) + " '" +
            std::string(fields[next].substr(0, 64)) +
            "' is not a vertex name (a pose: one capital letter other than "
            "L and a number, A12; a landmark: L and a number, L3)");
        return false;
      }
      record.names.push_back(name);
    }
    record.numbers.resize(layout.numbers);
    if (!ParseFiniteDoubles(reader, fields, next, layout.numbers,
                            record.numbers.data(), error)) {
      return false;
    }
    records->push_back(std::move(record));
  }
  if (!reader.ok()) {
    *error = reader.error();
    return false;
  }
  if (records->empty()) {
    *error = source + ": no records (empty file?)";
    return false;
  }
  return true;
}

// Turns the parsed records into the Dataset of one robot.
class PyfgReader {
 public:
  PyfgReader(const std::string& source, const PyfgReadOptions& options,
             Dataset* dataset, PyfgReadSummary* summary, std::string* error)
      : source_(source),
        options_(options),
        dataset_(dataset),
        summary_(summary),
        error_(error) {}

  bool Read(const std::vector<Record>& records) {
    if (!CollectVertices(records) || !ChooseRobot()) return false;
    // Vertices first: edges and priors need the times of their poses.
    for (const Record& r : records) {
      if (!Convert(r)) return false;
    }
    if (!ConvertEdges()) return false;
    if (dataset_->pose_priors.empty()) AddPrior();
    summary_->records = records.size();
    return true;
  }

 private:
  bool Fail(int line, const std::string& message) {
    *error_ = source_ + ":" + std::to_string(line) + ": " + message;
    return false;
  }

  bool CollectVertices(const std::vector<Record>& records) {
    for (const Record& r : records) {
      if (r.type != "VERTEX_SE2" && r.type != "VERTEX_XY") continue;
      const VertexName& name = r.names[0];
      const bool want_landmark = r.type == "VERTEX_XY";
      if (name.landmark() != want_landmark) {
        return Fail(r.line, r.type + " " + name.text + ": " +
                                (want_landmark ? "a landmark name is L and "
                                                 "a number"
                                               : "L names landmarks, not "
                                                 "poses"));
      }
      auto& first_line = want_landmark
                             ? landmark_lines_[name.number]
                             : pose_lines_[{name.letter, name.number}];
      if (first_line != 0) {
        return Fail(r.line, "second " + r.type + " " + name.text +
                                " (first on line " +
                                std::to_string(first_line) + ")");
      }
      first_line = r.line;
      if (!want_landmark) robots_.insert(name.letter);
    }
    if (robots_.empty()) {
      *error_ = source_ + ": no VERTEX_SE2 record (no pose)";
      return false;
    }
    return true;
  }

  bool ChooseRobot() {
    std::vector<std::string> names;
    for (const char c : robots_) names.push_back(std::string(1, c));
    summary_->robots = JoinAlternatives(names);
    summary_->num_robots = names.size();
    if (options_.robot.empty() && robots_.size() == 1) {
      robot_ = *robots_.begin();
    } else if (options_.robot.size() == 1 && robots_.count(options_.robot[0])) {
      robot_ = options_.robot[0];
    } else {
      *error_ = OptionError("robot", options_.robot,
                            source_ + " has " + std::to_string(robots_.size()) +
                                (robots_.size() == 1 ? " robot" : " robots") +
                                (options_.robot.empty() ? ": pick one" : ""),
                            summary_->robots);
      return false;
    }
    summary_->robot = std::string(1, robot_);
    return true;
  }

  bool IsRobot(const VertexName& name) const {
    return !name.landmark() && name.letter == robot_;
  }

  // The time of a pose vertex of the robot from its VERTEX_SE2 record; two
  // poses never share one.
  bool SetTime(const Record& r) {
    const VertexName& name = r.names[0];
    const double t = options_.rate > 0.0 ? name.number / options_.rate : r.t;
    const auto [it, added] = pose_at_time_.emplace(t, name.text);
    if (!added) {
      return Fail(r.line, "poses " + it->second + " and " + name.text +
                              " have the same time " + FormatNumber(t));
    }
    time_of_[name.number] = t;
    return true;
  }

  // Checks that `name` is a defined vertex of the wanted kind.
  bool Defined(const Record& r, const VertexName& name, bool landmark) {
    if (name.landmark() != landmark) {
      return Fail(r.line, r.type + " " + name.text + ": expected a " +
                              (landmark ? "landmark (L3)" : "pose (A12)"));
    }
    const bool defined =
        landmark ? landmark_lines_.count(name.number) > 0
                 : pose_lines_.count({name.letter, name.number}) > 0;
    if (!defined) {
      return Fail(r.line, r.type + " refers to " + name.text + ", which no " +
                              (landmark ? "VERTEX_XY" : "VERTEX_SE2") +
                              " defines");
    }
    return true;
  }

  bool Sigmas(const Record& r, std::size_t first, int n,
              std::vector<double>* sigmas) {
    std::string why;
    if (!DiagonalSigmas(&r.numbers[first], n, false, sigmas, &why)) {
      return Fail(r.line, r.type + " " + why);
    }
    return true;
  }

  // The x and y variances of the n x n covariance at `first` are equal.
  bool Isotropic(const Record& r, std::size_t first, int n) {
    const double x = r.numbers[first], y = r.numbers[first + n];
    if (x == y) return true;
    return Fail(r.line, r.type + " x and y variances differ (" +
                            FormatNumber(x) + ", " + FormatNumber(y) +
                            "; .rffd priors have one position sigma)");
  }

  bool Convert(const Record& r) {
    const std::vector<double>& v = r.numbers;
    if (r.type == "VERTEX_XY") {
      Landmark landmark;
      landmark.id = r.names[0].number;
      landmark.x = v[0];
      landmark.y = v[1];
      dataset_->ground_truth_landmarks.push_back(landmark);
      return true;
    }
    if (r.type == "VERTEX_XY:PRIOR") {
      std::vector<double> s;
      if (!Defined(r, r.names[0], true) || !Sigmas(r, 2, 2, &s) ||
          !Isotropic(r, 2, 2)) {
        return false;
      }
      if (!landmark_priors_.insert(r.names[0].number).second) {
        return Fail(r.line, "second VERTEX_XY:PRIOR for " + r.names[0].text);
      }
      dataset_->landmark_priors.push_back(
          {r.names[0].number, v[0], v[1], s[0]});
      return true;
    }
    // Every other record names a pose first.
    if (!Defined(r, r.names[0], false)) return false;
    if (r.type == "VERTEX_SE2") {
      if (!IsRobot(r.names[0])) return Other();
      if (!SetTime(r)) return false;
      dataset_->ground_truth.push_back(
          {time_of_[r.names[0].number], v[0], v[1], WrapAngle(v[2])});
      return true;
    }
    if (r.type == "VERTEX_SE2:PRIOR") {
      if (!IsRobot(r.names[0])) return Other();
      std::vector<double> s;
      if (!Sigmas(r, 3, 3, &s) || !Isotropic(r, 3, 3)) return false;
      priors_.push_back({r.names[0].number, v[0], v[1], v[2], s});
      return true;
    }
    const bool to_landmark = r.type == "EDGE_SE2_XY" ||
                             (r.type == "EDGE_RANGE" && r.names[1].landmark());
    if (!Defined(r, r.names[1], to_landmark)) return false;
    const bool first = IsRobot(r.names[0]);
    const bool second = !to_landmark && IsRobot(r.names[1]);
    if (!to_landmark && first != second) return Inter();
    if (!first) return Other();
    edges_.push_back(&r);
    return true;
  }

  bool Other() {
    ++summary_->other_robot_records;
    return true;
  }
  bool Inter() {
    ++summary_->inter_robot_edges;
    return true;
  }

  // Edges and priors of the robot, now that every pose has its time.
  bool ConvertEdges() {
    for (const Prior& p : priors_) {
      dataset_->pose_priors.push_back(
          {{time_of_.at(p.number), p.x, p.y, WrapAngle(p.theta)},
           p.sigmas[0],
           p.sigmas[2]});
    }
    for (const Record* edge : edges_) {
      if (!ConvertEdge(*edge)) return false;
    }
    return true;
  }

  bool ConvertEdge(const Record& r) {
    const std::vector<double>& v = r.numbers;
    const double t0 = time_of_.at(r.names[0].number);
    if (r.type == "EDGE_SE2") {
      const double t1 = time_of_.at(r.names[1].number);
      if (!(t1 > t0)) {
        return Fail(r.line, "EDGE_SE2 " + r.names[0].text + " -> " +
                                r.names[1].text +
                                " does not go forward in "
                                "time (" +
                                FormatNumber(t0) + " -> " + FormatNumber(t1) +
                                "; .rffd ODOM needs t1 > "
                                "t0)");
      }
      std::vector<double> s;
      if (!Sigmas(r, 3, 3, &s)) return false;
      dataset_->odometry.push_back(
          {t0, t1, v[0], v[1], WrapAngle(v[2]), s[0], s[1], s[2]});
      return true;
    }
    if (r.type == "EDGE_RANGE" && !r.names[1].landmark()) {
      return Fail(r.line, "EDGE_RANGE between two poses of robot " +
                              summary_->robot + " (" + r.names[0].text + ", " +
                              r.names[1].text +
                              "): .rffd ranges go to landmarks");
    }
    Observation obs;
    obs.t = t0;
    obs.id = r.names[1].number;
    if (r.type == "EDGE_RANGE") {
      if (!(v[1] > 0.0)) {
        return Fail(r.line, "EDGE_RANGE variance must be > 0, got " +
                                FormatNumber(v[1]));
      }
      obs.type = ObservationType::kRange;
      obs.range = v[0];
      obs.sigma_range = std::sqrt(v[1]);
    } else {  // EDGE_SE2_XY.
      RelativePosition position;
      position.x = v[0];
      position.y = v[1];
      position.covariance << v[2], v[3], v[3], v[4];
      std::string why;
      if (!ToRangeBearing(position, &obs, &why)) {
        return Fail(r.line, "EDGE_SE2_XY " + why);
      }
    }
    dataset_->observations.push_back(obs);
    return true;
  }

  // A PRIOR_POSE at the robot's first pose, for files without one.
  void AddPrior() {
    const TimedPose& first = *std::min_element(
        dataset_->ground_truth.begin(), dataset_->ground_truth.end(),
        [](const TimedPose& a, const TimedPose& b) { return a.t < b.t; });
    dataset_->pose_priors.push_back(
        {first, options_.prior_sigma_xy, options_.prior_sigma_theta});
    summary_->prior_added = true;
  }

 private:
  struct Prior {
    std::int64_t number;
    double x, y, theta;
    std::vector<double> sigmas;
  };

  const std::string& source_;
  const PyfgReadOptions& options_;
  Dataset* dataset_;
  PyfgReadSummary* summary_;
  std::string* error_;
  std::map<std::pair<char, std::int64_t>, int> pose_lines_;
  std::map<std::int64_t, int> landmark_lines_;
  std::set<char> robots_;
  char robot_ = 0;
  std::map<double, std::string> pose_at_time_;
  std::map<std::int64_t, double> time_of_;  // Pose number -> time.
  std::set<std::int64_t> landmark_priors_;
  std::vector<Prior> priors_;
  std::vector<const Record*> edges_;
};

}  // namespace

bool ParsePyfg(std::istream* input, const std::string& source,
               const PyfgReadOptions& options, Dataset* dataset,
               PyfgReadSummary* summary, std::string* error) {
  *dataset = Dataset();
  *summary = PyfgReadSummary();
  if (!CheckNonNegativeOption(options.rate, "rate", error) ||
      !CheckPositiveOption(options.prior_sigma_xy, "prior_sigma_xy", error) ||
      !CheckPositiveOption(options.prior_sigma_theta, "prior_sigma_theta",
                           error)) {
    return false;
  }
  std::vector<Record> records;
  if (!ParseRecords(input, source, &records, error)) return false;
  PyfgReader reader(source, options, dataset, summary, error);
  if (!reader.Read(records)) return false;
  dataset->metadata = {
      {"source", "PyFG file '" +
                     std::filesystem::path(source).filename().string() +
                     "', robot " + summary->robot},
      {"converter",
       "rff_convert --format=pyfg --robot=" + summary->robot +
           (options.rate > 0.0 ? " --rate=" + FormatNumber(options.rate)
                               : "")}};
  SortRecords(dataset);
  return true;
}

bool ReadPyfg(const std::string& path, const PyfgReadOptions& options,
              Dataset* dataset, PyfgReadSummary* summary, std::string* error) {
  std::ifstream stream;
  if (!OpenForReading(path, &stream, error)) return false;
  return ParsePyfg(&stream, path, options, dataset, summary, error);
}

namespace {

// "A12" for the pose at vertex index 12; "L3" for landmark 3.
std::string PoseName(std::size_t index) { return "A" + std::to_string(index); }
std::string LandmarkName(LandmarkId id) { return "L" + std::to_string(id); }

// Pose vertex values: ground truth at the time (a GT_POSE row or
// interpolated between two), else dead reckoning, counted in `summary`.
std::vector<TimedPose> PoseValues(const Dataset& dataset,
                                  const std::vector<double>& times,
                                  PyfgWriteSummary* summary) {
  const std::vector<TimedPose>& truth = dataset.ground_truth;
  std::vector<TimedPose> reckoned;
  std::vector<TimedPose> values;
  for (std::size_t k = 0; k < times.size(); ++k) {
    const double t = times[k];
    if (!truth.empty() && t >= truth.front().t && t <= truth.back().t) {
      const auto row = std::lower_bound(
          truth.begin(), truth.end(), t,
          [](const TimedPose& p, double time) { return p.t < time; });
      ++(row->t == t ? summary->poses_from_truth : summary->poses_interpolated);
      values.push_back(PoseAtTime(truth, t));
      continue;
    }
    if (reckoned.empty()) reckoned = DeadReckonedPoses(dataset, times);
    ++summary->poses_dead_reckoned;
    values.push_back(reckoned[k]);
  }
  return values;
}

// Landmark vertex values: GT_LANDMARK, else the prior mean, else (0, 0).
std::map<LandmarkId, std::pair<double, double>> LandmarkValues(
    const Dataset& dataset, PyfgWriteSummary* summary) {
  std::map<LandmarkId, std::pair<double, double>> values;
  for (const Landmark& l : dataset.ground_truth_landmarks) {
    values[l.id] = {l.x, l.y};
  }
  const std::size_t with_truth = values.size();
  for (const LandmarkPrior& p : dataset.landmark_priors) {
    values.emplace(p.id, std::make_pair(p.x, p.y));
  }
  for (const Observation& o : dataset.observations) {
    values.emplace(o.id, std::make_pair(0.0, 0.0));
  }
  summary->landmarks_without_truth = values.size() - with_truth;
  return values;
}

}  // namespace

bool WritePyfg(const Dataset& dataset, std::ostream* output,
               PyfgWriteSummary* summary, std::string* error) {
  *summary = PyfgWriteSummary();
  const std::vector<double> times = PoseVertexTimes(dataset);
  auto pose = [&](double t) {
    return PoseName(std::lower_bound(times.begin(), times.end(), t) -
                    times.begin());
  };
  auto n = [](double v) { return FormatNumber(v); };
  std::ostringstream out;
  // VERTEX_SE2 first: PyFactorGraph tells 2D from 3D by the first line.
  const std::vector<TimedPose> values = PoseValues(dataset, times, summary);
  for (std::size_t k = 0; k < times.size(); ++k) {
    out << "VERTEX_SE2 " << n(times[k]) << " " << PoseName(k) << " "
        << JoinNumbers({values[k].x, values[k].y, values[k].theta}) << "\n";
  }
  const auto landmarks = LandmarkValues(dataset, summary);
  for (const auto& [id, xy] : landmarks) {
    out << "VERTEX_XY " << LandmarkName(id) << " "
        << JoinNumbers({xy.first, xy.second}) << "\n";
  }
  for (const PosePrior& p : dataset.pose_priors) {
    out << "VERTEX_SE2:PRIOR " << n(p.pose.t) << " " << pose(p.pose.t) << " "
        << JoinNumbers({p.pose.x, p.pose.y, p.pose.theta}) << " "
        << JoinNumbers(DiagonalUpperTriangle(
               {p.sigma_xy, p.sigma_xy, p.sigma_theta}, false))
        << "\n";
  }
  for (const LandmarkPrior& p : dataset.landmark_priors) {
    out << "VERTEX_XY:PRIOR " << n(times.front()) << " " << LandmarkName(p.id)
        << " " << JoinNumbers({p.x, p.y}) << " "
        << JoinNumbers(DiagonalUpperTriangle({p.sigma, p.sigma}, false))
        << "\n";
  }
  std::set<double> odometry_times;
  for (const Odometry& o : dataset.odometry) {
    odometry_times.insert({o.t0, o.t1});
    out << "EDGE_SE2 " << n(o.t1) << " " << pose(o.t0) << " " << pose(o.t1)
        << " " << JoinNumbers({o.dx, o.dy, o.dtheta}) << " "
        << JoinNumbers(DiagonalUpperTriangle(
               {o.sigma_x, o.sigma_y, o.sigma_theta}, false))
        << "\n";
  }
  if (!dataset.odometry.empty()) {
    summary->poses_without_odometry = times.size() - odometry_times.size();
  }
  for (const Observation& o : dataset.observations) {
    const std::string edge =
        " " + n(o.t) + " " + pose(o.t) + " " + LandmarkName(o.id) + " ";
    if (o.type == ObservationType::kRange) {
      out << "EDGE_RANGE" << edge
          << JoinNumbers({o.range, o.sigma_range * o.sigma_range}) << "\n";
    } else if (o.type == ObservationType::kRangeBearing) {
      RelativePosition p;
      if (!ToRelativePosition(o, &p, error)) return false;
      const Eigen::Matrix2d& c = p.covariance;
      // + 0: a cross term of -0 is written as 0.
      out << "EDGE_SE2_XY" << edge
          << JoinNumbers({p.x, p.y, c(0, 0), c(0, 1) + 0.0, c(1, 1)}) << "\n";
    } else {
      ++summary->bearings_left_out;
    }
  }
  summary->pose_vertices = times.size();
  summary->landmark_vertices = landmarks.size();
  *output << out.str();
  return true;
}

bool WritePyfg(const Dataset& dataset, const std::string& path,
               PyfgWriteSummary* summary, std::string* error) {
  return WriteGraphFile<PyfgWriteSummary>(&WritePyfg, &ParsePyfg, dataset, path,
                                          summary, error);
}

}  // namespace rff
