#include "rff_ceres/io/tum_io.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"

namespace rff {

void WriteTum(const std::vector<TimedPose>& poses, std::ostream* output) {
  for (const TimedPose& p : poses) {
    const double half = 0.5 * WrapAngle(p.theta);
    *output << FormatNumber(p.t) << " " << FormatNumber(p.x) << " "
            << FormatNumber(p.y) << " 0 0 0 " << FormatNumber(std::sin(half))
            << " " << FormatNumber(std::cos(half)) << "\n";
  }
}

bool WriteTum(const std::vector<TimedPose>& poses, const std::string& path,
              std::string* error) {
  return WriteOutputFile(
      path, [&](std::ostream* out) { WriteTum(poses, out); }, error);
}

bool ParseTum(std::istream* input, const std::string& source,
              std::vector<TimedPose>* poses, std::string* error) {
  poses->clear();
  LineReader reader(input, source);
  std::vector<std::string_view> fields;
  while (reader.Next(&fields)) {
    if (fields.size() != 8) {
      *error = reader.Error(
          "a TUM pose needs 8 fields (t x y z qx qy qz qw), "
          "got " +
          std::to_string(fields.size()));
      return false;
    }
    double v[8];
    if (!ParseFiniteDoubles(reader, fields, 0, 8, v, error)) return false;
    // Divide by the largest component first: the squares of components
    // above ~1e154 overflow to inf and would give a NaN yaw.
    const double scale = std::max(
        {std::abs(v[4]), std::abs(v[5]), std::abs(v[6]), std::abs(v[7])});
    if (!(scale > 0.0)) {
      *error = reader.Error("quaternion has zero norm");
      return false;
    }
    const double qx = v[4] / scale, qy = v[5] / scale, qz = v[6] / scale,
                 qw = v[7] / scale;
    const double norm2 = qx * qx + qy * qy + qz * qz + qw * qw;
    if (!(scale * scale * norm2 > 1e-12)) {
      *error = reader.Error("quaternion has zero norm");
      return false;
    }
    // Planar poses only: a 3-D pose's yaw and (x, y) would be compared as
    // if it were one, silently.
    constexpr double kMaxOffPlane = 1e-6;  // m, and rad of tilt.
    const double tilt = 2.0 * std::hypot(qx, qy) / std::sqrt(norm2);
    if (!(std::abs(v[3]) <= kMaxOffPlane) || !(tilt <= kMaxOffPlane)) {
      *error = reader.Error(
          "not a planar pose (z = " + FormatNumber(v[3]) + " m, tilt " +
          FormatNumber(tilt) + " rad; at most " + FormatNumber(kMaxOffPlane) +
          "): the tools compare planar trajectories, z = 0 and qx = qy = 0");
      return false;
    }
    if (!poses->empty() && !(v[0] > poses->back().t)) {
      *error = reader.Error("time " + FormatNumber(v[0]) +
                            " does not increase (previous " +
                            FormatNumber(poses->back().t) + ")");
      return false;
    }
    // Yaw of a (possibly unnormalised) quaternion.
    const double yaw = std::atan2(2.0 * (qw * qz + qx * qy),
                                  qw * qw + qx * qx - qy * qy - qz * qz);
    poses->push_back({v[0], v[1], v[2], WrapAngle(yaw)});
  }
  if (!reader.ok()) {
    *error = reader.error();
    return false;
  }
  if (poses->empty()) {
    *error = source + ": no poses (empty trajectory)";
    return false;
  }
  return true;
}

bool ReadTum(const std::string& path, std::vector<TimedPose>* poses,
             std::string* error) {
  std::ifstream stream;
  if (!OpenForReading(path, &stream, error)) return false;
  return ParseTum(&stream, path, poses, error);
}

}  // namespace rff
