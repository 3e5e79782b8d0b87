#include "rff_ceres/io/flagfile_check.h"

#include <sys/stat.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "test/test_files.h"

namespace rff {
namespace {

using testing::TempDir;
using testing::WriteFile;

FlagKind Kind(const std::string& name) {
  if (name == "num_features" || name == "prior") return FlagKind::kValued;
  if (name == "evaluate" || name == "noevaluate") return FlagKind::kBoolean;
  return FlagKind::kUnknown;
}

std::string Check(const std::vector<std::string>& args) {
  std::string error;
  return CheckFlagfiles(args, Kind, &error) ? "ok" : error;
}

TEST(FlagfileCheckTest, AcceptsCommentsBlanksAndKnownFlags) {
  const std::string dir = TempDir("FlagfileCheckTest");
  WriteFile(dir + "/a.flags",
            "# a comment\n\n  --prior=wnoa\n-num_features=12\n--noevaluate\n");
  EXPECT_EQ(Check({"--flagfile=" + dir + "/a.flags"}), "ok");
  EXPECT_EQ(Check({"--flagfile", dir + "/a.flags"}), "ok");
  EXPECT_EQ(Check({"--prior=rff"}), "ok");
}

TEST(FlagfileCheckTest, AnUnknownFlagInsideIsAnError) {
  const std::string dir = TempDir("FlagfileCheckTest");
  WriteFile(dir + "/typo.flags", "--prior=wnoa\n--num_featurs=12\n");
  EXPECT_EQ(Check({"--flagfile=" + dir + "/typo.flags"}),
            dir + "/typo.flags:2: unknown flag '--num_featurs'");
  WriteFile(dir + "/bare.flags", "num_features=12\n");
  EXPECT_EQ(
      Check({"--flagfile=" + dir + "/bare.flags"}),
      dir + "/bare.flags:1: expected --name=value, got 'num_features=12'");
}

TEST(FlagfileCheckTest, SelfInclusionIsAnError) {
  const std::string dir = TempDir("FlagfileCheckTest");
  WriteFile(dir + "/self.flags", "--flagfile=" + dir + "/self.flags\n");
  EXPECT_EQ(Check({"--flagfile=" + dir + "/self.flags"}),
            "--flagfile=" + dir + "/self.flags: includes itself");
  WriteFile(dir + "/a.flags", "--flagfile=" + dir + "/b.flags\n");
  WriteFile(dir + "/b.flags", "--prior=rff\n--flagfile=" + dir + "/a.flags\n");
  EXPECT_EQ(Check({"--flagfile=" + dir + "/a.flags"}),
            "--flagfile=" + dir +
                "/a.flags: includes itself through other "
                "flagfiles");
}

// Read here, a pipe would reach gflags empty (its flags silently lost); a
// device may never end.
TEST(FlagfileCheckTest, APipeOrADeviceIsAnError) {
  const std::string fifo = TempDir("FlagfileCheckTest") + "/flags.pipe";
  ::unlink(fifo.c_str());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(Check({"--flagfile=" + fifo}),
            "--flagfile=" + fifo +
                ": not a regular file (a device, pipe or socket); allowed a "
                "file path");
  EXPECT_EQ(Check({"--flagfile=/dev/zero"}),
            "--flagfile=/dev/zero: not a regular file (a device, pipe or "
            "socket); allowed a file path");
}

// gflags skips an empty flagfile name, on the command line or inside.
TEST(FlagfileCheckTest, AnEmptyFlagfileNameIsAnError) {
  EXPECT_EQ(Check({"--flagfile="}),
            "--flagfile=: an empty file name; allowed comma-separated file "
            "paths");
  const std::string dir = TempDir("FlagfileCheckTest");
  WriteFile(dir + "/a.flags", "--prior=rff\n");
  EXPECT_EQ(Check({"--flagfile=" + dir + "/a.flags,"}),
            "--flagfile=" + dir +
                "/a.flags,: an empty file name; allowed comma-separated file "
                "paths");
  WriteFile(dir + "/outer.flags", "--flagfile=\n");
  EXPECT_EQ(Check({"--flagfile=" + dir + "/outer.flags"}),
            dir +
                "/outer.flags:1: --flagfile=: an empty file name; allowed "
                "comma-separated file paths");
}

// gflags drops a valued flag's line without its value; a boolean needs none.
TEST(FlagfileCheckTest, AValuedFlagWithoutItsValueIsAnError) {
  const std::string dir = TempDir("FlagfileCheckTest");
  WriteFile(dir + "/bare.flags", "--evaluate\n--noevaluate\n--prior\n");
  EXPECT_EQ(Check({"--flagfile=" + dir + "/bare.flags"}),
            dir + "/bare.flags:3: '--prior' needs a value: --prior=VALUE");
  WriteFile(dir + "/empty.flags", "--prior=\n");
  EXPECT_EQ(Check({"--flagfile=" + dir + "/empty.flags"}), "ok");
}

// gflags would read FLAGS_flagfile from the environment unchecked.
TEST(FlagfileCheckTest, AFlagfileFromTheEnvironmentIsAnError) {
  const std::string why =
      ": a flagfile read from the environment (directly or through another "
      "--fromenv) is not checked; allowed --flagfile=PATH instead";
  EXPECT_EQ(Check({"--fromenv=flagfile"}), "--fromenv=flagfile" + why);
  EXPECT_EQ(Check({"--tryfromenv", "prior,flagfile"}),
            "--tryfromenv=prior,flagfile" + why);
  EXPECT_EQ(Check({"--fromenv=prior"}), "ok");
  // FLAGS_fromenv=flagfile would be read through a second --fromenv.
  EXPECT_EQ(Check({"--fromenv=fromenv"}), "--fromenv=fromenv" + why);
  EXPECT_EQ(Check({"--fromenv=prior,tryfromenv"}),
            "--fromenv=prior,tryfromenv" + why);
  const std::string dir = TempDir("FlagfileCheckTest");
  WriteFile(dir + "/env.flags", "--prior=rff\n--tryfromenv=flagfile\n");
  EXPECT_EQ(Check({"--flagfile=" + dir + "/env.flags"}),
            dir + "/env.flags:2: --tryfromenv=flagfile" + why);
}

TEST(FlagfileCheckTest, TheSameFileTwiceWithoutACycleIsFine) {
  const std::string dir = TempDir("FlagfileCheckTest");
  WriteFile(dir + "/common.flags", "--prior=rff\n");
  WriteFile(dir + "/a.flags", "--flagfile=" + dir + "/common.flags\n");
  EXPECT_EQ(Check({"--flagfile=" + dir + "/a.flags," + dir + "/common.flags"}),
            "ok");
}

TEST(FlagfileCheckTest, TheVisitorSeesEveryFlagLineInGflagsOrder) {
  const std::string dir = TempDir("FlagfileCheckTest");
  WriteFile(dir + "/inner.flags", "--num_features=12\n");
  WriteFile(dir + "/outer.flags", "# c\n  --prior=wnoa\n--flagfile=" + dir +
                                      "/inner.flags\n--noevaluate\n");
  std::vector<std::string> seen;
  const FlagLineVisitor record =
      [&seen](const std::string& where, const std::string& line, std::string*) {
        seen.push_back(where + line);
        return true;
      };
  std::string error;
  ASSERT_TRUE(CheckFlagfiles({"--flagfile=" + dir + "/outer.flags"}, Kind,
                             &error, record))
      << error;
  EXPECT_EQ(seen,
            (std::vector<std::string>{dir + "/outer.flags:2:   --prior=wnoa",
                                      dir + "/inner.flags:1: --num_features=12",
                                      dir + "/outer.flags:4: --noevaluate"}));

  const FlagLineVisitor refuse = [](const std::string& where,
                                    const std::string& line,
                                    std::string* error) {
    *error = where + "refused '" + line + "'";
    return false;
  };
  EXPECT_FALSE(CheckFlagfiles({"--flagfile=" + dir + "/outer.flags"}, Kind,
                              &error, refuse));
  EXPECT_EQ(error, dir + "/outer.flags:2: refused '  --prior=wnoa'");
}

TEST(FlagfileCheckTest, AMissingFileOrDirectoryIsAnError) {
  const std::string dir = TempDir("FlagfileCheckTest");
  EXPECT_EQ(Check({"--flagfile=" + dir + "/none.flags"}),
            "--flagfile=" + dir + "/none.flags: cannot open for reading");
  EXPECT_EQ(Check({"--flagfile=" + dir}),
            "--flagfile=" + dir + ": a directory; allowed a file path");
}

}  // namespace
}  // namespace rff
