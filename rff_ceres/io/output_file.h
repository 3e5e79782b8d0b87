// Output files that never destroy data: each is written to a temporary file
// beside its path and renamed over it only when complete, so a reader sees
// the old file or the new one, never a part; and every output path is
// checked against the inputs and the other outputs before any work.
#ifndef RFF_CERES_IO_OUTPUT_FILE_H_
#define RFF_CERES_IO_OUTPUT_FILE_H_

#include <fstream>
#include <string>
#include <vector>

namespace rff {

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
  // Flushes and closes the temporary file and renames it over the path;
  // on a write error removes it and leaves any old file as it was.
  bool Commit(std::string* error);

  const std::string& path() const { return path_; }

 private:
  void Discard();

  std::string path_;
  std::string temporary_;  // Empty when no temporary file exists.
  std::ofstream stream_;
};

// Writes `text` to `path` atomically.
bool WriteTextFile(const std::string& path, const std::string& text,
                   std::string* error);

}  // namespace rff

#endif  // RFF_CERES_IO_OUTPUT_FILE_H_
