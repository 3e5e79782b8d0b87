// rff_experiment: the paper's evaluation grid in one command.
//
//   rff_experiment --out_dir=DIR [--quick] [--methods=rff,wnoa]
//                  [--experiments=table1,figure1,table2,figure2,solvers]
//                  [--configs_dir=configs] [--data_dir=data]
//                  [--shared_dir=../shared] [--num_threads=1]
//
// Runs every method on every dataset of the selected experiments and writes
// CSV and Markdown tables and SVG plots into DIR (see
// rff_ceres/experiment/experiment.h). A method's options come from its
// flagfile: <configs_dir>/<family>.flags for rff,
// <configs_dir>/<family>_wnoa.flags for wnoa, or any name=pattern with
// {family} and {configs} in the pattern. One line per run goes to stderr.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "gflags/gflags.h"
#include "glog/logging.h"
#include "rff_ceres/allocator.h"
#include "rff_ceres/experiment/experiment.h"
#include "rff_ceres/io/flagfile_check.h"
#include "slam_flags.h"
#include "tool_flags.h"

DEFINE_string(out_dir, "", "Directory for the tables and plots (created).");
DEFINE_bool(quick, false,
            "Small preset (2 seeds, 2 landmark counts, a short KITTI-scale "
            "set, no raw MRCLAM robots) that runs in a few minutes.");
DEFINE_string(methods, "rff,wnoa",
              "Comma list of methods: rff, wnoa, or name=flagfile-pattern "
              "with {family} and {configs} in the pattern, e.g. "
              "d12={configs}/{family}_d12.flags.");
DEFINE_string(experiments, "table1,figure1,table2,figure2,solvers",
              "Comma list of experiments to run.");
DEFINE_string(configs_dir, "",
              "Directory of the method configs (default: configs/ of the "
              "source tree this binary was built from).");
DEFINE_string(data_dir, "",
              "Directory with plaza1.rffd and mrclam6_robot1.rffd (default: "
              "data/ of the source tree).");
DEFINE_string(shared_dir, "",
              "Optional directory with data/mrclam6/*.dat for MRCLAM robots "
              "2-5 (default: ../shared next to the source tree; skipped "
              "when absent).");
DEFINE_string(figure2_dataset, "plaza1",
              "Table II (or Table I) dataset whose trajectory Figure 2 "
              "shows.");
DECLARE_int32(num_threads);  // Of slam_flags: overrides every config.

namespace {

int Fail(const std::string& message) {
  std::cerr << "rff_experiment: error: " << message << "\n";
  return 1;
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> items;
  std::string item;
  for (char c : text + ",") {
    if (c != ',') {
      item += c;
    } else if (!item.empty()) {
      items.push_back(item);
      item.clear();
    }
  }
  return items;
}

// The source tree: the CMAKE_HOME_DIRECTORY of the build directory holding
// this binary, else the nearest ancestor of the binary or the working
// directory with configs/plaza.flags.
std::string FindSourceRoot(const char* argv0) {
  namespace fs = std::filesystem;
  std::error_code ignored;
  fs::path binary = fs::read_symlink("/proc/self/exe", ignored);
  if (binary.empty()) binary = fs::absolute(argv0, ignored);
  const auto has_configs = [](const fs::path& dir) {
    std::error_code e;
    return fs::exists(dir / "configs" / "plaza.flags", e);
  };
  std::ifstream cache(binary.parent_path() / "CMakeCache.txt");
  const std::string key = "CMAKE_HOME_DIRECTORY:INTERNAL=";
  for (std::string line; std::getline(cache, line);) {
    if (line.compare(0, key.size(), key) == 0 &&
        has_configs(line.substr(key.size()))) {
      return line.substr(key.size());
    }
  }
  for (fs::path start : {binary.parent_path(), fs::current_path(ignored)}) {
    for (fs::path dir = start; !dir.empty(); dir = dir.parent_path()) {
      if (has_configs(dir)) return dir.string();
      if (dir == dir.parent_path()) break;
    }
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  rff::RetainFreedMemory();
  FLAGS_logtostderr = true;
  gflags::SetUsageMessage(
      "rff_experiment --out_dir=DIR [--quick] [--methods=rff,wnoa] "
      "[--experiments=table1,figure1,table2,figure2,solvers]");
  std::string error;
  if (!rff::ParseToolFlags(&argc, &argv, &error)) return Fail(error);
  google::InitGoogleLogging(argv[0]);
  if (FLAGS_out_dir.empty()) return Fail("--out_dir is required");
  // The command line's solver options underlie every method's flagfile:
  // checked once here, not row by row after the grid has started.
  if (!rff::ValidateSlamOptions(rff::SlamOptionsFromFlags(), &error)) {
    return Fail(error);
  }

  const std::string root = FindSourceRoot(argv[0]);
  std::string configs_dir = FLAGS_configs_dir;
  std::string data_dir = FLAGS_data_dir;
  std::string shared_dir = FLAGS_shared_dir;
  if (configs_dir.empty() || data_dir.empty()) {
    if (root.empty()) {
      return Fail(
          "cannot find the source tree (configs/plaza.flags); give "
          "--configs_dir and --data_dir");
    }
    if (configs_dir.empty()) configs_dir = root + "/configs";
    if (data_dir.empty()) data_dir = root + "/data";
  }
  if (shared_dir.empty() && !root.empty()) shared_dir = root + "/../shared";

  rff::ExperimentConfig config;
  if (!rff::ParseMethods(FLAGS_methods, &config.methods, &error)) {
    return Fail(error);
  }
  config.out_dir = FLAGS_out_dir;
  config.quick = FLAGS_quick;
  config.experiments = SplitList(FLAGS_experiments);
  config.data_dir = data_dir;
  config.shared_dir = shared_dir;
  config.figure2_dataset = FLAGS_figure2_dataset;
  config.progress = &std::cerr;

  // The command line's thread count, before any flagfile is read.
  const int num_threads = FLAGS_num_threads;
  const std::vector<rff::Method> methods = config.methods;
  const char* program = argv[0];
  auto options_from_flagfile = [&](const std::string& method_name,
                                   const std::string& family,
                                   rff::SlamOptions* options,
                                   std::string* message) {
    const rff::Method* method = nullptr;
    for (const rff::Method& m : methods) {
      if (m.name == method_name) method = &m;
    }
    if (method == nullptr) {
      *message = "unknown method '" + method_name + "'";
      return false;
    }
    const std::string path = rff::MethodFlagfile(*method, family, configs_dir);
    if (access(path.c_str(), R_OK) != 0) {
      *message = path + ": cannot read the flagfile of method '" + method_name +
                 "' for " + family;
      return false;
    }
    // Every flagfile starts from the command line's flags; the saver puts
    // them back afterwards. Not fatal: a bad file is a failed row.
    if (!rff::CheckFlagfiles({"--flagfile=" + path}, rff::ToolFlagKind,
                             message)) {
      return false;
    }
    gflags::FlagSaver saver;
    if (!gflags::ReadFromFlagsFile(path, program, false)) {
      *message = path +
                 ": gflags rejected the flagfile (see its message "
                 "above)";
      return false;
    }
    *options = rff::SlamOptionsFromFlags();
    options->solver.num_threads = num_threads;
    options->solver.log_progress = false;
    // Checked here, before the row reads its dataset.
    if (!rff::ValidateSlamOptions(*options, message)) {
      *message = path + ": " + *message;
      return false;
    }
    return true;
  };

  std::cerr << "rff_experiment: configs " << configs_dir << ", data "
            << data_dir << ", shared " << shared_dir << "\n";
  rff::ExperimentSummary summary;
  if (!rff::RunExperiments(config, options_from_flagfile, &summary, &error)) {
    return Fail(error);
  }
  int failed = 0;
  for (const rff::RunRow& row : summary.rows) failed += row.ok() ? 0 : 1;
  std::cout << "rff_experiment: " << summary.rows.size() << " runs, " << failed
            << " failed; wrote";
  for (const std::string& file : summary.files) std::cout << " " << file;
  std::cout << "\n";
  if (failed > 0) {
    return Fail(std::to_string(failed) + " of " +
                std::to_string(summary.rows.size()) +
                " runs failed (their messages are in runs.csv)");
  }
  return 0;
}
