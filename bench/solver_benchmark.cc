// Google Benchmark suite of the RFF-SLAM solver (see bench/README.md):
//
// - BM_Iteration/N/D/L/solver/seg: one Levenberg-Marquardt iteration
//   (linearisation + Schur linear solve), with its ratio to the BLAS-3 bound.
// - BM_GramLowerBound/rows/D: a dense BLAS-3 Gram J^T J (Eigen SYRK).
// - BM_FullSolve/N/solver: the whole RunSlam, windowed, fixed iterations,
//   with SPARSE_SCHUR or the default linear solver.
// - BM_DefaultSolver/prior/poses/solver: the whole RunSlam with default
//   options, the "auto" linear solver against each explicit one.
// - BM_FeatureCache/N/D/cached: building the pose maps with and without the
//   per-time feature cache.
// - BM_PosteriorCovariance/poses/method: every output pose's and landmark's
//   covariance of a WNOA run, from the envelope (the default) against the
//   selected inverse of a sparse Cholesky.
//
// Flags of our own (removed before Google Benchmark parses the rest):
//   --large      also register the N = 1e6 BM_Iteration rows and the
//                whole solves at 125000 and 1e6 observations
//   --solver_choice  register the BM_DefaultSolver rows
//   --threads=K  Ceres threads (default 1: the BLAS-3 bound is one thread)
//   --lm_iterations=K  LM iterations per BM_Iteration solve (default 3)
#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <numeric>
#include <string>
#include <tuple>
#include <vector>

#include "Eigen/Core"
#include "benchmark/benchmark.h"
#include "ceres/solver.h"
#include "rff_ceres/banded_minimizer.h"
#include "rff_ceres/banded_problem.h"
#include "rff_ceres/feature_trajectory.h"
#include "rff_ceres/io/dataset_io.h"
#include "rff_ceres/io/text_parser.h"
#include "rff_ceres/landmark_init.h"
#include "rff_ceres/mean/prior_mean.h"
#include "rff_ceres/mean/mean_function.h"
#include "rff_ceres/metrics.h"
#include "rff_ceres/posterior_covariance.h"
#include "rff_ceres/simulate.h"
#include "rff_ceres/slam_problem.h"
#include "rff_ceres/slam_solver.h"
#include "rff_ceres/wnoa_trajectory.h"
#include "test/synthetic_options.h"

namespace rff {
namespace {

int g_threads = 1;
int g_lm_iterations = 3;

// Observations per pose (1 Hz): N observations span N / 10 seconds.
constexpr int kObservationsPerStep = 10;
// Each landmark is seen from about this many steps either side of its anchor
// (more when there are too few landmarks to give every pose 10 candidates).
constexpr int kVisibilitySteps = 10;

const char* const kSolverNames[] = {"DENSE_SCHUR", "SPARSE_SCHUR",
                                    "ITERATIVE_SCHUR", "BANDED_CHOLESKY"};

double PeakRssMiB() {
  rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // Linux reports KiB.
}

// CPU seconds of the whole process (all threads).
double ProcessCpuSeconds() {
  timespec now;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return now.tv_sec + 1e-9 * now.tv_nsec;
}

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
      .count();
}

// N range-bearing observations (10 per pose, 1 Hz) along the paper's
// wandering unicycle from Simulate (its odometry, first-pose prior and ground
// truth kept). Simulate draws landmarks from the whole run; here the L
// landmarks are anchored along the path instead and each is observed only
// from a local stretch, as a real sensor would, so the reduced system stays
// banded. Every landmark gets a 5 m prior, as in the paper's protocol.
// `per_step` observations per pose; with `landmark_seen_throughout` one more
// landmark (id L) is also observed from every pose, the structure that
// makes a Schur complement dense.
bool MakeDataset(int num_observations, int num_landmarks, Dataset* dataset,
                 std::string* error, int per_step = kObservationsPerStep,
                 bool landmark_seen_throughout = false) {
  const int steps = num_observations / per_step;
  if (steps < 2 || num_landmarks < per_step) {
    *error = "need N >= 2 per_step and L >= per_step";
    return false;
  }
  SimulationOptions sim = PaperOptions(/*seed=*/1);
  sim.num_steps = steps;
  sim.num_landmarks = 1;  // Replaced below.
  sim.observations_per_step = 1;
  if (!Simulate(sim, dataset, error)) return false;
  dataset->observations.clear();
  dataset->landmark_priors.clear();
  dataset->ground_truth_landmarks.clear();
  const std::vector<TimedPose>& poses = dataset->ground_truth;

  SimulationRandom random(/*seed=*/7);
  for (int j = 0; j < num_landmarks; ++j) {
    const int anchor = std::min(
        steps - 1, static_cast<int>((j + 0.5) * steps / num_landmarks));
    const double r = random.Uniform(3.0, 15.0);
    const double a = random.Uniform(-M_PI, M_PI);
    Landmark landmark;
    landmark.id = j;
    landmark.x = poses[anchor].x + r * std::cos(a);
    landmark.y = poses[anchor].y + r * std::sin(a);
    dataset->ground_truth_landmarks.push_back(landmark);
    LandmarkPrior prior;
    prior.id = j;
    prior.sigma = sim.landmark_prior_sigma;
    prior.x = landmark.x + prior.sigma * random.Normal();
    prior.y = landmark.y + prior.sigma * random.Normal();
    dataset->landmark_priors.push_back(prior);
  }
  if (landmark_seen_throughout) {
    Landmark landmark;
    landmark.id = num_landmarks;
    landmark.x = poses[steps / 2].x + 20.0;
    landmark.y = poses[steps / 2].y;
    dataset->ground_truth_landmarks.push_back(landmark);
    dataset->landmark_priors.push_back(
        {landmark.id, landmark.x, landmark.y, sim.landmark_prior_sigma});
  }
  const int observed_locally =
      landmark_seen_throughout ? per_step - 1 : per_step;
  const int half_window = std::max(
      per_step / 2 + 1, static_cast<int>(std::ceil(
                            kVisibilitySteps * double(num_landmarks) / steps)));
  std::vector<int> candidates;
  for (int i = 0; i < steps; ++i) {
    const int centre =
        static_cast<int>(std::lround((i + 0.5) * num_landmarks / steps - 0.5));
    int lo = std::max(0, centre - half_window);
    int hi = std::min(num_landmarks - 1, centre + half_window);
    while (hi - lo + 1 < per_step) {  // At the ends of the run.
      if (lo > 0) --lo;
      if (hi < num_landmarks - 1) ++hi;
    }
    candidates.resize(hi - lo + 1);
    std::iota(candidates.begin(), candidates.end(), lo);
    for (int k = 0; k < per_step; ++k) {
      if (k < observed_locally) {
        std::swap(candidates[k],
                  candidates[k + random.Index(candidates.size() - k)]);
      }
      const Landmark& l =
          dataset->ground_truth_landmarks[k < observed_locally ? candidates[k]
                                                               : num_landmarks];
      const double dx = l.x - poses[i].x, dy = l.y - poses[i].y;
      Observation o;
      o.type = ObservationType::kRangeBearing;
      o.t = poses[i].t;
      o.id = l.id;
      o.sigma_range = sim.sigma_range;
      o.sigma_bearing = sim.sigma_bearing;
      o.range = std::hypot(dx, dy) + o.sigma_range * random.Normal();
      o.bearing = WrapAngle(std::atan2(dy, dx) - poses[i].theta +
                            o.sigma_bearing * random.Normal());
      dataset->observations.push_back(o);
    }
  }
  return true;
}

// The settings of configs/synthetic_*.flags (RBF, Hilbert features, 5 s
// lengthscale) with D features per coordinate and per segment, and windows of
// `segment` seconds overlapping by 30 % (50 s / 15 s in the configs); 0: one
// global feature map.
SlamOptions BenchOptions(int num_features, double segment,
                         const std::string& solver) {
  // Odometry mean: the dataset has ODOM.
  SlamOptions options = testing::SyntheticRangeBearingOptions();
  FeatureTrajectoryOptions& t = options.features;
  t.num_position_features = num_features;
  t.num_heading_features = num_features;
  t.segment_length = segment;
  t.segment_overlap = 0.3 * segment;
  options.solver.linear_solver = solver;
  options.solver.num_threads = g_threads;
  // No early stop: every solve does exactly max_iterations iterations.
  options.solver.function_tolerance = 0.0;
  options.solver.gradient_tolerance = 0.0;
  options.solver.parameter_tolerance = 0.0;
  return options;
}

// The datasets of the last (N, L), shared by the rows that differ in D,
// segment or solver only.
const Dataset& CachedDataset(int num_observations, int num_landmarks,
                             int per_step = kObservationsPerStep,
                             bool landmark_seen_throughout = false) {
  static std::tuple<int, int, int, bool> key(-1, -1, -1, false);
  static Dataset dataset;
  const auto wanted = std::make_tuple(num_observations, num_landmarks, per_step,
                                      landmark_seen_throughout);
  if (key != wanted) {
    dataset = Dataset();
    std::string error;
    if (!MakeDataset(num_observations, num_landmarks, &dataset, &error,
                     per_step, landmark_seen_throughout)) {
      fprintf(stderr, "MakeDataset: %s\n", error.c_str());
      std::exit(1);
    }
    key = wanted;
    // The row's data as .rffd, to rerun it with rff_slam --dataset.
    const char* path = std::getenv("RFF_BENCH_DUMP");
    if (path != nullptr && !WriteDataset(dataset, path, &error)) {
      fprintf(stderr, "RFF_BENCH_DUMP: %s\n", error.c_str());
      std::exit(1);
    }
  }
  return dataset;
}

struct Timing {
  double wall = 1e300;  // Seconds.
  double cpu = 1e300;   // Process CPU seconds: robust on a loaded machine.
};

// One dense Gram G = J^T J (the lower triangle, Eigen's SYRK) for J of
// rows x cols; the best of `repeats`.
Timing TimeGram(int rows, int cols, int repeats) {
  const Eigen::MatrixXd jacobian = Eigen::MatrixXd::Random(rows, cols);
  Eigen::MatrixXd gram(cols, cols);
  Timing best;
  for (int r = 0; r < repeats; ++r) {
    gram.setZero();
    const double cpu = ProcessCpuSeconds();
    const auto start = std::chrono::steady_clock::now();
    gram.selfadjointView<Eigen::Lower>().rankUpdate(jacobian.transpose());
    benchmark::DoNotOptimize(gram.data());
    best.wall = std::min(best.wall, Seconds(start));
    best.cpu = std::min(best.cpu, ProcessCpuSeconds() - cpu);
  }
  return best;
}

// Dense Gram time of `rows` x `cols`, timed on a slice of at most ~2^21
// entries and scaled by rows (SYRK costs rows * cols^2).
Timing GramLowerBound(long rows, int cols) {
  const long slice =
      std::min<long>(rows, std::max<long>(cols, (1L << 21) / cols));
  Timing t = TimeGram(static_cast<int>(slice), cols, 3);
  t.wall *= double(rows) / slice;
  t.cpu *= double(rows) / slice;
  return t;
}

// Everything RunSlam builds before ceres::Solve, kept across the benchmark's
// repeated calls and its solver rows.
struct ProblemSetup {
  std::tuple<int, int, int, int> key{-1, -1, -1, -1};  // N, D, L, segment
  std::unique_ptr<FeatureTrajectory> model;
  std::unique_ptr<SlamProblem> problem;
  std::vector<double*> blocks;
  std::vector<std::vector<double>> initial_values;
  int num_segments = 0;
  long trajectory_rows = 0;  // Scalar residuals touching trajectory blocks.
  int trajectory_params = 0;
  double build_seconds = 0.0;
  Timing gram;  // The dense lower bound, see CachedSetup.

  void Reset() {
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      std::copy(initial_values[i].begin(), initial_values[i].end(), blocks[i]);
    }
  }
};

ProblemSetup& CachedSetup(int n, int d, int l, int segment) {
  static ProblemSetup setup;
  const auto key = std::make_tuple(n, d, l, segment);
  if (setup.key == key) return setup;
  setup = ProblemSetup();
  const Dataset& dataset = CachedDataset(n, l);
  const SlamOptions options = BenchOptions(d, segment, "DENSE_SCHUR");
  std::string error;
  const auto start = std::chrono::steady_clock::now();
  std::shared_ptr<const MeanFunction> mean =
      BuildPriorMean(options.mean.name, dataset, &error);
  std::map<LandmarkId, Eigen::Vector2d> landmarks;
  bool ok = mean != nullptr;
  if (ok) {
    // RunSlam's window: every time the dataset mentions (here the GT and
    // odometry times cover the observations).
    const double t_begin = dataset.ground_truth.front().t;
    const double t_end = dataset.ground_truth.back().t;
    setup.model = FeatureTrajectory::Create(options.features, mean, t_begin,
                                            t_end, &error);
    ok = setup.model != nullptr &&
         InitializeLandmarks(
             dataset, [&](double t) { return mean->Evaluate(t); }, &landmarks,
             &error);
  }
  if (ok) {
    setup.problem =
        std::make_unique<SlamProblem>(setup.model.get(), options.problem);
    ok = setup.problem->Build(dataset, landmarks, &error);
  }
  if (!ok) {
    fprintf(stderr, "setup N=%d D=%d L=%d: %s\n", n, d, l, error.c_str());
    std::exit(1);
  }
  setup.build_seconds = Seconds(start);
  ceres::Problem* problem = setup.problem->problem();
  problem->GetParameterBlocks(&setup.blocks);
  for (double* block : setup.blocks) {
    setup.initial_values.emplace_back(
        block, block + problem->ParameterBlockSize(block));
  }
  setup.num_segments = setup.model->num_segments();
  for (int b = 0; b < setup.model->num_blocks(); ++b) {
    setup.trajectory_params += setup.model->block_size(b);
  }
  // Rows of observations, odometry and pose priors: all residuals minus the
  // weight priors (one row per weight) and the landmark priors (two each).
  setup.trajectory_rows = problem->NumResiduals() - setup.trajectory_params -
                          2L * dataset.landmark_priors.size();
  // The bound: per segment, a dense Gram of that segment's share of the rows
  // over its 3D weights, summed over segments (cross-segment blocks of the
  // overlaps and the landmark columns left out, so it stays a lower bound).
  const int cols = setup.trajectory_params / setup.num_segments;
  setup.gram = GramLowerBound(
      (setup.trajectory_rows + setup.num_segments - 1) / setup.num_segments,
      cols);
  setup.gram.wall *= setup.num_segments;
  setup.gram.cpu *= setup.num_segments;
  setup.key = key;
  return setup;
}

// Mean of per-iteration values over the iterations after the first step
// (iteration 1 carries one-off work such as the symbolic factorisation).
double SteadyMean(const ceres::Solver::Summary& summary,
                  double ceres::IterationSummary::*field) {
  const auto& it = summary.iterations;
  if (it.size() < 2) return 0.0;
  const std::size_t first = it.size() > 2 ? 2 : 1;
  double sum = 0.0;
  for (std::size_t i = first; i < it.size(); ++i) sum += it[i].*field;
  return sum / (it.size() - first);
}

// BM_Iteration on BANDED_CHOLESKY (banded_minimizer.h): the layout built
// once, as Ceres's preprocessor is left out of the other rows; an iteration
// is the minimiser's time over its steps (a linearisation, a factorisation
// and a cost each), its linear solve the factorisation and the solves.
void TimeBandedIteration(ProblemSetup& setup,
                         const ceres::Solver::Options& ceres_options,
                         benchmark::State* state) {
  const BandedColumns columns = setup.problem->BandColumns();
  std::string why;
  if (!BandedSolvable(*setup.problem->problem(), columns, &why)) {
    state->SkipWithError(why.c_str());
    return;
  }
  BandedProblem banded(*setup.problem->problem(), columns);
  double iteration = 0.0, linear = 0.0, first_linear = 0.0, cpu_fraction = 0.0;
  int runs = 0;
  for (auto _ : *state) {
    state->PauseTiming();
    setup.Reset();
    state->ResumeTiming();
    const double cpu = ProcessCpuSeconds();
    ceres::Solver::Summary summary;
    MinimizeBanded(ceres_options, &banded, setup.problem->problem(), &summary,
                   /*decrement_tolerance=*/0.0);
    state->PauseTiming();
    cpu_fraction +=
        (ProcessCpuSeconds() - cpu) / summary.minimizer_time_in_seconds;
    if (summary.termination_type == ceres::FAILURE ||
        summary.iterations.size() < 2) {
      state->SkipWithError(("solve failed: " + summary.message).c_str());
      state->ResumeTiming();
      break;
    }
    iteration += summary.minimizer_time_in_seconds /
                 static_cast<double>(summary.iterations.size() - 1);
    linear += SteadyMean(summary,
                         &ceres::IterationSummary::step_solver_time_in_seconds);
    first_linear += summary.iterations[1].step_solver_time_in_seconds;
    ++runs;
    state->ResumeTiming();
  }
  if (runs == 0) return;
  const double ms = 1e3 / runs;
  state->counters["iteration_ms"] = iteration * ms;
  state->counters["linear_ms"] = linear * ms;
  state->counters["first_linear_ms"] = first_linear * ms;
  state->counters["blas3_ms"] = setup.gram.wall * 1e3;
  state->counters["ratio_to_blas3"] = iteration * ms / (setup.gram.wall * 1e3);
  const double iteration_cpu = iteration * ms * cpu_fraction / runs;
  state->counters["iteration_cpu_ms"] = iteration_cpu;
  state->counters["ratio_to_blas3_cpu"] =
      iteration_cpu / (setup.gram.cpu * 1e3);
  const BandedSize size = banded.Size();
  state->counters["envelope_work_per_variable"] =
      size.multiply_adds / std::max(size.num_columns, 1);
  state->counters["segments"] = setup.num_segments;
  state->counters["peak_rss_MiB"] = PeakRssMiB();
  state->SetLabel("BANDED_CHOLESKY windows");
}

void BM_Iteration(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int d = static_cast<int>(state.range(1));
  const int l = static_cast<int>(state.range(2));
  const std::string solver = kSolverNames[state.range(3)];
  const int segment = static_cast<int>(state.range(4));
  ProblemSetup& setup = CachedSetup(n, d, l, segment);

  SlamOptions options = BenchOptions(d, segment, solver);
  options.solver.max_iterations = g_lm_iterations;
  ceres::Solver::Options ceres_options;
  std::string error;
  if (!ToCeresOptions(options.solver, &ceres_options, &error)) {
    state.SkipWithError(error.c_str());
    return;
  }

  if (solver == "BANDED_CHOLESKY") {
    TimeBandedIteration(setup, ceres_options, &state);
    return;
  }
  double jacobian = 0, residual = 0, linear = 0, first_linear = 0;
  double preprocess = 0, cg_iterations = 0, cpu_fraction = 0;
  int runs = 0;
  ceres::Solver::Summary summary;
  for (auto _ : state) {
    state.PauseTiming();
    setup.Reset();
    // The preprocessor edits the ordering it is given: a fresh one per solve.
    ceres_options.linear_solver_ordering = setup.problem->Ordering();
    state.ResumeTiming();
    const double cpu = ProcessCpuSeconds();
    const auto start = std::chrono::steady_clock::now();
    ceres::Solve(ceres_options, setup.problem->problem(), &summary);
    const double wall = Seconds(start);
    state.PauseTiming();
    cpu_fraction += (ProcessCpuSeconds() - cpu) / wall;
    if (summary.termination_type == ceres::FAILURE ||
        summary.iterations.size() < 2) {
      state.SkipWithError(("solve failed: " + summary.message).c_str());
      state.ResumeTiming();
      break;
    }
    ++runs;
    jacobian += summary.jacobian_evaluation_time_in_seconds /
                std::max(1, summary.num_jacobian_evaluations);
    residual += summary.residual_evaluation_time_in_seconds /
                std::max(1, summary.num_residual_evaluations);
    linear += SteadyMean(summary,
                         &ceres::IterationSummary::step_solver_time_in_seconds);
    first_linear += summary.iterations[1].step_solver_time_in_seconds;
    preprocess += summary.preprocessor_time_in_seconds;
    double cg = 0;
    for (std::size_t i = 1; i < summary.iterations.size(); ++i) {
      cg += summary.iterations[i].linear_solver_iterations;
    }
    cg_iterations += cg / (summary.iterations.size() - 1);
    state.ResumeTiming();
  }
  if (runs == 0) return;
  const double ms = 1e3 / runs;
  const double iteration = (jacobian + linear + residual) * ms;
  state.counters["iteration_ms"] = iteration;
  state.counters["jacobian_ms"] = jacobian * ms;
  state.counters["linear_ms"] = linear * ms;
  state.counters["first_linear_ms"] = first_linear * ms;
  state.counters["residual_ms"] = residual * ms;
  state.counters["preprocess_ms"] = preprocess * ms;
  state.counters["linear_iterations"] = cg_iterations / runs;
  state.counters["blas3_ms"] = setup.gram.wall * 1e3;
  state.counters["ratio_to_blas3"] = iteration / (setup.gram.wall * 1e3);
  // The same on CPU time: Ceres's wall-clock parts scaled by the solve's
  // CPU / wall fraction (equal to the above on an idle machine, one thread).
  const double iteration_cpu = iteration * cpu_fraction / runs;
  state.counters["iteration_cpu_ms"] = iteration_cpu;
  state.counters["blas3_cpu_ms"] = setup.gram.cpu * 1e3;
  state.counters["ratio_to_blas3_cpu"] = iteration_cpu / (setup.gram.cpu * 1e3);
  state.counters["segments"] = setup.num_segments;
  state.counters["traj_params"] = setup.trajectory_params;
  state.counters["traj_rows"] = setup.trajectory_rows;
  state.counters["residual_blocks"] = summary.num_residual_blocks;
  state.counters["build_ms"] = setup.build_seconds * 1e3;
  state.counters["peak_rss_MiB"] = PeakRssMiB();
  state.SetLabel(solver + (segment > 0
                               ? " windows " + std::to_string(segment) + "s/" +
                                     FormatNumber(0.3 * segment) + "s"
                               : " global map"));
}

void BM_GramLowerBound(benchmark::State& state) {
  const int rows = static_cast<int>(state.range(0));
  const int cols = 3 * static_cast<int>(state.range(1));
  const Eigen::MatrixXd jacobian = Eigen::MatrixXd::Random(rows, cols);
  Eigen::MatrixXd gram(cols, cols);
  for (auto _ : state) {
    gram.setZero();
    gram.selfadjointView<Eigen::Lower>().rankUpdate(jacobian.transpose());
    benchmark::DoNotOptimize(gram.data());
    benchmark::ClobberMemory();
  }
  // SYRK: rows * cols * (cols + 1) / 2 multiply-adds, 2 flops each.
  state.counters["GFLOPs"] =
      benchmark::Counter(2.0 * rows * cols * (cols + 1.0) / 2.0 * 1e-9,
                         benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel("J " + std::to_string(rows) + " x " + std::to_string(cols));
}

// The timed loop of a whole-solve benchmark; false (the row marked with the
// error) when RunSlam fails.
bool TimeRunSlam(const Dataset& dataset, const SlamOptions& options,
                 benchmark::State* state, SlamResult* result) {
  std::string error;
  for (auto _ : *state) {
    if (!RunSlam(dataset, options, result, &error)) {
      state->SkipWithError(error.c_str());
      return false;
    }
  }
  return true;
}

// Row 0 is what the whole-solve goal was first measured with; row 1
// is the default linear solver.
const char* const kFullSolveSolvers[] = {"SPARSE_SCHUR", "auto"};

void BM_FullSolve(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int l = n / 50;
  const std::string solver = kFullSolveSolvers[state.range(1)];
  const Dataset& dataset = CachedDataset(n, l);
  SlamOptions options = BenchOptions(24, 50, solver);
  options.solver.max_iterations = 10;
  SlamResult result;
  if (!TimeRunSlam(dataset, options, &state, &result)) return;
  state.counters["iterations"] = result.total_iterations;
  state.counters["ms_per_iteration"] =
      1e3 * result.summary.minimizer_time_in_seconds /
      result.summary.iterations.size();
  state.counters["ceres_ms"] = 1e3 * result.summary.total_time_in_seconds;
  // The localisation mean: a solve of its own before the main one.
  state.counters["mean_ms"] = 1e3 * result.mean_seconds;
  // Landmark set-up, problem build, checks, output poses.
  state.counters["outside_ceres_ms"] =
      1e3 * (result.solve_seconds - result.mean_seconds -
             result.summary.total_time_in_seconds);
  state.counters["peak_rss_MiB"] = PeakRssMiB();
  state.counters["landmarks"] = l;
  state.SetLabel(result.linear_solver +
                 " D=24 windows 50s/15s L=N/50, 10 iterations");
}

const char* const kPriorNames[] = {"rff", "wnoa"};
// Row 0 is the default; the others are the explicit choices it must match.
const char* const kDefaultSolverRows[] = {"auto", "SPARSE_NORMAL_CHOLESKY",
                                          "SPARSE_SCHUR", "ITERATIVE_SCHUR",
                                          "DENSE_SCHUR"};

// The whole RunSlam with rff_slam's defaults but the prior and the linear
// solver: auto against every explicit solver on the same problem. A solver
// whose system would not fit is refused (the row shows the message).
void BM_DefaultSolver(benchmark::State& state) {
  const std::string prior = kPriorNames[state.range(0)];
  const int poses = static_cast<int>(state.range(1));
  const std::string solver = kDefaultSolverRows[state.range(2)];
  // Three range-bearing observations per pose at 1 Hz: two of local
  // landmarks (L = poses / 10), one of a landmark seen from every pose.
  const Dataset& dataset = CachedDataset(3 * poses, poses / 10, /*per_step=*/3,
                                         /*landmark_seen_throughout=*/true);
  SlamOptions options;
  options.prior = prior;
  options.solver.linear_solver = solver;
  options.solver.num_threads = g_threads;
  SlamResult result;
  if (!TimeRunSlam(dataset, options, &state, &result)) return;
  Evaluation evaluation;
  std::string error;
  if (!Evaluate(dataset.ground_truth, dataset.ground_truth_landmarks,
                result.trajectory, nullptr, EvaluationOptions(), &evaluation,
                &error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  state.counters["ape_m"] = evaluation.ape_translation.rms;
  state.counters["iterations"] = result.total_iterations;
  state.counters["mean_ms"] = 1e3 * result.mean_seconds;
  state.counters["peak_rss_MiB"] = PeakRssMiB();
  state.SetLabel(result.linear_solver + ": " + result.linear_solver_reason);
}

// Pose maps of every observation, as SlamProblem::Build makes them, from a
// fresh trajectory (empty cache). cached = 1: the real times, 10 observations
// per time share one feature evaluation. cached = 0: every observation time
// moved by a few ulps so that no two coincide, which is what the build would
// cost without the cache (one evaluation and one vector per observation).
void BM_FeatureCache(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int d = static_cast<int>(state.range(1));
  const bool cached = state.range(2) != 0;
  const Dataset& dataset = CachedDataset(n, n / 50);
  std::vector<double> times;
  double previous = -1e300;
  for (const Observation& o : dataset.observations) {
    double t = o.t;
    if (!cached && t <= previous) t = std::nextafter(previous, 1e300);
    times.push_back(t);
    previous = t;
  }
  const SlamOptions options = BenchOptions(d, 50, "DENSE_SCHUR");
  std::string error;
  std::shared_ptr<const MeanFunction> mean =
      BuildPriorMean(options.mean.name, dataset, &error);
  std::size_t distinct = 0;
  for (auto _ : state) {
    state.PauseTiming();
    auto model = FeatureTrajectory::Create(options.features, mean,
                                           times.front(), times.back(), &error);
    std::vector<PoseMap> maps;
    maps.reserve(times.size());
    state.ResumeTiming();
    for (const double t : times) maps.push_back(model->PoseAt(t));
    state.PauseTiming();
    std::map<const double*, int> vectors;
    for (const PoseMap& map : maps) {
      for (const PoseTerm& term : map.terms) vectors[term.phi->data()] = 1;
    }
    distinct = vectors.size();
    maps.clear();
    model.reset();
    state.ResumeTiming();
  }
  state.counters["feature_vectors"] = distinct;
  state.counters["feature_MiB"] = distinct * d * 8.0 / (1 << 20);
  state.SetLabel(cached ? "cache shared per time" : "no sharing (distinct t)");
}

// The posterior covariance at every pose of a WNOA model on BM_DefaultSolver's
// data (states and landmarks at the truth: the cost does not depend on the
// point), by the envelope's inverse (method 0, the default) or the selected
// inverse of a sparse Cholesky (method 1).
void BM_PosteriorCovariance(benchmark::State& state) {
  const int poses = static_cast<int>(state.range(0));
  const int method = static_cast<int>(state.range(1));
  const Dataset& dataset = CachedDataset(3 * poses, poses / 10, /*per_step=*/3,
                                         /*landmark_seen_throughout=*/true);
  std::vector<double> times;
  for (const TimedPose& p : dataset.ground_truth) times.push_back(p.t);
  std::string error;
  std::unique_ptr<WnoaTrajectory> model = WnoaTrajectory::Create(
      WnoaOptions(),
      std::make_shared<PiecewiseLinearMean>(dataset.ground_truth), times,
      &error);
  std::map<LandmarkId, Eigen::Vector2d> initial;
  std::vector<Landmark> landmarks;
  for (const Landmark& l : dataset.ground_truth_landmarks) {
    initial[l.id] = Eigen::Vector2d(l.x, l.y);
    landmarks.push_back(l);
  }
  SlamProblem problem(model.get(), ProblemOptions());
  if (model == nullptr || !problem.Build(dataset, initial, &error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  CovarianceOptions options;
  options.use_envelope = method == 0;
  CovarianceMethod used = CovarianceMethod::kCeres;
  for (auto _ : state) {
    std::vector<Eigen::Matrix3d> covariances;
    std::vector<Landmark> with_covariance = landmarks;
    if (!ComputePosteriorCovariance(&problem, *model, times, options,
                                    &covariances, &with_covariance, &error,
                                    &used)) {
      state.SkipWithError(error.c_str());
      return;
    }
  }
  state.SetLabel(used == CovarianceMethod::kEnvelope ? "envelope"
                 : used == CovarianceMethod::kSelectedInverse
                     ? "selected inverse"
                     : "another method");
}

// Rows: {N, D, L, solver (0 dense, 1 sparse, 2 iterative), segment seconds}.
// Solver index: 0 DENSE_SCHUR, 1 SPARSE_SCHUR, 2 ITERATIVE_SCHUR, 3
// BANDED_CHOLESKY (kSolverNames).
void QuickIterationRows(benchmark::internal::Benchmark* b) {
  // N scaling at the config settings (D = 24, windows 50 s / 15 s, L = N/50).
  b->Args({1000, 24, 20, 0, 50})->Args({1000, 24, 20, 1, 50});
  b->Args({1000, 24, 20, 2, 50});
  b->Args({10000, 24, 200, 0, 50})->Args({10000, 24, 200, 1, 50});
  b->Args({10000, 24, 200, 2, 50});
  b->Args({100000, 24, 2000, 1, 50})->Args({100000, 24, 2000, 2, 50});
  for (int n : {1000, 10000, 100000}) b->Args({n, 24, n / 50, 3, 50});
  // D sweep with one global feature map (100 s run).
  for (int d : {20, 100, 400}) b->Args({1000, d, 20, 0, 0});
  // D sweep with windows at N = 1e4.
  for (int d : {50, 100}) b->Args({10000, d, 200, 1, 50});
  // Landmark sweep at N = 1e4 (fewer landmarks: longer tracks, wider band).
  for (int l : {50, 1000}) b->Args({10000, 24, l, 1, 50});
}

void LargeIterationRows(benchmark::internal::Benchmark* b) {
  b->Args({1000000, 24, 20000, 1, 50})->Args({1000000, 24, 20000, 2, 50});
  b->Args({1000000, 24, 20000, 3, 50});
}

void Configure(benchmark::internal::Benchmark* b) {
  b->ArgNames({"N", "D", "L", "solver", "seg"})
      ->UseRealTime()
      ->Unit(benchmark::kMillisecond);
}

}  // namespace
}  // namespace rff

int main(int argc, char** argv) {
  bool large = false, solver_choice = false;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--large") == 0) {
      large = true;
    } else if (std::strcmp(argv[i], "--solver_choice") == 0) {
      solver_choice = true;
    } else if (std::strncmp(argv[i], "--threads=", 10) == 0) {
      rff::g_threads = std::atoi(argv[i] + 10);
    } else if (std::strncmp(argv[i], "--lm_iterations=", 16) == 0) {
      rff::g_lm_iterations = std::max(2, std::atoi(argv[i] + 16));
    } else {
      args.push_back(argv[i]);
    }
  }
  using benchmark::RegisterBenchmark;
  // Registration order is run order: small to large, so the process-wide
  // peak RSS of the last rows is theirs.
  RegisterBenchmark("BM_GramLowerBound", rff::BM_GramLowerBound)
      ->ArgNames({"rows", "D"})
      ->ArgsProduct({{1000, 10000}, {24, 100, 400}})
      ->UseRealTime()
      ->Unit(benchmark::kMillisecond);
  RegisterBenchmark("BM_FeatureCache", rff::BM_FeatureCache)
      ->ArgNames({"N", "D", "cached"})
      ->ArgsProduct({{10000, 100000}, {24, 100}, {1, 0}})
      ->UseRealTime()
      ->Unit(benchmark::kMillisecond);
  RegisterBenchmark("BM_PosteriorCovariance", rff::BM_PosteriorCovariance)
      ->ArgNames({"poses", "method"})
      ->ArgsProduct({{2000, 20000}, {1, 0}})
      ->UseRealTime()
      ->Unit(benchmark::kMillisecond);
  rff::Configure(RegisterBenchmark("BM_Iteration", rff::BM_Iteration)
                     ->Apply(rff::QuickIterationRows));
  RegisterBenchmark("BM_FullSolve", rff::BM_FullSolve)
      ->ArgNames({"N", "solver"})
      ->ArgsProduct({{12500, 100000}, {0, 1}})
      ->UseRealTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(1);
  if (solver_choice) {
    // Default against explicit solvers at 2k, 20k and 1e5 poses, both
    // priors; some explicit rows take hours (run them under a timeout).
    RegisterBenchmark("BM_DefaultSolver", rff::BM_DefaultSolver)
        ->ArgNames({"prior", "poses", "solver"})
        ->ArgsProduct({{0, 1}, {2000, 20000, 100000}, {0, 1, 2, 3, 4}})
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond)
        ->Iterations(1);
  }
  if (large) {
    rff::Configure(RegisterBenchmark("BM_Iteration", rff::BM_Iteration)
                       ->Apply(rff::LargeIterationRows));
    // Whole solves with the default linear solver at 1e6 observations and
    // an eighth of that: memory and time(8N) / time(N).
    RegisterBenchmark("BM_FullSolve", rff::BM_FullSolve)
        ->ArgNames({"N", "solver"})
        ->ArgsProduct({{125000, 1000000}, {1}})
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond)
        ->Iterations(1);
  }
  int count = static_cast<int>(args.size());
  benchmark::Initialize(&count, args.data());
  if (benchmark::ReportUnrecognizedArguments(count, args.data())) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
