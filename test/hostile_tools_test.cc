// Hostile flags, sizes and paths against the built tools: each case has one
// expected outcome. A refused case exits 1 with a message naming the cause,
// writes no output and leaves every input byte for byte as it was; an
// accepted one exits 0 with finite output.
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/io/tum_io.h"
#include "test/app_runner.h"
#include "test/test_files.h"

namespace rff {
namespace {

using ::testing::ContainsRegex;
using testing::Expand;
using testing::HasNonFiniteToken;
using ::testing::HasSubstr;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunResult;
using testing::ValidDataset;
using testing::WriteFile;

using HostileCase = testing::ToolCase;

// The files every case may use, in {dir}.
void WriteInputs(const std::string& dir) {
  const std::string valid = ValidDataset(0.0);
  WriteFile(dir + "/valid.rffd", valid);
  WriteFile(dir + "/self.flags", "--flagfile=" + dir + "/self.flags\n");
  WriteFile(dir + "/a.flags", "--flagfile=" + dir + "/b.flags\n");
  WriteFile(dir + "/b.flags", "--flagfile=" + dir + "/a.flags\n");
  WriteFile(dir + "/typo.flags", "--num_featurs=12\n");
  WriteFile(dir + "/my.flags", "--lengthscale=10\n");
  std::string tiny = valid;
  for (std::size_t at = tiny.find("0.05 0.05 0.01"); at != std::string::npos;
       at = tiny.find("0.05 0.05 0.01", at)) {
    tiny.replace(at, 14, "1e-100 1e-100 1e-100");
  }
  WriteFile(dir + "/tiny_odometry_sigma.rffd", tiny);
  WriteFile(dir + "/overflowing_odometry.rffd",
            "RFFD 1\nPRIOR_POSE 0 0 0 0 1 1\n"
            "ODOM 0 1 1e308 0 0 1e300 1 1\nODOM 1 2 1e308 0 0 1e300 1 1\n"
            "GT_POSE 2 0 0 0\n");
  WriteFile(dir + "/far_truth.rffd",
            "RFFD 1\nPRIOR_POSE 0 0 0 0 1 1\nGT_POSE 0 -1e308 0 0\n");
  WriteFile(dir + "/far.tum", "0 1e308 0 0 0 0 0 1\n");
  std::string many = valid;
  for (int id = 100; id < 100 + 10000; ++id) {
    many += "PRIOR_LANDMARK " + std::to_string(id) + " 0 0 1\n";
  }
  WriteFile(dir + "/many_landmarks.rffd", many);
  WriteFile(dir + "/overlapping_odometry.rffd",
            valid + "ODOM 2.5 3.5 1 0 0 0.05 0.05 0.01\n");
  WriteFile(dir + "/unlocatable.rffd",
            "RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.01\n"
            "ODOM 0 1 1 0 0 0.05 0.05 0.01\nRANGE 1 7 5 0.1\n");
  std::filesystem::create_directories(dir + "/raw");
  WriteFile(dir + "/raw/Plaza1_GT.txt", "raw ground truth\n");
}

class HostileToolTest : public ::testing::TestWithParam<HostileCase> {};

TEST_P(HostileToolTest, ExitsOneNamingTheCauseAndWritesNothing) {
  const std::string dir = testing::TempDir("hostile_tools_test");
  WriteInputs(dir);
  std::vector<std::pair<std::string, std::string>> inputs;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file()) {
      inputs.emplace_back(entry.path().string(), ReadFile(entry.path()));
    }
  }
  const RunResult run = RunCommand(Expand(GetParam().command, dir));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_THAT(run.output, HasSubstr(Expand(GetParam().message, dir)));
  const std::string output = Expand(GetParam().output, dir);
  if (!output.empty()) EXPECT_FALSE(std::filesystem::exists(output));
  int files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    files += entry.is_regular_file();
  }
  EXPECT_EQ(files, static_cast<int>(inputs.size())) << "a file was written";
  for (const auto& [path, bytes] : inputs) {
    EXPECT_EQ(ReadFile(path), bytes) << path << " changed";
  }
}

#define SLAM "{bin}/rff_slam --dataset={dir}/valid.rffd "
#define OUT " --output_trajectory={dir}/out.tum"

const HostileCase kHostileCases[] = {
    // Data loss: an output on an input, two outputs on one path, and output
    // directories checked before any work.
    {"SlamOutputOnDataset", SLAM "--output_trajectory={dir}/valid.rffd",
     "rff_slam: error: --output_trajectory={dir}/valid.rffd: the same file as "
     "the input --dataset={dir}/valid.rffd, never overwritten; allowed "
     "another path\n",
     ""},
    {"SlamLandmarksOnDatasetOtherSpelling",
     SLAM "--output_landmarks={dir}/./valid.rffd",
     "rff_slam: error: --output_landmarks={dir}/./valid.rffd: the same file "
     "as the input --dataset={dir}/valid.rffd, never overwritten; allowed "
     "another path\n",
     ""},
    {"SlamTwoOutputsOnOnePath",
     SLAM "--output_trajectory={dir}/o.txt --summary_json={dir}/o.txt",
     "rff_slam: error: --summary_json={dir}/o.txt: the same file as the "
     "output --output_trajectory={dir}/o.txt; allowed a path of its own\n",
     "{dir}/o.txt"},
    {"SlamOutputOnItsFlagfile",
     SLAM "--flagfile={dir}/my.flags --output_trajectory={dir}/my.flags",
     "rff_slam: error: --output_trajectory={dir}/my.flags: the same file as "
     "the input --flagfile={dir}/my.flags, never overwritten; allowed "
     "another path\n",
     ""},
    {"SlamBadLandmarkDirectoryWritesNoTrajectory",
     SLAM OUT " --output_landmarks={dir}/no/l.txt",
     "rff_slam: error: --output_landmarks={dir}/no/l.txt: directory "
     "'{dir}/no' does not exist\n",
     "{dir}/out.tum"},
    {"ConvertOverRawFile",
     "{bin}/rff_convert --format=plaza --input={dir}/raw "
     "--output={dir}/raw/Plaza1_GT.txt",
     "rff_convert: error: --output={dir}/raw/Plaza1_GT.txt: a file of the "
     "input directory --input={dir}/raw, never overwritten; allowed a path "
     "outside it\n",
     ""},
    {"DeadReckoningOutputOnDataset",
     "{bin}/rff_dead_reckoning --dataset={dir}/valid.rffd "
     "--output_trajectory={dir}/valid.rffd",
     "rff_dead_reckoning: error: --output_trajectory={dir}/valid.rffd: the "
     "same file as the input --dataset={dir}/valid.rffd, never overwritten; "
     "allowed another path\n",
     ""},
    {"EvaluateJsonOnTrajectory",
     "{bin}/rff_evaluate --dataset={dir}/valid.rffd --trajectory={dir}/far.tum "
     "--json={dir}/far.tum",
     "rff_evaluate: error: --json={dir}/far.tum: the same file as the input "
     "--trajectory={dir}/far.tum, never overwritten; allowed another path\n",
     ""},
    {"SimulateOutputIsDirectory", "{bin}/rff_simulate --output={dir}",
     "rff_simulate: error: --output={dir}: a directory; allowed a file "
     "path\n",
     ""},
    // Sizes no machine can solve.
    {"Features30000", SLAM "--num_features=30000" OUT,
     "rff_slam: error: --num_features=30000: allowed 0 (from the capacity "
     "rule) to 512\n",
     "{dir}/out.tum"},
    {"Features65535", SLAM "--num_features=65535" OUT,
     "rff_slam: error: --num_features=65535: allowed 0 (from the capacity "
     "rule) to 512\n",
     "{dir}/out.tum"},
    {"HeadingFeatures65536",
     SLAM "--num_features=10 --num_heading_features=65536" OUT,
     "rff_slam: error: --num_heading_features=65536: allowed 0 (from the "
     "capacity rule) to 512\n",
     "{dir}/out.tum"},
    {"HeadingFeaturesWithAutoCapacity", SLAM "--num_heading_features=50" OUT,
     "rff_slam: error: --num_heading_features=50: --num_features=0 derives "
     "both counts from the capacity rule; allowed 0 there, or give "
     "--num_features too\n",
     "{dir}/out.tum"},
    {"SegmentOverflowingInt", SLAM "--segment_length=1e-10" OUT,
     "rff_slam: error: --segment_length=1e-10: cuts any run of 1 s or more "
     "into more than 100000 segments; allowed 0 or at least 1e-05\n",
     "{dir}/out.tum"},
    // Automatic segments follow the lengthscale, the option at fault.
    {"LengthscaleTooShortForTheRun", SLAM "--lengthscale=1e-6" OUT,
     "rff_slam: error: {dir}/valid.rffd: --lengthscale=1e-06: the run's 10 s "
     "need 1e+06 segments of 24 features (x, y) and 26 (theta): more "
     "weights than memory allows (automatic segments of 10 lengthscales); "
     "allowed at least about 9.14e-06, or --segment_length of at least "
     "9.140015903627673e-05 for this run\n",
     "{dir}/out.tum"},
    {"SegmentsOverTheRun",
     SLAM "--segment_length=1e-5 --linear_solver=SPARSE_NORMAL_CHOLESKY" OUT,
     "rff_slam: error: {dir}/valid.rffd: --segment_length=1e-05: cuts the "
     "run's 10 s into more than 100000 segments; allowed 0 or at least 1e-04 "
     "for this run\n",
     "{dir}/out.tum"},
    {"OverlapWithoutSegments", SLAM "--segment_overlap=1e308" OUT,
     "rff_slam: error: --segment_overlap=1e+308: blends segments, but "
     "--segment_length=0 has none; allowed 0 there\n",
     "{dir}/out.tum"},
    {"OuterRoundsForever", SLAM "--outer_rounds=2147483647" OUT,
     "rff_slam: error: --outer_rounds=2147483647: more spline refits than "
     "supported; allowed 0 to 100\n",
     "{dir}/out.tum"},
    {"SubsetPreconditioner",
     SLAM "--preconditioner=SUBSET --linear_solver=ITERATIVE_SCHUR" OUT,
     "rff_slam: error: --preconditioner=SUBSET: needs residual blocks chosen "
     "for it, which no flag gives; allowed auto, IDENTITY, JACOBI, "
     "SCHUR_JACOBI, CLUSTER_JACOBI or CLUSTER_TRIDIAGONAL\n",
     "{dir}/out.tum"},
    {"LengthscaleBeyondDoubles", SLAM "--lengthscale=1e308" OUT,
     "rff_slam: error: --lengthscale=1e+308: the features' frequencies and "
     "weights leave double range; allowed more than 0 up to 1e+12\n",
     "{dir}/out.tum"},
    {"WnoaLengthscaleNaN", SLAM "--prior=wnoa --lengthscale=nan" OUT,
     "rff_slam: error: --lengthscale=nan: not a finite number; allowed more "
     "than 0 up to 1e+12\n",
     "{dir}/out.tum"},
    {"PreintegrationNaN", SLAM "--max_preintegration_seconds=nan" OUT,
     "rff_slam: error: --max_preintegration_seconds=nan: not a finite "
     "number; allowed 0 or more\n",
     "{dir}/out.tum"},
    {"PreintegrationNegative", SLAM "--max_preintegration_seconds=-1" OUT,
     "rff_slam: error: --max_preintegration_seconds=-1: allowed 0 or "
     "more\n",
     "{dir}/out.tum"},
    {"OdometryScaleSigmaZero", SLAM "--odometry_scale_sigma=0" OUT,
     "rff_slam: error: --odometry_scale_sigma=0: allowed more than 0\n",
     "{dir}/out.tum"},
    {"RangeOffsetSigmaNaN",
     SLAM "--estimate_range_calibration --range_offset_sigma=nan" OUT,
     "rff_slam: error: --range_offset_sigma=nan: not a finite number; "
     "allowed more than 0\n",
     "{dir}/out.tum"},
    {"ConvertPriorSigmaNaN",
     "{bin}/rff_convert --format=plaza --input={dir}/raw --output={dir}/o.rffd "
     "--prior_sigma_xy=nan",
     "rff_convert: error: --prior_sigma_xy=nan: not a finite number; "
     "allowed more than 0\n",
     "{dir}/o.rffd"},
    // A denormal "positive" value has no digits, and its inverse overflows.
    {"DenormalDiffusion", SLAM "--prior=wnoa --wnoa_position_qc=0x1p-1074" OUT,
     "rff_slam: error: --wnoa_position_qc=5e-324: a denormal number, below "
     "double precision's normal range; allowed more than 0\n",
     "{dir}/out.tum"},
    // A loss scale so small that every residual is an outlier, and its
    // 1 / scale^2 overflows.
    {"LossScaleTiny", SLAM "--loss=cauchy --loss_scale=1e-150" OUT,
     "rff_slam: error: --loss_scale=1e-150: allowed 0.001 to 1000 sigmas\n",
     "{dir}/out.tum"},
    // Options of a mode not in use are checked all the same.
    {"ConvertInactiveFormatOption",
     "{bin}/rff_convert --to=g2o --input={dir}/valid.rffd --output={dir}/o.g2o "
     "--mrclam_bearing_sigma=nan",
     "rff_convert: error: --mrclam_bearing_sigma=nan: not a finite number; "
     "allowed more than 0\n",
     "{dir}/o.g2o"},
    {"ConvertPriorSigmaNaNToG2o",
     "{bin}/rff_convert --to=g2o --input={dir}/valid.rffd --output={dir}/o.g2o "
     "--prior_sigma_xy=nan",
     "rff_convert: error: --prior_sigma_xy=nan: not a finite number; "
     "allowed more than 0\n",
     "{dir}/o.g2o"},
    {"LossScaleWithoutLoss", SLAM "--loss=none --loss_scale=nan" OUT,
     "rff_slam: error: --loss_scale=nan: not a finite number; allowed more "
     "than 0\n",
     "{dir}/out.tum"},
    {"OdometryLossScaleWithoutLoss",
     SLAM "--odometry_loss=none --odometry_loss_scale=-1" OUT,
     "rff_slam: error: --odometry_loss_scale=-1: allowed more than 0\n",
     "{dir}/out.tum"},
    {"PeriodOfAnotherKernel", SLAM "--kernel=rbf --period=nan" OUT,
     "rff_slam: error: --period=nan: ", "{dir}/out.tum"},
    // Flagfiles.
    {"EnvironmentFlagfile", SLAM "--fromenv=flagfile" OUT,
     "rff_slam: error: --fromenv=flagfile: a flagfile read from the "
     "environment (directly or through another --fromenv) is not checked; "
     "allowed --flagfile=PATH instead\n",
     "{dir}/out.tum"},
    {"SlamSelfIncludingFlagfile", SLAM "--flagfile={dir}/self.flags" OUT,
     "rff_slam: error: --flagfile={dir}/self.flags: includes itself",
     "{dir}/out.tum"},
    {"ExperimentSelfIncludingFlagfile",
     "{bin}/rff_experiment --flagfile={dir}/self.flags --out_dir={dir}/exp",
     "rff_experiment: error: --flagfile={dir}/self.flags: includes itself",
     "{dir}/exp"},
    {"SlamFlagfileCycle", SLAM "--flagfile={dir}/a.flags" OUT,
     "--flagfile={dir}/a.flags: includes itself through other flagfiles",
     "{dir}/out.tum"},
    {"SlamTypoInFlagfile", SLAM "--flagfile={dir}/typo.flags" OUT,
     "rff_slam: error: {dir}/typo.flags:1: unknown flag '--num_featurs'",
     "{dir}/out.tum"},
    // Numbers that overflow and messages that name the cause.
    {"TinyOdometrySigma",
     "{bin}/rff_slam --dataset={dir}/tiny_odometry_sigma.rffd" OUT,
     "tiny_odometry_sigma.rffd:10: sigma_x 1e-100 is finer than double "
     "precision resolves its dx; allowed at least 2.220446049250313e-16\n",
     "{dir}/out.tum"},
    {"DeadReckoningOverflow",
     "{bin}/rff_dead_reckoning --dataset={dir}/overflowing_odometry.rffd "
     "--output_trajectory={dir}/out.tum",
     "overflows double precision", "{dir}/out.tum"},
    {"EvaluateOverflow",
     "{bin}/rff_evaluate --dataset={dir}/far_truth.rffd "
     "--trajectory={dir}/far.tum --json={dir}/out.json",
     "the APE translation overflows double precision", "{dir}/out.json"},
    {"CovarianceOfTooManyLandmarks",
     "{bin}/rff_slam --dataset={dir}/many_landmarks.rffd" OUT
     " --output_covariance={dir}/out.cov",
     "the covariance of 10003 landmarks is more than the 10000 supported",
     "{dir}/out.cov"},
    {"BearingSigmaInDegreesStaysInDegrees",
     "{bin}/rff_simulate --output={dir}/s.rffd --sigma_bearing_deg=1e308",
     "rff_simulate: error: --sigma_bearing_deg=1e+308: allowed more than 0 "
     "up to 360\n",
     "{dir}/s.rffd"},
    {"OverlappingOdometryWithConstantMean",
     "{bin}/rff_slam --dataset={dir}/overlapping_odometry.rffd "
     "--prior_mean=constant" OUT,
     "ODOM records [2, 3] and [2.5, 3.5] overlap (the motion in between "
     "would be counted twice)",
     "{dir}/out.tum"},
    {"IncrementalUnlocatableLandmark",
     "{bin}/rff_slam --dataset={dir}/unlocatable.rffd "
     "--incremental_every=1" OUT,
     "landmark 7 has no PRIOR_LANDMARK and its 0 bearing(s) and 1 range(s) "
     "do not locate it",
     "{dir}/out.tum"},
    {"DirectoryAsDataset", "{bin}/rff_slam --dataset={dir}" OUT,
     "rff_slam: error: {dir}: cannot open for reading: is a directory, not a "
     "file",
     "{dir}/out.tum"},
};
INSTANTIATE_TEST_SUITE_P(Cases, HostileToolTest,
                         ::testing::ValuesIn(kHostileCases),
                         [](const ::testing::TestParamInfo<HostileCase>& info) {
                           return std::string(info.param.name);
                         });

// Accepted: the run without range or bearing measurements in incremental
// mode is solved (it used to exit 0 with an unsolved trajectory).
TEST(HostileToolAcceptTest, IncrementalOdometryOnlyIsSolved) {
  const std::string dir = testing::TempDir("hostile_tools_test");
  WriteFile(dir + "/odometry.rffd",
            "RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.01\n"
            "ODOM 0 1 1 0 0 0.05 0.05 0.01\nODOM 1 2 1 0 0 0.05 0.05 0.01\n"
            "GT_POSE 0 0 0 0\nGT_POSE 1 1 0 0\nGT_POSE 2 2 0 0\n");
  const RunResult run = RunCommand(Expand(
      "{bin}/rff_slam --dataset={dir}/odometry.rffd --incremental_every=1 "
      "--output_trajectory={dir}/out.tum",
      dir));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("CONVERGENCE"));
  std::vector<TimedPose> poses;
  std::string error;
  ASSERT_TRUE(ReadTum(dir + "/out.tum", &poses, &error)) << error;
  ASSERT_EQ(poses.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(poses[k].x, k, 1e-6);
    EXPECT_NEAR(poses[k].y, 0.0, 1e-6);
  }
}

// Accepted: two observations 9e5 s apart with a stray ground-truth pose
// beyond them solve in seconds, to finite numbers.
TEST(HostileToolAcceptTest, ObservationsFarApartInTimeSolve) {
  const std::string dir = testing::TempDir("hostile_tools_test");
  const std::string far = "RANGE_BEARING 900000 1 5 0.1 0.1 0.02\n";
  WriteFile(dir + "/gap.rffd",
            ValidDataset(0.0) + far + "GT_POSE 1800000 0 0 0\n");
  // Without odometry only the prior spans the gap, 1e17 m^2 wide: the
  // prior's scales cannot be learned in double precision, and it says so.
  // The noise-free records leave a round or two (as the last bits of the
  // initial trajectory's exact fixes fall) before a round's Hessian is past
  // double precision.
  std::string without_odometry;
  std::istringstream lines(ValidDataset(0.0));
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("ODOM", 0) != 0) without_odometry += line + "\n";
  }
  WriteFile(dir + "/gap_without_odometry.rffd", without_odometry + far);
  for (const std::string file : {"gap", "gap_without_odometry"}) {
    for (const std::string prior : {"rff", "wnoa"}) {
      const RunResult run = RunCommand(Expand(
          "{bin}/rff_slam --dataset={dir}/" + file + ".rffd --prior=" + prior +
              " --output_trajectory={dir}/out.tum",
          dir));
      ASSERT_EQ(run.exit_code, 0) << file << " " << prior << ": " << run.output;
      EXPECT_FALSE(HasNonFiniteToken(ReadFile(dir + "/out.tum")))
          << file << " " << prior;
      if (file == "gap_without_odometry" && prior == "wnoa") {
        EXPECT_THAT(run.output,
                    ContainsRegex("warning: learning the scales stopped after "
                                  "[12] rounds: the Gauss-Newton Hessian is "
                                  "not positive definite"));
        // The solve is finished with the scales of the round that was
        // learned, on the truth before the gap (x = t, y = 0).
        std::vector<TimedPose> poses;
        std::string error;
        ASSERT_TRUE(ReadTum(dir + "/out.tum", &poses, &error)) << error;
        ASSERT_EQ(poses.size(), 12u);
        for (int k = 0; k <= 10; ++k) {
          EXPECT_NEAR(poses[k].x, k, 2e-3) << k;
          EXPECT_NEAR(poses[k].y, 0.0, 2e-3) << k;
        }
      }
    }
  }
}

// Accepted: errors whose squares overflow (1e200 m) are still reported, in
// valid JSON with finite numbers.
TEST(HostileToolAcceptTest, ErrorsWhoseSquaresOverflowAreFinite) {
  const std::string dir = testing::TempDir("hostile_tools_test");
  WriteFile(dir + "/truth.rffd",
            "RFFD 1\nPRIOR_POSE 0 0 0 0 1 1\nGT_POSE 0 0 0 0\n"
            "GT_POSE 1 0 0 0\n");
  WriteFile(dir + "/far.tum", "0 1e200 0 0 0 0 0 1\n1 -1e200 0 0 0 0 0 1\n");
  const RunResult run =
      RunCommand(Expand("{bin}/rff_evaluate --dataset={dir}/truth.rffd "
                        "--trajectory={dir}/far.tum --json={dir}/out.json",
                        dir));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::string json = ReadFile(dir + "/out.json");
  EXPECT_FALSE(HasNonFiniteToken(json)) << json;
  EXPECT_THAT(json, HasSubstr("1e+200"));
}

// Accepted: segments of 1 ms over a 10 s run (10000 segments) solve.
TEST(HostileToolAcceptTest, MillisecondSegmentsSolve) {
  const std::string dir = testing::TempDir("hostile_tools_test");
  WriteFile(dir + "/valid.rffd", ValidDataset(0.0));
  const RunResult run =
      RunCommand(Expand(SLAM "--segment_length=1e-3" OUT, dir));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_FALSE(HasNonFiniteToken(ReadFile(dir + "/out.tum")));
}

}  // namespace
}  // namespace rff
