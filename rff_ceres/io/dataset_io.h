// Reader and writer of the .rffd dataset format (docs/FORMAT.md).
#ifndef RFF_CERES_IO_DATASET_IO_H_
#define RFF_CERES_IO_DATASET_IO_H_

#include <istream>
#include <ostream>
#include <string>
#include <vector>

#include "rff_ceres/types.h"

namespace rff {

// Reads a .rffd file. Returns false and sets `error` to "path:line: problem"
// on the first malformed record; never skips a line. On success the
// observations, odometry and ground truth are sorted by time and the landmark
// lists by id.
bool ReadDataset(const std::string& path, Dataset* dataset, std::string* error);

// The same from a stream; `source` names it in error messages.
bool ParseDataset(std::istream* input, const std::string& source,
                  Dataset* dataset, std::string* error);

// Sorts the records as the reader does: observations, odometry and ground
// truth by time (stable: equal times keep their order), landmarks by id. For
// the converters that build a Dataset from other formats.
void SortRecords(Dataset* dataset);

// Appends the `key: value` lines of `comments` (the text after '#' of the
// lines before the first record) to the dataset's metadata; prose is skipped.
void ParseMetadata(const std::vector<std::string>& comments, Dataset* dataset);

// Writes `dataset` as .rffd (metadata as leading `# key: value` comments).
// Numbers are written in the shortest form that reads back exactly.
void WriteDataset(const Dataset& dataset, std::ostream* output);
bool WriteDataset(const Dataset& dataset, const std::string& path,
                  std::string* error);

}  // namespace rff

#endif  // RFF_CERES_IO_DATASET_IO_H_
