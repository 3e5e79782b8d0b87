// rff_slam's flags at their defaults give the library's default SlamOptions:
// a caller of RunSlam (C++ or Python) gets the solver a user of the command
// line gets.
#include "apps/slam_flags.h"

#include "gflags/gflags.h"
#include "gtest/gtest.h"
#include "rff_ceres/priors/trajectory_prior.h"
#include "rff_ceres/slam_solver.h"

namespace rff {
namespace {

void ExpectSameKernel(const KernelOptions& flags, const KernelOptions& library,
                      const char* which) {
  SCOPED_TRACE(which);
  EXPECT_EQ(flags.name, library.name);
  EXPECT_EQ(flags.variance, library.variance);
  EXPECT_EQ(flags.lengthscale, library.lengthscale);
  EXPECT_EQ(flags.period, library.period);
}

TEST(SlamFlagsTest, DefaultFlagsGiveTheLibraryDefaults) {
  const SlamOptions flags = SlamOptionsFromFlags();
  const SlamOptions library;
  EXPECT_EQ(flags.prior, library.prior);
  EXPECT_EQ(flags.mean.name, library.mean.name);
  EXPECT_EQ(flags.start.trajectory, library.start.trajectory);
  EXPECT_EQ(flags.localization.position_smoothing,
            library.localization.position_smoothing);
  EXPECT_EQ(flags.localization.heading_smoothing,
            library.localization.heading_smoothing);
  EXPECT_EQ(flags.localization.correction_smoothing,
            library.localization.correction_smoothing);
  EXPECT_EQ(flags.localization.use_odometry, library.localization.use_odometry);
  EXPECT_EQ(flags.wnoa.position_qc, library.wnoa.position_qc);
  EXPECT_EQ(flags.wnoj.position_qc, library.wnoj.position_qc);
  EXPECT_EQ(flags.wnoj.heading_qc, library.wnoj.heading_qc);
  EXPECT_EQ(flags.wnoj.initial_acceleration_sigma,
            library.wnoj.initial_acceleration_sigma);
  EXPECT_EQ(flags.wnoj.initial_angular_acceleration_sigma,
            library.wnoj.initial_angular_acceleration_sigma);
  EXPECT_EQ(flags.wnoj.min_state_spacing, library.wnoj.min_state_spacing);
  EXPECT_EQ(flags.wnoa.heading_qc, library.wnoa.heading_qc);
  EXPECT_EQ(flags.wnoa.initial_position_sigma,
            library.wnoa.initial_position_sigma);
  EXPECT_EQ(flags.wnoa.initial_heading_sigma,
            library.wnoa.initial_heading_sigma);
  EXPECT_EQ(flags.wnoa.initial_velocity_sigma,
            library.wnoa.initial_velocity_sigma);
  EXPECT_EQ(flags.wnoa.initial_angular_velocity_sigma,
            library.wnoa.initial_angular_velocity_sigma);
  EXPECT_EQ(flags.wnoa.min_state_spacing, library.wnoa.min_state_spacing);
  EXPECT_EQ(flags.incremental.every, library.incremental.every);
  EXPECT_EQ(flags.incremental.lag, library.incremental.lag);
  EXPECT_EQ(flags.mean.outer_rounds, library.mean.outer_rounds);
  EXPECT_EQ(flags.learn_hyperparameters, library.learn_hyperparameters);
  EXPECT_EQ(flags.mean.spline_smoothing, library.mean.spline_smoothing);
  const FeatureTrajectoryOptions& t = flags.features;
  ExpectSameKernel(t.position_kernel, library.features.position_kernel,
                   "position kernel");
  ExpectSameKernel(t.heading_kernel, library.features.heading_kernel,
                   "heading kernel");
  EXPECT_EQ(t.family, library.features.family);
  EXPECT_EQ(t.num_position_features, library.features.num_position_features);
  EXPECT_EQ(t.num_heading_features, library.features.num_heading_features);
  EXPECT_EQ(t.seed, library.features.seed);
  EXPECT_EQ(t.segment_length, library.features.segment_length);
  EXPECT_EQ(t.segment_overlap, library.features.segment_overlap);
  const ProblemOptions& p = flags.problem;
  EXPECT_EQ(p.loss.name, library.problem.loss.name);
  EXPECT_EQ(p.loss.scale, library.problem.loss.scale);
  EXPECT_EQ(p.odometry_loss.name, library.problem.odometry_loss.name);
  EXPECT_EQ(p.odometry_loss.scale, library.problem.odometry_loss.scale);
  EXPECT_EQ(p.use_odometry, library.problem.use_odometry);
  EXPECT_EQ(p.range_calibration.estimate,
            library.problem.range_calibration.estimate);
  EXPECT_EQ(p.range_calibration.scale_sigma,
            library.problem.range_calibration.scale_sigma);
  EXPECT_EQ(p.range_calibration.offset_sigma,
            library.problem.range_calibration.offset_sigma);
  EXPECT_EQ(p.odometry_calibration.estimate,
            library.problem.odometry_calibration.estimate);
  EXPECT_EQ(p.odometry_calibration.scale_sigma,
            library.problem.odometry_calibration.scale_sigma);
  EXPECT_EQ(p.preintegrate_odometry, library.problem.preintegrate_odometry);
  EXPECT_EQ(p.max_preintegration_seconds,
            library.problem.max_preintegration_seconds);
  const SolverOptions& s = flags.solver;
  EXPECT_EQ(s.linear_solver, library.solver.linear_solver);
  EXPECT_EQ(s.preconditioner, library.solver.preconditioner);
  EXPECT_EQ(s.trust_region_strategy, library.solver.trust_region_strategy);
  EXPECT_EQ(s.num_threads, library.solver.num_threads);
  EXPECT_EQ(s.max_iterations, library.solver.max_iterations);
  EXPECT_EQ(s.function_tolerance, library.solver.function_tolerance);
  EXPECT_EQ(s.gradient_tolerance, library.solver.gradient_tolerance);
  EXPECT_EQ(s.parameter_tolerance, library.solver.parameter_tolerance);
  EXPECT_EQ(s.decrement_tolerance, library.solver.decrement_tolerance);
  EXPECT_EQ(s.max_memory_gb, library.solver.max_memory_gb);
}

// A scale the user gives keeps "auto" learning off for the prior it
// belongs to (and for an RFF prior, whose WNOA mean uses WNOA's), not for
// the others: a WNOA flagfile run with --prior=wnoj still learns.
TEST(SlamFlagsTest, OnlyTheChosenPriorsScalesKeepLearningOff) {
  struct Case {
    const char* prior;
    const char* flag;
    const char* learning;
  };
  for (const Case& c : {Case{"wnoa", "wnoj_position_qc", "auto"},
                        Case{"wnoj", "wnoj_position_qc", "off"},
                        Case{"wnoj", "wnoa_heading_qc", "auto"},
                        Case{"wnoj", "lengthscale", "auto"},
                        Case{"wnoa", "wnoa_heading_qc", "off"},
                        Case{"rff", "wnoa_position_qc", "off"},
                        Case{"rff", "heading_lengthscale", "off"},
                        Case{"rff", "wnoj_heading_qc", "auto"}}) {
    gflags::FlagSaver saver;
    gflags::SetCommandLineOption("prior", c.prior);
    gflags::SetCommandLineOption(c.flag, "2");
    EXPECT_EQ(SlamOptionsFromFlags().learn_hyperparameters, c.learning)
        << "--prior=" << c.prior << " --" << c.flag << "=2";
  }
}

TEST(SlamFlagsTest, EveryPriorsScaleFlagsAreSolverFlags) {
  for (const std::string& name : PriorNames()) {
    for (const std::string& flag : FindPrior(name)->scale_flags()) {
      EXPECT_TRUE(IsSlamFlag(flag)) << name << ": " << flag;
    }
  }
}

TEST(SlamFlagsTest, IsSlamFlagKnowsTheSolverFlagsOnly) {
  for (const char* name :
       {"prior", "num_features", "estimate_range_calibration", "max_memory_gb",
        "parameter_tolerance"}) {
    EXPECT_TRUE(IsSlamFlag(name)) << name;
  }
  // gflags's, glog's, a negated boolean and an unknown name.
  for (const char* name : {"flagfile", "helpfull", "v", "logtostderr",
                           "noestimate_range_calibration", "nonsense", ""}) {
    EXPECT_FALSE(IsSlamFlag(name)) << name;
  }
}

}  // namespace
}  // namespace rff
