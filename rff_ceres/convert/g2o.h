// Converter between .rffd and the 2D records of g2o's text format
// (github.com/RainerKuemmerle/g2o, types_slam2d), one record per line:
//
//   VERTEX_SE2 id x y theta              VERTEX_XY id x y
//   EDGE_SE2 id0 id1 dx dy dtheta i6     EDGE_SE2_XY pose landmark x y i3
//   EDGE_BEARING_SE2_XY pose landmark bearing i1
//   EDGE_PRIOR_SE2 id x y theta i6       FIX id...
//
// iN: the upper triangle of an information matrix, row by row; '#' starts
// a comment. Vertex values are starting estimates, not truth, and g2o has
// no timestamps: the writer puts each pose's time in a trailing comment
// "# t=SECONDS", which g2o ignores, and the reader takes the times from
// there, from a rate, or from the vertex order.
#ifndef RFF_CERES_CONVERT_G2O_H_
#define RFF_CERES_CONVERT_G2O_H_

#include <cstddef>
#include <istream>
#include <ostream>
#include <string>

#include "rff_ceres/types.h"

namespace rff {

struct G2oReadOptions {
  // When > 0, the k-th pose vertex in id order is at k / rate seconds (the
  // "# t=" comments are not used); when 0, the comments give the times, or
  // without them the vertex order, 1 s apart.
  double rate = 0.0;
  // PRIOR_POSE sigmas for the FIX'd pose vertices (or the first one) when
  // the file has no EDGE_PRIOR_SE2; the mean is the vertex estimate.
  double prior_sigma_xy = 0.01;
  double prior_sigma_theta = 0.01;
};

struct G2oReadSummary {
  std::size_t pose_vertices = 0;
  std::size_t landmark_vertices = 0;
  std::string times;             // Where the times came from, for the user.
  std::size_t priors_added = 0;  // PRIOR_POSE made for FIX or the first pose.
};

// Reads a g2o 2D file into `dataset` (sorted as the .rffd reader sorts).
// Landmark ids are the g2o vertex ids; EDGE_SE2_XY becomes RANGE_BEARING
// (ToRangeBearing). Leading "# key: value" comments become metadata. Fails
// with "source:line: problem" on a malformed line and on what .rffd cannot
// express (correlated noise, an edge back in time).
bool ParseG2o(std::istream* input, const std::string& source,
              const G2oReadOptions& options, Dataset* dataset,
              G2oReadSummary* summary, std::string* error);
bool ReadG2o(const std::string& path, const G2oReadOptions& options,
             Dataset* dataset, G2oReadSummary* summary, std::string* error);

struct G2oWriteSummary {
  std::size_t pose_vertices = 0;
  std::size_t landmark_vertices = 0;
  // Records g2o's 2D types cannot express, left out.
  std::size_t ranges_left_out = 0;
  std::size_t landmark_priors_left_out = 0;
  std::size_t ground_truth_left_out = 0;  // GT_POSE and GT_LANDMARK.
};

// Writes `dataset` as g2o 2D. Landmarks keep their ids; the pose vertices
// (PoseVertexTimes without the RANGE records, dead-reckoned values) follow the
// largest landmark id in time order. PRIOR_POSE becomes EDGE_PRIOR_SE2,
// RANGE_BEARING EDGE_SE2_XY (ToRelativePosition), BEARING EDGE_BEARING_SE2_XY;
// metadata stays as comments. Fails when a RANGE_BEARING range is not > 0 or an
// id does not fit g2o's int. The file is written only when complete.
bool WriteG2o(const Dataset& dataset, std::ostream* output,
              G2oWriteSummary* summary, std::string* error);
bool WriteG2o(const Dataset& dataset, const std::string& path,
              G2oWriteSummary* summary, std::string* error);

}  // namespace rff

#endif  // RFF_CERES_CONVERT_G2O_H_
