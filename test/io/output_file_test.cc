#include "rff_ceres/io/output_file.h"

#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <string>

#include "gtest/gtest.h"
#include "test/test_files.h"

namespace rff {
namespace {

using testing::ReadFile;
using testing::TempDir;
using testing::WriteFile;

// Names in `dir` other than the given ones (left-over temporary files).
int CountFiles(const std::string& dir) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    (void)entry;
    ++count;
  }
  return count;
}

TEST(OutputFileTest, CommitReplacesTheFileWhole) {
  const std::string dir = TempDir("OutputFileTest");
  WriteFile(dir + "/out.txt", "old\n");
  OutputFile file(dir + "/out.txt");
  std::string error;
  ASSERT_TRUE(file.Open(&error)) << error;
  file.stream() << "new\n";
  // Until the commit a reader sees the old file.
  EXPECT_EQ(ReadFile(dir + "/out.txt"), "old\n");
  ASSERT_TRUE(file.Commit(&error)) << error;
  EXPECT_EQ(ReadFile(dir + "/out.txt"), "new\n");
  EXPECT_EQ(CountFiles(dir), 1);
}

TEST(OutputFileTest, AnUncommittedFileLeavesTheOldOneAndNoTemporary) {
  const std::string dir = TempDir("OutputFileTest");
  WriteFile(dir + "/out.txt", "old\n");
  {
    OutputFile file(dir + "/out.txt");
    std::string error;
    ASSERT_TRUE(file.Open(&error)) << error;
    file.stream() << "half a li";
  }
  EXPECT_EQ(ReadFile(dir + "/out.txt"), "old\n");
  EXPECT_EQ(CountFiles(dir), 1);
}

// A write that fails midway (here the file-size limit, as a full disk
// would) reports the error and leaves the previous file as it was.
TEST(OutputFileTest, AWriteErrorKeepsThePreviousFile) {
  const std::string dir = TempDir("OutputFileTest");
  WriteFile(dir + "/out.txt", "old\n");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit = {4096, 4096};
    setrlimit(RLIMIT_FSIZE, &limit);
    OutputFile file(dir + "/out.txt");
    std::string error;
    if (!file.Open(&error)) _exit(2);
    for (int i = 0; i < 100000; ++i) file.stream() << "0123456789\n";
    _exit(file.Commit(&error) ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  EXPECT_EQ(ReadFile(dir + "/out.txt"), "old\n");
  EXPECT_EQ(CountFiles(dir), 1);
}

TEST(OutputFileTest, OpenFailsForAMissingDirectory) {
  const std::string dir = TempDir("OutputFileTest");
  OutputFile file(dir + "/no/out.txt");
  std::string error;
  EXPECT_FALSE(file.Open(&error));
  EXPECT_EQ(error, dir +
                       "/no/out.txt: cannot open for writing: No such file "
                       "or directory");
}

TEST(CheckOutputPathsTest, RefusesAnInputUnderAnySpelling) {
  const std::string dir = TempDir("CheckOutputPathsTest");
  WriteFile(dir + "/in.rffd", "RFFD 1\n");
  std::filesystem::create_hard_link(dir + "/in.rffd", dir + "/link.rffd");
  std::string error;
  for (const std::string& output :
       {dir + "/in.rffd", dir + "/./in.rffd",
        dir + "/../" + std::filesystem::path(dir).filename().string() +
            "/in.rffd",
        dir + "/link.rffd"}) {
    EXPECT_FALSE(CheckOutputPaths({{"--dataset", dir + "/in.rffd"}},
                                  {{"--output_trajectory", output}}, &error))
        << output;
    EXPECT_EQ(error, "--output_trajectory=" + output +
                         ": the same file as the input --dataset=" + dir +
                         "/in.rffd, never overwritten; allowed another path");
  }
}

TEST(CheckOutputPathsTest, RefusesTwoOutputsOnOnePath) {
  const std::string dir = TempDir("CheckOutputPathsTest");
  std::string error;
  EXPECT_FALSE(CheckOutputPaths(
      {}, {{"--a", dir + "/o.txt"}, {"--b", ""}, {"--c", dir + "/./o.txt"}},
      &error));
  EXPECT_EQ(error, "--c=" + dir + "/./o.txt: the same file as the output --a=" +
                       dir + "/o.txt; allowed a path of its own");
}

// Relative spellings of one file that does not exist yet, from the working
// directory: "o.txt", "./o.txt" and "../<dir>/o.txt" are one output.
TEST(CheckOutputPathsTest, RefusesTwoRelativeSpellingsOfANewFile) {
  const std::string dir = TempDir("CheckOutputPathsTest");
  const std::filesystem::path previous = std::filesystem::current_path();
  std::filesystem::current_path(dir);
  const std::string name = std::filesystem::path(dir).filename().string();
  std::string error;
  const bool dot =
      CheckOutputPaths({}, {{"--a", "new.txt"}, {"--b", "./new.txt"}}, &error);
  const std::string dot_error = error;
  const bool parent = CheckOutputPaths(
      {}, {{"--a", "new.txt"}, {"--b", "../" + name + "/new.txt"}}, &error);
  std::filesystem::current_path(previous);
  EXPECT_FALSE(dot);
  EXPECT_EQ(dot_error,
            "--b=./new.txt: the same file as the output --a=new.txt; allowed "
            "a path of its own");
  EXPECT_FALSE(parent);
  EXPECT_FALSE(std::filesystem::exists(dir + "/new.txt"));
}

TEST(CheckOutputPathsTest, RefusesAFileOfAnInputDirectory) {
  const std::string dir = TempDir("CheckOutputPathsTest");
  std::filesystem::create_directories(dir + "/raw");
  WriteFile(dir + "/raw/GT.txt", "1 2 3\n");
  std::string error;
  EXPECT_FALSE(CheckOutputPaths({{"--input", dir + "/raw"}},
                                {{"--output", dir + "/raw/GT.txt"}}, &error));
  EXPECT_EQ(error,
            "--output=" + dir +
                "/raw/GT.txt: a file of the input directory --input=" + dir +
                "/raw, never overwritten; allowed a path outside "
                "it");
  // A new file beside the raw ones overwrites nothing.
  EXPECT_TRUE(CheckOutputPaths({{"--input", dir + "/raw"}},
                               {{"--output", dir + "/raw/new.rffd"}}, &error))
      << error;
}

TEST(CheckOutputPathsTest, ChecksTheDirectoryBeforeAnyWork) {
  const std::string dir = TempDir("CheckOutputPathsTest");
  WriteFile(dir + "/file", "");
  std::string error;
  EXPECT_FALSE(CheckOutputPaths({}, {{"--o", dir + "/no/o.txt"}}, &error));
  EXPECT_EQ(error, "--o=" + dir + "/no/o.txt: directory '" + dir +
                       "/no' does not exist");
  EXPECT_FALSE(CheckOutputPaths({}, {{"--o", dir + "/file/o.txt"}}, &error));
  EXPECT_EQ(error, "--o=" + dir + "/file/o.txt: directory '" + dir +
                       "/file' is not a directory");
  EXPECT_FALSE(CheckOutputPaths({}, {{"--o", dir}}, &error));
  EXPECT_EQ(error, "--o=" + dir + ": a directory; allowed a file path");
  EXPECT_TRUE(CheckOutputPaths({}, {{"--o", dir + "/o.txt"}}, &error)) << error;
  // A name longer than the file system allows once the temporary file's
  // suffix is added fails here, not after a solve; the check leaves nothing.
  const std::string long_name(250, 'x');
  EXPECT_FALSE(CheckOutputPaths({}, {{"--o", dir + "/" + long_name}}, &error));
  EXPECT_EQ(error, "--o=" + (dir + "/" + long_name).substr(0, 200) +
                       "...: the file name is 250 characters long; allowed "
                       "at most 244 characters (the file system's 255 less "
                       "the temporary name's suffix)");
  const std::string longest(244, 'x');
  EXPECT_TRUE(CheckOutputPaths({}, {{"--o", dir + "/" + longest}}, &error))
      << error;
  EXPECT_EQ(CountFiles(dir), 1);
}

// Renaming over a device or a pipe would replace it with a plain file.
TEST(CheckOutputPathsTest, RefusesWhatIsNotARegularFile) {
  const std::string dir = TempDir("CheckOutputPathsTest");
  ASSERT_EQ(mkfifo((dir + "/pipe").c_str(), 0600), 0);
  std::string error;
  EXPECT_FALSE(CheckOutputPaths({}, {{"--o", dir + "/pipe"}}, &error));
  EXPECT_EQ(error, "--o=" + dir +
                       "/pipe: not a regular file (a device, pipe or "
                       "socket); allowed a regular file path: the output "
                       "replaces the file");
  EXPECT_FALSE(CheckOutputPaths({}, {{"--o", "/dev/null"}}, &error));
  EXPECT_TRUE(std::filesystem::is_fifo(dir + "/pipe"));
}

// Another user's file in a sticky directory cannot be renamed over: refused
// before any work. Run as root, the check runs in a child as user 65534.
TEST(CheckOutputPathsTest, RefusesAnotherUsersFileInAStickyDirectory) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root to make another user's file";
  const std::string dir = TempDir("CheckOutputPathsTest") + "/sticky";
  ASSERT_TRUE(std::filesystem::create_directory(dir));
  ASSERT_EQ(chmod(dir.c_str(), 01777), 0);
  WriteFile(dir + "/root.txt", "root's\n");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::string error;
    const bool refused =
        setgid(65534) == 0 && setuid(65534) == 0 &&
        !CheckOutputPaths({}, {{"--o", dir + "/root.txt"}}, &error) &&
        error == "--o=" + dir +
                     "/root.txt: another user's file in a sticky directory, "
                     "which cannot be replaced; allowed a path of your own" &&
        CheckOutputPaths({}, {{"--o", dir + "/mine.txt"}}, &error);
    _exit(refused ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(ReadFile(dir + "/root.txt"), "root's\n");
}

// A replaced file keeps its permissions.
TEST(OutputFileTest, CommitKeepsTheModeOfTheFileItReplaces) {
  const std::string dir = TempDir("OutputFileTest");
  WriteFile(dir + "/private.txt", "old\n");
  ASSERT_EQ(chmod((dir + "/private.txt").c_str(), 0600), 0);
  std::string error;
  ASSERT_TRUE(WriteOutputFile(
      dir + "/private.txt", [](std::ostream* out) { *out << "new\n"; }, &error))
      << error;
  struct stat written;
  ASSERT_EQ(stat((dir + "/private.txt").c_str(), &written), 0);
  EXPECT_EQ(written.st_mode & 07777, 0600u);
  EXPECT_EQ(ReadFile(dir + "/private.txt"), "new\n");
  // A read-only file is replaced all the same (the directory is writable)
  // and stays read-only; setuid bits are not carried over.
  WriteFile(dir + "/readonly.txt", "old\n");
  ASSERT_EQ(chmod((dir + "/readonly.txt").c_str(), 04444), 0);
  ASSERT_TRUE(WriteOutputFile(
      dir + "/readonly.txt", [](std::ostream* out) { *out << "new\n"; },
      &error))
      << error;
  ASSERT_EQ(stat((dir + "/readonly.txt").c_str(), &written), 0);
  EXPECT_EQ(written.st_mode & 07777, 0444u);
  EXPECT_EQ(ReadFile(dir + "/readonly.txt"), "new\n");
}

}  // namespace
}  // namespace rff
