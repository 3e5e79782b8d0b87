#include "rff_ceres/io/landmarks_io.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>

#include "rff_ceres/io/output_file.h"
#include "rff_ceres/io/text_parser.h"

namespace rff {

void WriteLandmarks(std::vector<Landmark> landmarks, std::ostream* output) {
  std::sort(landmarks.begin(), landmarks.end(),
            [](const Landmark& a, const Landmark& b) { return a.id < b.id; });
  const bool with_covariance =
      !landmarks.empty() && landmarks.front().has_covariance;
  for (const Landmark& l : landmarks) {
    *output << l.id << " " << FormatNumber(l.x) << " " << FormatNumber(l.y);
    if (with_covariance) {
      *output << " " << FormatNumber(l.sxx) << " " << FormatNumber(l.sxy) << " "
              << FormatNumber(l.syy);
    }
    *output << "\n";
  }
}

bool WriteLandmarks(const std::vector<Landmark>& landmarks,
                    const std::string& path, std::string* error) {
  return WriteOutputFile(
      path, [&](std::ostream* out) { WriteLandmarks(landmarks, out); }, error);
}

bool ParseLandmarks(std::istream* input, const std::string& source,
                    std::vector<Landmark>* landmarks, std::string* error) {
  landmarks->clear();
  LineReader reader(input, source);
  std::vector<std::string_view> fields;
  std::set<LandmarkId> ids;
  while (reader.Next(&fields)) {
    if (fields.size() != 3 && fields.size() != 6) {
      *error = reader.Error(
          "a landmark needs 3 fields (id x y) or 6 (id x y sxx sxy syy), got " +
          std::to_string(fields.size()));
      return false;
    }
    Landmark l;
    if (!ParseNonNegativeInt(fields[0], &l.id)) {
      *error =
          reader.Error("landmark id '" + std::string(fields[0].substr(0, 64)) +
                       "' is not a non-negative 64-bit integer");
      return false;
    }
    double v[5];
    if (!ParseFiniteDoubles(reader, fields, 1, fields.size() - 1, v, error)) {
      return false;
    }
    l.x = v[0];
    l.y = v[1];
    if (fields.size() == 6) {
      l.has_covariance = true;
      l.sxx = v[2];
      l.sxy = v[3];
      l.syy = v[4];
      // sxy^2 <= sxx syy; with the square roots when the products overflow
      // (inf > inf would pass any sxy).
      const double product = l.sxx * l.syy;
      const bool correlated_too_much =
          std::isinf(product) || std::isinf(l.sxy * l.sxy)
              ? std::abs(l.sxy) > std::sqrt(l.sxx) * std::sqrt(l.syy)
              : l.sxy * l.sxy > product;
      if (l.sxx < 0.0 || l.syy < 0.0 || correlated_too_much) {
        *error = reader.Error("covariance is not positive semi-definite");
        return false;
      }
    }
    if (!ids.insert(l.id).second) {
      *error = reader.Error("duplicate landmark id " + std::to_string(l.id));
      return false;
    }
    landmarks->push_back(l);
  }
  if (!reader.ok()) {
    *error = reader.error();
    return false;
  }
  std::sort(landmarks->begin(), landmarks->end(),
            [](const Landmark& a, const Landmark& b) { return a.id < b.id; });
  return true;
}

bool ReadLandmarks(const std::string& path, std::vector<Landmark>* landmarks,
                   std::string* error) {
  std::ifstream stream;
  if (!OpenForReading(path, &stream, error)) return false;
  return ParseLandmarks(&stream, path, landmarks, error);
}

}  // namespace rff
