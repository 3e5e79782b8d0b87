// libFuzzer target of the .rffd reader (see test/fuzz/README.md).
//
// Feeds the bytes to ParseDataset and checks the reader's contract on every
// input: a rejected input has an error that names the source; an accepted
// one holds only finite numbers and positive sigmas, is sorted, and survives
// WriteDataset -> ParseDataset bit for bit.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>

#include "rff_ceres/io/dataset_io.h"

namespace {

constexpr char kSource[] = "fuzz.rffd";

[[noreturn]] void Violation(const char* what) {
  std::fprintf(stderr, "dataset_fuzzer: contract violated: %s\n", what);
  std::abort();
}

void Check(bool condition, const char* what) {
  if (!condition) Violation(what);
}

bool Same(double a, double b) { return std::memcmp(&a, &b, sizeof(a)) == 0; }

bool Finite(std::initializer_list<double> values) {
  for (const double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

bool Wrapped(double angle) { return angle > -M_PI && angle <= M_PI; }

void CheckAccepted(const rff::Dataset& d) {
  Check(!d.pose_priors.empty(), "accepted without PRIOR_POSE");
  for (const rff::PosePrior& p : d.pose_priors) {
    Check(Finite({p.pose.t, p.pose.x, p.pose.y, p.pose.theta, p.sigma_xy,
                  p.sigma_theta}),
          "PRIOR_POSE not finite");
    Check(p.sigma_xy > 0.0 && p.sigma_theta > 0.0, "PRIOR_POSE sigma <= 0");
    Check(Wrapped(p.pose.theta), "PRIOR_POSE theta not wrapped");
  }
  for (std::size_t i = 0; i < d.landmark_priors.size(); ++i) {
    const rff::LandmarkPrior& p = d.landmark_priors[i];
    Check(p.id >= 0, "negative PRIOR_LANDMARK id");
    Check(Finite({p.x, p.y, p.sigma}) && p.sigma > 0.0, "bad PRIOR_LANDMARK");
    Check(i == 0 || d.landmark_priors[i - 1].id < p.id,
          "PRIOR_LANDMARK not sorted by unique id");
  }
  for (std::size_t i = 0; i < d.odometry.size(); ++i) {
    const rff::Odometry& o = d.odometry[i];
    Check(Finite({o.t0, o.t1, o.dx, o.dy, o.dtheta, o.sigma_x, o.sigma_y,
                  o.sigma_theta}),
          "ODOM not finite");
    Check(o.t1 > o.t0, "ODOM with t1 <= t0");
    Check(o.sigma_x > 0.0 && o.sigma_y > 0.0 && o.sigma_theta > 0.0,
          "ODOM sigma <= 0");
    Check(Wrapped(o.dtheta), "ODOM dtheta not wrapped");
    Check(i == 0 || d.odometry[i - 1].t0 <= o.t0, "ODOM not sorted");
  }
  for (std::size_t i = 0; i < d.observations.size(); ++i) {
    const rff::Observation& o = d.observations[i];
    Check(o.id >= 0, "negative observation id");
    Check(Finite({o.t, o.range, o.bearing, o.sigma_range, o.sigma_bearing}),
          "observation not finite");
    Check(!o.HasRange() || o.sigma_range > 0.0, "sigma_range <= 0");
    Check(!o.HasBearing() || o.sigma_bearing > 0.0, "sigma_bearing <= 0");
    Check(Wrapped(o.bearing), "bearing not wrapped");
    Check(i == 0 || d.observations[i - 1].t <= o.t, "observations not sorted");
  }
  for (std::size_t i = 0; i < d.ground_truth.size(); ++i) {
    const rff::TimedPose& p = d.ground_truth[i];
    Check(Finite({p.t, p.x, p.y, p.theta}) && Wrapped(p.theta), "bad GT_POSE");
    Check(i == 0 || d.ground_truth[i - 1].t < p.t,
          "GT_POSE not strictly increasing");
  }
  for (std::size_t i = 0; i < d.ground_truth_landmarks.size(); ++i) {
    const rff::Landmark& l = d.ground_truth_landmarks[i];
    Check(l.id >= 0 && Finite({l.x, l.y}), "bad GT_LANDMARK");
    Check(i == 0 || d.ground_truth_landmarks[i - 1].id < l.id,
          "GT_LANDMARK not sorted by unique id");
  }
}

void CheckRoundTrip(const rff::Dataset& d) {
  std::ostringstream out;
  rff::WriteDataset(d, &out);
  std::istringstream in(out.str());
  rff::Dataset back;
  std::string error;
  if (!rff::ParseDataset(&in, kSource, &back, &error)) {
    std::fprintf(stderr, "re-read failed: %s\n", error.c_str());
    Violation("written dataset does not read back");
  }
  Check(back.metadata == d.metadata, "metadata changed in round trip");
  Check(
      back.pose_priors.size() == d.pose_priors.size() &&
          back.landmark_priors.size() == d.landmark_priors.size() &&
          back.odometry.size() == d.odometry.size() &&
          back.observations.size() == d.observations.size() &&
          back.ground_truth.size() == d.ground_truth.size() &&
          back.ground_truth_landmarks.size() == d.ground_truth_landmarks.size(),
      "record count changed in round trip");
  for (std::size_t i = 0; i < d.pose_priors.size(); ++i) {
    const rff::PosePrior &a = d.pose_priors[i], &b = back.pose_priors[i];
    Check(Same(a.pose.t, b.pose.t) && Same(a.pose.x, b.pose.x) &&
              Same(a.pose.y, b.pose.y) && Same(a.pose.theta, b.pose.theta) &&
              Same(a.sigma_xy, b.sigma_xy) &&
              Same(a.sigma_theta, b.sigma_theta),
          "PRIOR_POSE changed in round trip");
  }
  for (std::size_t i = 0; i < d.odometry.size(); ++i) {
    const rff::Odometry &a = d.odometry[i], &b = back.odometry[i];
    Check(Same(a.t0, b.t0) && Same(a.t1, b.t1) && Same(a.dx, b.dx) &&
              Same(a.dy, b.dy) && Same(a.dtheta, b.dtheta) &&
              Same(a.sigma_x, b.sigma_x) && Same(a.sigma_y, b.sigma_y) &&
              Same(a.sigma_theta, b.sigma_theta),
          "ODOM changed in round trip");
  }
  for (std::size_t i = 0; i < d.observations.size(); ++i) {
    const rff::Observation &a = d.observations[i], &b = back.observations[i];
    Check(a.type == b.type && a.id == b.id && Same(a.t, b.t) &&
              Same(a.range, b.range) && Same(a.bearing, b.bearing) &&
              Same(a.sigma_range, b.sigma_range) &&
              Same(a.sigma_bearing, b.sigma_bearing),
          "observation changed in round trip");
  }
  for (std::size_t i = 0; i < d.ground_truth.size(); ++i) {
    const rff::TimedPose &a = d.ground_truth[i], &b = back.ground_truth[i];
    Check(Same(a.t, b.t) && Same(a.x, b.x) && Same(a.y, b.y) &&
              Same(a.theta, b.theta),
          "GT_POSE changed in round trip");
  }
  for (std::size_t i = 0; i < d.landmark_priors.size(); ++i) {
    const rff::LandmarkPrior &a = d.landmark_priors[i],
                             &b = back.landmark_priors[i];
    Check(a.id == b.id && Same(a.x, b.x) && Same(a.y, b.y) &&
              Same(a.sigma, b.sigma),
          "PRIOR_LANDMARK changed in round trip");
  }
  for (std::size_t i = 0; i < d.ground_truth_landmarks.size(); ++i) {
    const rff::Landmark &a = d.ground_truth_landmarks[i],
                        &b = back.ground_truth_landmarks[i];
    Check(a.id == b.id && Same(a.x, b.x) && Same(a.y, b.y),
          "GT_LANDMARK changed in round trip");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data,
                                      std::size_t size) {
  std::istringstream input(
      std::string(reinterpret_cast<const char*>(data), size));
  rff::Dataset dataset;
  std::string error;
  if (!rff::ParseDataset(&input, kSource, &dataset, &error)) {
    Check(error.rfind(kSource, 0) == 0, "error does not start with source");
    return 0;
  }
  Check(error.empty(), "accepted input left an error message");
  CheckAccepted(dataset);
  CheckRoundTrip(dataset);
  return 0;
}
