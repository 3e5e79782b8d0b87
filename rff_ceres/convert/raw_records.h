// Strict readers of the whitespace-separated raw files of the public datasets
// (one record per line, `#` comments), shared by the converters.
#ifndef RFF_CERES_CONVERT_RAW_RECORDS_H_
#define RFF_CERES_CONVERT_RAW_RECORDS_H_

#include <cmath>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/types.h"

namespace rff {

// Reads every record of `path`; each must have exactly `num_fields` fields.
// `parse_row(reader, fields, error)` handles one record. A file without data
// rows is an error. When `leading_comments` is not null it receives the
// comment-only lines before the first record (the text after '#'), where
// some raw layouts declare per-recording constants.
template <typename RowParser>
bool ReadRecords(const std::string& path, std::size_t num_fields,
                 RowParser parse_row, std::string* error,
                 std::vector<std::string>* leading_comments = nullptr) {
  std::ifstream stream;
  if (!OpenForReading(path, &stream, error)) return false;
  LineReader reader(&stream, path);
  std::vector<std::string_view> fields;
  std::size_t rows = 0;
  while (reader.Next(&fields)) {
    if (fields.size() != num_fields) {
      *error = reader.Error("expected " + std::to_string(num_fields) +
                            " fields, got " + std::to_string(fields.size()));
      return false;
    }
    if (!parse_row(reader, fields, error)) return false;
    ++rows;
  }
  if (!reader.ok()) {
    *error = reader.error();
    return false;
  }
  if (rows == 0) {
    *error = path + ": no data rows";
    return false;
  }
  if (leading_comments != nullptr) {
    *leading_comments = reader.leading_comments();
  }
  return true;
}

// Parses field number `column` (1-based, for the message) as a non-negative
// integer (an id, a barcode, a subject).
inline bool ParseRawInteger(const LineReader& reader, std::string_view field,
                            int column, LandmarkId* value, std::string* error) {
  if (!ParseNonNegativeInt(field, value)) {
    *error = reader.Error("field " + std::to_string(column) + " '" +
                          std::string(field.substr(0, 64)) +
                          "' is not a non-negative integer");
    return false;
  }
  return true;
}

}  // namespace rff

#endif  // RFF_CERES_CONVERT_RAW_RECORDS_H_
