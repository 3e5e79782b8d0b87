// Runs the built command-line tools (from RFF_BINARY_DIR) on hostile files
// and flags: each error exits non-zero with a message that names the problem,
// and leaves no output file (in particular none with NaN or inf). The
// solver-level cases (degenerate but valid datasets) check that rff_slam
// either solves them to a finite trajectory or fails cleanly.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/io/tum_io.h"
#include "test/app_runner.h"
#include "test/test_files.h"

namespace rff {
namespace {

using testing::Expand;
using testing::HasNonFiniteToken;
using ::testing::HasSubstr;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunResult;
using testing::ValidDataset;
using testing::WriteFile;

// ---------------------------------------------------------------------------
// Errors: one command per case. {dir}/valid.rffd holds ValidDataset(0),
// {dir}/bad.rffd a dataset with a bad line 3, {dir}/single.rffd a single
// PRIOR_POSE and {dir}/gt.tum a two-pose trajectory.
using AppCase = testing::ToolCase;

class AppErrorTest : public ::testing::TestWithParam<AppCase> {};

TEST_P(AppErrorTest, ExitsNonZeroWithMessageAndNoOutput) {
  const std::string dir = testing::TempDir("app_errors_test");
  WriteFile(dir + "/valid.rffd", ValidDataset(0.0));
  WriteFile(dir + "/bad.rffd", "RFFD 1\nPRIOR_POSE 0 0 0 0 1 1\nRANGE 1 2 3\n");
  WriteFile(dir + "/gt.tum", "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n");
  WriteFile(dir + "/single.rffd", "RFFD 1\nPRIOR_POSE 0 0 0 0 1 1\n");
  const RunResult run = RunCommand(Expand(GetParam().command, dir));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_THAT(run.output, HasSubstr(Expand(GetParam().message, dir)));
  const std::string output = Expand(GetParam().output, dir);
  if (!output.empty()) {
    EXPECT_FALSE(std::filesystem::exists(output)) << output << ":\n"
                                                  << ReadFile(output);
  }
}

#define SLAM "{bin}/rff_slam --dataset={dir}/valid.rffd "
#define SLAM_OUT " --output_trajectory={dir}/out.tum"

const AppCase kAppCases[] = {
    // rff_slam: files.
    {"SlamNoDataset", "{bin}/rff_slam" SLAM_OUT,
     "rff_slam: error: --dataset is required", "{dir}/out.tum"},
    {"SlamMissingFile", "{bin}/rff_slam --dataset={dir}/none.rffd" SLAM_OUT,
     "rff_slam: error: {dir}/none.rffd: cannot open for reading",
     "{dir}/out.tum"},
    {"SlamBadLine", "{bin}/rff_slam --dataset={dir}/bad.rffd" SLAM_OUT,
     "rff_slam: error: {dir}/bad.rffd:3: RANGE needs 4 fields, got 3",
     "{dir}/out.tum"},
    {"SlamDirectoryAsDataset", "{bin}/rff_slam --dataset={dir}" SLAM_OUT,
     "rff_slam: error: {dir}", "{dir}/out.tum"},
    {"SlamUnexpectedArgument", SLAM "extra" SLAM_OUT,
     "rff_slam: error: unexpected argument 'extra'", "{dir}/out.tum"},
    {"SlamUnwritableOutput",
     SLAM "--output_trajectory={dir}/no/such/dir/out.tum",
     "rff_slam: error: --output_trajectory={dir}/no/such/dir/out.tum: "
     "directory '{dir}/no/such/dir' does not exist",
     ""},
    // rff_slam: flags (gflags itself rejects unknown and malformed ones).
    {"SlamUnknownFlag", SLAM "--no_such_flag=1" SLAM_OUT,
     "unknown command line flag 'no_such_flag'", "{dir}/out.tum"},
    {"SlamMalformedInteger", SLAM "--num_features=abc" SLAM_OUT,
     "illegal value 'abc' specified for int32 flag 'num_features'",
     "{dir}/out.tum"},
    {"SlamNegativeD", SLAM "--num_features=-5" SLAM_OUT,
     "rff_slam: error: --num_features=-5: allowed 0 (from the capacity rule) "
     "to 512\n",
     "{dir}/out.tum"},
    {"SlamBadLearning", SLAM "--learn_hyperparameters=maybe" SLAM_OUT,
     "rff_slam: error: --learn_hyperparameters=maybe: allowed auto, on or "
     "off\n",
     "{dir}/out.tum"},
    {"SlamBadInitialTrajectory", SLAM "--initial_trajectory=truth" SLAM_OUT,
     "rff_slam: error: --initial_trajectory=truth: allowed auto or mean\n",
     "{dir}/out.tum"},
    {"SlamUnknownKernel", SLAM "--kernel=gaussian" SLAM_OUT,
     "rff_slam: error: --kernel=gaussian: unknown kernel; allowed rbf, "
     "matern12, matern32, matern52 or periodic\n",
     "{dir}/out.tum"},
    {"SlamUnknownHeadingKernel", SLAM "--heading_kernel=bogus" SLAM_OUT,
     "rff_slam: error: --heading_kernel=bogus: unknown kernel; allowed rbf, "
     "matern12, matern32, matern52 or periodic\n",
     "{dir}/out.tum"},
    {"SlamZeroLengthscale", SLAM "--lengthscale=0" SLAM_OUT,
     "rff_slam: error: --lengthscale=0: allowed more than 0 up to 1e+12\n",
     "{dir}/out.tum"},
    {"SlamNaNLengthscale", SLAM "--lengthscale=nan" SLAM_OUT,
     "rff_slam: error: --lengthscale=nan: not a finite number; allowed more "
     "than 0 up to 1e+12\n",
     "{dir}/out.tum"},
    {"SlamNegativeVariance", SLAM "--kernel_variance=-1" SLAM_OUT,
     "rff_slam: error: --kernel_variance=-1: allowed more than 0 up to "
     "1e+24\n",
     "{dir}/out.tum"},
    {"SlamZeroThreads", SLAM "--num_threads=0" SLAM_OUT,
     "rff_slam: error: --num_threads=0: allowed 1 or more\n", "{dir}/out.tum"},
    {"SlamZeroIterations", SLAM "--max_iterations=0" SLAM_OUT,
     "rff_slam: error: --max_iterations=0: allowed 1 or more\n",
     "{dir}/out.tum"},
    {"SlamNegativeTolerance", SLAM "--function_tolerance=-1" SLAM_OUT,
     "rff_slam: error: --function_tolerance=-1: allowed 0 or more\n",
     "{dir}/out.tum"},
    {"SlamNegativeDecrementTolerance",
     SLAM "--decrement_tolerance=-0.5" SLAM_OUT,
     "rff_slam: error: --decrement_tolerance=-0.5: allowed 0 or more\n",
     "{dir}/out.tum"},
    {"SlamUnknownLinearSolver", SLAM "--linear_solver=MAGIC" SLAM_OUT,
     "rff_slam: error: --linear_solver=MAGIC: unknown linear solver; allowed "
     "auto, BANDED_CHOLESKY, DENSE_SCHUR, SPARSE_SCHUR, ITERATIVE_SCHUR, "
     "DENSE_QR, DENSE_NORMAL_CHOLESKY, SPARSE_NORMAL_CHOLESKY or CGNR\n",
     "{dir}/out.tum"},
    {"SlamUnknownPreconditioner",
     SLAM "--linear_solver=ITERATIVE_SCHUR --preconditioner=MAGIC" SLAM_OUT,
     "rff_slam: error: --preconditioner=MAGIC: unknown preconditioner; "
     "allowed auto, IDENTITY, JACOBI, SCHUR_JACOBI, CLUSTER_JACOBI or "
     "CLUSTER_TRIDIAGONAL\n",
     "{dir}/out.tum"},
    {"SlamCgnrWithSchurPreconditioner",
     SLAM "--linear_solver=CGNR --preconditioner=SCHUR_JACOBI" SLAM_OUT,
     "rff_slam: error: --preconditioner=SCHUR_JACOBI: --linear_solver=CGNR "
     "takes IDENTITY or JACOBI only; allowed auto, IDENTITY or JACOBI with "
     "CGNR\n",
     "{dir}/out.tum"},
    {"SlamUnknownTrustRegion", SLAM "--trust_region_strategy=MAGIC" SLAM_OUT,
     "rff_slam: error: --trust_region_strategy=MAGIC: unknown trust region "
     "strategy; allowed LEVENBERG_MARQUARDT or DOGLEG\n",
     "{dir}/out.tum"},
    {"SlamOverlapEqualsLength",
     SLAM "--segment_length=5 --segment_overlap=5" SLAM_OUT,
     "rff_slam: error: --segment_overlap=5: allowed 0 or more, less than "
     "--segment_length=5\n",
     "{dir}/out.tum"},
    {"SlamOverlapExceedsLength",
     SLAM "--segment_length=2 --segment_overlap=3" SLAM_OUT,
     "rff_slam: error: --segment_overlap=3: allowed 0 or more, less than "
     "--segment_length=2\n",
     "{dir}/out.tum"},
    {"SlamNegativeSegmentLength", SLAM "--segment_length=-1" SLAM_OUT,
     "rff_slam: error: --segment_length=-1: allowed 0 (one global map) or "
     "more\n",
     "{dir}/out.tum"},
    {"SlamUnknownFeatures", SLAM "--features=wavelets" SLAM_OUT,
     "rff_slam: error: --features=wavelets: unknown feature family; allowed "
     "rff, qmc, gauss_hermite or hilbert\n",
     "{dir}/out.tum"},
    {"SlamUnknownLoss", SLAM "--loss=tukey" SLAM_OUT,
     "rff_slam: error: --loss=tukey: unknown loss; allowed none, huber, "
     "cauchy or auto\n",
     "{dir}/out.tum"},
    {"SlamZeroLossScale", SLAM "--loss=huber --loss_scale=0" SLAM_OUT,
     "rff_slam: error: --loss_scale=0: allowed more than 0\n", "{dir}/out.tum"},
    {"SlamUnknownOdometryLoss", SLAM "--odometry_loss=l1" SLAM_OUT,
     "rff_slam: error: --odometry_loss=l1: unknown loss; allowed none, "
     "huber, cauchy or auto\n",
     "{dir}/out.tum"},
    {"SlamNegativeLocalizationSmoothing",
     SLAM "--prior_mean=localization "
          "--localization_correction_smoothing=-1" SLAM_OUT,
     "rff_slam: error: --localization_correction_smoothing=-1: allowed more "
     "than 0\n",
     "{dir}/out.tum"},
    {"SlamUnknownPriorMean", SLAM "--prior_mean=psychic" SLAM_OUT,
     "rff_slam: error: --prior_mean=psychic: unknown prior mean; allowed "
     "auto, odometry, wnoa, localization, spline or constant\n",
     "{dir}/out.tum"},
    {"SlamNegativeMemoryLimit", SLAM "--max_memory_gb=-1" SLAM_OUT,
     "rff_slam: error: --max_memory_gb=-1: allowed 0 or more\n",
     "{dir}/out.tum"},
    // Options are checked before the dataset is read.
    {"SlamBadOptionBeforeMissingDataset",
     "{bin}/rff_slam --dataset={dir}/missing.rffd --prior=brownian" SLAM_OUT,
     "rff_slam: error: --prior=brownian: unknown prior; allowed rff, wnoa "
     "or wnoj\n",
     "{dir}/out.tum"},
    {"SlamNegativeOuterRounds", SLAM "--outer_rounds=-1" SLAM_OUT,
     "rff_slam: error: --outer_rounds=-1: allowed 0 to 100\n", "{dir}/out.tum"},
    {"SlamSplineSmoothingAboveOne", SLAM "--spline_smoothing=2" SLAM_OUT,
     "rff_slam: error: --spline_smoothing=2: allowed 0 to 1\n",
     "{dir}/out.tum"},
    // rff_convert.
    {"ConvertUnknownFormat",
     "{bin}/rff_convert --format=kitti --input={dir} --output={dir}/o.rffd",
     "rff_convert: error: --format=kitti: unknown format; allowed plaza, "
     "mrclam, pyfg, g2o or rffd\n",
     "{dir}/o.rffd"},
    {"ConvertNoFormat",
     "{bin}/rff_convert --input={dir}/valid.rffd --output={dir}/o.rffd",
     "rff_convert: error: --format=: unknown format; allowed plaza, mrclam, "
     "pyfg, g2o or rffd\n",
     "{dir}/o.rffd"},
    {"ConvertUnknownOutputFormat",
     "{bin}/rff_convert --to=csv --input={dir}/valid.rffd --output={dir}/o",
     "rff_convert: error: --to=csv: unknown output format; allowed rffd, "
     "pyfg or g2o\n",
     "{dir}/o"},
    {"ConvertToPyfgOverTheInput",
     "{bin}/rff_convert --to=pyfg --input={dir}/valid.rffd "
     "--output={dir}/valid.rffd",
     "rff_convert: error: --output={dir}/valid.rffd: the same file as the "
     "input --input={dir}/valid.rffd, never overwritten; allowed another "
     "path\n",
     ""},
    {"ConvertBadDatasetToG2o",
     "{bin}/rff_convert --to=g2o --input={dir}/bad.rffd --output={dir}/o.g2o",
     "rff_convert: error: {dir}/bad.rffd:3: RANGE needs 4 fields, got 3\n",
     "{dir}/o.g2o"},
    {"ConvertDatasetReadAsPyfg",
     "{bin}/rff_convert --format=pyfg --input={dir}/valid.rffd "
     "--output={dir}/o.rffd",
     "rff_convert: error: {dir}/valid.rffd:2: unknown record 'RFFD' (2D PyFG "
     "has VERTEX_SE2, VERTEX_XY, their :PRIOR, EDGE_SE2, EDGE_SE2_XY and "
     "EDGE_RANGE)\n",
     "{dir}/o.rffd"},
    {"ConvertG2oNegativeRate",
     "{bin}/rff_convert --format=g2o --input={dir}/valid.rffd --rate=-1 "
     "--output={dir}/o.rffd",
     "rff_convert: error: --rate=-1: allowed 0 or more\n", "{dir}/o.rffd"},
    // A flag of another format would change nothing.
    {"ConvertMrclamFlagForPlaza",
     "{bin}/rff_convert --format=plaza --input={dir} --mrclam_robot=1 "
     "--output={dir}/o.rffd",
     "rff_convert: error: --mrclam_robot=1: applies to --format=mrclam "
     "only\n",
     "{dir}/o.rffd"},
    {"ConvertRateForADataset",
     "{bin}/rff_convert --input={dir}/valid.rffd --to=g2o --rate=10 "
     "--output={dir}/o.g2o",
     "rff_convert: error: --rate=10: applies to --format=pyfg or g2o only\n",
     "{dir}/o.g2o"},
    {"ConvertNoInput", "{bin}/rff_convert --format=plaza --output={dir}/o.rffd",
     "rff_convert: error: --input=DIR is required", "{dir}/o.rffd"},
    {"ConvertNoOutput", "{bin}/rff_convert --format=plaza --input={dir}",
     "rff_convert: error: --output=OUT.rffd is required", ""},
    {"ConvertMissingRawFiles",
     "{bin}/rff_convert --format=plaza --input={dir}/none "
     "--output={dir}/o.rffd",
     "rff_convert: error: {dir}/none/Plaza1_GT.txt: cannot open for reading",
     "{dir}/o.rffd"},
    {"ConvertUnknownCalibration",
     "{bin}/rff_convert --format=plaza --input={dir} --output={dir}/o.rffd "
     "--plaza_calibration=cubic",
     "rff_convert: error: --plaza_calibration=cubic: unknown calibration; "
     "allowed linear or none\n",
     "{dir}/o.rffd"},
    {"ConvertMrclamWithoutRobot",
     "{bin}/rff_convert --format=mrclam --input={dir} --output={dir}/o.rffd",
     "rff_convert: error: --mrclam_robot=0: no robot given (the default); "
     "allowed 1 to 5\n",
     "{dir}/o.rffd"},
    {"ConvertNegativeGtRate",
     "{bin}/rff_convert --format=mrclam --mrclam_robot=1 --input={dir} "
     "--output={dir}/o.rffd --gt_rate_hz=-1",
     "rff_convert: error: --gt_rate_hz=-1: allowed 0 or more\n",
     "{dir}/o.rffd"},
    {"ConvertNaNSigma",
     "{bin}/rff_convert --format=plaza --input={dir} --output={dir}/o.rffd "
     "--plaza_odom_sigma_xy_floor=nan",
     "rff_convert: error: --plaza_odom_sigma_xy_floor=nan: not a finite "
     "number; allowed more than 0\n",
     "{dir}/o.rffd"},
    // rff_simulate.
    {"SimulateNoOutput", "{bin}/rff_simulate",
     "rff_simulate: error: --output is required", ""},
    {"SimulateUnknownPreset",
     "{bin}/rff_simulate --output={dir}/s.rffd --preset=huge",
     "rff_simulate: error: --preset=huge: unknown preset; allowed paper, "
     "kitti_scale, laser_10hz or gp_draw\n",
     "{dir}/s.rffd"},
    {"SimulateUnknownKind",
     "{bin}/rff_simulate --output={dir}/s.rffd --kind=sonar",
     "rff_simulate: error: --kind=sonar: unknown measurement kind; allowed "
     "range, bearing or range_bearing\n",
     "{dir}/s.rffd"},
    {"SimulateZeroSteps",
     "{bin}/rff_simulate --output={dir}/s.rffd --num_steps=0",
     "rff_simulate: error: --num_steps=0: allowed 1 to 10000000\n",
     "{dir}/s.rffd"},
    {"SimulateNegativeLandmarks",
     "{bin}/rff_simulate --output={dir}/s.rffd --landmarks=-3",
     "rff_simulate: error: --landmarks=-3: allowed 1 to 10000000\n",
     "{dir}/s.rffd"},
    // No visibility model, no nearest-first selection: it would change
    // nothing.
    {"SimulateMinRangeWithoutAUse",
     "{bin}/rff_simulate --output={dir}/s.rffd --min_range=5",
     "rff_simulate: error: --min_range=5: applies with --sensor_range > 0 or "
     "--observe_nearest only\n",
     "{dir}/s.rffd"},
    {"SimulateZeroTimeStep", "{bin}/rff_simulate --output={dir}/s.rffd --dt=0",
     "rff_simulate: error: --dt=0: allowed more than 0 up to 1e+06\n",
     "{dir}/s.rffd"},
    {"SimulateNaNRangeSigma",
     "{bin}/rff_simulate --output={dir}/s.rffd --sigma_range=nan",
     "rff_simulate: error: --sigma_range=nan: not a finite number; allowed "
     "more than 0 up to 1e+06\n",
     "{dir}/s.rffd"},
    {"SimulateNaNBearingSigma",
     "{bin}/rff_simulate --output={dir}/s.rffd --sigma_bearing_deg=nan",
     "rff_simulate: error: --sigma_bearing_deg=nan: not a finite number; "
     "allowed more than 0 up to 360\n",
     "{dir}/s.rffd"},
    {"SimulateFieldOfViewBelowRadians",
     "{bin}/rff_simulate --output={dir}/s.rffd --field_of_view_deg=0x1p-1074",
     "rff_simulate: error: --field_of_view_deg=5e-324: too small for radians "
     "in double precision; allowed more than 0 up to 360\n",
     "{dir}/s.rffd"},
    {"SimulateFieldOfViewWithoutSensorRange",
     "{bin}/rff_simulate --output={dir}/s.rffd --field_of_view_deg=10",
     "rff_simulate: error: --field_of_view_deg=10: applies with "
     "--sensor_range > 0 only\n",
     "{dir}/s.rffd"},
    {"SimulateZeroFieldOfView",
     "{bin}/rff_simulate --output={dir}/s.rffd --field_of_view_deg=0",
     "rff_simulate: error: --field_of_view_deg=0: allowed more than 0 up to "
     "360\n",
     "{dir}/s.rffd"},
    // rff_evaluate.
    {"EvaluateNoTrajectory", "{bin}/rff_evaluate --dataset={dir}/valid.rffd",
     "rff_evaluate: error: --trajectory is required", ""},
    {"EvaluateDatasetWithoutTruth",
     "{bin}/rff_evaluate --dataset={dir}/bad.rffd --trajectory={dir}/gt.tum",
     "rff_evaluate: error: {dir}/bad.rffd:3:", ""},
    {"EvaluateBadTrajectory",
     "{bin}/rff_evaluate --dataset={dir}/valid.rffd "
     "--trajectory={dir}/valid.rffd --json={dir}/e.json",
     "rff_evaluate: error: {dir}/valid.rffd:2: a TUM pose needs 8 fields",
     "{dir}/e.json"},
    {"EvaluateBadLandmarks",
     "{bin}/rff_evaluate --dataset={dir}/valid.rffd --trajectory={dir}/gt.tum "
     "--landmarks={dir}/gt.tum --json={dir}/e.json",
     "rff_evaluate: error: {dir}/gt.tum:1: a landmark needs 3 fields",
     "{dir}/e.json"},
    // rff_dead_reckoning.
    {"DeadReckoningNoOutput",
     "{bin}/rff_dead_reckoning --dataset={dir}/valid.rffd",
     "rff_dead_reckoning: error: --output_trajectory is required", ""},
    {"DeadReckoningBadLine",
     "{bin}/rff_dead_reckoning --dataset={dir}/bad.rffd "
     "--output_trajectory={dir}/dr.tum",
     "rff_dead_reckoning: error: {dir}/bad.rffd:3: RANGE needs 4 fields",
     "{dir}/dr.tum"},
    {"DeadReckoningMalformedBool",
     "{bin}/rff_dead_reckoning --dataset={dir}/valid.rffd "
     "--output_trajectory={dir}/dr.tum --hold_through_gaps=maybe",
     "illegal value 'maybe' specified for bool flag 'hold_through_gaps'",
     "{dir}/dr.tum"},
    {"DeadReckoningWithoutOdometry",
     "{bin}/rff_dead_reckoning --dataset={dir}/single.rffd "
     "--output_trajectory={dir}/dr.tum",
     "rff_dead_reckoning: error: {dir}/single.rffd: the dataset has no "
     "ODOM records",
     "{dir}/dr.tum"},
    // rff_perturb.
    {"PerturbNoInput", "{bin}/rff_perturb --output={dir}/p.rffd",
     "rff_perturb: error: --input is required", "{dir}/p.rffd"},
    {"PerturbNoOutput", "{bin}/rff_perturb --input={dir}/valid.rffd",
     "rff_perturb: error: --output is required", ""},
    {"PerturbUnexpectedArgument",
     "{bin}/rff_perturb --input={dir}/valid.rffd --output={dir}/p.rffd extra",
     "rff_perturb: error: unexpected argument 'extra'", "{dir}/p.rffd"},
    {"PerturbOutputIsInput",
     "{bin}/rff_perturb --input={dir}/valid.rffd --output={dir}/valid.rffd "
     "--landmark_prior_offset=1",
     "rff_perturb: error: --output={dir}/valid.rffd: the same file as the "
     "input --input={dir}/valid.rffd, never overwritten; allowed another "
     "path\n",
     ""},
    {"PerturbMissingInput",
     "{bin}/rff_perturb --input={dir}/none.rffd --output={dir}/p.rffd "
     "--landmark_prior_offset=1",
     "rff_perturb: error: {dir}/none.rffd: cannot open for reading",
     "{dir}/p.rffd"},
    {"PerturbBadLine",
     "{bin}/rff_perturb --input={dir}/bad.rffd --output={dir}/p.rffd "
     "--landmark_prior_offset=1",
     "rff_perturb: error: {dir}/bad.rffd:3: RANGE needs 4 fields, got 3",
     "{dir}/p.rffd"},
    // No perturbation: the copy would pass for a perturbed file.
    {"PerturbNothing",
     "{bin}/rff_perturb --input={dir}/valid.rffd --output={dir}/p.rffd",
     "rff_perturb: error: nothing to perturb: give --landmark_prior_offset, "
     "--start_heading_offset_deg or --start_heading_sigma\n",
     "{dir}/p.rffd"},
    {"PerturbNegativeOffset",
     "{bin}/rff_perturb --input={dir}/valid.rffd --output={dir}/p.rffd "
     "--landmark_prior_offset=-1",
     "rff_perturb: error: --landmark_prior_offset=-1: allowed 0 to 1e+06 "
     "m\n",
     "{dir}/p.rffd"},
    {"PerturbNaNHeadingOffset",
     "{bin}/rff_perturb --input={dir}/valid.rffd --output={dir}/p.rffd "
     "--start_heading_offset_deg=nan",
     "rff_perturb: error: --start_heading_offset_deg=nan: allowed -360 to "
     "360 degrees\n",
     "{dir}/p.rffd"},
    {"PerturbZeroHeadingSigma",
     "{bin}/rff_perturb --input={dir}/valid.rffd --output={dir}/p.rffd "
     "--start_heading_sigma=0",
     "rff_perturb: error: --start_heading_sigma=0: allowed more than 0 up to "
     "1e+06 rad\n",
     "{dir}/p.rffd"},
    {"PerturbOffsetWithoutLandmarkPriors",
     "{bin}/rff_perturb --input={dir}/single.rffd --output={dir}/p.rffd "
     "--landmark_prior_offset=1",
     "rff_perturb: error: {dir}/single.rffd: landmark_prior_offset=1 seed=1 "
     "moves the landmark priors, but there is no PRIOR_LANDMARK record",
     "{dir}/p.rffd"},
};

INSTANTIATE_TEST_SUITE_P(Cases, AppErrorTest, ::testing::ValuesIn(kAppCases),
                         [](const ::testing::TestParamInfo<AppCase>& info) {
                           return std::string(info.param.name);
                         });

// ---------------------------------------------------------------------------
// Hostile files through the apps, where the case needs more than one file.

// The quality verdict is on stderr and in the JSON; --fail_on_suspect turns a
// "suspect" one into exit status 3, with the outputs written for inspection.
TEST(AppQualityTest, SuspectVerdictExitsThreeOnlyWhenAsked) {
  const std::string dir = testing::TempDir("app_quality_test");
  WriteFile(dir + "/valid.rffd", ValidDataset(0.0));
  // The odometry drives backwards while every range-bearing says forwards.
  std::string backwards = ValidDataset(0.0);
  for (std::size_t at = backwards.find(" 1 0 0 0.05"); at != std::string::npos;
       at = backwards.find(" 1 0 0 0.05", at + 1)) {
    backwards.replace(at, 11, " -1 0 0 0.05");
  }
  WriteFile(dir + "/backwards.rffd", backwards);
  const std::string slam =
      "{bin}/rff_slam --fail_on_suspect --output_trajectory={dir}/out.tum "
      "--summary_json={dir}/out.json --dataset={dir}/";
  RunResult run = RunCommand(Expand(slam + "valid.rffd", dir));
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("rff_slam: quality ok\n"));
  EXPECT_THAT(ReadFile(dir + "/out.json"), HasSubstr("\"quality\": \"ok\""));

  run = RunCommand(Expand(slam + "backwards.rffd", dir));
  EXPECT_EQ(run.exit_code, 3) << run.output;
  EXPECT_THAT(run.output,
              HasSubstr("rff_slam: quality suspect: range-bearing chi2/n "));
  EXPECT_THAT(ReadFile(dir + "/out.json"),
              HasSubstr("\"quality\": \"suspect\""));
  EXPECT_TRUE(std::filesystem::exists(dir + "/out.tum"));

  run =
      RunCommand(Expand("{bin}/rff_slam --output_trajectory={dir}/out.tum "
                        "--dataset={dir}/backwards.rffd",
                        dir));
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("rff_slam: quality suspect: "));
}

TEST(AppHostileFileTest, ConvertRawFileErrorNamesFileAndLineAndWritesNothing) {
  const std::string dir = testing::TempDir("app_errors_test");
  WriteFile(dir + "/Tiny_GT.txt", "0 0 0 0\r\n1 1 0 nan\r\n");
  const RunResult run =
      RunCommand(Expand("{bin}/rff_convert --format=plaza --plaza_name=Tiny "
                        "--input={dir} --output={dir}/o.rffd",
                        dir));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_THAT(run.output,
              HasSubstr(dir + "/Tiny_GT.txt:2: field 4 'nan' is not a finite"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/o.rffd"));
}

TEST(AppHostileFileTest, ConvertPyfgPicksOneRobotAndCountsInterRobotEdges) {
  const std::string dir = testing::TempDir("app_errors_test");
  WriteFile(dir + "/two.pyfg",
            "VERTEX_SE2 0 A0 0 0 0\nVERTEX_SE2 1 A1 1 0 0\n"
            "VERTEX_SE2 0 B0 0 5 0\nVERTEX_XY L0 3 3\n"
            "EDGE_SE2 1 A0 A1 1 0 0 0.01 0 0 0.01 0 0.01\n"
            "EDGE_RANGE 1 A1 B0 5 0.01\nEDGE_RANGE 1 A1 L0 3.6 0.01\n");
  RunResult run = RunCommand(
      Expand("{bin}/rff_convert --format=pyfg --input={dir}/two.pyfg "
             "--output={dir}/a.rffd",
             dir));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_EQ(run.output, "rff_convert: error: --robot=: " + dir +
                            "/two.pyfg has 2 robots: pick one; allowed A or "
                            "B\n");
  EXPECT_FALSE(std::filesystem::exists(dir + "/a.rffd"));
  run = RunCommand(
      Expand("{bin}/rff_convert --format=pyfg --robot=A --input={dir}/two.pyfg "
             "--output={dir}/a.rffd",
             dir));
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output,
              HasSubstr("rff_convert: note: --robot=A: left out 1 "
                        "inter-robot edges (.rffd holds one robot)\n"));
  EXPECT_THAT(ReadFile(dir + "/a.rffd"), HasSubstr("RANGE 1 0 3.6 0.1\n"));
}

TEST(AppHostileFileTest, ConvertG2oErrorNamesFileAndLineAndWritesNothing) {
  const std::string dir = testing::TempDir("app_errors_test");
  WriteFile(dir + "/bad.g2o",
            "VERTEX_SE2 0 0 0 0\r\nVERTEX_SE2 1 1 0 0\r\n"
            "EDGE_SE2 0 1 1 0 0 1 0 0 1 0\r\n");
  const RunResult run =
      RunCommand(Expand("{bin}/rff_convert --format=g2o --input={dir}/bad.g2o "
                        "--output={dir}/o.rffd",
                        dir));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_EQ(run.output, "rff_convert: error: " + dir +
                            "/bad.g2o:3: EDGE_SE2 needs 11 fields, got 10\n");
  EXPECT_FALSE(std::filesystem::exists(dir + "/o.rffd"));
}

TEST(AppHostileFileTest, EvaluateTrajectoryWithNaNIsRefused) {
  const std::string dir = testing::TempDir("app_errors_test");
  WriteFile(dir + "/valid.rffd", ValidDataset(0.0));
  WriteFile(dir + "/est.tum", "0 0 0 0 0 0 0 1\n1 nan 0 0 0 0 0 1\n");
  const RunResult run =
      RunCommand(Expand("{bin}/rff_evaluate --dataset={dir}/valid.rffd "
                        "--trajectory={dir}/est.tum",
                        dir));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_THAT(run.output,
              HasSubstr(dir + "/est.tum:2: field 2 'nan' is not a finite"));
}

TEST(AppHostileFileTest, BinaryJunkDatasetIsRefused) {
  const std::string dir = testing::TempDir("app_errors_test");
  WriteFile(dir + "/junk.rffd", std::string("\x7f"
                                            "ELF\x02\x01\x01\x00\x00",
                                            9));
  const RunResult run =
      RunCommand(Expand("{bin}/rff_slam --dataset={dir}/junk.rffd "
                        "--output_trajectory={dir}/o.tum",
                        dir));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_THAT(run.output, HasSubstr(dir + "/junk.rffd:1: NUL byte in line"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/o.tum"));
}

TEST(AppHostileFileTest, EmptyDatasetIsRefused) {
  const std::string dir = testing::TempDir("app_errors_test");
  WriteFile(dir + "/empty.rffd", "");
  const RunResult run =
      RunCommand(Expand("{bin}/rff_dead_reckoning --dataset={dir}/empty.rffd "
                        "--output_trajectory={dir}/o.tum",
                        dir));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_THAT(run.output, HasSubstr(dir + "/empty.rffd: missing header"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/o.tum"));
}

// FORMAT.md allows CRLF: the same dataset with CRLF line ends solves.
TEST(AppHostileFileTest, CrlfDatasetSolves) {
  const std::string dir = testing::TempDir("app_errors_test");
  std::string crlf;
  for (const char c : ValidDataset(0.0)) {
    crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  }
  WriteFile(dir + "/crlf.rffd", crlf);
  const RunResult run =
      RunCommand(Expand("{bin}/rff_slam --dataset={dir}/crlf.rffd "
                        "--output_trajectory={dir}/o.tum",
                        dir));
  EXPECT_EQ(run.exit_code, 0) << run.output;
  std::vector<TimedPose> poses;
  std::string error;
  ASSERT_TRUE(ReadTum(dir + "/o.tum", &poses, &error)) << error;
  EXPECT_EQ(poses.size(), 11u);
}

// ---------------------------------------------------------------------------
// Solver-level: well-formed but degenerate datasets. rff_slam either solves
// them (exit 0, a finite trajectory at the expected times) or fails with
// "rff_slam: error: DATASET: ..." and exit 1; never a crash, a hang or NaN.
struct SolveOutcome {
  RunResult run;
  std::string trajectory;  // The TUM file, "" when not written.
};

SolveOutcome Solve(const std::string& dir, const std::string& dataset_text,
                   const std::string& flags = "") {
  WriteFile(dir + "/in.rffd", dataset_text);
  SolveOutcome outcome;
  outcome.run =
      RunCommand(Expand("{bin}/rff_slam --dataset={dir}/in.rffd "
                        "--output_trajectory={dir}/out.tum "
                        "--output_landmarks={dir}/out.landmarks " +
                            flags,
                        dir));
  if (std::filesystem::exists(dir + "/out.tum")) {
    outcome.trajectory = ReadFile(dir + "/out.tum");
  }
  return outcome;
}

// Checks the contract; returns true when the case solved.
bool SolvedOrFailedCleanly(const std::string& dir, const SolveOutcome& o) {
  EXPECT_TRUE(o.run.exit_code == 0 || o.run.exit_code == 1)
      << "exit " << o.run.exit_code << "\n"
      << o.run.output;
  EXPECT_FALSE(HasNonFiniteToken(o.trajectory)) << o.trajectory;
  if (std::filesystem::exists(dir + "/out.landmarks")) {
    EXPECT_FALSE(HasNonFiniteToken(ReadFile(dir + "/out.landmarks")));
  }
  if (o.run.exit_code == 1) {
    EXPECT_THAT(o.run.output,
                HasSubstr("rff_slam: error: " + dir + "/in.rffd: "));
  }
  return o.run.exit_code == 0;
}

TEST(SolverHostileTest, DatasetWithoutObservationsFollowsOdometry) {
  const std::string dir = testing::TempDir("app_errors_test");
  const SolveOutcome o =
      Solve(dir,
            "RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.01\n"
            "ODOM 0 1 1 0 0 0.05 0.05 0.01\nODOM 1 2 1 0 0 0.05 0.05 0.01\n");
  if (!SolvedOrFailedCleanly(dir, o)) return;
  std::vector<TimedPose> poses;
  std::string error;
  ASSERT_TRUE(ReadTum(dir + "/out.tum", &poses, &error)) << error;
  ASSERT_EQ(poses.size(), 3u);  // The ODOM times 0, 1, 2.
  EXPECT_NEAR(poses[2].x, 2.0, 0.05);
}

TEST(SolverHostileTest, SinglePose) {
  const std::string dir = testing::TempDir("app_errors_test");
  const SolveOutcome o = Solve(dir, "RFFD 1\nPRIOR_POSE 3 1 2 0.5 0.1 0.01\n");
  if (!SolvedOrFailedCleanly(dir, o)) return;
  std::vector<TimedPose> poses;
  std::string error;
  ASSERT_TRUE(ReadTum(dir + "/out.tum", &poses, &error)) << error;
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_NEAR(poses[0].x, 1.0, 1e-3);
  EXPECT_NEAR(poses[0].y, 2.0, 1e-3);
}

TEST(SolverHostileTest, AllObservationsAtOneTime) {
  const std::string dir = testing::TempDir("app_errors_test");
  const SolveOutcome o =
      Solve(dir,
            "RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.01\n"
            "PRIOR_LANDMARK 1 5 0 1\nPRIOR_LANDMARK 2 0 5 1\n"
            "RANGE_BEARING 0 1 5 0 0.1 0.02\n"
            "RANGE_BEARING 0 2 5 1.5707963267948966 0.1 0.02\n");
  if (!SolvedOrFailedCleanly(dir, o)) return;
  std::vector<TimedPose> poses;
  std::string error;
  ASSERT_TRUE(ReadTum(dir + "/out.tum", &poses, &error)) << error;
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_NEAR(poses[0].x, 0.0, 0.05);
}

// One range to a landmark without a prior does not locate it: a clear error
// naming the landmark (landmark_init), exit 1, no output.
TEST(SolverHostileTest, SingleRangeToUnconstrainedLandmarkIsAnError) {
  const std::string dir = testing::TempDir("app_errors_test");
  const SolveOutcome o =
      Solve(dir,
            "RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.01\n"
            "ODOM 0 1 1 0 0 0.05 0.05 0.01\nRANGE 1 9 4 0.1\n");
  EXPECT_EQ(o.run.exit_code, 1) << o.run.output;
  EXPECT_THAT(o.run.output, HasSubstr("rff_slam: error: " + dir +
                                      "/in.rffd: landmark 9 has no "
                                      "PRIOR_LANDMARK"));
  EXPECT_TRUE(o.trajectory.empty());
}

// Unix-epoch times (1.2e9 s) solve like the same run started at 0.
TEST(SolverHostileTest, UnixEpochTimesSolveLikeZeroOrigin) {
  const std::string dir = testing::TempDir("app_errors_test");
  const SolveOutcome zero = Solve(dir, ValidDataset(0.0));
  ASSERT_EQ(zero.run.exit_code, 0) << zero.run.output;
  std::vector<TimedPose> a, b;
  std::string error;
  ASSERT_TRUE(ReadTum(dir + "/out.tum", &a, &error)) << error;
  const SolveOutcome epoch = Solve(dir, ValidDataset(1.2e9));
  ASSERT_EQ(epoch.run.exit_code, 0) << epoch.run.output;
  ASSERT_TRUE(ReadTum(dir + "/out.tum", &b, &error)) << error;
  ASSERT_EQ(a.size(), 11u);
  ASSERT_EQ(b.size(), 11u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(b[i].t, 1.2e9 + static_cast<double>(i));
    EXPECT_NEAR(b[i].x, a[i].x, 0.01) << i;
    EXPECT_NEAR(b[i].y, a[i].y, 0.01) << i;
    EXPECT_NEAR(b[i].x, static_cast<double>(i), 0.1) << i;
  }
}

}  // namespace
}  // namespace rff
