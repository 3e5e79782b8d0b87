#include "rff_ceres/experiment/grid.h"

#include <cmath>
#include <filesystem>
#include <utility>

#include "rff_ceres/convert/mrclam.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/priors/trajectory_prior.h"
#include "rff_ceres/simulate.h"

namespace rff {
namespace {

std::string ShortKind(const std::string& kind) {
  return kind == "range_bearing" ? "rb" : kind;
}

// The simulated paper set (PaperOptions) of `kind` with `landmarks` and the
// observation sigmas times `noise`.
DatasetSpec PaperSpec(const std::string& kind, int landmarks, double noise,
                      int seed) {
  DatasetSpec spec;
  spec.name = "s" + std::to_string(seed) + "_" + ShortKind(kind) + "_L" +
              std::to_string(landmarks) + "_" + NoiseLabel(noise, "x");
  spec.family = SyntheticFamily(kind);
  spec.kind = kind;
  spec.landmarks = landmarks;
  spec.noise = noise;
  spec.noise_unit = "x";
  spec.seed = seed;
  spec.make = [kind, landmarks, noise, seed](Dataset* dataset,
                                             std::string* error) {
    SimulationOptions options = PaperOptions(seed);
    if (!ParseMeasurementKind(kind, &options.kind, error)) return false;
    options.num_landmarks = landmarks;
    options.sigma_range *= noise;
    options.sigma_bearing *= noise;
    return Simulate(options, dataset, error);
  };
  return spec;
}

DatasetSpec FileSpec(const std::string& name, const std::string& family,
                     const std::string& kind, const std::string& path) {
  DatasetSpec spec;
  spec.name = name;
  spec.family = family;
  spec.kind = kind;
  spec.make = [path](Dataset* dataset, std::string* error) {
    return ReadDataset(path, dataset, error);
  };
  return spec;
}

// MRCLAM Dataset 6 robot `robot` converted as data/mrclam6_robot1.rffd was
// (rff_convert --format=mrclam --mrclam_odometry_interval=1).
DatasetSpec MrclamSpec(const std::string& directory, int robot) {
  DatasetSpec spec;
  spec.name = "mrclam6_robot" + std::to_string(robot);
  spec.family = "mrclam";
  spec.kind = "range_bearing";
  spec.make = [directory, robot](Dataset* dataset, std::string* error) {
    MrclamOptions options;
    options.robot = robot;
    options.odometry_interval = 1.0;
    MrclamSummary summary;
    return ConvertMrclam(directory, options, dataset, &summary, error);
  };
  return spec;
}

// The KITTI-projected bearing-only set with bearing sigma `sigma_deg`; the
// quick preset drives a fifth of the distance among a fifth of the
// landmarks.
DatasetSpec KittiSpec(bool quick, double sigma_deg, int seed) {
  DatasetSpec spec;
  spec.name = std::string(quick ? "kitti_scale_short" : "kitti_scale") + "_s" +
              std::to_string(seed) + "_b" + FormatNumber(sigma_deg) + "deg";
  spec.family = "kitti_bearing";
  spec.kind = "bearing";
  spec.noise = sigma_deg;
  spec.noise_unit = "deg";
  spec.seed = seed;
  spec.make = [quick, sigma_deg, seed](Dataset* dataset, std::string* error) {
    SimulationOptions options = KittiScaleOptions(seed);
    options.sigma_bearing = sigma_deg * M_PI / 180.0;
    if (quick) {
      options.num_steps /= 5;
      options.num_landmarks /= 5;
    }
    return Simulate(options, dataset, error);
  };
  return spec;
}

}  // namespace

std::string SyntheticFamily(const std::string& kind) {
  return "synthetic_" + kind;
}

std::string NoiseLabel(double noise, const std::string& unit) {
  if (noise == 0.0 || unit.empty()) return "";
  if (unit == "x") return "x" + FormatNumber(noise);
  return FormatNumber(noise) + " " + unit;
}

std::vector<DatasetSpec> Table1Datasets(bool quick) {
  const std::vector<int> landmarks =
      quick ? std::vector<int>{10, 50} : std::vector<int>{5, 10, 25, 50, 100};
  const int seeds = quick ? 2 : 10;
  std::vector<DatasetSpec> specs;
  for (const std::string kind : {"range_bearing", "range", "bearing"}) {
    for (int l : landmarks) {
      for (int seed = 1; seed <= seeds; ++seed) {
        specs.push_back(PaperSpec(kind, l, 1.0, seed));
      }
    }
  }
  return specs;
}

int Figure1NoiseLandmarks(bool quick) { return quick ? 25 : 50; }

std::vector<DatasetSpec> Figure1Datasets(bool quick) {
  const std::vector<int> landmarks = quick
                                         ? std::vector<int>{10, 25, 50}
                                         : std::vector<int>{5, 10, 25, 50, 100};
  const std::vector<double> noises =
      quick ? std::vector<double>{0.5, 1.0, 2.0}
            : std::vector<double>{0.5, 1.0, 2.0, 4.0};
  const int noise_landmarks = Figure1NoiseLandmarks(quick);
  const int seeds = quick ? 2 : 10;
  std::vector<DatasetSpec> specs;
  for (const std::string kind : {"range_bearing", "range", "bearing"}) {
    // The landmark sweep at the paper's noise, then the noise sweep (its
    // x1 point is already in the landmark sweep).
    std::vector<std::pair<int, double>> settings;
    for (int l : landmarks) settings.emplace_back(l, 1.0);
    for (double n : noises) {
      if (n != 1.0) settings.emplace_back(noise_landmarks, n);
    }
    for (const auto& [l, n] : settings) {
      for (int seed = 1; seed <= seeds; ++seed) {
        specs.push_back(PaperSpec(kind, l, n, seed));
      }
    }
  }
  return specs;
}

std::vector<DatasetSpec> Table2Datasets(bool quick, const std::string& data_dir,
                                        const std::string& shared_dir) {
  std::vector<DatasetSpec> specs;
  specs.push_back(
      FileSpec("plaza1", "plaza", "range", data_dir + "/plaza1.rffd"));
  specs.push_back(FileSpec("mrclam6_robot1", "mrclam", "range_bearing",
                           data_dir + "/mrclam6_robot1.rffd"));
  const std::string mrclam_dir = shared_dir + "/data/mrclam6";
  if (!quick && !shared_dir.empty()) {
    for (int robot = 2; robot <= 5; ++robot) {
      const std::string odometry =
          mrclam_dir + "/Robot" + std::to_string(robot) + "_Odometry.dat";
      if (std::filesystem::exists(odometry)) {
        specs.push_back(MrclamSpec(mrclam_dir, robot));
      }
    }
  }
  for (double sigma_deg : {1.0, 3.0, 5.0}) {
    specs.push_back(KittiSpec(quick, sigma_deg, 1));
  }
  return specs;
}

std::vector<DatasetSpec> SolverDatasets(bool /*quick*/,
                                        const std::string& data_dir) {
  return {PaperSpec("range_bearing", 50, 1.0, 1),
          FileSpec("plaza1", "plaza", "range", data_dir + "/plaza1.rffd")};
}

std::vector<OptionsVariant> SolverVariants(bool quick) {
  const std::vector<int> sizes =
      quick ? std::vector<int>{12, 24} : std::vector<int>{12, 24, 48};
  std::vector<OptionsVariant> variants;
  for (const std::string solver :
       {"DENSE_SCHUR", "SPARSE_SCHUR", "ITERATIVE_SCHUR",
        "SPARSE_NORMAL_CHOLESKY"}) {
    for (const std::string family :
         {"hilbert", "rff", "qmc", "gauss_hermite"}) {
      for (int d : sizes) {
        OptionsVariant variant;
        variant.name = solver + " " + family + " D=" + std::to_string(d);
        const bool first_features = family == "hilbert" && d == sizes[0];
        variant.apply = [solver, family, d,
                         first_features](SlamOptions* options) {
          // Priors without features run once, with the sparse Cholesky:
          // eliminating landmarks seen from the whole run first leaves the
          // WNOA states in one dense system (Plaza: 21000 unknowns, hours).
          const TrajectoryPrior* prior = FindPrior(options->prior);
          if ((prior == nullptr || !prior->has_features()) &&
              (!first_features || solver != "SPARSE_NORMAL_CHOLESKY")) {
            return false;
          }
          options->solver.linear_solver = solver;
          options->features.family = family;
          options->features.num_position_features = d;
          options->features.num_heading_features = d;
          return true;
        };
        variants.push_back(variant);
      }
    }
  }
  return variants;
}

}  // namespace rff
