// Landmark files: one landmark per line, `id x y` or `id x y sxx sxy syy`
// (with the position covariance), sorted by id.
#ifndef RFF_CERES_IO_LANDMARKS_IO_H_
#define RFF_CERES_IO_LANDMARKS_IO_H_

#include <istream>
#include <ostream>
#include <string>
#include <vector>

#include "rff_ceres/types.h"

namespace rff {

// Writes the landmarks sorted by id; the covariance columns are written for
// all rows when the first landmark has one.
void WriteLandmarks(std::vector<Landmark> landmarks, std::ostream* output);
bool WriteLandmarks(const std::vector<Landmark>& landmarks,
                    const std::string& path, std::string* error);

// Reads a landmark file; ids must be unique, a covariance must be symmetric
// positive semi-definite (sxx >= 0, syy >= 0, sxy^2 <= sxx syy).
bool ParseLandmarks(std::istream* input, const std::string& source,
                    std::vector<Landmark>* landmarks, std::string* error);
bool ReadLandmarks(const std::string& path, std::vector<Landmark>* landmarks,
                   std::string* error);

}  // namespace rff

#endif  // RFF_CERES_IO_LANDMARKS_IO_H_
