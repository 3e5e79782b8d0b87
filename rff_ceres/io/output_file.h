// Output files that never destroy data: each is written to a temporary file
// beside its path and renamed over it only when complete, so a reader sees
// the old file or the new one, never a part; and every output path is
// checked against the inputs and the other outputs before any work.
#ifndef RFF_CERES_IO_OUTPUT_FILE_H_
#define RFF_CERES_IO_OUTPUT_FILE_H_

#include <fstream>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace rff {

// Whether `a` and `b` name one file: the same device and inode when both
// exist, else the same resolved path.
bool SameFile(const std::string& a, const std::string& b);

// One path given to a tool, with the flag that named it (for messages).
struct NamedPath {
  std::string flag;  // "--output_trajectory"
  std::string path;  // Empty: not given, skipped.
};

// Before any work: every output's directory exists and is writable, no
// output is a directory, and no output is the same file as an input or as
// another output (the same path, or the same device and inode for files
// that exist). An input that is a directory covers every file under it.
// On failure `error` reads "--flag=path: why".
bool CheckOutputPaths(const std::vector<NamedPath>& inputs,
                      const std::vector<NamedPath>& outputs,
                      std::string* error);

// Writes `path` atomically: Open creates a temporary file in the same
// directory, Commit renames it over `path`; a file never committed (an
// error, an early return) is removed by the destructor.
class OutputFile {
 public:
  explicit OutputFile(std::string path);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  bool Open(std::string* error);
  std::ostream& stream() { return stream_; }
  // Flushes and closes the temporary file; on a write error removes it
  // (any old file at the path stays as it was).
  bool Close(std::string* error);
  // Closes the temporary file if still open and renames it over the path.
  bool Commit(std::string* error);

 private:
  void Discard();

  std::string path_;
  std::string temporary_;  // Empty when no temporary file exists.
  std::ofstream stream_;
};

// Writes `path` atomically with `write` (an OutputFile opened, written and
// committed).
bool WriteOutputFile(const std::string& path,
                     const std::function<void(std::ostream*)>& write,
                     std::string* error);

}  // namespace rff

#endif  // RFF_CERES_IO_OUTPUT_FILE_H_
