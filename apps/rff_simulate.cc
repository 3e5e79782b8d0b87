// rff_simulate: writes a synthetic .rffd dataset (the seed paper's protocol,
// the large bearing-only kitti_scale preset, a ground robot with a laser,
// laser_10hz, or a trajectory drawn from a GP prior, gp_draw). See
// docs/simulator.md.
//
//   rff_simulate --output=s1_rb_L50_o1.rffd --seed=1 --landmarks=50
//   rff_simulate --output=kitti_scale.rffd --preset=kitti_scale --seed=1
//   rff_simulate --output=laser.rffd --preset=laser_10hz --seed=1
//   rff_simulate --output=gp.rffd --preset=gp_draw --gp_lengthscale=30
#include <gflags/gflags.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>

#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/simulate_gp_draw.h"
#include "rff_ceres/types.h"
#include "tool_flags.h"

DEFINE_string(output, "", "Output .rffd path (required).");
DEFINE_string(preset, "paper",
              "paper (the seed paper's protocol), kitti_scale (3000 poses, "
              "~4000 landmarks, bearing-only), laser_10hz (12000 poses at "
              "10 Hz, range-bearing to the 6 nearest landmarks in a 270 "
              "degree, 20 m view, odometry) or gp_draw (x, y, theta drawn "
              "from GPs, 600 poses, no odometry, 4 nearest of 25 landmarks). "
              "Flags given explicitly override the preset; the defaults "
              "below are the paper's. Lengths, times, speeds and sigmas are "
              "at most 1e6.");
DEFINE_uint64(seed, 1, "Random seed; the same seed gives the same file.");
DEFINE_int32(num_steps, 300,
             "Number of poses (kitti_scale: 3000), 1 to 10000000 (gp_draw: "
             "at most 5000).");
DEFINE_double(dt, 1.0, "Time step in s (kitti_scale: 0.1).");
DEFINE_double(speed, 1.0, "Mean forward speed in m/s (kitti_scale: 10).");
DEFINE_int32(landmarks, 50,
             "Number of landmarks (kitti_scale: 4000), 1 to 10000000.");
DEFINE_string(kind, "range_bearing",
              "Measurement: range, bearing or range_bearing (kitti_scale: "
              "bearing).");
DEFINE_double(sigma_range, 1.0, "Range noise sigma in m.");
DEFINE_double(sigma_bearing_deg, 2.0,
              "Bearing noise sigma in degrees (kitti_scale: 1), more than 0 "
              "up to 360.");
DEFINE_int32(observations_per_step, 4,
             "Landmarks observed per pose (kitti_scale: up to 15 visible), "
             "1 or more, at most --landmarks without --sensor_range or "
             "--observe_nearest; with --num_steps at most 20000000 "
             "observations.");
DEFINE_bool(odometry, true, "Write ODOM records between consecutive poses.");
DEFINE_double(odometry_sigma_xy, 0.05, "Odometry translation sigma in m.");
DEFINE_double(odometry_sigma_theta, 0.01, "Odometry rotation sigma in rad.");
DEFINE_double(landmark_prior_sigma, 5.0,
              "Landmark prior sigma in m; 0 writes no landmark priors.");
DEFINE_double(landmark_margin, 15.0,
              "Margin in m around the trajectory's bounding box in which "
              "landmarks are placed (without a sensor range).");
DEFINE_double(sensor_range, 0.0,
              "Visibility range in m; 0 = every landmark visible "
              "(kitti_scale: 40).");
DEFINE_double(min_range, 2.0, "Closest visible distance in m.");
DEFINE_double(field_of_view_deg, 360.0,
              "Field of view in degrees (kitti_scale: 90), more than 0 up "
              "to 360.");
DEFINE_int32(min_visible_landmarks, 0,
             "Least number of landmarks every pose sees (kitti_scale: 10), "
             "0 to 10000.");
DEFINE_bool(noise_free, false,
            "Add no noise (the sigmas are still written as given).");
DEFINE_bool(observe_nearest, false,
            "Observe the nearest landmarks at least --min_range away instead "
            "of a random sample (gp_draw: true).");
DEFINE_string(gp_kernel, "matern52",
              "gp_draw: kernel of x, y and theta (rbf, matern12, matern32, "
              "matern52, ...).");
DEFINE_double(gp_lengthscale, 8.0,
              "gp_draw: lengthscale of x and y in s, more than 0 up to 1e6 "
              "(and the other gp_ scales).");
DEFINE_double(gp_kernel_variance, 25.0,
              "gp_draw: kernel variance of x and y in m^2.");
DEFINE_double(gp_heading_lengthscale, 12.0,
              "gp_draw: lengthscale of theta in s.");
DEFINE_double(gp_heading_kernel_variance, 0.25,
              "gp_draw: kernel variance of theta in rad^2.");

namespace {

bool Given(const char* flag) {
  return !gflags::GetCommandLineFlagInfoOrDie(flag).is_default;
}

int Fail(const std::string& message) {
  std::fprintf(stderr, "rff_simulate: error: %s\n", message.c_str());
  return 1;
}

// An angle flag in degrees, checked in the unit given (the library's bounds
// are in radians): more than 0 in radians too, up to 360.
bool CheckDegrees(const char* flag, double degrees, std::string* error) {
  if (rff::IsNormalPositive(degrees * M_PI / 180.0) && degrees <= 360.0) {
    return true;
  }
  *error = rff::OptionError(
      flag, rff::FormatNumber(degrees),
      std::isfinite(degrees) && degrees > 0.0 && degrees <= 360.0
          ? "too small for radians in double precision"
          : rff::WhyNotOption(degrees),
      "more than 0 up to 360");
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  gflags::SetUsageMessage(
      "rff_simulate --output=OUT.rffd "
      "[--preset=paper|kitti_scale|laser_10hz|gp_draw] "
      "[--seed=1] [--kind=range_bearing] [--landmarks=50] ...");
  std::string error;
  if (!rff::ParseToolFlags(&argc, &argv, &error)) return Fail(error);
  if (FLAGS_output.empty()) return Fail("--output is required");
  if (!rff::CheckOutputPaths(rff::WithFlagfiles({}),
                             {{"--output", FLAGS_output}}, &error)) {
    return Fail(error);
  }

  rff::SimulationOptions options;
  if (FLAGS_preset == "paper") {
    options = rff::PaperOptions(FLAGS_seed);
  } else if (FLAGS_preset == "kitti_scale") {
    options = rff::KittiScaleOptions(FLAGS_seed);
  } else if (FLAGS_preset == "laser_10hz") {
    options = rff::Laser10HzOptions(FLAGS_seed);
  } else if (FLAGS_preset == "gp_draw") {
    options = rff::GpDrawOptions(FLAGS_seed);
  } else {
    return Fail(rff::OptionError("preset", FLAGS_preset, "unknown preset",
                                 "paper, kitti_scale, laser_10hz or gp_draw"));
  }
  // With the paper preset every flag applies (its defaults are the paper's);
  // with another preset only the flags given on the command line do.
  const bool all = FLAGS_preset == "paper";
  constexpr double kDegree = M_PI / 180.0;
  if (all || Given("num_steps")) options.num_steps = FLAGS_num_steps;
  if (all || Given("dt")) options.dt = FLAGS_dt;
  if (all || Given("speed")) options.speed = FLAGS_speed;
  if (all || Given("landmarks")) options.num_landmarks = FLAGS_landmarks;
  if (all || Given("kind")) {
    if (!rff::ParseMeasurementKind(FLAGS_kind, &options.kind, &error)) {
      return Fail(error);
    }
  }
  if (all || Given("sigma_range")) options.sigma_range = FLAGS_sigma_range;
  if (all || Given("sigma_bearing_deg")) {
    if (!CheckDegrees("sigma_bearing_deg", FLAGS_sigma_bearing_deg, &error)) {
      return Fail(error);
    }
    options.sigma_bearing = FLAGS_sigma_bearing_deg * kDegree;
  }
  if (all || Given("observations_per_step")) {
    options.observations_per_step = FLAGS_observations_per_step;
  }
  if (all || Given("odometry")) options.odometry = FLAGS_odometry;
  if (all || Given("odometry_sigma_xy")) {
    options.odometry_sigma_xy = FLAGS_odometry_sigma_xy;
  }
  if (all || Given("odometry_sigma_theta")) {
    options.odometry_sigma_theta = FLAGS_odometry_sigma_theta;
  }
  if (all || Given("landmark_prior_sigma")) {
    options.landmark_prior_sigma = FLAGS_landmark_prior_sigma;
  }
  if (all || Given("landmark_margin")) {
    options.landmark_margin = FLAGS_landmark_margin;
  }
  if (all || Given("sensor_range")) options.sensor_range = FLAGS_sensor_range;
  if (all || Given("min_range")) options.min_range = FLAGS_min_range;
  if (all || Given("field_of_view_deg")) {
    if (!CheckDegrees("field_of_view_deg", FLAGS_field_of_view_deg, &error)) {
      return Fail(error);
    }
    // 360 degrees must map to exactly 2 pi, the "all around" value.
    options.field_of_view = FLAGS_field_of_view_deg == 360.0
                                ? 2.0 * M_PI
                                : FLAGS_field_of_view_deg * kDegree;
  }
  if (all || Given("min_visible_landmarks")) {
    options.min_visible_landmarks = FLAGS_min_visible_landmarks;
  }
  if (all || Given("noise_free")) options.noise_free = FLAGS_noise_free;
  if (all || Given("observe_nearest")) {
    options.observe_nearest = FLAGS_observe_nearest;
  }
  // The GP's kernel is used by gp_draw only; the options check its values.
  const std::pair<const char*, std::string> gp_flags[] = {
      {"gp_kernel", FLAGS_gp_kernel},
      {"gp_lengthscale", rff::FormatNumber(FLAGS_gp_lengthscale)},
      {"gp_kernel_variance", rff::FormatNumber(FLAGS_gp_kernel_variance)},
      {"gp_heading_lengthscale",
       rff::FormatNumber(FLAGS_gp_heading_lengthscale)},
      {"gp_heading_kernel_variance",
       rff::FormatNumber(FLAGS_gp_heading_kernel_variance)}};
  for (const auto& [flag, value] : gp_flags) {
    if (Given(flag) && FLAGS_preset != "gp_draw") {
      return Fail(
          rff::OptionError(flag, value, "applies to --preset=gp_draw only"));
    }
  }
  if (Given("gp_kernel")) options.gp_kernel = FLAGS_gp_kernel;
  if (Given("gp_lengthscale")) options.gp_lengthscale = FLAGS_gp_lengthscale;
  if (Given("gp_kernel_variance")) {
    options.gp_kernel_variance = FLAGS_gp_kernel_variance;
  }
  if (Given("gp_heading_lengthscale")) {
    options.gp_heading_lengthscale = FLAGS_gp_heading_lengthscale;
  }
  if (Given("gp_heading_kernel_variance")) {
    options.gp_heading_kernel_variance = FLAGS_gp_heading_kernel_variance;
  }

  if (!rff::ValidateSimulationOptions(options, &error)) return Fail(error);
  // Without a visibility model or nearest-first selection no distance is
  // checked: a given --min_range would change nothing.
  if (Given("min_range") && !(options.sensor_range > 0.0) &&
      !options.observe_nearest) {
    return Fail(rff::OptionError(
        "min_range", rff::FormatNumber(FLAGS_min_range),
        "applies with --sensor_range > 0 or --observe_nearest only"));
  }
  // The view is part of the visibility model only.
  if (Given("field_of_view_deg") && !(options.sensor_range > 0.0) &&
      options.field_of_view < 2.0 * M_PI) {
    return Fail(rff::OptionError("field_of_view_deg",
                                 rff::FormatNumber(FLAGS_field_of_view_deg),
                                 "applies with --sensor_range > 0 only"));
  }

  rff::Dataset dataset;
  if (!rff::Simulate(options, &dataset, &error)) return Fail(error);
  if (!rff::WriteDataset(dataset, FLAGS_output, &error)) return Fail(error);
  std::printf(
      "wrote %s: preset %s, seed %llu, %zu poses, %zu landmarks, "
      "%zu %s observations, %zu odometry, %zu landmark priors%s\n",
      FLAGS_output.c_str(), options.preset.c_str(),
      static_cast<unsigned long long>(options.seed),
      dataset.ground_truth.size(), dataset.ground_truth_landmarks.size(),
      dataset.observations.size(),
      rff::MeasurementKindName(options.kind).c_str(), dataset.odometry.size(),
      dataset.landmark_priors.size(), options.noise_free ? ", noise-free" : "");
  return 0;
}
