// rffslam: rff-slam for Python. Reads .rffd datasets, solves them with
// rff_slam's options (its flag names as keywords) and evaluates the result,
// with numpy arrays (float64) and plain Python types. Errors are exceptions,
// never an exit of the interpreter: ValueError for a bad option, file,
// query or path, RuntimeError for a solve that fails, KeyboardInterrupt for
// Ctrl-C during a solve.
#include <atomic>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "apps/slam_flags.h"
#include "gflags/gflags.h"
#include "glog/logging.h"
#include "pybind11/numpy.h"
#include "pybind11/pybind11.h"
#include "python/solve_options.h"
#include "rff_ceres/consistency.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/landmarks_io.h"
#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/pose_covariance_io.h"
#include "rff_ceres/io/tum_io.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/slam_report.h"
#include "rff_ceres/slam_solver.h"

namespace py = pybind11;

namespace rff {
namespace {

using Array = py::array_t<double>;

// A dataset as read; results solved from it name its path in messages.
struct PyDataset {
  std::shared_ptr<const Dataset> data;
  std::string path;  // Empty when not read from a file.
};

struct PyResult {
  SlamResult slam;
  // At the trajectory's times; empty when solved without covariance.
  std::vector<PoseCovariance> covariances;
  std::string summary_json;  // WriteSummaryJson, as --summary_json has it.
  std::string source;        // The dataset's path.
};

// rff_slam's own flags, which name its files rather than solver settings,
// and what stands for each here.
const std::map<std::string, std::string>& ToolFlags() {
  static const auto* flags = new std::map<std::string, std::string>{
      {"dataset", "pass the dataset or its path as the first argument"},
      {"output_trajectory", "use Result.save_tum(path)"},
      {"output_landmarks", "use Result.save_landmarks(path)"},
      {"output_covariance",
       "pass compute_covariance=True, then Result.save_covariance(path)"},
      {"summary_json", "use Result.summary"},
      {"evaluate", "use rffslam.evaluate(dataset, result)"},
      {"fail_on_suspect", "check Result.summary['quality']"},
  };
  return *flags;
}

std::string PathOf(py::handle path) {
  // str, bytes or os.PathLike, as open() takes them (TypeError otherwise),
  // as the bytes the system sees (a name that is no UTF-8 too).
  const std::string bytes =
      py::bytes(py::module_::import("os").attr("fsencode")(path));
  // As open(): the C library would stop at a NUL and read another file.
  if (bytes.find('\0') != std::string::npos) {
    throw py::value_error("embedded null byte in path");
  }
  if (bytes.empty()) throw py::value_error("empty path");
  return bytes;
}

// Text of a file (a path, a comment) for Python: undecodable bytes as
// os.fsdecode gives them back, never an error on reading an attribute.
py::str TextOf(const std::string& bytes) {
  return py::module_::import("os").attr("fsdecode")(py::bytes(bytes));
}

Array Zeros(std::vector<py::ssize_t> shape) {
  Array array(shape);
  std::fill(array.mutable_data(), array.mutable_data() + array.size(), 0.0);
  return array;
}

Array Times(const std::vector<TimedPose>& poses) {
  Array times({static_cast<py::ssize_t>(poses.size())});
  auto t = times.mutable_unchecked<1>();
  for (std::size_t i = 0; i < poses.size(); ++i) t(i) = poses[i].t;
  return times;
}

Array Poses(const std::vector<TimedPose>& poses) {
  Array array({static_cast<py::ssize_t>(poses.size()), py::ssize_t{3}});
  auto a = array.mutable_unchecked<2>();
  for (std::size_t i = 0; i < poses.size(); ++i) {
    a(i, 0) = poses[i].x;
    a(i, 1) = poses[i].y;
    a(i, 2) = poses[i].theta;
  }
  return array;
}

template <typename T>
py::array_t<std::int64_t> Ids(const std::vector<T>& items) {
  py::array_t<std::int64_t> ids({static_cast<py::ssize_t>(items.size())});
  auto a = ids.mutable_unchecked<1>();
  for (std::size_t i = 0; i < items.size(); ++i) a(i) = items[i].id;
  return ids;
}

template <typename T>
Array Positions(const std::vector<T>& items) {
  Array array({static_cast<py::ssize_t>(items.size()), py::ssize_t{2}});
  auto a = array.mutable_unchecked<2>();
  for (std::size_t i = 0; i < items.size(); ++i) {
    a(i, 0) = items[i].x;
    a(i, 1) = items[i].y;
  }
  return array;
}

py::object ParseJson(const std::string& text) {
  return py::module_::import("json").attr("loads")(text);
}

PyDataset ReadPyDataset(const std::string& path) {
  auto dataset = std::make_shared<Dataset>();
  std::string error;
  bool read;
  {
    py::gil_scoped_release release;
    read = ReadDataset(path, dataset.get(), &error);
  }
  if (!read) throw py::value_error(error);
  return {std::move(dataset), path};
}

PyDataset DatasetOf(py::handle dataset_or_path) {
  if (py::isinstance<PyDataset>(dataset_or_path)) {
    return dataset_or_path.cast<PyDataset>();
  }
  return ReadPyDataset(PathOf(dataset_or_path));
}

// numpy scalars and 0-d arrays as the Python values they hold; a larger
// array is no option value.
py::object SingleValue(const std::string& name, py::object v) {
  if (!py::hasattr(v, "dtype") || !py::hasattr(v, "item")) return v;
  if (py::hasattr(v, "ndim") && v.attr("ndim").cast<int>() != 0) {
    throw py::value_error("option '" + name +
                          "' must be a single value, got an array of shape " +
                          std::string(py::str(v.attr("shape"))));
  }
  return v.attr("item")();
}

// A keyword's value as rff_slam's command line would spell it.
std::string OptionText(const std::string& name, py::handle value) {
  const py::object v =
      SingleValue(name, py::reinterpret_borrow<py::object>(value));
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::int_>(v)) return py::str(v);
  if (py::isinstance<py::float_>(v)) return py::repr(v);  // Round-trips.
  if (py::isinstance<py::str>(v)) {
    const std::string text = v.cast<std::string>();
    // gflags would read the value up to the NUL.
    if (text.find('\0') != std::string::npos) {
      throw py::value_error("option '" + name + "' holds a NUL character");
    }
    return text;
  }
  if (name == "flagfile" && py::hasattr(v, "__fspath__")) return PathOf(v);
  throw py::value_error("option '" + name +
                        "' must be a bool, int, float or str, got " +
                        std::string(py::str(v.get_type().attr("__name__"))));
}

bool BoolOption(const std::string& name, py::handle value) {
  const py::object v =
      SingleValue(name, py::reinterpret_borrow<py::object>(value));
  if (!py::isinstance<py::bool_>(v)) {
    throw py::value_error("option '" + name + "' must be True or False");
  }
  return v.cast<bool>();
}

PyResult Solve(py::handle dataset_or_path, const py::kwargs& kwargs) {
  std::vector<Setting> settings;
  bool compute_covariance = false;
  bool verbose = false;
  std::string error;
  for (const auto& [key, value] : kwargs) {
    const std::string name = py::str(key);
    if (name.find('\0') != std::string::npos) {
      throw py::value_error("an option name holds a NUL character");
    }
    if (name == "compute_covariance") {
      compute_covariance = BoolOption(name, value);
    } else if (name == "verbose") {
      verbose = BoolOption(name, value);
    } else if (ToolFlags().count(name)) {
      throw py::value_error("option '" + name +
                            "' is a file flag of the rff_slam command line, "
                            "not a solver option: " +
                            ToolFlags().at(name));
    } else if (!CheckOptionName(name, &error)) {
      throw py::value_error(error);
    } else {
      settings.emplace_back(name, OptionText(name, value));
    }
  }
  // rff_slam's order: the options are checked before the dataset is read.
  SlamOptions options;
  if (!SlamOptionsFromSettings(settings, &options, &error)) {
    throw py::value_error(error);
  }
  options.output.covariance = compute_covariance;
  options.solver.log_progress = verbose;
  if (!ValidateSlamOptions(options, &error)) throw py::value_error(error);
  const PyDataset dataset = DatasetOf(dataset_or_path);

  // Python runs its SIGINT handler only when asked, in the main thread and
  // with the GIL: there each Ceres iteration asks, and a KeyboardInterrupt
  // stops the solve and is raised again once RunSlam has returned. (Other
  // threads get no signals; their solves never wait for the GIL.)
  std::atomic<bool> interrupted{false};
  PyObject* type = nullptr;
  PyObject* value = nullptr;
  PyObject* trace = nullptr;
  const py::module_ threading = py::module_::import("threading");
  if (threading.attr("current_thread")().is(threading.attr("main_thread")())) {
    options.solver.should_abort = [&]() {
      if (interrupted) return true;
      py::gil_scoped_acquire gil;
      if (PyErr_CheckSignals() != 0) {
        PyErr_Fetch(&type, &value, &trace);
        interrupted = true;
      }
      return interrupted.load();
    };
  }
  PyResult result;
  result.source = dataset.path;
  bool solved;
  {
    py::gil_scoped_release release;
    solved = RunSlam(*dataset.data, options, &result.slam, &error);
  }
  options.solver.should_abort = nullptr;
  if (interrupted) {
    PyErr_Restore(type, value, trace);
    throw py::error_already_set();
  }
  // A Ctrl-C outside Ceres's iterations (reading, learning, covariance).
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  if (!solved) {
    throw std::runtime_error(
        dataset.path.empty() ? error : dataset.path + ": " + error);
  }
  std::ostringstream summary;
  WriteSummaryJson(options, result.slam, &summary);
  result.summary_json = summary.str();
  if (options.output.covariance) {
    const SlamResult& slam = result.slam;
    if (slam.pose_covariances.size() != slam.trajectory.size()) {
      throw std::runtime_error(
          "the solve returned " + std::to_string(slam.pose_covariances.size()) +
          " covariances for " + std::to_string(slam.trajectory.size()) +
          " poses");
    }
    for (std::size_t i = 0; i < slam.trajectory.size(); ++i) {
      result.covariances.push_back(
          {slam.trajectory[i].t, slam.pose_covariances[i]});
    }
  }
  return result;
}

// Query times: a number (scalar = true) or a 1-D array of finite numbers.
std::vector<double> QueryTimes(py::handle t, bool* scalar) {
  // Real numbers only: a cast would read '0.5', True, 1+2j or a datetime.
  const py::array given = py::module_::import("numpy").attr("asarray")(t);
  const char kind = given.dtype().kind();
  if (kind != 'i' && kind != 'u' && kind != 'f') {
    throw py::value_error("times must be real numbers, got " +
                          std::string(py::str(given.dtype().attr("name"))) +
                          " values");
  }
  const auto array =
      py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(
          given);
  if (!array || array.ndim() > 1) {
    throw py::value_error("times must be a number or a 1-D array of numbers");
  }
  *scalar = array.ndim() == 0;
  std::vector<double> times(array.data(), array.data() + array.size());
  for (const double time : times) {
    if (!std::isfinite(time)) {
      throw py::value_error("times must be finite, got " +
                            std::to_string(time));
    }
  }
  return times;
}

// The poses at `times`, ValueError naming the times outside the span.
std::vector<TimedPose> PosesAt(const PyResult& result,
                               const std::vector<double>& times) {
  std::vector<TimedPose> poses;
  std::string error;
  if (!InterpolateTrajectory(result.slam.trajectory, times, &poses, &error)) {
    throw py::value_error(error);
  }
  return poses;
}

py::object PoseAt(const PyResult& result, py::handle t) {
  bool scalar;
  const std::vector<TimedPose> poses = PosesAt(result, QueryTimes(t, &scalar));
  Array array = Poses(poses);
  if (scalar) return array.attr("reshape")(3);
  return std::move(array);
}

void RequireCovariance(const PyResult& result) {
  if (result.covariances.empty()) {
    throw py::value_error(
        "this result has no covariance: solve with compute_covariance=True");
  }
}

py::object PoseCovarianceAt(const PyResult& result, py::handle t) {
  RequireCovariance(result);
  bool scalar;
  const std::vector<double> times = QueryTimes(t, &scalar);
  PosesAt(result, times);  // The span check, with its message.
  Array array = Zeros({static_cast<py::ssize_t>(times.size()), 3, 3});
  auto a = array.mutable_unchecked<3>();
  for (std::size_t i = 0; i < times.size(); ++i) {
    const Eigen::Matrix3d covariance =
        CovarianceAt(result.covariances, times[i]);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) a(i, r, c) = covariance(r, c);
    }
  }
  if (scalar) return array.attr("reshape")(3, 3);
  return std::move(array);
}

// Writes with the tools' writers, after their check that the path is not
// the dataset the result came from.
void Save(const PyResult& result, const std::string& path,
          const std::function<bool(std::string*)>& write) {
  std::string error;
  if (!CheckOutputPaths({{"dataset", result.source}}, {{"path", path}},
                        &error) ||
      !write(&error)) {
    throw py::value_error(error);
  }
}

py::dict EvaluatePy(py::handle dataset_or_path, const PyResult& result,
                    py::handle align_option) {
  const bool align = BoolOption("align", align_option);
  const PyDataset dataset = DatasetOf(dataset_or_path);
  const Dataset& data = *dataset.data;
  const std::string prefix = dataset.path.empty() ? "" : dataset.path + ": ";
  if (data.ground_truth.empty()) {
    throw py::value_error(prefix +
                          "no GT_POSE record, nothing to evaluate against");
  }
  EvaluationOptions options;
  options.align = align;
  Evaluation evaluation;
  std::string error;
  if (!Evaluate(data.ground_truth, data.ground_truth_landmarks,
                result.slam.trajectory, &result.slam.landmarks, options,
                &evaluation, &error) ||
      (!result.covariances.empty() &&
       !EvaluateConsistency(data.ground_truth, result.slam.trajectory,
                            result.covariances, &evaluation, &error))) {
    throw py::value_error(prefix + error);
  }
  std::ostringstream json;
  WriteEvaluationJson(evaluation, {}, &json);
  return ParseJson(json.str());
}

// The solver options: name -> {"type", "default", "help"}.
py::dict Options() {
  std::vector<gflags::CommandLineFlagInfo> flags;
  gflags::GetAllFlags(&flags);
  py::dict options;
  for (const gflags::CommandLineFlagInfo& flag : flags) {
    if (!IsSlamFlag(flag.name)) continue;
    py::dict info;
    info["type"] = flag.type;
    info["default"] = flag.default_value;
    info["help"] = flag.description;
    options[py::str(flag.name)] = info;
  }
  return options;
}

std::string DatasetRepr(const PyDataset& d) {
  const Dataset& data = *d.data;
  return "<rffslam.Dataset" + (d.path.empty() ? "" : " '" + d.path + "'") +
         ": " + std::to_string(data.observations.size()) + " observations, " +
         std::to_string(data.odometry.size()) + " odometry, " +
         std::to_string(data.ground_truth.size()) + " ground-truth poses>";
}

std::string ResultRepr(const PyResult& r) {
  const std::vector<TimedPose>& trajectory = r.slam.trajectory;
  std::string span;
  if (!trajectory.empty()) {
    span = " over [" + std::to_string(trajectory.front().t) + ", " +
           std::to_string(trajectory.back().t) + "] s";
  }
  return "<rffslam.Result: " + std::to_string(trajectory.size()) + " poses" +
         span + ", " + std::to_string(r.slam.landmarks.size()) +
         " landmarks, quality " + r.slam.quality.verdict +
         (r.covariances.empty() ? "" : ", with covariance") + ">";
}

}  // namespace
}  // namespace rff

PYBIND11_MODULE(rffslam, m) {
  using rff::PyDataset;
  using rff::PyResult;
  // Every array needs numpy: say so at import, not at the first array.
  try {
    py::module_::import("numpy");
  } catch (const py::error_already_set&) {
    const std::string python =
        py::str(py::module_::import("sys").attr("executable"));
    throw py::import_error(
        "rffslam needs numpy, which " + python +
        " lacks: run /usr/bin/python3 (Debian's python3-numpy), or install "
        "numpy for this interpreter");
  }
  // glog as rff_slam sets it up, to stderr; left alone when the process
  // (another module) has set it up already, which a second call would abort.
  if (!google::IsGoogleLoggingInitialized()) {
    FLAGS_logtostderr = true;
    google::InitGoogleLogging("rffslam");
  }
  m.doc() =
      "rff-slam: continuous-time 2D SLAM with Gaussian-process trajectory "
      "priors.\n\n"
      "read_dataset(path) -> Dataset; solve(dataset_or_path, **options) -> "
      "Result;\nevaluate(dataset_or_path, result, align=False) -> dict; "
      "options() -> dict.\nArrays are numpy float64 (ids int64). Bad "
      "options, files, queries and paths\nraise ValueError, a failed solve "
      "RuntimeError.";
  m.attr("__version__") = RFF_VERSION;

  py::class_<PyDataset>(m, "Dataset",
                        "A .rffd dataset as read by read_dataset().")
      .def_property_readonly(
          "path",
          [](const PyDataset& d) -> py::object {
            if (d.path.empty()) return py::none();
            return rff::TextOf(d.path);
          },
          "The file it was read from.")
      .def_property_readonly(
          "metadata",
          [](const PyDataset& d) {
            py::dict metadata;
            for (const auto& [key, value] : d.data->metadata) {
              metadata[rff::TextOf(key)] = rff::TextOf(value);
            }
            return metadata;
          },
          "The '# key: value' header comments, as a dict.")
      .def_property_readonly(
          "num_observations",
          [](const PyDataset& d) { return d.data->observations.size(); })
      .def_property_readonly(
          "num_odometry",
          [](const PyDataset& d) { return d.data->odometry.size(); })
      .def_property_readonly(
          "observation_times",
          [](const PyDataset& d) {
            rff::Array times(
                {static_cast<py::ssize_t>(d.data->observations.size())});
            auto t = times.mutable_unchecked<1>();
            for (std::size_t i = 0; i < d.data->observations.size(); ++i) {
              t(i) = d.data->observations[i].t;
            }
            return times;
          },
          "(O,) times of the RANGE/BEARING/RANGE_BEARING records, sorted.")
      .def_property_readonly(
          "ground_truth_times",
          [](const PyDataset& d) { return rff::Times(d.data->ground_truth); },
          "(G,) times of the GT_POSE records.")
      .def_property_readonly(
          "ground_truth_poses",
          [](const PyDataset& d) { return rff::Poses(d.data->ground_truth); },
          "(G, 3) x, y, theta of the GT_POSE records.")
      .def_property_readonly(
          "ground_truth_landmark_ids",
          [](const PyDataset& d) {
            return rff::Ids(d.data->ground_truth_landmarks);
          },
          "(K,) ids of the GT_LANDMARK records.")
      .def_property_readonly(
          "ground_truth_landmarks",
          [](const PyDataset& d) {
            return rff::Positions(d.data->ground_truth_landmarks);
          },
          "(K, 2) x, y of the GT_LANDMARK records.")
      .def_property_readonly(
          "landmark_prior_ids",
          [](const PyDataset& d) { return rff::Ids(d.data->landmark_priors); },
          "(P,) ids of the PRIOR_LANDMARK records.")
      .def_property_readonly(
          "landmark_priors",
          [](const PyDataset& d) {
            return rff::Positions(d.data->landmark_priors);
          },
          "(P, 2) x, y of the PRIOR_LANDMARK records.")
      .def("__repr__", &rff::DatasetRepr);

  py::class_<PyResult>(m, "Result", "The outcome of solve().")
      .def_property_readonly(
          "times",
          [](const PyResult& r) { return rff::Times(r.slam.trajectory); },
          "(N,) output times: every distinct observation and ground-truth "
          "time.")
      .def_property_readonly(
          "poses",
          [](const PyResult& r) { return rff::Poses(r.slam.trajectory); },
          "(N, 3) x, y, theta at `times` (theta wrapped to (-pi, pi]).")
      .def_property_readonly(
          "landmark_ids",
          [](const PyResult& r) { return rff::Ids(r.slam.landmarks); },
          "(L,) int64 landmark ids, sorted.")
      .def_property_readonly(
          "landmarks",
          [](const PyResult& r) { return rff::Positions(r.slam.landmarks); },
          "(L, 2) x, y of the landmarks of `landmark_ids`.")
      .def_property_readonly(
          "summary",
          [](const PyResult& r) { return rff::ParseJson(r.summary_json); },
          "The solve's summary: the dict rff_slam --summary_json writes.")
      .def_property_readonly(
          "has_covariance",
          [](const PyResult& r) { return !r.covariances.empty(); },
          "Whether the solve computed covariances (compute_covariance=True).")
      .def_property_readonly(
          "pose_covariances",
          [](const PyResult& r) -> py::object {
            if (r.covariances.empty()) return py::none();
            const auto n = static_cast<py::ssize_t>(r.covariances.size());
            return rff::PoseCovarianceAt(r, rff::Times(r.slam.trajectory))
                .attr("reshape")(n, 3, 3);
          },
          "(N, 3, 3) covariance of (x, y, theta) at `times`, or None.")
      .def_property_readonly(
          "landmark_covariances",
          [](const PyResult& r) -> py::object {
            if (r.covariances.empty()) return py::none();
            const std::vector<rff::Landmark>& landmarks = r.slam.landmarks;
            rff::Array array =
                rff::Zeros({static_cast<py::ssize_t>(landmarks.size()), 2, 2});
            auto a = array.mutable_unchecked<3>();
            for (std::size_t i = 0; i < landmarks.size(); ++i) {
              a(i, 0, 0) = landmarks[i].sxx;
              a(i, 0, 1) = a(i, 1, 0) = landmarks[i].sxy;
              a(i, 1, 1) = landmarks[i].syy;
            }
            return std::move(array);
          },
          "(L, 2, 2) covariance of each landmark's position, or None.")
      .def("pose_at", &rff::PoseAt, py::arg("t"),
           "Pose (x, y, theta) at time t: (3,) for a number, (M, 3) for M "
           "times.\n\n"
           "The library keeps no trajectory model after the solve: between "
           "output times\nthe poses are interpolated, linearly in x and y, "
           "along the shorter arc in\ntheta (as rff_evaluate does). At an "
           "output time it is that pose exactly.\nTimes outside "
           "[times[0], times[-1]] (1e-6 s tolerance) raise ValueError.")
      .def("pose_covariance_at", &rff::PoseCovarianceAt, py::arg("t"),
           "Covariance of (x, y, theta) at time t: (3, 3) or (M, 3, 3).\n\n"
           "Needs solve(..., compute_covariance=True), else ValueError. "
           "Between output\ntimes it is interpolated linearly element by "
           "element (as rff_evaluate's\nconsistency check does); at an output "
           "time it is that pose's exactly.")
      .def(
          "save_tum",
          [](const PyResult& r, py::handle path) {
            const std::string file = rff::PathOf(path);
            rff::Save(r, file, [&](std::string* error) {
              return rff::WriteTum(r.slam.trajectory, file, error);
            });
          },
          py::arg("path"),
          "Writes the trajectory as TUM (rff_slam --output_trajectory).")
      .def(
          "save_landmarks",
          [](const PyResult& r, py::handle path) {
            const std::string file = rff::PathOf(path);
            rff::Save(r, file, [&](std::string* error) {
              return rff::WriteLandmarks(r.slam.landmarks, file, error);
            });
          },
          py::arg("path"),
          "Writes the landmarks (rff_slam --output_landmarks), with their "
          "covariance\nwhen the solve computed it.")
      .def(
          "save_covariance",
          [](const PyResult& r, py::handle path) {
            rff::RequireCovariance(r);
            const std::string file = rff::PathOf(path);
            rff::Save(r, file, [&](std::string* error) {
              return rff::WritePoseCovariances(r.covariances, file, error);
            });
          },
          py::arg("path"),
          "Writes the pose covariances (rff_slam --output_covariance).")
      .def("__repr__", &rff::ResultRepr);

  m.def(
      "read_dataset",
      [](py::handle path) { return rff::ReadPyDataset(rff::PathOf(path)); },
      py::arg("path"),
      "Reads a .rffd file; ValueError with rff_slam's 'file:line: problem' "
      "message\nwhen it is malformed.");
  m.def("solve", &rff::Solve, py::arg("dataset_or_path"),
        "solve(dataset_or_path, **options) -> Result\n\n"
        "Solves a Dataset or the .rffd file at a path. The options are "
        "rff_slam's solver\nflags without dashes (prior='wnoa', "
        "num_features=50, flagfile='configs/plaza.flags';\nrffslam.options() "
        "lists them) and mean what they mean there; the flagfile is\nread "
        "first, the others override it. Two more: compute_covariance=True "
        "(the\ncovariances rff_slam --output_covariance writes) and "
        "verbose=True (Ceres's\nprogress on stderr). An unknown name or a "
        "bad value raises ValueError naming\nit; a failed solve "
        "RuntimeError. The GIL is released during the solve, and\nCtrl-C "
        "stops it with KeyboardInterrupt.");
  m.def("evaluate", &rff::EvaluatePy, py::arg("dataset_or_path"),
        py::arg("result"), py::arg("align") = py::bool_(false),
        "Errors of `result` against the dataset's ground truth: the dict of "
        "rff_evaluate\n--json with the trajectory and landmarks (and "
        "covariances, when computed) of\n`result`, without its input file "
        "names. align=True is --align.");
  m.def("options", &rff::Options,
        "The options of solve(): name -> {'type', 'default', 'help'}.");
}
