#include "rff_ceres/io/output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <utility>

#include "rff_ceres/option_error.h"

namespace rff {
namespace {

namespace fs = std::filesystem;

// The absolute, normalised form of `path` with its existing part resolved
// (symbolic links included), so that two spellings of one file compare
// equal.
fs::path Resolved(const std::string& path) {
  std::error_code ec;
  // Absolute first: weakly_canonical keeps a relative path to a missing file
  // relative ("o.txt") but makes "./o.txt" absolute.
  const fs::path absolute = fs::absolute(path, ec).lexically_normal();
  fs::path resolved = fs::weakly_canonical(absolute, ec);
  if (ec) resolved = absolute;
  return resolved;
}

// Whether `file` lies under the directory `directory`.
bool IsUnder(const std::string& file, const std::string& directory) {
  const fs::path dir = Resolved(directory);
  const fs::path resolved = Resolved(file);
  auto d = dir.begin();
  auto f = resolved.begin();
  for (; d != dir.end(); ++d, ++f) {
    if (f == resolved.end() || *d != *f) return false;
  }
  return true;
}

std::string Named(const NamedPath& p) { return p.flag + "=" + p.path; }

// The option message about `p` (its flag without the leading "--").
std::string PathError(const NamedPath& p, const std::string& why,
                      const std::string& allowed = "") {
  const std::size_t dashes = p.flag.find_first_not_of('-');
  const std::string flag =
      dashes == std::string::npos ? p.flag : p.flag.substr(dashes);
  // A name too long for the file system is cut for the message.
  const std::string path =
      p.path.size() > 200 ? p.path.substr(0, 200) + "..." : p.path;
  return OptionError(flag, path, why, allowed);
}

// Outputs are first written to this file beside their path.
constexpr char kTemporarySuffix[] = ".tmp.XXXXXX";

std::string TemporaryPattern(const std::string& path) {
  return path + kTemporarySuffix;
}

bool CheckDirectory(const NamedPath& output, std::string* error) {
  std::error_code ec;
  const fs::file_status status = fs::status(output.path, ec);
  if (fs::is_directory(status)) {
    *error = PathError(output, "a directory", "a file path");
    return false;
  }
  // Renaming a new file over a device or a pipe would replace it.
  if (fs::exists(status) && !fs::is_regular_file(status)) {
    *error = PathError(output, "not a regular file (a device, pipe or socket)",
                       "a regular file path: the output replaces the file");
    return false;
  }
  // Longer names fail only when the file is opened, after the work.
  const std::string name = fs::path(output.path).filename().string();
  const std::size_t max_name = NAME_MAX - (sizeof(kTemporarySuffix) - 1);
  if (name.size() > max_name) {
    *error = PathError(
        output,
        "the file name is " + std::to_string(name.size()) + " characters long",
        "at most " + std::to_string(max_name) +
            " characters (the file system's " + std::to_string(NAME_MAX) +
            " less the temporary name's suffix)");
    return false;
  }
  fs::path directory = fs::path(output.path).parent_path();
  if (directory.empty()) directory = ".";
  if (!fs::is_directory(directory, ec)) {
    *error =
        PathError(output, "directory '" + directory.string() + "' " +
                              (fs::exists(directory, ec) ? "is not a directory"
                                                         : "does not exist"));
    return false;
  }
  // A trial temporary file, as Open makes it: permission bits alone miss
  // read-only file systems and directories that even root cannot write.
  std::string trial = TemporaryPattern(output.path);
  const int fd = mkstemp(trial.data());
  if (fd < 0) {
    *error =
        PathError(output, "directory '" + directory.string() +
                              "' is not writable: " + std::strerror(errno));
    return false;
  }
  close(fd);
  std::remove(trial.c_str());
  // In a sticky directory (/tmp) only a file's owner, the directory's or
  // root may rename over it.
  struct stat file, dir;
  if (stat(output.path.c_str(), &file) == 0 &&
      stat(directory.c_str(), &dir) == 0 && (dir.st_mode & S_ISVTX) != 0 &&
      geteuid() != 0 && file.st_uid != geteuid() && dir.st_uid != geteuid()) {
    *error = PathError(output,
                       "another user's file in a sticky directory, which "
                       "cannot be replaced",
                       "a path of your own");
    return false;
  }
  return true;
}

}  // namespace

bool SameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) {
    const bool same = fs::equivalent(a, b, ec);
    if (!ec) return same;
  }
  return Resolved(a) == Resolved(b);
}

bool CheckOutputPaths(const std::vector<NamedPath>& inputs,
                      const std::vector<NamedPath>& outputs,
                      std::string* error) {
  std::vector<const NamedPath*> checked;
  for (const NamedPath& output : outputs) {
    if (output.path.empty()) continue;
    if (!CheckDirectory(output, error)) return false;
    for (const NamedPath& input : inputs) {
      if (input.path.empty()) continue;
      std::error_code ec;
      const bool inside = fs::is_directory(input.path, ec) &&
                          fs::exists(output.path, ec) &&
                          IsUnder(output.path, input.path);
      if (inside || SameFile(output.path, input.path)) {
        *error = PathError(output,
                           (inside ? "a file of the input directory "
                                   : "the same file as the input ") +
                               Named(input) + ", never overwritten",
                           inside ? "a path outside it" : "another path");
        return false;
      }
    }
    for (const NamedPath* other : checked) {
      if (SameFile(output.path, other->path)) {
        *error =
            PathError(output, "the same file as the output " + Named(*other),
                      "a path of its own");
        return false;
      }
    }
    checked.push_back(&output);
  }
  return true;
}

OutputFile::OutputFile(std::string path) : path_(std::move(path)) {}

OutputFile::~OutputFile() { Discard(); }

void OutputFile::Discard() {
  if (stream_.is_open()) stream_.close();
  if (!temporary_.empty()) std::remove(temporary_.c_str());
  temporary_.clear();
}

bool OutputFile::Open(std::string* error) {
  Discard();
  std::error_code ec;
  if (fs::is_directory(path_, ec)) {
    *error = path_ + ": cannot open for writing: is a directory";
    return false;
  }
  std::string name = TemporaryPattern(path_);
  const int fd = mkstemp(name.data());
  if (fd < 0) {
    *error = path_ + ": cannot open for writing: " + std::strerror(errno);
    return false;
  }
  // mkstemp's 0600 while it is written; Commit gives it its final mode.
  close(fd);
  temporary_ = name;
  stream_.open(temporary_, std::ios::out | std::ios::trunc);
  if (!stream_.is_open()) {
    *error = path_ + ": cannot open for writing: " + std::strerror(errno);
    Discard();
    return false;
  }
  return true;
}

bool OutputFile::Close(std::string* error) {
  if (temporary_.empty()) {
    *error = path_ + ": write failed: the file was not opened";
    return false;
  }
  if (!stream_.is_open()) return true;
  stream_.flush();
  const bool written = static_cast<bool>(stream_);
  const int write_errno = errno;
  stream_.close();
  if (!written || stream_.fail()) {
    *error = path_ +
             ": write failed: " + std::strerror(written ? errno : write_errno) +
             "; the file was left as it was";
    Discard();
    return false;
  }
  // On disk before the rename: a crash then leaves the old file or the new.
  const int fd = open(temporary_.c_str(), O_RDONLY);
  const bool synced = fd >= 0 && fsync(fd) == 0;
  const int sync_errno = errno;
  if (fd >= 0) close(fd);
  if (!synced) {
    *error = path_ + ": write failed: " + std::strerror(sync_errno) +
             "; the file was left as it was";
    Discard();
    return false;
  }
  return true;
}

bool OutputFile::Commit(std::string* error) {
  if (!Close(error)) return false;
  // The mode of the file it replaces (a read-only one too: only the
  // directory must be writable), or the one a new file would get.
  struct stat old_file;
  mode_t mode;
  if (stat(path_.c_str(), &old_file) == 0 && S_ISREG(old_file.st_mode)) {
    mode = old_file.st_mode & 0777;
  } else {
    const mode_t mask = umask(0);
    umask(mask);
    mode = 0666 & ~mask;
  }
  chmod(temporary_.c_str(), mode);
  if (std::rename(temporary_.c_str(), path_.c_str()) != 0) {
    *error = path_ + ": cannot replace the file: " + std::strerror(errno);
    Discard();
    return false;
  }
  temporary_.clear();
  return true;
}

bool WriteOutputFile(const std::string& path,
                     const std::function<void(std::ostream*)>& write,
                     std::string* error) {
  OutputFile file(path);
  if (!file.Open(error)) return false;
  write(&file.stream());
  return file.Commit(error);
}

}  // namespace rff
