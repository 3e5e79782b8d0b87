#include "rff_ceres/simulate.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/option_error.h"
#include "rff_ceres/se2.h"
#include "rff_ceres/simulate_gp_draw.h"

namespace rff {

double SimulationRandom::Uniform() {
  // The top 53 bits: every value is exact and the result is < 1.
  return static_cast<double>(engine_() >> 11) * 0x1.0p-53;
}

double SimulationRandom::Uniform(double low, double high) {
  return low + (high - low) * Uniform();
}

std::uint64_t SimulationRandom::Index(std::uint64_t n) {
  // Rejects the top partial block of 2^64 so that every index is equally
  // likely; at most half the draws are rejected.
  const std::uint64_t limit = ~std::uint64_t{0} - (~std::uint64_t{0} % n);
  std::uint64_t bits = engine_();
  while (bits >= limit) bits = engine_();
  return bits % n;
}

double SimulationRandom::Normal() {
  if (has_spare_normal_) {
    has_spare_normal_ = false;
    return spare_normal_;
  }
  // u1 in (0, 1] keeps the logarithm finite.
  const double u1 = static_cast<double>((engine_() >> 11) + 1) * 0x1.0p-53;
  const double u2 = Uniform();
  const double radius = std::sqrt(-2.0 * std::log(u1));
  const double angle = 2.0 * M_PI * u2;
  spare_normal_ = radius * std::sin(angle);
  has_spare_normal_ = true;
  return radius * std::cos(angle);
}

std::string TrajectoryShapeName(TrajectoryShape model) {
  switch (model) {
    case TrajectoryShape::kWandering:
      return "wandering";
    case TrajectoryShape::kRoad:
      return "road";
    case TrajectoryShape::kGpDraw:
      return "gp_draw";
  }
  return "unknown";
}

SimulationOptions PaperOptions(std::uint64_t seed) {
  SimulationOptions options;
  options.seed = seed;
  return options;
}

SimulationOptions KittiScaleOptions(std::uint64_t seed) {
  SimulationOptions options;
  options.seed = seed;
  options.preset = "kitti_scale";
  options.trajectory = TrajectoryShape::kRoad;
  options.num_steps = 3000;
  options.dt = 0.1;
  options.speed = 10.0;
  options.num_landmarks = 4000;
  options.kind = ObservationType::kBearing;
  options.sigma_bearing = 1.0 * M_PI / 180.0;
  options.observations_per_step = 15;
  options.sensor_range = 40.0;
  options.min_range = 2.0;
  options.field_of_view = M_PI / 2.0;
  options.min_visible_landmarks = 10;
  return options;
}

SimulationOptions Laser10HzOptions(std::uint64_t seed) {
  SimulationOptions options;
  options.seed = seed;
  options.preset = "laser_10hz";
  options.trajectory = TrajectoryShape::kWandering;
  options.num_steps = 12000;
  options.dt = 0.1;
  options.speed = 1.0;
  // A 2D scanner (270 degrees, 1 to 20 m) whose feature extractor reports
  // the nearest features: posts, trees, corners.
  options.kind = ObservationType::kRangeBearing;
  options.sigma_range = 0.05;
  options.sigma_bearing = 0.5 * M_PI / 180.0;
  options.sensor_range = 20.0;
  options.min_range = 1.0;
  options.field_of_view = 1.5 * M_PI;
  options.observations_per_step = 6;
  options.observe_nearest = true;
  // Placed along the path: a pose sees about 10 on average; the few poses
  // that would see fewer than 4 get more.
  options.num_landmarks = 150;
  options.min_visible_landmarks = 4;
  options.landmark_prior_sigma = 1.0;
  // Wheel odometry: white noise per 0.1 s step; over the 1.2 km run the
  // heading drifts by about 6 degrees.
  options.odometry = true;
  options.odometry_sigma_xy = 0.005;
  options.odometry_sigma_theta = 0.001;
  return options;
}

namespace {

// Caps that keep a run within memory and minutes; far above any benchmark.
constexpr int kMaxSteps = 10000000;
constexpr int kMaxLandmarks = 10000000;
constexpr std::int64_t kMaxObservations = 20000000;
constexpr double kMaxMagnitude = 1e6;

// Independent random streams, so that switching one option (odometry on or
// off, the measurement kind, the noise) leaves every other draw unchanged.
enum class Stream : std::uint64_t {
  kTrajectory = 1,
  kLandmarks = 2,
  kLandmarkPriors = 3,
  kSelection = 4,
  kMeasurementNoise = 5,
  kOdometryNoise = 6,
};

// SplitMix64 finaliser: turns (seed, stream) into well-mixed engine seeds.
std::uint64_t StreamSeed(std::uint64_t seed, Stream stream) {
  std::uint64_t z =
      seed + 0x9E3779B97F4A7C15ull * (static_cast<std::uint64_t>(stream) + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

class OptionChecker {
 public:
  explicit OptionChecker(std::string* error) : error_(error) {}

  bool ok() const { return ok_; }

  void IntAtLeast(const char* name, int value, int low, int high) {
    if (!ok_) return;
    if (value < low || value > high) {
      Fail(OptionError(name, std::to_string(value), "",
                       std::to_string(low) + " to " + std::to_string(high)));
    }
  }
  // Finite and in (0, kMaxMagnitude] (positive) or [0, kMaxMagnitude].
  void Positive(const char* name, double value) {
    Range(name, value, /*allow_zero=*/false);
  }
  void NonNegative(const char* name, double value) {
    Range(name, value, /*allow_zero=*/true);
  }
  void Fail(const std::string& message) {
    if (!ok_) return;
    ok_ = false;
    *error_ = message;
  }

 private:
  void Range(const char* name, double value, bool allow_zero) {
    if (!ok_) return;
    const bool low_ok = IsNormalPositive(value) || (allow_zero && value == 0.0);
    if (!(std::isfinite(value) && low_ok && value <= kMaxMagnitude)) {
      Fail(OptionError(name, FormatNumber(value), WhyNotOption(value),
                       (allow_zero ? "0 to " : "more than 0 up to ") +
                           FormatNumber(kMaxMagnitude)));
    }
  }

  std::string* error_;
  bool ok_ = true;
};

// Forward speed and turn rate as functions of time.
class Controls {
 public:
  Controls(const SimulationOptions& options, SimulationRandom* random)
      : model_(options.trajectory), speed_(options.speed) {
    const double duration = options.num_steps * options.dt;
    if (model_ == TrajectoryShape::kWandering) {
      // Speed between 0.5 and 1.5 x, period about 100 s; turn rate a sum of
      // three sinusoids of 20-80 s periods and 0.1-0.25 rad/s amplitudes.
      speed_period_ = random->Uniform(80.0, 120.0);
      speed_phase_ = random->Uniform(0.0, 2.0 * M_PI);
      speed_swing_ = 0.5;
      for (Wave& wave : waves_) {
        wave.amplitude = random->Uniform(0.1, 0.25);
        wave.period = random->Uniform(20.0, 80.0);
        wave.phase = random->Uniform(0.0, 2.0 * M_PI);
      }
    } else {
      // Speed within 10% of the mean; straights of 15-40 s, turns of 30-90
      // degrees either way over 4-8 s with a raised-cosine turn rate.
      speed_period_ = random->Uniform(40.0, 80.0);
      speed_phase_ = random->Uniform(0.0, 2.0 * M_PI);
      speed_swing_ = 0.1;
      double start = random->Uniform(10.0, 30.0);
      while (start < duration) {
        Turn turn;
        turn.start = start;
        turn.duration = random->Uniform(4.0, 8.0);
        turn.angle = random->Uniform(M_PI / 6.0, M_PI / 2.0);
        if (random->Uniform() < 0.5) turn.angle = -turn.angle;
        turns_.push_back(turn);
        start += turn.duration + random->Uniform(15.0, 40.0);
      }
    }
  }

  double Speed(double t) const {
    return speed_ *
           (1.0 + speed_swing_ *
                      std::sin(2.0 * M_PI * t / speed_period_ + speed_phase_));
  }

  double TurnRate(double t) const {
    double rate = 0.0;
    if (model_ == TrajectoryShape::kWandering) {
      for (const Wave& wave : waves_) {
        rate += wave.amplitude *
                std::sin(2.0 * M_PI * t / wave.period + wave.phase);
      }
      return rate;
    }
    for (const Turn& turn : turns_) {
      const double s = t - turn.start;
      if (s >= 0.0 && s < turn.duration) {
        rate += turn.angle / turn.duration *
                (1.0 - std::cos(2.0 * M_PI * s / turn.duration));
      }
    }
    return rate;
  }

 private:
  struct Wave {
    double amplitude = 0.0;
    double period = 1.0;
    double phase = 0.0;
  };
  struct Turn {
    double start = 0.0;
    double duration = 1.0;
    double angle = 0.0;
  };

  TrajectoryShape model_;
  double speed_;
  double speed_period_ = 1.0;
  double speed_phase_ = 0.0;
  double speed_swing_ = 0.0;
  Wave waves_[3];
  std::vector<Turn> turns_;
};

// Integrates the controls exactly over each step (constant speed and turn
// rate within a step: an arc whose chord points half-way through the turn),
// or draws the GP trajectory (headings wrapped here).
bool SimulateTrajectory(const SimulationOptions& options,
                        std::vector<TimedPose>* trajectory,
                        std::string* error) {
  SimulationRandom random(StreamSeed(options.seed, Stream::kTrajectory));
  if (options.trajectory == TrajectoryShape::kGpDraw) {
    if (!DrawGpTrajectory(options, &random, trajectory, error)) return false;
    for (TimedPose& pose : *trajectory) pose.theta = WrapAngle(pose.theta);
    return true;
  }
  TimedPose pose;
  pose.theta = WrapAngle(random.Uniform(-M_PI, M_PI));
  const Controls controls(options, &random);
  std::vector<TimedPose> poses;
  poses.reserve(options.num_steps);
  poses.push_back(pose);
  for (int k = 1; k < options.num_steps; ++k) {
    const double t = (k - 1) * options.dt;
    IntegrateUnicycle(controls.Speed(t), controls.TurnRate(t), options.dt,
                      &pose.x, &pose.y, &pose.theta);
    pose.theta = WrapAngle(pose.theta);
    pose.t = k * options.dt;
    poses.push_back(pose);
  }
  *trajectory = std::move(poses);
  return true;
}

bool IsVisible(const SimulationOptions& options, const TimedPose& pose,
               const Landmark& landmark) {
  const double dx = landmark.x - pose.x;
  const double dy = landmark.y - pose.y;
  const double squared = dx * dx + dy * dy;
  if (squared < options.min_range * options.min_range ||
      squared > options.sensor_range * options.sensor_range) {
    return false;
  }
  if (options.field_of_view >= 2.0 * M_PI) return true;
  const double bearing = WrapAngle(std::atan2(dy, dx) - pose.theta);
  return std::abs(bearing) <= 0.5 * options.field_of_view;
}

// A point drawn uniformly (by area) in the view of `pose`, kept a hair inside
// the limits so that rounding cannot push it out.
Landmark LandmarkInView(const SimulationOptions& options, const TimedPose& pose,
                        SimulationRandom* random) {
  const double shrink = 1e-9;
  const double r_low = options.min_range * (1.0 + shrink);
  const double r_high = options.sensor_range * (1.0 - shrink);
  const double half_view = 0.5 * options.field_of_view * (1.0 - shrink);
  const double r = std::sqrt(random->Uniform(r_low * r_low, r_high * r_high));
  const double bearing = random->Uniform(-half_view, half_view);
  Landmark landmark;
  landmark.x = pose.x + r * std::cos(pose.theta + bearing);
  landmark.y = pose.y + r * std::sin(pose.theta + bearing);
  return landmark;
}

// Landmarks hashed into square cells as wide as the sensor range, so that a
// pose only checks the 3 x 3 cells around it.
class LandmarkGrid {
 public:
  explicit LandmarkGrid(double cell) : cell_(cell) {}

  void Add(const Landmark& landmark, int index) {
    cells_[Key(Cell(landmark.x), Cell(landmark.y))].push_back(index);
  }

  // Indices of the visible landmarks, ascending.
  std::vector<int> Visible(const SimulationOptions& options,
                           const TimedPose& pose,
                           const std::vector<Landmark>& landmarks) const {
    std::vector<int> visible;
    const std::int64_t cx = Cell(pose.x);
    const std::int64_t cy = Cell(pose.y);
    for (std::int64_t ix = cx - 1; ix <= cx + 1; ++ix) {
      for (std::int64_t iy = cy - 1; iy <= cy + 1; ++iy) {
        const auto it = cells_.find(Key(ix, iy));
        if (it == cells_.end()) continue;
        for (int index : it->second) {
          if (IsVisible(options, pose, landmarks[index])) {
            visible.push_back(index);
          }
        }
      }
    }
    std::sort(visible.begin(), visible.end());
    return visible;
  }

 private:
  std::int64_t Cell(double coordinate) const {
    return static_cast<std::int64_t>(std::floor(coordinate / cell_));
  }
  static std::uint64_t Key(std::int64_t ix, std::int64_t iy) {
    return (static_cast<std::uint64_t>(ix) << 32) ^
           (static_cast<std::uint64_t>(iy) & 0xffffffffull);
  }

  double cell_;
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

// Uniform in the bounding box of the trajectory grown by the margin.
std::vector<Landmark> LandmarksInBox(const SimulationOptions& options,
                                     const std::vector<TimedPose>& poses) {
  SimulationRandom random(StreamSeed(options.seed, Stream::kLandmarks));
  double x_min = poses[0].x, x_max = poses[0].x;
  double y_min = poses[0].y, y_max = poses[0].y;
  for (const TimedPose& pose : poses) {
    x_min = std::min(x_min, pose.x);
    x_max = std::max(x_max, pose.x);
    y_min = std::min(y_min, pose.y);
    y_max = std::max(y_max, pose.y);
  }
  const double m = options.landmark_margin;
  std::vector<Landmark> landmarks(options.num_landmarks);
  for (int i = 0; i < options.num_landmarks; ++i) {
    landmarks[i].id = i;
    landmarks[i].x = random.Uniform(x_min - m, x_max + m);
    landmarks[i].y = random.Uniform(y_min - m, y_max + m);
  }
  return landmarks;
}

// Landmarks in the view of random poses, then extra ones for any pose that
// sees fewer than min_visible_landmarks. Fills `visible` per pose. Fails only
// when the geometry leaves no room (a view too small for double precision).
bool LandmarksAlongPath(const SimulationOptions& options,
                        const std::vector<TimedPose>& poses,
                        std::vector<Landmark>* landmarks,
                        std::vector<std::vector<int>>* visible,
                        std::string* error) {
  SimulationRandom random(StreamSeed(options.seed, Stream::kLandmarks));
  landmarks->clear();
  LandmarkGrid grid(options.sensor_range);
  auto add = [&](Landmark landmark) {
    landmark.id = static_cast<LandmarkId>(landmarks->size());
    grid.Add(landmark, static_cast<int>(landmarks->size()));
    landmarks->push_back(landmark);
  };
  for (int i = 0; i < options.num_landmarks; ++i) {
    add(LandmarkInView(options, poses[random.Index(poses.size())], &random));
  }
  // Adding a landmark only raises the counts of other poses, so one pass in
  // order leaves every pose with enough.
  for (const TimedPose& pose : poses) {
    int count =
        static_cast<int>(grid.Visible(options, pose, *landmarks).size());
    int attempts = 0;
    while (count < options.min_visible_landmarks) {
      if (++attempts > 100 * options.min_visible_landmarks ||
          landmarks->size() >= static_cast<std::size_t>(kMaxLandmarks)) {
        *error = "cannot place " +
                 std::to_string(options.min_visible_landmarks) +
                 " visible landmarks around the pose at t = " +
                 FormatNumber(pose.t) + " (sensor_range " +
                 FormatNumber(options.sensor_range) + ", min_range " +
                 FormatNumber(options.min_range) + ")";
        return false;
      }
      const Landmark landmark = LandmarkInView(options, pose, &random);
      if (IsVisible(options, pose, landmark)) {
        add(landmark);
        ++count;
      }
    }
  }
  visible->clear();
  visible->reserve(poses.size());
  for (const TimedPose& pose : poses) {
    visible->push_back(grid.Visible(options, pose, *landmarks));
  }
  return true;
}

void AddMetadata(const SimulationOptions& options, int num_landmarks,
                 Dataset* dataset) {
  auto add = [dataset](const std::string& key, const std::string& value) {
    dataset->metadata.emplace_back(key, value);
  };
  auto number = [](double value) { return FormatNumber(value); };
  auto flag = [](bool value) { return std::string(value ? "true" : "false"); };
  add("source", "rff_simulate");
  add("simulator_version", "1");
  add("seed", std::to_string(options.seed));
  add("preset", options.preset);
  add("trajectory", TrajectoryShapeName(options.trajectory));
  add("num_steps", std::to_string(options.num_steps));
  add("dt", number(options.dt));
  add("speed", number(options.speed));
  add("landmarks", std::to_string(num_landmarks));
  add("landmarks_requested", std::to_string(options.num_landmarks));
  add("landmark_margin", number(options.landmark_margin));
  add("landmark_prior_sigma", number(options.landmark_prior_sigma));
  add("kind", MeasurementKindName(options.kind));
  add("sigma_range", number(options.sigma_range));
  add("sigma_bearing", number(options.sigma_bearing));
  add("sigma_bearing_deg", number(options.sigma_bearing * 180.0 / M_PI));
  add("observations_per_step", std::to_string(options.observations_per_step));
  add("sensor_range", number(options.sensor_range));
  add("min_range", number(options.min_range));
  add("field_of_view", number(options.field_of_view));
  add("min_visible_landmarks", std::to_string(options.min_visible_landmarks));
  add("odometry", flag(options.odometry));
  add("odometry_sigma_xy", number(options.odometry_sigma_xy));
  add("odometry_sigma_theta", number(options.odometry_sigma_theta));
  add("first_pose_sigma_xy", number(options.first_pose_sigma_xy));
  add("first_pose_sigma_theta", number(options.first_pose_sigma_theta));
  add("noise_free", flag(options.noise_free));
  // Keys that older files do not have are written only when in use, so
  // that the paper and kitti_scale files stay byte for byte as they were.
  if (options.observe_nearest) add("observe_nearest", flag(true));
  if (options.trajectory == TrajectoryShape::kGpDraw) {
    add("gp_kernel", options.gp_kernel);
    add("gp_lengthscale", number(options.gp_lengthscale));
    add("gp_kernel_variance", number(options.gp_kernel_variance));
    add("gp_heading_lengthscale", number(options.gp_heading_lengthscale));
    add("gp_heading_kernel_variance",
        number(options.gp_heading_kernel_variance));
    add("truth", GpDrawTruth(options));
  }
}

// The `count` candidates nearest to `pose` at least min_range away, nearest
// first (ties by index), in place at the front of `candidates`; returns how
// many there are.
std::size_t SelectNearest(const SimulationOptions& options,
                          const TimedPose& pose,
                          const std::vector<Landmark>& landmarks,
                          std::vector<int>* candidates) {
  std::vector<std::pair<double, int>> by_distance;
  for (const int index : *candidates) {
    const double dx = landmarks[index].x - pose.x;
    const double dy = landmarks[index].y - pose.y;
    const double squared = dx * dx + dy * dy;
    if (squared >= options.min_range * options.min_range) {
      by_distance.emplace_back(squared, index);
    }
  }
  const std::size_t count = std::min<std::size_t>(
      options.observations_per_step, by_distance.size());
  std::partial_sort(by_distance.begin(), by_distance.begin() + count,
                    by_distance.end());
  for (std::size_t j = 0; j < count; ++j) {
    (*candidates)[j] = by_distance[j].second;
  }
  return count;
}

}  // namespace

bool ValidateSimulationOptions(const SimulationOptions& o, std::string* error) {
  OptionChecker check(error);
  check.IntAtLeast("num_steps", o.num_steps, 1, kMaxSteps);
  check.Positive("dt", o.dt);
  check.NonNegative("speed", o.speed);
  check.IntAtLeast("landmarks", o.num_landmarks, 1, kMaxLandmarks);
  check.NonNegative("landmark_margin", o.landmark_margin);
  check.NonNegative("landmark_prior_sigma", o.landmark_prior_sigma);
  check.Positive("sigma_range", o.sigma_range);
  check.Positive("sigma_bearing", o.sigma_bearing);
  check.IntAtLeast("observations_per_step", o.observations_per_step, 1,
                   kMaxLandmarks);
  check.NonNegative("sensor_range", o.sensor_range);
  check.NonNegative("min_range", o.min_range);
  check.Positive("field_of_view", o.field_of_view);
  check.IntAtLeast("min_visible_landmarks", o.min_visible_landmarks, 0, 10000);
  check.Positive("odometry_sigma_xy", o.odometry_sigma_xy);
  check.Positive("odometry_sigma_theta", o.odometry_sigma_theta);
  check.Positive("first_pose_sigma_xy", o.first_pose_sigma_xy);
  check.Positive("first_pose_sigma_theta", o.first_pose_sigma_theta);
  if (!check.ok()) return false;
  if (o.trajectory == TrajectoryShape::kGpDraw &&
      !ValidateGpDrawOptions(o, error)) {
    return false;
  }
  const bool preset_is_word =
      !o.preset.empty() && o.preset.size() <= 64 &&
      std::all_of(o.preset.begin(), o.preset.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' ||
               c == '-';
      });
  if (!preset_is_word) {
    check.Fail(OptionError("preset", o.preset, "",
                           "one word of up to 64 letters, digits, '_' or '-'"));
  } else if (o.field_of_view > 2.0 * M_PI) {
    check.Fail(OptionError("field_of_view", FormatNumber(o.field_of_view),
                           "more than all around", "more than 0 up to 2 pi"));
  } else if (o.sensor_range > 0.0 && o.sensor_range <= o.min_range) {
    check.Fail(OptionError(
        "sensor_range", FormatNumber(o.sensor_range),
        "sees nothing beyond --min_range=" + FormatNumber(o.min_range),
        "0 (every landmark visible) or more than " +
            FormatNumber(o.min_range)));
  } else if (o.sensor_range == 0.0 &&
             o.min_visible_landmarks > o.num_landmarks) {
    check.Fail(OptionError(
        "min_visible_landmarks", std::to_string(o.min_visible_landmarks),
        "more than --landmarks=" + std::to_string(o.num_landmarks) +
            ", and no --sensor_range to place more",
        "at most " + std::to_string(o.num_landmarks)));
  } else if (o.sensor_range == 0.0 && !o.observe_nearest &&
             o.observations_per_step > o.num_landmarks) {
    // Each step observes distinct landmarks, drawn from all of them.
    check.Fail(OptionError(
        "observations_per_step", std::to_string(o.observations_per_step),
        "more than --landmarks=" + std::to_string(o.num_landmarks) +
            ", and each step observes distinct landmarks",
        "at most " + std::to_string(o.num_landmarks) +
            " (or a --sensor_range or --observe_nearest, which observe as "
            "many as they find)"));
  } else if (static_cast<std::int64_t>(o.num_steps) *
                 (o.sensor_range > 0.0
                      ? o.observations_per_step
                      : std::min(o.observations_per_step, o.num_landmarks)) >
             kMaxObservations) {
    check.Fail(OptionError(
        "observations_per_step", std::to_string(o.observations_per_step),
        "with --num_steps=" + std::to_string(o.num_steps) + " more than " +
            std::to_string(kMaxObservations) + " observations",
        "at most " + std::to_string(kMaxObservations / o.num_steps) +
            " for these steps"));
  }
  return check.ok();
}

bool Simulate(const SimulationOptions& options, Dataset* dataset,
              std::string* error) {
  if (!ValidateSimulationOptions(options, error)) return false;
  *dataset = Dataset();
  std::vector<TimedPose> poses;
  if (!SimulateTrajectory(options, &poses, error)) return false;

  const bool use_visibility = options.sensor_range > 0.0;
  std::vector<std::vector<int>> visible;
  std::vector<Landmark> landmarks;
  if (use_visibility) {
    if (!LandmarksAlongPath(options, poses, &landmarks, &visible, error)) {
      return false;
    }
  } else {
    landmarks = LandmarksInBox(options, poses);
  }
  const int num_landmarks = static_cast<int>(landmarks.size());
  // Zero scale keeps every draw in place, so a noise-free file differs from
  // the noisy one with the same seed by the noise alone.
  const double noise = options.noise_free ? 0.0 : 1.0;

  AddMetadata(options, num_landmarks, dataset);
  PosePrior first;
  first.pose = poses[0];
  first.sigma_xy = options.first_pose_sigma_xy;
  first.sigma_theta = options.first_pose_sigma_theta;
  dataset->pose_priors.push_back(first);

  if (options.landmark_prior_sigma > 0.0) {
    SimulationRandom random(StreamSeed(options.seed, Stream::kLandmarkPriors));
    const double sigma = options.landmark_prior_sigma;
    for (const Landmark& landmark : landmarks) {
      LandmarkPrior prior;
      prior.id = landmark.id;
      prior.x = landmark.x + noise * sigma * random.Normal();
      prior.y = landmark.y + noise * sigma * random.Normal();
      prior.sigma = sigma;
      dataset->landmark_priors.push_back(prior);
    }
  }

  SimulationRandom selection(StreamSeed(options.seed, Stream::kSelection));
  SimulationRandom measurement(
      StreamSeed(options.seed, Stream::kMeasurementNoise));
  std::vector<int> candidates(num_landmarks);
  std::iota(candidates.begin(), candidates.end(), 0);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const TimedPose& pose = poses[k];
    if (use_visibility) {
      candidates = visible[k];
    } else if (options.observe_nearest) {
      std::iota(candidates.begin(), candidates.end(), 0);
    }
    // Nearest first, or a partial Fisher-Yates shuffle: the first `count`
    // entries are a uniformly random ordered sample without replacement.
    const std::size_t count =
        options.observe_nearest
            ? SelectNearest(options, pose, landmarks, &candidates)
            : std::min<std::size_t>(options.observations_per_step,
                                    candidates.size());
    for (std::size_t j = 0; j < count; ++j) {
      if (!options.observe_nearest) {
        std::swap(candidates[j],
                  candidates[j + selection.Index(candidates.size() - j)]);
      }
      const Landmark& landmark = landmarks[candidates[j]];
      const double dx = landmark.x - pose.x;
      const double dy = landmark.y - pose.y;
      // Both draws always happen, so every kind sees the same noise.
      const double range_noise =
          noise * options.sigma_range * measurement.Normal();
      const double bearing_noise =
          noise * options.sigma_bearing * measurement.Normal();
      Observation observation;
      observation.t = pose.t;
      observation.id = landmark.id;
      observation.type = options.kind;
      if (observation.HasRange()) {
        // Plain Gaussian noise: near a landmark the measured range may be
        // negative, as in the shared benchmark sets (the format allows it).
        observation.range = std::sqrt(dx * dx + dy * dy) + range_noise;
        observation.sigma_range = options.sigma_range;
      }
      if (observation.HasBearing()) {
        observation.bearing =
            WrapAngle(std::atan2(dy, dx) - pose.theta + bearing_noise);
        observation.sigma_bearing = options.sigma_bearing;
      }
      dataset->observations.push_back(observation);
    }
  }

  if (options.odometry) {
    SimulationRandom random(StreamSeed(options.seed, Stream::kOdometryNoise));
    for (std::size_t k = 1; k < poses.size(); ++k) {
      const TimedPose& from = poses[k - 1];
      const TimedPose& to = poses[k];
      const double c = std::cos(from.theta);
      const double s = std::sin(from.theta);
      const double dx = to.x - from.x;
      const double dy = to.y - from.y;
      Odometry odometry;
      odometry.t0 = from.t;
      odometry.t1 = to.t;
      odometry.dx =
          c * dx + s * dy + noise * options.odometry_sigma_xy * random.Normal();
      odometry.dy = -s * dx + c * dy +
                    noise * options.odometry_sigma_xy * random.Normal();
      odometry.dtheta =
          WrapAngle(to.theta - from.theta +
                    noise * options.odometry_sigma_theta * random.Normal());
      odometry.sigma_x = options.odometry_sigma_xy;
      odometry.sigma_y = options.odometry_sigma_xy;
      odometry.sigma_theta = options.odometry_sigma_theta;
      dataset->odometry.push_back(odometry);
    }
  }

  dataset->ground_truth = poses;
  dataset->ground_truth_landmarks = landmarks;
  return true;
}

}  // namespace rff
