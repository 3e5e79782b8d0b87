// TUM trajectory files: one pose per line, `t x y z qx qy qz qw`, the format
// read by evo and most SLAM benchmarks. Planar poses are written with z = 0,
// qx = qy = 0, qz = sin(theta / 2), qw = cos(theta / 2).
#ifndef RFF_CERES_IO_TUM_IO_H_
#define RFF_CERES_IO_TUM_IO_H_

#include <istream>
#include <ostream>
#include <string>
#include <vector>

#include "rff_ceres/types.h"

namespace rff {

// Writes poses sorted by time (the caller's order is kept; it must be sorted).
void WriteTum(const std::vector<TimedPose>& poses, std::ostream* output);
bool WriteTum(const std::vector<TimedPose>& poses, const std::string& path,
              std::string* error);

// Reads a TUM file. The heading is the yaw of the quaternion (z and the roll
// and pitch are ignored). Times must strictly increase; the quaternion must
// have a non-zero norm.
bool ParseTum(std::istream* input, const std::string& source,
              std::vector<TimedPose>* poses, std::string* error);
bool ReadTum(const std::string& path, std::vector<TimedPose>* poses,
             std::string* error);

}  // namespace rff

#endif  // RFF_CERES_IO_TUM_IO_H_
