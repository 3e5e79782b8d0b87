#include "rff_ceres/io/text_parser.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

namespace rff {

LineReader::LineReader(std::istream* input, std::string source)
    : input_(input), source_(std::move(source)) {}

std::string LineReader::Error(const std::string& message) const {
  return source_ + ":" + std::to_string(line_number_) + ": " + message;
}

bool LineReader::Next(std::vector<std::string_view>* fields) {
  fields->clear();
  while (true) {
    comment_ = std::string_view();
    line_.clear();
    // Read one line by hand so that a huge line is refused before it is
    // held in memory whole, through the stream's buffer (istream::get
    // builds a sentry per char). A failed read throws there (libstdc++'s
    // filebuf) where get would set badbit: a read error either way.
    std::streambuf* buffer = input_->rdbuf();
    bool got_any = false;
    try {
      int c;
      while ((c = buffer->sbumpc()) != std::char_traits<char>::eof()) {
        got_any = true;
        if (c == '\n') break;
        if (line_.size() >= kMaxLineLength) {
          ++line_number_;
          error_ = Error("line longer than " + std::to_string(kMaxLineLength) +
                         " bytes (binary or broken file?)");
          return false;
        }
        line_.push_back(static_cast<char>(c));
      }
    } catch (const std::exception&) {
      error_ = Error("read error");
      return false;
    }
    if (!got_any) {
      if (input_->bad()) error_ = Error("read error");
      return false;
    }
    ++line_number_;
    if (!line_.empty() && line_.back() == '\r') line_.pop_back();
    // A UTF-8 byte order mark (written by some Windows editors) is not text.
    if (line_number_ == 1 && line_.compare(0, 3, "\xEF\xBB\xBF") == 0) {
      line_.erase(0, 3);
    }
    if (line_.find('\0') != std::string::npos) {
      error_ = Error("NUL byte in line (binary file?)");
      return false;
    }
    std::string_view text(line_);
    const std::size_t hash = text.find('#');
    if (hash != std::string_view::npos) {
      comment_ = text.substr(hash + 1);
      text = text.substr(0, hash);
    }
    std::size_t i = 0;
    while (i < text.size()) {
      while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
      if (i >= text.size()) break;
      std::size_t j = i;
      while (j < text.size() && text[j] != ' ' && text[j] != '\t') ++j;
      fields->push_back(text.substr(i, j - i));
      i = j;
    }
    if (!fields->empty()) {
      seen_record_ = true;
      return true;
    }
    if (!seen_record_ && !comment_.empty()) {
      leading_comments_.emplace_back(comment_);
    }
  }
}

bool ParseFiniteDouble(std::string_view field, double* value) {
  if (field.empty() || field.size() > 64) return false;
  // from_chars reads a subset of strtod's grammar (no '+', no hex) and
  // rounds alike; what it does not take whole and finite, strtod decides.
  double fast = 0.0;
  const char* last = field.data() + field.size();
  const std::from_chars_result read = std::from_chars(field.data(), last, fast);
  if (read.ec == std::errc() && read.ptr == last && std::isfinite(fast)) {
    *value = fast;
    return true;
  }
  char buffer[65];
  std::memcpy(buffer, field.data(), field.size());
  buffer[field.size()] = '\0';
  char* end = nullptr;
  errno = 0;
  const double parsed = std::strtod(buffer, &end);
  if (end != buffer + field.size()) return false;
  if (!std::isfinite(parsed)) return false;
  // strtod sets ERANGE on overflow (returns inf, caught above) and on
  // underflow; underflow to a denormal or zero is harmless.
  *value = parsed;
  return true;
}

bool ParseNonNegativeInt(std::string_view field, std::int64_t* value) {
  if (field.empty()) return false;
  std::int64_t result = 0;
  for (const char c : field) {
    if (c < '0' || c > '9') return false;
    const int digit = c - '0';
    if (result > (std::numeric_limits<std::int64_t>::max() - digit) / 10) {
      return false;
    }
    result = result * 10 + digit;
  }
  *value = result;
  return true;
}

bool ParseFiniteDoubles(const LineReader& reader,
                        const std::vector<std::string_view>& fields,
                        std::size_t first, std::size_t count, double* values,
                        std::string* error) {
  for (std::size_t k = 0; k < count; ++k) {
    const std::string_view field = fields[first + k];
    if (!ParseFiniteDouble(field, &values[k])) {
      *error = reader.Error("field " + std::to_string(first + k + 1) + " '" +
                            std::string(field.substr(0, 64)) +
                            "' is not a finite number");
      return false;
    }
  }
  return true;
}

std::string FormatNumber(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string JsonString(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
          out += buffer;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

std::string JoinAlternatives(const std::vector<std::string>& names) {
  std::string joined;
  for (std::size_t i = 0; i < names.size(); ++i) {
    joined += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  }
  return joined;
}

std::string ReplaceAll(std::string text, const std::string& from,
                       const std::string& to) {
  for (std::size_t at = text.find(from); at != std::string::npos;
       at = text.find(from, at + to.size())) {
    text.replace(at, from.size(), to);
  }
  return text;
}

namespace {

// A named pipe: opening it to read waits, maybe forever, for a writer. An
// anonymous one (a shell's <(...), /dev/fd/N, its link "pipe:[inode]")
// has its writer already and opens at once.
bool IsNamedPipe(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_fifo(path, ec)) return false;
  fs::path at = path;
  for (int hop = 0; hop < 40 && fs::is_symlink(at, ec); ++hop) {
    const fs::path target = fs::read_symlink(at, ec);
    if (ec) break;
    if (target.string().rfind("pipe:", 0) == 0) return false;
    at = target.is_absolute() ? target : at.parent_path() / target;
  }
  return true;
}

}  // namespace

bool OpenForReading(const std::string& path, std::ifstream* stream,
                    std::string* error) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    *error = path + ": cannot open for reading: is a directory, not a file";
    return false;
  }
  if (IsNamedPipe(path)) {
    *error = path +
             ": cannot open for reading: is a named pipe, which may wait "
             "forever for a writer; give a file, or the pipe as <(cat " +
             path + ")";
    return false;
  }
  stream->open(path, std::ios::in | std::ios::binary);
  if (!stream->is_open()) {
    *error = path + ": cannot open for reading: " + std::strerror(errno);
    return false;
  }
  return true;
}

}  // namespace rff
