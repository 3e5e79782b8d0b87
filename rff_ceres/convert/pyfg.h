// Converter between .rffd and PyFG, the text format of PyFactorGraph
// (github.com/MarineRoboticsGroup/PyFactorGraph, py_factor_graph/io/
// pyfg_text.py) in which the CORA range-aided SLAM datasets are published.
// The 2D records, one per line, fields separated by blanks:
//
//   VERTEX_SE2 t A12 x y theta           VERTEX_XY L3 x y
//   VERTEX_SE2:PRIOR t A0 x y theta c6   VERTEX_XY:PRIOR t L3 x y c3
//   EDGE_SE2 t A0 A1 dx dy dtheta c6     EDGE_SE2_XY t A2 L3 x y c3
//   EDGE_RANGE t A2 L3 range variance
//
// cN: the upper triangle of a covariance, row by row. A pose is named by its
// robot (one capital letter other than L) and its number, a landmark by L
// and its id. Vertex values are the true poses and landmark positions
// (PyFG's own meaning), so they read as GT_POSE and GT_LANDMARK.
#ifndef RFF_CERES_CONVERT_PYFG_H_
#define RFF_CERES_CONVERT_PYFG_H_

#include <cstddef>
#include <istream>
#include <ostream>
#include <string>

#include "rff_ceres/types.h"

namespace rff {

struct PyfgReadOptions {
  // The robot whose trajectory is read ("A"); empty: the file's only one.
  std::string robot;
  // When > 0, pose number k is at k / rate seconds and the file's vertex
  // timestamps are not used.
  double rate = 0.0;
  // PRIOR_POSE sigmas at the robot's first pose when the file has no
  // VERTEX_SE2:PRIOR for it (the mean is that vertex).
  double prior_sigma_xy = 0.01;
  double prior_sigma_theta = 0.01;
};

struct PyfgReadSummary {
  std::string robot;
  std::string robots;  // Every robot of the file, "A, B or C".
  std::size_t num_robots = 0;
  std::size_t records = 0;
  // Vertices, priors and edges that concern other robots only.
  std::size_t other_robot_records = 0;
  // Edges between the robot and another robot: .rffd has one robot, so
  // they are left out (EDGE_SE2 and EDGE_RANGE).
  std::size_t inter_robot_edges = 0;
  bool prior_added = false;  // No VERTEX_SE2:PRIOR for the robot.
};

// Reads a 2D PyFG file into `dataset` (records sorted as the .rffd reader
// sorts them). Fails with "source:line: problem" on a malformed line, on
// what .rffd cannot express (correlated noise, an edge back in time, a range
// between two poses of the robot), and on a bad option.
bool ParsePyfg(std::istream* input, const std::string& source,
               const PyfgReadOptions& options, Dataset* dataset,
               PyfgReadSummary* summary, std::string* error);
bool ReadPyfg(const std::string& path, const PyfgReadOptions& options,
              Dataset* dataset, PyfgReadSummary* summary, std::string* error);

struct PyfgWriteSummary {
  std::size_t pose_vertices = 0;
  std::size_t landmark_vertices = 0;
  // Where the pose vertex values come from: a GT_POSE at that time, ground
  // truth interpolated, or dead reckoning (no ground truth there).
  std::size_t poses_from_truth = 0;
  std::size_t poses_interpolated = 0;
  std::size_t poses_dead_reckoned = 0;
  // Landmarks without GT_LANDMARK: the prior mean, else (0, 0).
  std::size_t landmarks_without_truth = 0;
  // Pose vertices at observation times between ODOM endpoints: no EDGE_SE2
  // reaches them (a discrete solver needs them associated with a pose).
  std::size_t poses_without_odometry = 0;
  std::size_t bearings_left_out = 0;  // PyFG has no bearing edge.
};

// Writes `dataset` as PyFG for robot A: one pose vertex per time of
// PoseVertexTimes, named A0, A1, ... in time order. RANGE_BEARING becomes
// EDGE_SE2_XY (ToRelativePosition); GT_POSE and GT_LANDMARK become the
// vertex values; metadata is lost (PyFG has no comments). Fails when a
// RANGE_BEARING range is not > 0. The file is written only when complete.
bool WritePyfg(const Dataset& dataset, std::ostream* output,
               PyfgWriteSummary* summary, std::string* error);
bool WritePyfg(const Dataset& dataset, const std::string& path,
               PyfgWriteSummary* summary, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_CONVERT_PYFG_H_
