// range_nlm_bench: times range_nlm (fast and direct evaluation) against PCL's
// FastBilateralFilterOMP and MovingLeastSquares in one run, on the same frames, in the paper's
// configurations, each method in a child process of its own (its own peak memory) and the
// methods of a configuration taking turns (a warm-up call, then the timed one).
#include "accuracy_time.h"
#include "bench_support.h"
#include "generalisation_comparison.h"
#include "hole_filling_comparison.h"
#include "peers.h"
#include "quality_comparison.h"
#include "real_noise_comparison.h"
#include "temporal_comparison.h"
#include "uncertainty_calibration.h"
#include "cli/cli.h"
#include "io/output_file.h"

#include <range_nlm/core/pipeline.h>
#include <range_nlm/grid_adaptor.h>
#include <range_nlm/nonlocal_means_filter.h>
#include <range_nlm/parameter_registry.h>
#include <range_nlm/temporal_nonlocal_means_filter.h>
#include <range_nlm/temporal_stream.h>

#include <pcl/filters/fast_bilateral_omp.h>
#include <pcl/pcl_config.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/mls.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <deque>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <sstream>
#include <tuple>

#ifndef RANGE_NLM_DATA_DIR
#error "RANGE_NLM_DATA_DIR must name the directory of the shipped frames"
#endif

namespace po = boost::program_options;
using namespace range_nlm;
using namespace range_nlm::tools;
namespace bench = range_nlm::tools::bench;

namespace
{

const char* const kUsage =
    "Usage:\n"
    "  range_nlm_bench [options]\n"
    "Times range_nlm's NonLocalMeansFilter (fast and direct evaluation) and the temporal filter\n"
    "against pcl::FastBilateralFilterOMP and pcl::MovingLeastSquares on the same frames: first the\n"
    "preset as users run it (its own window sizes; static on a 640x480 frame, then temporal with\n"
    "radius 1 on three whole frames), then the paper's configurations: static 7x7 search / 5x5\n"
    "patch on a 640x480 frame, and temporal 19x19 / 11x11 with radius 1 (3 frames) on 480x400\n"
    "centre crops. Each method runs in its own\n"
    "child process; its peak memory is the child's ru_maxrss reported by wait4. The methods of a\n"
    "configuration take turns, --runs rounds of one turn each: an untimed warm-up run, then a\n"
    "timed one. A change of the machine's speed then reaches all of them alike. Each method's\n"
    "figure is the median of its timed runs. Without options it uses the frames shipped in data/.\n"
    "With --accuracy-time, --quality, --real-noise, --generalisation, --temporal-comparison,\n"
    "--uncertainty-calibration or --hole-filling it measures accuracy instead (see each option).";

using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using CloudConstPtr = Cloud::ConstPtr;

const std::string kDataDir = RANGE_NLM_DATA_DIR;

constexpr int kStaticSearch = 7, kStaticPatch = 5;
constexpr int kTemporalSearch = 19, kTemporalPatch = 11, kTemporalRadius = 1;
constexpr unsigned kTemporalWidth = 480, kTemporalHeight = 400;
constexpr float kBilateralSigmaS = 5.0f, kBilateralSigmaR = 0.03f;
constexpr double kStaticTargetMs = 30.0, kTemporalTargetMs = 1000.0, kSequenceTargetMb = 200.0;
// The preset as users run it on a VGA frame: 30 frames per second.
constexpr double kRealTimeTargetMs = 33.0;
// The temporal filter with the preset (radius 1, three frames) against the static one per frame:
// a camera-rate stream must not lose most of its rate to the neighbour frames.
constexpr double kTemporalOverStatic = 1.3;

double
megabytes(std::uint64_t bytes)
{
  return static_cast<double>(bytes) / 1e6;
}

/// 0 = all cores, resolved the way the library does (OpenMP's default team size).
int
resolveThreads(int requested)
{
  if (requested > 0)
    return requested;
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

/// Conditions of the run, printed with the results.
struct RunInfo
{
  bench::MachineInfo machine;
  std::string build;
  double load_start = -1.0, load_end = -1.0;
  double wall_s = 0.0;
};

struct Settings
{
  std::string input;
  std::string sequence_dir;
  bool synthetic_frames = false;
  std::string config = "all";
  int runs = 5;
  int threads = 1;
  bool all = false;
  bool no_direct = false;
  bool breakdown = false;
  int sequence_memory = 0;
  int sequence_search = kTemporalSearch;
  int sequence_patch = kTemporalPatch;
  double mls_radius = 0.0;
  std::uint64_t seed = 1;
  bool json = false;
  std::string json_file;
  bool quiet = false;
  /// Preset of the range_nlm runs (and its name); search window, patch, evaluation and threads
  /// are set per configuration.
  std::string preset = "default";
  FilterParameters parameters;
};

/// The benchmark's parameters for one configuration.
FilterParameters
parametersFor(const Settings& s, int search, int patch, Evaluation evaluation)
{
  FilterParameters p = s.parameters;
  p.search_window = search;
  p.patch_size = patch;
  p.evaluation = evaluation;
  p.threads = s.threads;
  return p;
}

/// What the range_nlm runs do besides the window sizes, for the notes of the table: the preset
/// and every parameter of the registry set to another value than the preset's (--iterations,
/// --parameter).
std::string
describe(const Settings& s)
{
  const FilterParameters preset = FilterParameters::preset(s.preset);
  std::ostringstream d;
  d << "preset '" << s.preset << "'";
  const char* separator = ": ";
  for (const ParameterEntry& entry : parameterRegistry()) {
    const std::string name = entry.name;
    if (name == "search_window" || name == "patch_size" || name == "evaluation" || name == "threads")
      continue; // set by each configuration and --threads
    const std::string value = parameterText(entry, s.parameters);
    if (value != parameterText(entry, preset)) {
      d << separator << name << " " << value;
      separator = ", ";
    }
  }
  return d.str();
}

/// Applies a --parameter NAME=VALUE to `p`: NAME is a field of the parameter registry.
void
applyParameterOption(const std::string& spec, FilterParameters& p)
{
  try {
    bench::setRegistryField(spec, p);
  } catch (const std::invalid_argument& e) {
    throw UsageError("--parameter '" + spec + "': " + e.what());
  }
}

/// The frames of one configuration.
struct Frames
{
  std::string label;  // e.g. "static 7x7/5x5 640x480"
  std::string source; // where the frames come from
  std::vector<CloudConstPtr> clouds;
  std::size_t center = 0;
  double mls_radius = 0.0; // search radius given to MovingLeastSquares
  std::string mls_radius_origin;
  /// The preset's own search window and patch (the configuration users run) instead of the
  /// paper's window sizes of the timing targets.
  bool preset_windows = false;
};

/// One measured method in one configuration.
struct Row
{
  std::string method;
  std::string config;
  unsigned width = 0, height = 0;
  int frames = 1;
  int threads = 0;
  int runs = 0;
  bool warmup = true;
  std::string note;
  bench::ChildResult result;
  double median_ms = std::numeric_limits<double>::quiet_NaN();
  double min_ms = std::numeric_limits<double>::quiet_NaN();
  double max_ms = std::numeric_limits<double>::quiet_NaN();
  double cpu_ms = std::numeric_limits<double>::quiet_NaN(); // median process CPU time per run
  std::vector<double> samples_ms;

  double points() const { return static_cast<double>(width) * height; }
  double mpointsPerSecond() const
  {
    return result.ok ? points() / (median_ms * 1e3) : std::numeric_limits<double>::quiet_NaN();
  }
};

void
progress(const Settings& s, const std::string& text)
{
  if (!s.quiet)
    std::cerr << "range_nlm_bench: " << text << std::endl;
}

/// A prepared method: builds its objects (not timed) and returns the timed call.
using Prepare = std::function<std::function<void()>()>;

/// A method to time: its row (filled in by measureInterleaved) and how to prepare it.
struct Pending
{
  Row row;
  Prepare prepare;
};

Pending
pending(const Settings& s, const std::string& method, const Frames& frames, int runs, bool warmup,
        const std::string& note, const Prepare& prepare)
{
  Pending p;
  Row& row = p.row;
  row.method = method;
  row.config = frames.label;
  const Cloud& current = *frames.clouds[frames.center];
  row.width = current.width;
  row.height = current.height;
  row.frames = static_cast<int>(frames.clouds.size());
  row.threads = s.threads;
  row.runs = runs;
  row.warmup = warmup;
  row.note = note;
  p.prepare = prepare;
  return p;
}

/// Times the methods of one configuration in turns (bench::runInterleaved), each
/// in a child process of its own, and returns their rows in the given order.
std::vector<Row>
measureInterleaved(const Settings& s, const std::string& config, std::vector<Pending> methods)
{
  std::vector<bench::TimedMethod> timed;
  int rounds = 0;
  for (const Pending& p : methods) {
    timed.push_back({p.prepare, p.row.runs, p.row.warmup});
    rounds = std::max(rounds, p.row.runs);
  }
  progress(s, "timing " + std::to_string(methods.size()) + " methods [" + config + "] in turns, " +
                  std::to_string(rounds) + " round(s) of a warm-up call and a timed call each");
  const std::vector<bench::ChildResult> results = bench::runInterleaved(timed);
  std::vector<Row> rows;
  for (std::size_t k = 0; k < methods.size(); ++k) {
    Row row = methods[k].row;
    row.result = results[k];
    const int runs = row.runs;
    const std::vector<double>& v = row.result.values;
    if (row.result.ok && v.size() == 2 * static_cast<std::size_t>(runs)) {
      row.samples_ms.assign(v.begin(), v.begin() + runs);
      row.median_ms = bench::median(row.samples_ms);
      row.min_ms = *std::min_element(row.samples_ms.begin(), row.samples_ms.end());
      row.max_ms = *std::max_element(row.samples_ms.begin(), row.samples_ms.end());
      row.cpu_ms = bench::median(std::vector<double>(v.begin() + runs, v.end()));
      std::ostringstream done;
      done << "  " << row.method << ": median " << std::fixed << std::setprecision(1) << row.median_ms
           << " ms, peak " << megabytes(row.result.peak_rss_bytes) << " MB";
      progress(s, done.str());
    } else if (row.result.ok) {
      row.result.ok = false;
      row.result.error = "incomplete timing result";
    }
    if (!row.result.ok)
      progress(s, "  " + row.method + " failed: " + row.result.error);
    rows.push_back(std::move(row));
  }
  return rows;
}

Prepare
prepareStatic(const CloudConstPtr& cloud, const FilterParameters& parameters)
{
  return [=] {
    auto filter = std::make_shared<NonLocalMeansFilter<pcl::PointXYZ>>();
    filter->setParameters(parameters);
    filter->setInputCloud(cloud);
    auto output = std::make_shared<Cloud>();
    return std::function<void()>([filter, output] { filter->filter(*output); });
  };
}

Prepare
prepareTemporal(const Frames& frames, const FilterParameters& parameters)
{
  std::deque<CloudConstPtr> window(frames.clouds.begin(), frames.clouds.end());
  const std::size_t center = frames.center;
  return [=] {
    auto filter = std::make_shared<TemporalNonLocalMeansFilter<pcl::PointXYZ>>();
    filter->setParameters(parameters);
    filter->setFrames(window, center);
    auto output = std::make_shared<Cloud>();
    return std::function<void()>([filter, output] { filter->filter(*output); });
  };
}

/// A recursive stream (TemporalWindow::recursive, radius 1): each call pushes the next of the
/// frames, in turn, so that every call after the first filters a frame against the history of
/// the ones before it, as a camera's stream does.
Prepare
prepareRecursiveStream(const Frames& frames, const FilterParameters& parameters)
{
  const std::vector<CloudConstPtr> clouds(frames.clouds.begin(), frames.clouds.end());
  return [=] {
    auto stream = std::make_shared<TemporalStream<pcl::PointXYZ>>(kTemporalRadius, TemporalWindow::recursive,
                                                                   parameters);
    auto next = std::make_shared<std::size_t>(0);
    return std::function<void()>([stream, next, clouds] {
      const CloudConstPtr& frame = clouds[(*next)++ % clouds.size()];
      if (stream->push(frame).size() != 1)
        throw std::runtime_error("the recursive stream did not return the frame pushed");
    });
  };
}

Prepare
prepareBilateral(const CloudConstPtr& cloud, int threads)
{
  return [=] {
    auto filter = bench::makeFastBilateral(kBilateralSigmaS, kBilateralSigmaR, static_cast<unsigned>(threads));
    filter->setInputCloud(cloud);
    auto output = std::make_shared<Cloud>();
    return std::function<void()>([filter, output] { filter->filter(*output); });
  };
}

Prepare
prepareMls(const CloudConstPtr& cloud, double radius, int threads)
{
  return [=] {
    auto mls = bench::makeMovingLeastSquares(radius, static_cast<unsigned>(threads));
    auto output = std::make_shared<Cloud>();
    return std::function<void()>([mls, cloud, output] {
      // The index list and the k-d tree over the finite points are part of the timed call.
      bench::setMlsInput(*mls, cloud);
      mls->process(*output);
    });
  };
}

std::size_t
finiteCount(const Cloud& cloud)
{
  std::size_t n = 0;
  for (const auto& p : cloud.points)
    n += std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  return n;
}

/// The MLS radius: the user's, or that of the disc with the area of the static search window
/// (7x7 pixels) at the frame's median pixel spacing.
void
chooseMlsRadius(const Settings& s, Frames& frames)
{
  const Cloud& cloud = *frames.clouds[frames.center];
  if (s.mls_radius > 0.0) {
    frames.mls_radius = s.mls_radius;
    frames.mls_radius_origin = "--mls-radius";
    return;
  }
  const double spacing = bench::medianPixelSpacing(cloud);
  if (!(spacing > 0.0))
    throw InputError(frames.source + ": no two horizontally adjacent valid points; give --mls-radius");
  const double pi = 3.14159265358979323846;
  frames.mls_radius = std::sqrt(kStaticSearch * kStaticSearch / pi) * spacing;
  std::ostringstream origin;
  origin << "disc of the 7x7 window's area: 3.95 x median pixel spacing " << std::setprecision(3)
         << spacing * 1e3 << " mm at median depth " << bench::medianDepth(cloud) << " m";
  frames.mls_radius_origin = origin.str();
}

std::string
mlsNote(const Frames& frames)
{
  std::ostringstream note;
  note << "order 2, k-d tree over the " << finiteCount(*frames.clouds[frames.center])
       << " finite points (setIndices), radius " << std::setprecision(3) << frames.mls_radius * 1e3 << " mm ("
       << frames.mls_radius_origin << ")";
  return note.str();
}

std::vector<Row>
benchStatic(const Settings& s, const Frames& frames)
{
  const CloudConstPtr& cloud = frames.clouds[frames.center];
  std::vector<Pending> methods;
  if (frames.preset_windows) {
    // What users run, against the filter it must replace, in the same rounds.
    const FilterParameters& p = s.parameters;
    methods.push_back(pending(s, "range_nlm fast", frames, s.runs, true, describe(s) + "; Evaluation::fast",
                              prepareStatic(cloud, parametersFor(s, p.search_window, p.patch_size, Evaluation::fast))));
    methods.push_back(pending(s, "pcl FastBilateralFilterOMP", frames, s.runs, true,
                              "sigma_s 5, sigma_r 0.03; fills NaN pixels with a finite z (PCL #1027)",
                              prepareBilateral(cloud, s.threads)));
    return measureInterleaved(s, frames.label, std::move(methods));
  }
  methods.push_back(
      pending(s, "range_nlm fast", frames, s.runs, true, describe(s) + "; Evaluation::fast",
              prepareStatic(cloud, parametersFor(s, kStaticSearch, kStaticPatch, Evaluation::fast))));
  if (!s.no_direct)
    methods.push_back(
        pending(s, "range_nlm direct", frames, s.runs, true, describe(s) + "; Evaluation::direct",
                prepareStatic(cloud, parametersFor(s, kStaticSearch, kStaticPatch, Evaluation::direct))));
  methods.push_back(pending(s, "pcl FastBilateralFilterOMP", frames, s.runs, true,
                            "sigma_s 5, sigma_r 0.03; fills NaN pixels with a finite z (PCL #1027)",
                            prepareBilateral(cloud, s.threads)));
  methods.push_back(pending(s, "pcl MovingLeastSquares", frames, s.runs, true, mlsNote(frames),
                            prepareMls(cloud, frames.mls_radius, s.threads)));
  return measureInterleaved(s, frames.label, std::move(methods));
}

std::vector<Row>
benchTemporal(const Settings& s, const Frames& frames)
{
  const CloudConstPtr& cloud = frames.clouds[frames.center];
  std::vector<Pending> methods;
  Frames single = frames;
  single.clouds = {cloud};
  single.center = 0;
  if (frames.preset_windows) {
    // What users run on a sequence, against the static filter on its centre frame and the
    // filter it must replace, in the same rounds.
    const FilterParameters& p = s.parameters;
    methods.push_back(pending(s, "range_nlm temporal fast", frames, s.runs, true,
                              "TemporalNonLocalMeansFilter, centre of 3 frames; " + describe(s) + "; Evaluation::fast",
                              prepareTemporal(frames, parametersFor(s, p.search_window, p.patch_size, Evaluation::fast))));
    methods.push_back(pending(s, "range_nlm recursive stream fast", frames, s.runs, true,
                              "TemporalStream, recursive window, radius 1, the frames pushed in turn (a frame of "
                              "the stream with its history); " + describe(s) + "; Evaluation::fast",
                              prepareRecursiveStream(frames, parametersFor(s, p.search_window, p.patch_size,
                                                                           Evaluation::fast))));
    methods.push_back(pending(s, "range_nlm fast", single, s.runs, true,
                              "NonLocalMeansFilter on the centre frame alone; " + describe(s) + "; Evaluation::fast",
                              prepareStatic(cloud, parametersFor(s, p.search_window, p.patch_size, Evaluation::fast))));
    methods.push_back(pending(s, "pcl FastBilateralFilterOMP", single, s.runs, true,
                              "centre frame alone (no temporal neighbours), sigma_s 5, sigma_r 0.03",
                              prepareBilateral(cloud, s.threads)));
    return measureInterleaved(s, frames.label, std::move(methods));
  }
  const FilterParameters fast = parametersFor(s, kTemporalSearch, kTemporalPatch, Evaluation::fast);
  const FilterParameters direct = parametersFor(s, kTemporalSearch, kTemporalPatch, Evaluation::direct);
  methods.push_back(
      pending(s, "range_nlm temporal fast", frames, s.runs, true,
              "TemporalNonLocalMeansFilter, centre of 3 frames; " + describe(s) + "; Evaluation::fast",
              prepareTemporal(frames, fast)));
  if (s.no_direct) {
    // the reference path is left out (--no-direct)
  } else if (s.all)
    methods.push_back(pending(s, "range_nlm temporal direct", frames, s.runs, true,
                              "TemporalNonLocalMeansFilter; " + describe(s) + "; Evaluation::direct",
                              prepareTemporal(frames, direct)));
  else
    methods.push_back(pending(s, "range_nlm temporal direct", frames, 1, false,
                              "Evaluation::direct, timed once without warm-up (--all for warm-up + --runs)",
                              prepareTemporal(frames, direct)));
  methods.push_back(pending(s, "pcl FastBilateralFilterOMP", single, s.runs, true,
                            "centre frame alone (no temporal neighbours), sigma_s 5, sigma_r 0.03",
                            prepareBilateral(cloud, s.threads)));
  methods.push_back(pending(s, "pcl MovingLeastSquares", single, s.runs, true,
                            "centre frame alone; " + mlsNote(frames),
                            prepareMls(cloud, frames.mls_radius, s.threads)));
  return measureInterleaved(s, frames.label, std::move(methods));
}

// ---------------------------------------------------------------------------------------------
// Phase breakdown: runFilter itself with a StageObserver that times each of its phases, so the
// breakdown cannot drift from the pipeline. The end-to-end filter() is timed in the same rounds;
// the difference is the adaptors' conversions.

/// One timed phase.
struct Step
{
  std::string name;
  /// Runs once per filter() call (setup) or once per iteration (then timed per iteration).
  bool per_iteration = true;
  /// Part of the fast path (false for the direct evaluation and the end-to-end call).
  bool fast_path = true;
  bool end_to_end = false;
};

struct Breakdown
{
  std::string config;
  int iterations = 1;
  std::vector<Step> steps;
  bench::ChildResult result;
  std::vector<double> median_ms; // per step
};

Viewpoint
viewpointOf(const Cloud& cloud)
{
  return Viewpoint{cloud.sensor_origin_[0], cloud.sensor_origin_[1], cloud.sensor_origin_[2]};
}

/// Sums the time of each phase over one runFilter call, and lists the phases in the order they
/// first began: the phases that runFilter went through with its parameters and frames.
class StageTimer : public StageObserver
{
public:
  void begin(Stage stage, int) override
  {
    if (std::find(order.begin(), order.end(), stage) == order.end())
      order.push_back(stage);
    start_ = std::chrono::steady_clock::now();
  }
  void end(Stage stage, int) override { ms[static_cast<int>(stage)] += millisecondsSince(start_); }
  std::array<double, kStageCount> ms{};
  std::vector<Stage> order;

private:
  std::chrono::steady_clock::time_point start_;
};

/// A readable label of a phase with the parameters that set its cost.
std::string
stageLabel(Stage stage, const FilterParameters& p, std::size_t frames)
{
  const auto square = [](int n) { return std::to_string(n) + "x" + std::to_string(n); };
  switch (stage) {
  case Stage::outliers:
    return "outliers (noise profile, " + std::to_string(p.bandwidth_samples) + " samples; isolated points)";
  case Stage::dilation:
    return p.dilation == 0 ? "dilation (automatic: estimate, split into phases, merge)"
                           : "dilation " + std::to_string(p.dilation) + " (split into phases, merge)";
  case Stage::neighbour_frames:
    return "neighbour frames (" + std::to_string(frames - 1) + ")";
  case Stage::pyramid:
    return "pyramid (" + std::to_string(p.scales) + " scales: reduce, carry corrections up)";
  case Stage::bandwidths:
    return std::string("bandwidths (") +
           (p.bandwidth_model == BandwidthModel::range_adaptive ? "noise profile" : "global") + ", " +
           std::to_string(p.bandwidth_samples) + " samples)";
  case Stage::presmoothing:
    return "pre-smoothing " + square(p.normal_presmooth_window);
  case Stage::normals:
    return "normals " + square(p.normal_window) + (p.normal_edge_gate > 0.0f ? " gated" : "");
  case Stage::offsets:
    return "offsets fast " + square(p.search_window) + "/" + square(p.patch_size) +
           (frames > 1 ? ", " + std::to_string(frames) + " frames" : "");
  default:
    return toString(stage);
  }
}

/// Setup phases run once per filter() call; the others once per iteration.
bool
oncePerCall(Stage stage)
{
  return stage == Stage::outliers || stage == Stage::neighbour_frames || stage == Stage::dilation ||
         stage == Stage::pyramid || stage == Stage::hole_filling;
}

/// The breakdown's steps: the conversion, the phases runFilter went through (`stages`, in the
/// order they first began), the direct evaluation if timed, and filter() end to end.
std::vector<Step>
breakdownSteps(const std::vector<Stage>& stages, const FilterParameters& p, std::size_t count, bool with_direct)
{
  const bool temporal = count > 1;
  std::vector<Step> steps;
  steps.push_back({"cloud -> Grid (toGrid)" + (temporal ? ", " + std::to_string(count) + " frames" : ""),
                   false, true, false});
  for (Stage stage : stages)
    steps.push_back({stageLabel(stage, p, count), !oncePerCall(stage), true, false});
  if (with_direct)
    steps.push_back({"offsets direct " + std::to_string(p.search_window) + "x" + std::to_string(p.search_window) +
                         "/" + std::to_string(p.patch_size) + "x" + std::to_string(p.patch_size),
                     true, false, false});
  steps.push_back({std::string(temporal ? "TemporalNonLocalMeansFilter" : "NonLocalMeansFilter") +
                       "::filter() fast, end to end, " + std::to_string(p.iterations) + " iteration(s)",
                   false, false, true});
  return steps;
}

/// The child's result of benchBreakdown: the number m of phases, the m phases (Stage values) in
/// the order they first began, then the median of every step.
void
decodeBreakdown(const FilterParameters& p, std::size_t count, bool with_direct, Breakdown& b)
{
  const std::vector<double>& values = b.result.values;
  const std::size_t m = values.empty() ? 0 : static_cast<std::size_t>(values[0]);
  if (values.empty() || values.size() < 1 + m) {
    b.result.ok = false;
    b.result.error = "incomplete breakdown result";
    return;
  }
  std::vector<Stage> stages;
  for (std::size_t i = 1; i <= m; ++i)
    stages.push_back(static_cast<Stage>(static_cast<int>(values[i])));
  b.steps = breakdownSteps(stages, p, count, with_direct);
  if (values.size() != 1 + m + b.steps.size()) {
    b.result.ok = false;
    b.result.error = "incomplete breakdown result";
    return;
  }
  b.median_ms.assign(values.begin() + static_cast<std::ptrdiff_t>(1 + m), values.end());
}

Breakdown
benchBreakdown(const Settings& s, const Frames& frames, const FilterParameters& p, bool with_direct)
{
  const std::size_t count = frames.clouds.size(), c = frames.center;
  const bool temporal = count > 1;
  Breakdown b;
  b.config = frames.label;
  b.iterations = p.iterations;
  progress(s, "breakdown [" + frames.label + "], warm-up + " + std::to_string(s.runs) + " round(s)");
  b.result = bench::runInChild([&] {
    const Viewpoint viewpoint = viewpointOf(*frames.clouds[c]);
    FilterParameters fast = p, direct = p;
    fast.evaluation = Evaluation::fast;
    direct.evaluation = Evaluation::direct;
    std::vector<Grid> grids(count);
    std::vector<const Grid*> pointers;
    for (const Grid& g : grids)
      pointers.push_back(&g);
    FilterWorkspace workspace, direct_workspace;
    const std::function<void()> filter =
        temporal ? prepareTemporal(frames, fast)() : prepareStatic(frames.clouds[c], fast)();
    // The phases as the warm-up round's run reports them, so the breakdown cannot drift from
    // the pipeline. Every round runs all phases in pipeline order, so a change of machine load
    // hits every phase alike instead of whichever phase happened to be timed at the time.
    std::vector<Stage> stages;
    std::vector<std::vector<double>> samples;
    for (int round = -1; round < s.runs; ++round) { // round -1 is the warm-up
      std::vector<double> ms;
      auto start = std::chrono::steady_clock::now();
      for (std::size_t k = 0; k < count; ++k)
        toGrid(*frames.clouds[k], grids[k]);
      ms.push_back(millisecondsSince(start));
      StageTimer timer;
      workspace.setStageObserver(&timer);
      runFilter(pointers, static_cast<int>(c), fast, viewpoint, {}, workspace);
      if (round < 0)
        stages = timer.order;
      for (Stage stage : stages) {
        const double total = timer.ms[static_cast<int>(stage)];
        ms.push_back(oncePerCall(stage) ? total : total / p.iterations);
      }
      if (with_direct) {
        StageTimer direct_timer;
        direct_workspace.setStageObserver(&direct_timer);
        runFilter(pointers, static_cast<int>(c), direct, viewpoint, {}, direct_workspace);
        ms.push_back(direct_timer.ms[static_cast<int>(Stage::offsets)] / p.iterations);
      }
      start = std::chrono::steady_clock::now();
      filter();
      ms.push_back(millisecondsSince(start));
      samples.resize(ms.size());
      if (round >= 0)
        for (std::size_t i = 0; i < ms.size(); ++i)
          samples[i].push_back(ms[i]);
    }
    std::vector<double> result{static_cast<double>(stages.size())};
    for (Stage stage : stages)
      result.push_back(static_cast<int>(stage));
    for (const std::vector<double>& sample : samples)
      result.push_back(bench::median(sample));
    return result;
  });
  if (b.result.ok)
    decodeBreakdown(p, count, with_direct, b);
  if (!b.result.ok)
    progress(s, "  breakdown failed: " + b.result.error);
  return b;
}

// ---------------------------------------------------------------------------------------------
// Memory over a sequence: TemporalStream (radius 1) over N noisy copies of the input frame.

struct SequenceMemory
{
  int frames = 0;
  unsigned width = 0, height = 0;
  bench::ChildResult result;
  // From the child: outputs, most frames held, RSS after the first and the last output, median
  // and mean ms per pushed frame.
  double outputs = 0, max_held = 0, rss_first = 0, rss_last = 0, median_ms = 0, mean_ms = 0;
};

SequenceMemory
benchSequence(const Settings& s, const CloudConstPtr& base)
{
  SequenceMemory m;
  m.frames = s.sequence_memory;
  m.width = base->width;
  m.height = base->height;
  progress(s, "sequence memory: TemporalStream radius 1, " + std::to_string(s.sequence_search) + "x" +
                  std::to_string(s.sequence_search) + "/" + std::to_string(s.sequence_patch) + "x" +
                  std::to_string(s.sequence_patch) + ", " + std::to_string(m.frames) + " frames of " +
                  std::to_string(m.width) + "x" + std::to_string(m.height));
  m.result = bench::runInChild([&] {
    const FilterParameters p = parametersFor(s, s.sequence_search, s.sequence_patch, Evaluation::fast);
    TemporalStream<pcl::PointXYZ> stream(kTemporalRadius, false, p);
    std::vector<double> push_ms;
    double outputs = 0, max_held = 0, rss_first = 0, rss_last = 0;
    auto take = [&](const std::vector<Cloud::Ptr>& ready) {
      for (std::size_t r = 0; r < ready.size(); ++r) {
        ++outputs;
        rss_last = static_cast<double>(bench::residentBytes());
        if (outputs == 1)
          rss_first = rss_last;
      }
      max_held = std::max(max_held, static_cast<double>(stream.heldFrames()));
    };
    for (int i = 0; i < m.frames; ++i) {
      const CloudConstPtr frame = std::make_shared<Cloud>(bench::withFreshNoise(*base, s.seed + 1000u + i));
      const auto start = std::chrono::steady_clock::now();
      const std::vector<Cloud::Ptr> ready = stream.push(frame);
      push_ms.push_back(millisecondsSince(start));
      max_held = std::max(max_held, static_cast<double>(stream.heldFrames()));
      take(ready);
    }
    const auto start = std::chrono::steady_clock::now();
    const std::vector<Cloud::Ptr> rest = stream.flush();
    const double flush_ms = millisecondsSince(start);
    take(rest);
    double total = flush_ms;
    for (double v : push_ms)
      total += v;
    return std::vector<double>{outputs,         max_held, rss_first, rss_last, bench::median(push_ms),
                               total / m.frames};
  });
  if (m.result.ok && m.result.values.size() == 6) {
    m.outputs = m.result.values[0];
    m.max_held = m.result.values[1];
    m.rss_first = m.result.values[2];
    m.rss_last = m.result.values[3];
    m.median_ms = m.result.values[4];
    m.mean_ms = m.result.values[5];
  } else if (m.result.ok) {
    m.result.ok = false;
    m.result.error = "incomplete result";
  }
  if (!m.result.ok)
    progress(s, "  sequence memory failed: " + m.result.error);
  return m;
}

// ---------------------------------------------------------------------------------------------
// Frames.

CloudConstPtr
loadXyz(const std::string& path)
{
  const LoadedCloud loaded = loadCloud(path);
  return std::make_shared<Cloud>(xyzFromBlob(loaded, path));
}

std::string
sizeText(const Cloud& c)
{
  return std::to_string(c.width) + "x" + std::to_string(c.height);
}

Frames
staticFrames(const Settings& s, const CloudConstPtr& input)
{
  Frames f;
  f.clouds = {input};
  f.label = "static " + std::to_string(kStaticSearch) + "x" + std::to_string(kStaticSearch) + "/" +
            std::to_string(kStaticPatch) + "x" + std::to_string(kStaticPatch) + " " + sizeText(*input);
  f.source = "'" + s.input + "'";
  chooseMlsRadius(s, f);
  return f;
}

/// The static frame filtered with the preset as it is: the first row of the table.
Frames
presetFrames(const Settings& s, const CloudConstPtr& input)
{
  Frames f = staticFrames(s, input);
  const FilterParameters& p = s.parameters;
  f.label = "static " + s.preset + " " + std::to_string(p.search_window) + "x" + std::to_string(p.search_window) +
            "/" + std::to_string(p.patch_size) + "x" + std::to_string(p.patch_size) + " " + sizeText(*input);
  f.preset_windows = true;
  return f;
}

/// The temporal frames: the paper's configuration on centre crops (`crop`), or the preset as
/// users run it on whole frames.
Frames
temporalFrames(const Settings& s, const CloudConstPtr& input, bool crop = true)
{
  Frames f;
  const int count = 2 * kTemporalRadius + 1;
  const auto cut = [&](const Cloud& cloud, const std::string& what) {
    return crop ? bench::cropCentre(cloud, kTemporalWidth, kTemporalHeight, what) : cloud;
  };
  if (s.synthetic_frames) {
    const Cloud base = cut(*input, "'" + s.input + "'");
    for (int k = 0; k < count; ++k)
      f.clouds.push_back(std::make_shared<Cloud>(bench::withFreshNoise(base, s.seed + k)));
    f.source = "'" + s.input + "'" + (crop ? " centre crop" : "") + " with fresh noise (seeds " +
               std::to_string(s.seed) + ".." + std::to_string(s.seed + count - 1) + ")";
  } else {
    std::vector<std::string> files;
    try {
      files = listFrames(s.sequence_dir);
    } catch (const InputError& e) {
      throw InputError(std::string("--sequence-dir: ") + e.what());
    }
    if (files.size() < static_cast<std::size_t>(count))
      throw InputError("--sequence-dir '" + s.sequence_dir + "' holds " + std::to_string(files.size()) +
                       " .pcd frame(s); the temporal configuration needs " + std::to_string(count) +
                       " (or use --synthetic-frames)");
    for (int k = 0; k < count; ++k) {
      const CloudConstPtr frame = loadXyz(files[static_cast<std::size_t>(k)]);
      f.clouds.push_back(std::make_shared<Cloud>(cut(*frame, "'" + files[static_cast<std::size_t>(k)] + "'")));
    }
    f.source = "first " + std::to_string(count) + " frames of '" + s.sequence_dir + "'" + (crop ? ", centre crops" : "");
  }
  f.center = static_cast<std::size_t>(kTemporalRadius);
  f.label = "temporal " + std::to_string(kTemporalSearch) + "x" + std::to_string(kTemporalSearch) + "/" +
            std::to_string(kTemporalPatch) + "x" + std::to_string(kTemporalPatch) +
            " r=" + std::to_string(kTemporalRadius) + " " + sizeText(*f.clouds[f.center]);
  chooseMlsRadius(s, f);
  return f;
}

/// The temporal filter with the preset as it is (its windows, radius 1) on whole frames: the
/// second configuration of the table.
Frames
presetTemporalFrames(const Settings& s, const CloudConstPtr& input)
{
  Frames f = temporalFrames(s, input, false);
  const FilterParameters& p = s.parameters;
  f.label = "temporal " + s.preset + " " + std::to_string(p.search_window) + "x" + std::to_string(p.search_window) +
            "/" + std::to_string(p.patch_size) + "x" + std::to_string(p.patch_size) +
            " r=" + std::to_string(kTemporalRadius) + " " + sizeText(*f.clouds[f.center]);
  f.preset_windows = true;
  return f;
}

// ---------------------------------------------------------------------------------------------
// Report.

struct Target
{
  std::string name;
  double value = 0.0, limit = 0.0;
  std::string unit;
  /// How value is compared with limit, as printed: "<=" or "<".
  std::string relation;
  /// What the limit is ("target" or the method compared with).
  std::string limit_name;
  bool met = false;
};

const Row*
findRow(const std::vector<Row>& rows, const std::string& method, const std::string& config_prefix)
{
  for (const Row& r : rows)
    if (r.method == method && r.config.compare(0, config_prefix.size(), config_prefix) == 0 && r.result.ok)
      return &r;
  return nullptr;
}

std::vector<Target>
evaluateTargets(const Settings& s, const std::vector<Row>& rows, const SequenceMemory* sequence)
{
  std::vector<Target> targets;
  // The configuration users run: real time (30 fps) and no slower than the filter it replaces.
  const Row* preset = findRow(rows, "range_nlm fast", "static " + s.preset + " ");
  const Row* preset_fbf = findRow(rows, "pcl FastBilateralFilterOMP", "static " + s.preset + " ");
  if (preset)
    targets.push_back({"preset fast median ms/frame (" + preset->config + ")", preset->median_ms,
                       kRealTimeTargetMs, "ms", "<=", "30 fps", preset->median_ms <= kRealTimeTargetMs});
  if (preset && preset_fbf)
    targets.push_back({"preset fast vs FastBilateralFilterOMP, same run", preset->median_ms,
                       preset_fbf->median_ms, "ms", "<=", "FastBilateralFilterOMP",
                       preset->median_ms <= preset_fbf->median_ms});
  // The temporal filter (radius 1) with the preset: at most 1.3 times the static filter's time on
  // its centre frame, in the same rounds.
  const std::string preset_temporal = "temporal " + s.preset + " ";
  const Row* temporal_preset = findRow(rows, "range_nlm temporal fast", preset_temporal);
  const Row* temporal_static = findRow(rows, "range_nlm fast", preset_temporal);
  const Row* temporal_fbf = findRow(rows, "pcl FastBilateralFilterOMP", preset_temporal);
  // FastBilateralFilterOMP's time depends on the frame (its grid spans the frame's depth range and
  // is allocated on every call), so the comparison is made on the sequence's centre frame as well
  // as on the static frame.
  if (temporal_static && temporal_fbf)
    targets.push_back({"preset fast vs FastBilateralFilterOMP on the sequence's centre frame, same run",
                       temporal_static->median_ms, temporal_fbf->median_ms, "ms", "<=", "FastBilateralFilterOMP",
                       temporal_static->median_ms <= temporal_fbf->median_ms});
  if (temporal_preset && temporal_static) {
    const double limit = kTemporalOverStatic * temporal_static->median_ms;
    targets.push_back({"preset temporal fast (radius 1) vs 1.3 x static on its centre frame, same run",
                       temporal_preset->median_ms, limit, "ms", "<=", "1.3 x static",
                       temporal_preset->median_ms <= limit});
  }
  const Row* recursive_preset = findRow(rows, "range_nlm recursive stream fast", preset_temporal);
  if (recursive_preset && temporal_static) {
    const double limit = kTemporalOverStatic * temporal_static->median_ms;
    targets.push_back({"preset recursive stream (radius 1) vs 1.3 x static on the same frames, same run",
                       recursive_preset->median_ms, limit, "ms", "<=", "1.3 x static",
                       recursive_preset->median_ms <= limit});
  }
  const std::string paper_static = "static " + std::to_string(kStaticSearch) + "x";
  const Row* fast = findRow(rows, "range_nlm fast", paper_static);
  const Row* fbf = findRow(rows, "pcl FastBilateralFilterOMP", paper_static);
  if (fast)
    targets.push_back({"static fast median ms/frame (" + fast->config + ")", fast->median_ms, kStaticTargetMs,
                       "ms", "<=", "target", fast->median_ms <= kStaticTargetMs});
  if (fast && fbf)
    targets.push_back({"static fast vs FastBilateralFilterOMP, same run", fast->median_ms, fbf->median_ms,
                       "ms", "<=", "FastBilateralFilterOMP", fast->median_ms <= fbf->median_ms});
  const Row* temporal =
      findRow(rows, "range_nlm temporal fast", "temporal " + std::to_string(kTemporalSearch) + "x");
  if (temporal)
    targets.push_back({"temporal fast median ms/frame (" + temporal->config + ")", temporal->median_ms,
                       kTemporalTargetMs, "ms", "<=", "target", temporal->median_ms <= kTemporalTargetMs});
  if (sequence && sequence->result.ok) {
    const double mb = megabytes(sequence->result.peak_rss_bytes);
    targets.push_back({"sequence peak RSS (" + std::to_string(sequence->frames) + " frames)", mb,
                       kSequenceTargetMb, "MB", "<", "target", mb < kSequenceTargetMb});
  }
  return targets;
}

std::string
fixed(double v, int decimals)
{
  if (!std::isfinite(v))
    return "-";
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << v;
  return out.str();
}

/// `v` with `digits` significant digits, without exponent for the magnitudes of this table.
std::string
significant(double v, int digits)
{
  if (!std::isfinite(v))
    return "-";
  if (v == 0.0)
    return "0";
  const int magnitude = static_cast<int>(std::floor(std::log10(std::fabs(v))));
  return fixed(v, std::max(0, digits - 1 - magnitude));
}

void
printTable(const Settings& s, const RunInfo& info, const std::vector<std::string>& sources,
           double baseline_mb, const std::vector<Row>& rows, const std::vector<Breakdown>& breakdowns,
           const SequenceMemory* sequence, const std::vector<Target>& targets)
{
  std::ostream& out = std::cout;
  out << "machine: " << info.machine.cpu_model << ", " << info.machine.usable_cpus << " usable / "
      << info.machine.online_cpus << " online CPUs; PCL " << PCL_VERSION_PRETTY << "; " << info.build
      << "; load average " << fixed(info.load_start, 2) << " at start, " << fixed(info.load_end, 2)
      << " at end; " << fixed(info.wall_s, 0) << " s in all\n";
  for (const std::string& src : sources)
    out << src << "\n";
  out << "timing: median of " << s.runs
      << " timed run(s) per method, each method in its own child process, the methods of a configuration"
         " taking turns (each turn a warm-up run, then a timed one);"
      << " cpu ms = median process CPU time per run (all threads); Mpts/s = grid points (width x height) / "
         "median"
      << " time\n"
      << "peak MB: ru_maxrss of that child (wait4), 1 MB = 10^6 bytes, includes the " << fixed(baseline_mb, 1)
      << " MB of an idle child (process + loaded frames)\n\n";

  std::size_t mw = 6, cw = 6;
  for (const Row& r : rows) {
    mw = std::max(mw, r.method.size());
    cw = std::max(cw, r.config.size());
  }
  out << std::left << std::setw(static_cast<int>(mw)) << "method"
      << "  " << std::setw(static_cast<int>(cw)) << "config" << std::right
      << "  threads  runs  median ms    min ms    cpu ms  Mpts/s  peak MB\n";
  std::vector<std::string> notes;
  for (const Row& r : rows) {
    out << std::left << std::setw(static_cast<int>(mw)) << r.method << "  " << std::setw(static_cast<int>(cw))
        << r.config << std::right << "  " << std::setw(7) << r.threads << "  " << std::setw(4)
        << (std::to_string(r.runs) + (r.warmup ? "" : "*"));
    if (r.result.ok) {
      out << "  " << std::setw(9) << fixed(r.median_ms, r.median_ms < 100 ? 2 : 1) << "  " << std::setw(8)
          << fixed(r.min_ms, r.min_ms < 100 ? 2 : 1) << "  " << std::setw(8)
          << fixed(r.cpu_ms, r.cpu_ms < 100 ? 2 : 1) << "  " << std::setw(6)
          << significant(r.mpointsPerSecond(), 3) << "  " << std::setw(7)
          << fixed(megabytes(r.result.peak_rss_bytes), 1);
    } else {
      out << "  FAILED: " << r.result.error;
    }
    notes.push_back(r.method + " [" + r.config + "]: " + r.note);
    out << "  [" << notes.size() << "]\n";
  }
  out << "(* = no warm-up)\n";
  for (std::size_t i = 0; i < notes.size(); ++i)
    out << "  [" << i + 1 << "] " << notes[i] << "\n";

  for (const Breakdown& b : breakdowns) {
    out << "\nbreakdown [" << b.config << "], " << s.threads << " thread(s), " << b.iterations
        << " iteration(s); median per phase over " << s.runs
        << " round(s) of all phases in pipeline order, after a warm-up round:\n";
    if (!b.result.ok) {
      out << "  FAILED: " << b.result.error << "\n";
      continue;
    }
    double once = 0.0, per_iteration = 0.0, total = std::numeric_limits<double>::quiet_NaN();
    std::string total_name;
    for (std::size_t i = 0; i < b.steps.size(); ++i) {
      if (b.steps[i].end_to_end) {
        total = b.median_ms[i];
        total_name = b.steps[i].name;
      } else if (b.steps[i].fast_path) {
        (b.steps[i].per_iteration ? per_iteration : once) += b.median_ms[i];
      }
    }
    const double estimate = once + b.iterations * per_iteration;
    const std::string once_label = "setup phases (once per call)";
    const std::string iteration_label = "phases of one iteration";
    const std::string estimate_label =
        "setup + " + std::to_string(b.iterations) + " x one iteration (expected filter())";
    const std::string rest_label = "filter() minus expected (adaptor copies, noise)";
    std::size_t nw = std::max({once_label.size(), iteration_label.size(), estimate_label.size(),
                               rest_label.size(), total_name.size()});
    for (const Step& step : b.steps)
      nw = std::max(nw, step.name.size());
    auto line = [&](const std::string& name, double ms, const std::string& tail) {
      out << "  " << std::left << std::setw(static_cast<int>(nw)) << name << std::right << "  "
          << std::setw(12) << fixed(ms, 2) + " ms" << tail << "\n";
    };
    auto share = [&](double ms) {
      return std::isfinite(ms) && total > 0.0 ? "  " + fixed(100.0 * ms / total, 1) + " % of filter()"
                                              : std::string();
    };
    for (std::size_t i = 0; i < b.steps.size(); ++i) {
      const Step& step = b.steps[i];
      if (step.end_to_end)
        continue;
      if (!step.fast_path)
        line(step.name, b.median_ms[i], "  (not part of the fast path)");
      else
        line(step.name, b.median_ms[i],
             (step.per_iteration ? "  x" + std::to_string(b.iterations) : "  x1") +
                 share(b.median_ms[i] * (step.per_iteration ? b.iterations : 1)));
    }
    line(once_label, once, share(once));
    line(iteration_label, per_iteration,
         "  x" + std::to_string(b.iterations) + share(per_iteration * b.iterations));
    line(estimate_label, estimate, share(estimate));
    line(total_name, total, "");
    line(rest_label, total - estimate, share(total - estimate));
  }

  if (sequence) {
    out << "\nsequence memory: TemporalStream radius " << kTemporalRadius << ", " << s.sequence_search << "x"
        << s.sequence_search << "/" << s.sequence_patch << "x" << s.sequence_patch << ", " << sequence->frames
        << " frames of " << sequence->width << "x" << sequence->height << " (input + fresh noise), "
        << s.threads << " thread(s)\n";
    if (!sequence->result.ok) {
      out << "  FAILED: " << sequence->result.error << "\n";
    } else {
      out << "  peak RSS (ru_maxrss via wait4): " << fixed(megabytes(sequence->result.peak_rss_bytes), 1)
          << " MB; RSS after the first output " << fixed(sequence->rss_first / 1e6, 1)
          << " MB, after the last " << fixed(sequence->rss_last / 1e6, 1) << " MB; at most "
          << fixed(sequence->max_held, 0) << " frames held between pushes; " << fixed(sequence->outputs, 0)
          << " frames out; " << fixed(sequence->mean_ms, 1) << " ms/frame\n";
    }
  }

  if (!targets.empty()) {
    out << "\ntargets:\n";
    for (const Target& t : targets)
      out << "  " << (t.met ? "met    " : "MISSED ") << t.name << ": " << fixed(t.value, 1) << " " << t.unit
          << " (needs " << t.relation << " " << t.limit_name << " " << fixed(t.limit, 1) << " " << t.unit
          << ")\n";
  }
}

void
printJson(std::ostream& out, const Settings& s, const RunInfo& info, const std::vector<std::string>& sources,
          double baseline_mb, const std::vector<Row>& rows, const std::vector<Breakdown>& breakdowns,
          const SequenceMemory* sequence, const std::vector<Target>& targets)
{
  using bench::jsonNumber;
  using bench::jsonString;
  out << "{\"tool\": \"range_nlm_bench\", \"machine\": {\"cpu_model\": " << jsonString(info.machine.cpu_model)
      << ", \"usable_cpus\": " << info.machine.usable_cpus
      << ", \"online_cpus\": " << info.machine.online_cpus
      << ", \"load_average_start\": " << jsonNumber(info.load_start)
      << ", \"load_average_end\": " << jsonNumber(info.load_end)
      << "}, \"wall_s\": " << jsonNumber(info.wall_s) << ", \"build\": " << jsonString(info.build)
      << ", \"pcl_version\": " << jsonString(PCL_VERSION_PRETTY) << ", \"settings\": {\"runs\": " << s.runs
      << ", \"threads\": " << s.threads << ", \"warmup\": true, \"input\": " << jsonString(s.input)
      << ", \"all\": " << (s.all ? "true" : "false") << "}, \"frames\": [";
  for (std::size_t i = 0; i < sources.size(); ++i)
    out << (i ? ", " : "") << jsonString(sources[i]);
  out << "], \"memory_measure\": \"ru_maxrss of a forked child per method, via wait4; MB = 1e6 bytes\""
      << ", \"idle_child_peak_mb\": " << jsonNumber(baseline_mb) << ", \"results\": [";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    out << (i ? ", " : "") << "{\"method\": " << jsonString(r.method)
        << ", \"config\": " << jsonString(r.config) << ", \"width\": " << r.width
        << ", \"height\": " << r.height << ", \"frames\": " << r.frames << ", \"threads\": " << r.threads
        << ", \"runs\": " << r.runs << ", \"warmup\": " << (r.warmup ? "true" : "false")
        << ", \"ok\": " << (r.result.ok ? "true" : "false");
    if (r.result.ok) {
      out << ", \"median_ms\": " << jsonNumber(r.median_ms) << ", \"min_ms\": " << jsonNumber(r.min_ms)
          << ", \"cpu_ms\": " << jsonNumber(r.cpu_ms) << ", \"max_ms\": " << jsonNumber(r.max_ms)
          << ", \"mpoints_per_s\": " << jsonNumber(r.mpointsPerSecond())
          << ", \"peak_mb\": " << jsonNumber(megabytes(r.result.peak_rss_bytes)) << ", \"samples_ms\": [";
      for (std::size_t k = 0; k < r.samples_ms.size(); ++k)
        out << (k ? ", " : "") << jsonNumber(r.samples_ms[k]);
      out << "]";
    } else {
      out << ", \"error\": " << jsonString(r.result.error);
    }
    out << ", \"note\": " << jsonString(r.note) << "}";
  }
  out << "], \"breakdown\": [";
  for (std::size_t i = 0; i < breakdowns.size(); ++i) {
    const Breakdown& b = breakdowns[i];
    out << (i ? ", " : "") << "{\"config\": " << jsonString(b.config)
        << ", \"ok\": " << (b.result.ok ? "true" : "false");
    if (b.result.ok) {
      out << ", \"iterations\": " << b.iterations << ", \"phases\": [";
      for (std::size_t k = 0; k < b.steps.size(); ++k)
        out << (k ? ", " : "") << "{\"name\": " << jsonString(b.steps[k].name)
            << ", \"median_ms\": " << jsonNumber(b.median_ms[k])
            << ", \"per_iteration\": " << (b.steps[k].per_iteration ? "true" : "false")
            << ", \"fast_path\": " << (b.steps[k].fast_path ? "true" : "false")
            << ", \"end_to_end\": " << (b.steps[k].end_to_end ? "true" : "false") << "}";
      out << "]";
    } else {
      out << ", \"error\": " << jsonString(b.result.error);
    }
    out << "}";
  }
  out << "], \"sequence_memory\": ";
  if (!sequence) {
    out << "null";
  } else {
    out << "{\"frames\": " << sequence->frames << ", \"width\": " << sequence->width
        << ", \"height\": " << sequence->height << ", \"radius\": " << kTemporalRadius
        << ", \"search_window\": " << s.sequence_search << ", \"patch_size\": " << s.sequence_patch
        << ", \"threads\": " << s.threads << ", \"ok\": " << (sequence->result.ok ? "true" : "false");
    if (sequence->result.ok)
      out << ", \"peak_mb\": " << jsonNumber(megabytes(sequence->result.peak_rss_bytes))
          << ", \"rss_after_first_output_mb\": " << jsonNumber(sequence->rss_first / 1e6)
          << ", \"rss_after_last_output_mb\": " << jsonNumber(sequence->rss_last / 1e6)
          << ", \"max_frames_held\": " << jsonNumber(sequence->max_held)
          << ", \"frames_out\": " << jsonNumber(sequence->outputs)
          << ", \"mean_ms_per_frame\": " << jsonNumber(sequence->mean_ms);
    else
      out << ", \"error\": " << jsonString(sequence->result.error);
    out << "}";
  }
  out << ", \"targets\": [";
  for (std::size_t i = 0; i < targets.size(); ++i)
    out << (i ? ", " : "") << "{\"name\": " << jsonString(targets[i].name)
        << ", \"value\": " << jsonNumber(targets[i].value)
        << ", \"relation\": " << jsonString(targets[i].relation)
        << ", \"limit\": " << jsonNumber(targets[i].limit)
        << ", \"limit_name\": " << jsonString(targets[i].limit_name)
        << ", \"unit\": " << jsonString(targets[i].unit)
        << ", \"met\": " << (targets[i].met ? "true" : "false") << "}";
  out << "]}" << std::endl;
}

/// The frame size of --quality-size (WxH, at least 16x16).
std::pair<int, int>
qualitySize(const po::variables_map& vm)
{
  int w = 0, h = 0;
  char x = 0;
  std::istringstream size(vm["quality-size"].as<std::string>());
  if (!(size >> w >> x >> h) || x != 'x' || w < 16 || h < 16 || !size.eof())
    throw UsageError("--quality-size '" + vm["quality-size"].as<std::string>() + "' is invalid: expected WxH, at least 16x16");
  return {w, h};
}

/// --generalisation: the options of the table from the command line.
generalisation::Options
generalisationOptions(const po::variables_map& vm)
{
  generalisation::Options g;
  g.threads = vm["threads"].as<int>();
  std::tie(g.width, g.height) = qualitySize(vm);
  if (vm.count("generalisation-quick"))
    generalisation::makeQuick(g);
  if (vm.count("generalisation-scenes")) {
    const std::string list = vm["generalisation-scenes"].as<std::string>();
    std::vector<std::string> scenes;
    std::istringstream names(list);
    for (std::string name; std::getline(names, name, ',');) {
      const std::vector<std::string> known = generalisation::Options().scenes;
      if (std::find(known.begin(), known.end(), name) == known.end())
        throw UsageError("--generalisation-scenes '" + list + "': unknown scene '" + name +
                         "' (expected boxes, steps or ridges, separated by commas)");
      scenes.push_back(name);
    }
    g.scenes = scenes;
  }
  if (vm.count("generalisation-setting"))
    for (const std::string& spec : vm["generalisation-setting"].as<std::vector<std::string>>()) {
      try {
        g.extra_settings.push_back(generalisation::settingFromText(spec));
      } catch (const std::invalid_argument& e) {
        throw UsageError(std::string("--generalisation-setting ") + e.what());
      }
    }
  return g;
}

/// Refuses a --json-file that cannot be written (a directory, a socket, a missing or read-only
/// directory, ...) without creating it; the file is written whole at the end, through OutputFile
/// like every output (a temporary file renamed into place, links followed, a device or FIFO
/// written directly).
void
checkJsonFile(const std::string& path)
{
  try {
    io::detail::OutputFile::check(path);
  } catch (const io::InputError& e) {
    throw UsageError(std::string("--json-file ") + e.what());
  }
}

/// --accuracy-time, --quality, --temporal-comparison, ...: accuracy instead of timing.
void
runComparison(const po::variables_map& vm)
{
  const bool json = vm.count("json") > 0;
  std::ostringstream sink;
  std::ostream& log = vm.count("quiet") ? static_cast<std::ostream&>(sink) : std::cerr;
  std::ostringstream report, json_text;
  if (vm.count("json-file"))
    checkJsonFile(vm["json-file"].as<std::string>()); // now rather than after a long run
  if (vm.count("accuracy-time")) {
    accuracy_time::Options a;
    a.threads = vm["threads"].as<int>();
    a.runs = vm["runs"].as<int>();
    a.seed = vm["seed"].as<Unsigned64>().value;
    const auto [w, h] = qualitySize(vm);
    a.width = w, a.height = h;
    a.model = vm["accuracy-time-noise"].as<std::string>();
    a.real_frame = vm["accuracy-time-frame"].as<std::string>();
    try {
      accuracy_time::validate(a);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--accuracy-time: ") + e.what());
    }
    const auto rows = accuracy_time::run(a, log);
    accuracy_time::printJson(rows, a, json_text);
    if (json)
      accuracy_time::printJson(rows, a, report);
    else
      accuracy_time::printTable(rows, a, report);
  } else if (vm.count("hole-filling")) {
    holes::Options o;
    o.threads = vm["threads"].as<int>();
    o.fill_holes = vm["hole-filling-max"].as<int>();
    const auto [w, h] = qualitySize(vm);
    o.width = w, o.height = h;
    const auto results = holes::run(o, log);
    holes::printJson(results, o, json_text);
    if (json)
      holes::printJson(results, o, report);
    else
      holes::printTable(results, o, report);
  } else if (vm.count("generalisation")) {
    generalisation::run(generalisationOptions(vm), log, report, &json_text);
    if (json)
      report.str(json_text.str());
  } else if (vm.count("real-noise")) {
    real_noise::Options r;
    r.threads = vm["threads"].as<int>();
    if (vm.count("real-noise-quick")) {
      r.noise_scales = {1.0};
      r.seeds = {1};
      r.include_mls = false;
    }
    r.render_dir = vm["real-noise-renders"].as<std::string>();
    if (vm.count("real-noise-setting")) {
      r.settings.emplace_back("default", FilterParameters::recommended());
      for (const std::string& spec : vm["real-noise-setting"].as<std::vector<std::string>>()) {
        try {
          const generalisation::Setting setting = generalisation::settingFromText(spec);
          r.settings.emplace_back(setting.name, setting.parameters);
        } catch (const std::invalid_argument& e) {
          throw UsageError(std::string("--real-noise-setting ") + e.what());
        }
      }
    }
    real_noise::addShippedFrames(r, RANGE_NLM_DATA_DIR, vm["real-noise-data"].as<std::string>());
    real_noise::run(r, log, report, &json_text);
    if (json)
      report.str(json_text.str());
  } else if (vm.count("uncertainty-calibration")) {
    uncertainty_calibration::Options u;
    u.threads = vm["threads"].as<int>();
    u.seed = vm["seed"].as<Unsigned64>().value;
    const auto [w, h] = qualitySize(vm);
    u.width = w, u.height = h;
    u.plot = vm["uncertainty-plot"].as<std::string>();
    if (vm.count("parameter")) // on top of the default
      for (const std::string& spec : vm["parameter"].as<std::vector<std::string>>())
        applyParameterOption(spec, u.parameters);
    const auto rows = uncertainty_calibration::run(u, log);
    if (!u.plot.empty())
      uncertainty_calibration::plotReliability(rows, u.plot);
    uncertainty_calibration::printJson(rows, json_text);
    if (json)
      uncertainty_calibration::printJson(rows, report);
    else
      uncertainty_calibration::printTable(rows, report);
  } else if (vm.count("quality")) {
    quality::Options q = quality::defaultOptions();
    q.threads = vm["threads"].as<int>();
    if (vm.count("quality-scene")) {
      const std::string only = vm["quality-scene"].as<std::string>();
      sceneTypeFromString(only); // names an unknown scene
      q.scenarios.erase(std::remove_if(q.scenarios.begin(), q.scenarios.end(),
                                       [&only](const quality::Scenario& s) { return s.scene != only; }),
                        q.scenarios.end());
      if (q.scenarios.empty())
        throw UsageError("--quality-scene '" + only + "': no --quality scenario uses that scene (boxes or ridges)");
    }
    const auto [w, h] = qualitySize(vm);
    for (auto& scenario : q.scenarios)
      scenario.width = w, scenario.height = h;
    const auto rows = quality::run(q, log);
    quality::printJson(rows, json_text);
    if (json)
      quality::printJson(rows, report);
    else
      quality::printTable(rows, report);
  } else {
    temporal::Options t;
    t.frames = vm["temporal-frames"].as<int>();
    t.threads = vm["threads"].as<int>();
    if (t.frames < 3)
      throw UsageError("--temporal-frames must be at least 3");
    // The static real sequences (RealSense D435 triples) under data/ and --real-noise-data.
    for (const std::string& dir : {std::string(RANGE_NLM_DATA_DIR), vm["real-noise-data"].as<std::string>()})
      for (const auto& sequence : real_noise::staticRealSequences(dir))
        t.static_sequences.push_back(sequence);
    const auto rows = temporal::run(t, log);
    const auto real = temporal::runStatic(t, log);
    temporal::printJson(rows, real, json_text);
    if (json)
      temporal::printJson(rows, real, report);
    else
      temporal::printTable(rows, real, t, report);
  }
  std::cout << report.str();
  if (vm.count("json-file"))
    io::detail::writeWholeFile(vm["json-file"].as<std::string>(), json_text.str());
}

/// The timing run's settings from the command line, each checked.
Settings
settingsFrom(const po::variables_map& vm)
{
  Settings s;
  s.input = vm["input"].as<std::string>();
  s.sequence_dir = vm["sequence-dir"].as<std::string>();
  s.synthetic_frames = vm.count("synthetic-frames") > 0;
  s.config = vm["config"].as<std::string>();
  s.preset = vm["preset"].as<std::string>();
  try {
    s.parameters = FilterParameters::preset(s.preset);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--preset: ") + e.what());
  }
  const int iterations = vm["iterations"].as<int>();
  if (iterations < 0)
    throw UsageError("--iterations " + std::to_string(iterations) +
                     " is invalid: must be >= 1 (0 = the preset's)");
  if (iterations > 0)
    s.parameters.iterations = iterations;
  if (vm.count("parameter"))
    for (const std::string& spec : vm["parameter"].as<std::vector<std::string>>())
      applyParameterOption(spec, s.parameters);
  s.runs = vm["runs"].as<int>();
  const int threads = vm["threads"].as<int>();
  s.all = vm.count("all") > 0;
  s.no_direct = vm.count("no-direct") > 0;
  if (s.all && s.no_direct)
    throw UsageError("--all and --no-direct contradict each other (--all times the direct path more often)");
  s.breakdown = vm.count("breakdown") > 0;
  s.sequence_memory = vm["sequence-memory"].as<int>();
  s.sequence_search = vm["sequence-search"].as<int>();
  s.sequence_patch = vm["sequence-patch"].as<int>();
  s.mls_radius = vm["mls-radius"].as<double>();
  s.seed = vm["seed"].as<Unsigned64>().value;
  s.json = vm.count("json") > 0;
  if (vm.count("json-file")) {
    s.json_file = vm["json-file"].as<std::string>();
    checkJsonFile(s.json_file); // now rather than after a long run
  }
  s.quiet = vm.count("quiet") > 0;
  if (s.config != "all" && s.config != "static" && s.config != "temporal" && s.config != "preset")
    throw UsageError("--config '" + s.config + "' is invalid: expected all, static, temporal or preset");
  if (s.runs < 1 || s.runs > 1000)
    throw UsageError("--runs " + std::to_string(s.runs) + " is invalid: must be 1..1000");
  if (threads < 0 || threads > 1024)
    throw UsageError("--threads " + std::to_string(threads) + " is invalid: must be 0 (all cores) .. 1024");
  if (s.sequence_memory < 0)
    throw UsageError("--sequence-memory " + std::to_string(s.sequence_memory) + " is invalid: must be >= 0");
  if (!std::isfinite(s.mls_radius) || s.mls_radius < 0.0) {
    std::ostringstream msg;
    msg << "--mls-radius " << s.mls_radius << " is invalid: must be >= 0 (0 = automatic)";
    throw UsageError(msg.str());
  }
  if (s.sequence_search < 1 || s.sequence_search % 2 == 0)
    throw UsageError("--sequence-search " + std::to_string(s.sequence_search) +
                     " is invalid: must be odd and >= 1");
  if (s.sequence_patch < 1 || s.sequence_patch % 2 == 0)
    throw UsageError("--sequence-patch " + std::to_string(s.sequence_patch) +
                     " is invalid: must be odd and >= 1");
  s.threads = resolveThreads(threads);

  return s;
}

/// Times range_nlm against PCL's filters and prints the table or the JSON object.
void
runTiming(const Settings& s)
{
  RunInfo info;
  const auto start = std::chrono::steady_clock::now();
  info.load_start = bench::loadAverage();
#ifdef NDEBUG
  info.build = "optimised build (NDEBUG)";
#else
  info.build = "DEBUG build (assertions on): timings are not representative";
  progress(s, "warning: this is not a Release build; timings are not representative");
#endif
  info.machine = bench::machineInfo();

  // Frames are prepared in this process before any measurement; this process never runs
  // OpenMP code, so every child starts with a clean OpenMP runtime.
  const CloudConstPtr input = loadXyz(s.input);
  // "preset": only the preset's configurations (the first two of "all").
  const bool do_static = s.config != "temporal", do_temporal = s.config != "static";
  const bool do_paper = s.config != "preset";
  std::vector<std::string> sources;
  std::vector<Frames> configs;
  if (do_static) {
    configs.push_back(presetFrames(s, input));
    sources.push_back("static frames (" + s.preset + " preset): " + configs.back().source);
  }
  if (do_temporal) {
    try {
      configs.push_back(presetTemporalFrames(s, input));
    } catch (const std::invalid_argument& e) {
      throw InputError(e.what());
    }
    sources.push_back("temporal frames (" + s.preset + " preset): " + configs.back().source);
  }
  if (do_static && do_paper) {
    configs.push_back(staticFrames(s, input));
    sources.push_back("static frames: " + configs.back().source + ", " + sizeText(*input) + ", " +
                      std::to_string(finiteCount(*input)) + " valid points");
  }
  if (do_temporal && do_paper) {
    try {
      configs.push_back(temporalFrames(s, input));
    } catch (const std::invalid_argument& e) {
      throw InputError(e.what());
    }
    sources.push_back("temporal frames: " + configs.back().source);
  }

  const bench::ChildResult idle = bench::runInChild([] { return std::vector<double>{}; });
  const double baseline_mb = megabytes(idle.peak_rss_bytes);

  std::vector<Row> rows;
  std::vector<Breakdown> breakdowns;
  for (const Frames& f : configs) {
    const bool temporal = f.clouds.size() > 1;
    const std::vector<Row> part = temporal ? benchTemporal(s, f) : benchStatic(s, f);
    rows.insert(rows.end(), part.begin(), part.end());
  }
  if (s.breakdown)
    for (const Frames& f : configs) {
      const bool temporal = f.clouds.size() > 1;
      if (f.preset_windows)
        breakdowns.push_back(benchBreakdown(
            s, f, parametersFor(s, s.parameters.search_window, s.parameters.patch_size, Evaluation::fast), false));
      else
        breakdowns.push_back(
            temporal ? benchBreakdown(s, f, parametersFor(s, kTemporalSearch, kTemporalPatch, Evaluation::fast), false)
                     : benchBreakdown(s, f, parametersFor(s, kStaticSearch, kStaticPatch, Evaluation::fast),
                                      !s.no_direct));
    }
  std::unique_ptr<SequenceMemory> sequence;
  if (s.sequence_memory > 0)
    sequence = std::make_unique<SequenceMemory>(benchSequence(s, input));

  const std::vector<Target> targets = evaluateTargets(s, rows, sequence.get());
  info.load_end = bench::loadAverage();
  info.wall_s = millisecondsSince(start) / 1e3;
  if (!s.json_file.empty()) {
    std::ostringstream text;
    printJson(text, s, info, sources, baseline_mb, rows, breakdowns, sequence.get(), targets);
    io::detail::writeWholeFile(s.json_file, text.str());
  }
  if (s.json)
    printJson(std::cout, s, info, sources, baseline_mb, rows, breakdowns, sequence.get(), targets);
  else
    printTable(s, info, sources, baseline_mb, rows, breakdowns, sequence.get(), targets);

  int failed = 0;
  for (const Row& r : rows)
    failed += !r.result.ok;
  for (const Breakdown& b : breakdowns)
    failed += !b.result.ok;
  if (sequence && !sequence->result.ok)
    ++failed;
  if (failed > 0)
    throw InputError(std::to_string(failed) + " measurement(s) failed; see the report above");
}

int
run(int argc, char** argv)
{
  const std::string default_input = kDataDir + "/milk_cartoon_all_small_clorox.pcd";
  const std::string default_sequence = kDataDir + "/kinect-sequence";
  po::options_description options("Options");
  // clang-format off
  options.add_options()
    ("help,h", "print this help")
    ("input", po::value<std::string>()->default_value(default_input),
     "organized PCD frame of the static configuration (and of --synthetic-frames, --sequence-memory)")
    ("sequence-dir", po::value<std::string>()->default_value(default_sequence),
     "directory whose first 3 .pcd frames (name order), cropped to their centre 480x400, form the temporal configuration")
    ("synthetic-frames", "temporal configuration: 3 copies of the --input centre crop with fresh noise instead of --sequence-dir")
    ("config", po::value<std::string>()->default_value("all"), "configurations to time: all, static, temporal, or preset (the preset's static and temporal configurations only)")
    ("preset", po::value<std::string>()->default_value("default"),
     "range_nlm parameters: 'default' (recommended) or 'paper' (the literal method); the configuration sets search window and patch")
    ("iterations", po::value<int>()->default_value(0), "range_nlm filter passes; 0 = the preset's")
    ("parameter", po::value<std::vector<std::string>>(),
     "NAME=VALUE, repeatable: a field of range_nlm's FilterParameters (the parameter registry, docs/method.md's field table) set on top of --preset for every range_nlm run of the timing, e.g. patch_edge_gate=0; search_window, patch_size and evaluation are set by each configuration")
    ("runs", po::value<int>()->default_value(5), "timed runs per method, each right after an untimed warm-up run; the median is reported")
    ("threads", po::value<int>()->default_value(0), "threads for every method (range_nlm, FastBilateralFilterOMP, MLS); 0 = all cores")
    ("all", "also give the temporal direct path --runs runs with warm-ups (default: timed once without one, it is very slow)")
    ("no-direct", "leave out the direct (reference) evaluation, which takes minutes in the temporal configuration")
    ("breakdown", "time the phases of the filter pipeline (normals, pre-smoothing, bandwidths, offsets, ...) of each configuration, as runFilter reports them")
    ("sequence-memory", po::value<int>()->default_value(0),
     "N > 0: run TemporalStream (radius 1) over N noisy copies of --input and report its peak memory; 0 = off")
    ("sequence-search", po::value<int>()->default_value(kTemporalSearch), "search window S of the --sequence-memory run")
    ("sequence-patch", po::value<int>()->default_value(kTemporalPatch), "patch size P of the --sequence-memory run")
    ("mls-radius", po::value<double>()->default_value(0.0),
     "MovingLeastSquares search radius in cloud units; 0 = the radius of a disc with the 7x7 window's area at the frame's median pixel spacing")
    ("seed", unsigned64Value(1), "seed of the fresh noise of generated frames")
    ("json", "print one JSON object instead of the table")
    ("json-file", po::value<std::string>(), "also write that JSON object to this file")
    ("quality", "instead of timing: accuracy against ground truth on generated scenes (depth-camera and laser-grade noise, static and temporal; small features at both) of range_nlm (default, paper preset, each lever) and a parameter grid of pcl::FastBilateralFilter and pcl::MovingLeastSquares")
    ("quality-scene", po::value<std::string>(), "--quality: only the scenarios of this scene, boxes (depth-camera and laser-grade noise, static and temporal) or ridges (small features: steps, ridges and grooves of 2-5 mm, laser-grade and depth-camera noise) [default: all]")
    ("quality-size", po::value<std::string>()->default_value("640x480"), "frame size of the --quality and --generalisation scenes, WxH")
    ("generalisation", "instead of timing: range_nlm's default (and each --generalisation-setting) against the best-balanced settings of grids of pcl::FastBilateralFilter and pcl::MovingLeastSquares on the stereo sensor model at correlation lengths 0, 1, 2, 3, 4, 6 and 8 px and noise scales 0.5, 1 and 2, on the boxes, steps and ridges scenes (noise the default was not tuned on)")
    ("generalisation-scenes", po::value<std::string>(), "--generalisation: only these scenes, comma-separated, of boxes, steps and ridges (each keeps its seed) [default: all three]")
    ("generalisation-quick", "--generalisation: noise scale 1 only, correlation lengths 0, 2, 4 and 8 px, without MovingLeastSquares")
    ("generalisation-setting", po::value<std::vector<std::string>>(),
     "NAME=VALUE[,NAME=VALUE...], repeatable: --generalisation also scores range_nlm's default with these fields of FilterParameters (the parameter registry) set, e.g. iterations=3")
    ("real-noise", "instead of timing: range_nlm's settings against grids of pcl::FastBilateralFilter and pcl::MovingLeastSquares under realistic sensor noise: generated scenes with the stereo, kinect1, tof and kinect noise models (ground truth), the real frames in data/ (residual of their planar regions, interior and border band) and static real sequences (jitter)")
    ("real-noise-data", po::value<std::string>()->default_value(""), "--real-noise, --temporal-comparison: another folder laid out like data/ whose real frames are also used (e.g. one holding depth-images/realsense-d435-static/pose4 and pose5 for the jitter)")
    ("real-noise-renders", po::value<std::string>()->default_value(""), "--real-noise: write a flat-shaded image raw | range_nlm default | FastBilateral (sigma_s 5, sigma_r 0.03) of each real frame into this folder")
    ("real-noise-setting", po::value<std::vector<std::string>>(),
     "--real-noise: compare the default and this setting (NAME=VALUE[,NAME=VALUE...] on top of the default, or preset=NAME[,...]) instead of the usual settings; repeatable")
    ("real-noise-quick", "--real-noise: one noise level and seed per model, without MovingLeastSquares")
    ("temporal-comparison", "instead of timing: a generated sequence with a moving box filtered by range_nlm (per frame, temporal: centred, causal, recursive), by a per-pixel running average / median and by librealsense's temporal filter (reimplemented); temporal jitter and error at the moving edges; and the jitter of the static RealSense D435 triples if found (see --real-noise-data)")
    ("temporal-frames", po::value<int>()->default_value(12), "frames of the --temporal-comparison sequence")
    ("uncertainty-calibration", "instead of timing: whether the per-point uncertainty is calibrated: generated scenes of every sensor noise model (seed --seed, size --quality-size) filtered by the default with the uncertainty on, alone and as the middle frame of three; per decile of the predicted standard deviation the actual RMS error over the predicted RMS, all, flat and feature points")
    ("uncertainty-plot", po::value<std::string>()->default_value(""), "--uncertainty-calibration: also write the reliability diagram (predicted against actual RMS per decile, log-log, one colour per model) to this PNG")
    ("accuracy-time", "instead of timing: accuracy against time per frame of range_nlm's presets (default, live, paper), pcl::FastBilateralFilter (sigma_s 5, 10, 15 px) and pcl::MovingLeastSquares (radius 0.02, 0.03, 0.05 m) on one generated frame (boxes scene, --accuracy-time-noise, --seed, --quality-size; flat RMSE against ground truth) and one real frame (--accuracy-time-frame; residual to its planes); each method --runs timed runs after a warm-up, on --threads threads (scripts/plot_accuracy_time.py draws the --json-file)")
    ("accuracy-time-noise", po::value<std::string>()->default_value("stereo"), "--accuracy-time: noise model of the generated frame (range_nlm_synth --noise)")
    ("accuracy-time-frame", po::value<std::string>()->default_value(default_input), "--accuracy-time: the real frame (organized PCD, or depth PNG with an intrinsics.txt beside it); empty: none")
    ("hole-filling", "instead of timing: range_nlm's hole filling against librealsense's hole-filling filter (its three modes, reimplemented) and OpenCV's inpainting (Telea, Navier-Stokes), on the raw frame and after range_nlm, on generated scenes with shadows beside depth edges and blobs punched out, against ground truth (frame size: --quality-size)")
    ("hole-filling-max", po::value<int>()->default_value(24), "--hole-filling: range_nlm's --fill-holes")
    ("quiet,q", "no progress lines on stderr");
  // clang-format on
  po::positional_options_description positional;
  po::variables_map vm;
  if (!parseCommandLine(argc, argv, options, positional, vm, kUsage))
    return 0;

  if (vm.count("accuracy-time") || vm.count("quality") || vm.count("temporal-comparison") || vm.count("real-noise") ||
      vm.count("generalisation") || vm.count("uncertainty-calibration") || vm.count("hole-filling"))
    runComparison(vm);
  else
    runTiming(settingsFrom(vm));
  return 0;
}

} // namespace

int
main(int argc, char** argv)
{
  return runTool("range_nlm_bench", [&] { return run(argc, argv); });
}
