// Line-oriented parsing shared by every text reader of the project (.rffd,
// TUM, .landmarks and the raw dataset layouts the converters read).
//
// The readers are strict: each malformed line is reported with the file name,
// the line number and the problem, never skipped. Numbers must parse whole and
// be finite ("nan", "inf" and overflowing values such as 1e999 are errors).
#ifndef RFF_CERES_IO_TEXT_PARSER_H_
#define RFF_CERES_IO_TEXT_PARSER_H_

#include <cmath>
#include <cstdint>
#include <fstream>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

#include "costs/angle.h"  // WrapAngle, for the readers and writers.

namespace rff {

// Longest line a reader accepts; anything longer is binary junk or a broken
// file, and reading it whole could exhaust memory.
inline constexpr std::size_t kMaxLineLength = 1 << 16;

// Reads records from a text stream: strips '#' comments and CR before LF,
// skips blank lines, splits on blanks and tabs.
class LineReader {
 public:
  // `source` names the input in error messages (usually the file path).
  LineReader(std::istream* input, std::string source);

  // Reads the next record into `fields`. Returns false at the end of the input
  // or on an unreadable line; then ok() tells which, and error() says why.
  bool Next(std::vector<std::string_view>* fields);

  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }

  // The text after '#' on the current line ("" when it has none).
  std::string_view comment() const { return comment_; }
  // The comment-only lines before the first record (metadata lines).
  const std::vector<std::string>& leading_comments() const {
    return leading_comments_;
  }
  int line_number() const { return line_number_; }
  const std::string& source() const { return source_; }

  // "source:line: message", the form of every reader error.
  std::string Error(const std::string& message) const;

 private:
  std::istream* input_;
  std::string source_;
  std::string line_;
  std::string_view comment_;
  int line_number_ = 0;
  bool seen_record_ = false;
  std::vector<std::string> leading_comments_;
  std::string error_;
};

// Parses a whole field as a finite double.
bool ParseFiniteDouble(std::string_view field, double* value);

// Parses a whole field as a non-negative 64-bit integer (no sign, no
// exponent); values that overflow are rejected.
bool ParseNonNegativeInt(std::string_view field, std::int64_t* value);

// Parses the fields [first, first + count) of `fields` as finite doubles.
// On failure sets `error` (through `reader`) naming the bad field.
bool ParseFiniteDoubles(const LineReader& reader,
                        const std::vector<std::string_view>& fields,
                        std::size_t first, std::size_t count, double* values,
                        std::string* error);

// Shortest text that parses back to exactly `value` (std::to_chars).
std::string FormatNumber(double value);

// `text` as a JSON string literal, quotes included, with '"', '\\' and
// control characters escaped.
std::string JsonString(const std::string& text);

// Opens `path` for reading; on failure sets `error` ("cannot open ...").
bool OpenForReading(const std::string& path, std::ifstream* stream,
                    std::string* error);

// "a", "a or b", "a, b or c": the allowed values of an option, for messages.
std::string JoinAlternatives(const std::vector<std::string>& names);

// `text` with every occurrence of `from` (not empty) replaced by `to`, left
// to right; a replacement is not searched again.
std::string ReplaceAll(std::string text, const std::string& from,
                       const std::string& to);

}  // namespace rff

#endif  // RFF_CERES_IO_TEXT_PARSER_H_
