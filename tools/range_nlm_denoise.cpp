// range_nlm_denoise: filters one organized PCD frame, or every frame of a directory (optionally
// with the temporal filter, in one or several passes), keeping every field of the input.
#include "cli/bag_job.h"
#include "cli/cli.h"
#include "cli/frame_output.h"
#include "cli/pass_chain.h"
#include "cli/passes.h"
#include "cli/pipeline.h"
#include "cli/resume.h"
#include "cli/run_lock.h"
#include "cli/run_report.h"
#include "cli/shard_options.h"

#include <range_nlm/temporal_nonlocal_means_filter.h>
#include <range_nlm/temporal_stream.h>

#include <deque>
#include <exception>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>

namespace po = boost::program_options;
using namespace range_nlm;
using namespace range_nlm::tools;

namespace
{

const char* const kUsage =
    "Usage:\n"
    "  range_nlm_denoise INPUT.pcd OUTPUT.pcd [options]\n"
    "  range_nlm_denoise --input-dir DIR --output-dir DIR [--temporal-radius R [--causal]] [options]\n"
    "  range_nlm_denoise --input-dir DIR --output-dir DIR --pass search=19,patch=11,radius=1 --pass "
    "search=11,patch=5,radius=0\n"
    "  range_nlm_denoise --input-dir DIR --output-dir DIR --shard K/N [options]\n"
    "  range_nlm_denoise --input-bag IN.bag --topic /camera/depth/points --output-bag OUT.bag [options]\n"
    "Filters organized range frames with the feature-preserving non-local filter. Every field of\n"
    "the input is kept; only x, y, z move. Outputs are binary PCD.\n"
    "16-bit depth PNGs (INPUT.png, or a directory of *.png) are read with the intrinsics options;\n"
    "--output-format png writes 16-bit depth PNGs with the same depth scale, --colorize curvature\n"
    "writes PointXYZRGB clouds coloured by mean curvature.\n"
    "A frame that cannot be filtered (all NaN, or too few valid points) is written unchanged and\n"
    "reported. A frame that cannot be read (missing, truncated, malformed, another size than the\n"
    "sequence) stops the run after every frame before it is written, or with --keep-going is\n"
    "skipped and listed at the end.\n"
    "Exit status: 0 done, 1 error (a frame could not be read or written), 2 usage error,\n"
    "3 done with --keep-going but some frames were skipped, 4 another run holds the output\n"
    "directory or these frames (nothing written; try again when it has ended).\n"
    "--shard K/N writes only the K-th of N contiguous parts of the frames (K from 0), reading the\n"
    "frames around it that its temporal windows need, so that the N parts together are the output\n"
    "of one run, byte for byte; N runs may write into one output directory at once (docs/cluster.md).\n"
    "\n"
    "With --input-bag every sensor_msgs/PointCloud2 message of --topic is filtered (static or\n"
    "temporal, one pass) and every other message copied unchanged, with its record time; no ROS\n"
    "master is needed (builds with ROS support only).";

/// --recursive with --shard: default frames of history replayed before a shard, per frame of the
/// largest recursive radius (docs/cluster.md has the measurement behind it).
constexpr std::size_t kWarmupPerRadius = 8;

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

/// Everything a run needs, from the command line, checked.
struct Job
{
  std::vector<Pass> passes;
  bool single = false;
  std::vector<std::string> inputs, outputs;
  std::string output_dir; // directory mode
  DepthIntrinsics intrinsics;
  io::MemoryBudget budget;
  OutputOptions output;
  bool resume = false, keep_going = false, quiet = false, json = false;
  /// The frames written and read (directory mode; without --shard: every frame, shard 0 of 1).
  ShardJob sharding;
};

void
addOptions(po::options_description& options)
{
  // clang-format off
  options.add_options()
    ("help,h", "print this help")
    ("input", po::value<std::string>(), "input PCD file or 16-bit depth PNG (single-frame mode)")
    ("output", po::value<std::string>(), "output PCD file, or .png with PNG output (single-frame mode)")
    ("input-dir", po::value<std::string>(), "directory of *.pcd frames (if it has none: *.png depth images), filtered in name order")
    ("output-dir", po::value<std::string>(), "directory for the filtered frames (same file names)")
    ("temporal-radius", po::value<int>()->default_value(0), "R: frames on each side used by the temporal filter (0 = static)")
    ("causal", "temporal window uses only past frames (no output delay)")
    ("recursive", "the temporal neighbour is the history, a running average of the frames (newest weighted "
                  "1 / (2R + 1)): no output delay, the whole history carried along at the cost of one frame "
                  "(implies --causal)")
    ("pass", po::value<std::vector<std::string>>(), ("a pass of a schedule, repeatable: key=value items, e.g. search=9,patch=3,radius=1; keys: " + passKeys()).c_str())
    ("input-bag", po::value<std::string>(), "rosbag whose --topic PointCloud2 messages are filtered (other topics copied)")
    ("output-bag", po::value<std::string>(), "rosbag written with the filtered messages (same topics and record times)")
    ("topic", po::value<std::string>(), "topic of organized sensor_msgs/PointCloud2 messages to filter (with --input-bag)")
    ("overwrite", "allow the output to be the input (file or directory)")
    ("resume", "skip frames whose output already exists and is a complete frame of the input's size "
               "(temporal runs still read them as neighbours); removes temporary files an interrupted run left")
    ("keep-going", "skip frames that cannot be read (listed at the end, exit status 3) instead of stopping")
    ("quiet,q", "print nothing but errors and warnings (no per-frame lines, no progress)")
    ("json", "print a JSON summary instead of per-frame lines")
    ("colorize", po::value<std::string>(),
     "'curvature': write PointXYZRGB coloured by mean curvature instead of the input's fields [default: keep the fields]")
    ("curvature-limit", po::value<float>()->default_value(0.0f),
     "half-range of the --colorize colour scale, 1 / cloud unit (0 = 95th percentile of |H| of each frame)")
    ("output-format", po::value<std::string>()->default_value("auto"),
     "pcd or png (16-bit depth = round(z * --depth-scale) of each filtered point put back on its pixel's ray; "
     "x, y are not stored, a reader recomputes them from the intrinsics); "
     "auto = png for an OUTPUT.png, else the format of the input")
    ("shard", po::value<std::string>(),
     "K/N: write only the K-th (from 0) of N contiguous parts of the frames, reading the frames around it that "
     "the temporal windows need (the N parts together are byte-identical to one run; --recursive: see "
     "--shard-warmup); 'slurm': K and N of this "
     "task of a Slurm job array (SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN, SLURM_ARRAY_TASK_COUNT)")
    ("shard-warmup", po::value<std::string>(),
     ("--recursive with --shard: frames of history each recursive pass replays before its shard, or 'all' "
     "(exact, but every shard reads from the first frame) [default: " +
     std::to_string(kWarmupPerRadius) + " x the radius]").c_str());
  // clang-format on
  addFilterOptions(options);
  addDepthImageOptions(options);
  addMemoryLimitOption(options);
}

/// Bytes a width x height frame of `point_step`-byte points needs in a run of `passes`, above the
/// tool's own (about 40 MB). Per pass and pixel: the filter's buffers, 150 bytes (with the phases
/// of a dilation, automatic or given; contiguous windows alone take about 10 % less, one dilated
/// iteration alone less than half); 2R + 1 frames in flight, each held as the loaded points, a
/// PointXYZ cloud, the filter's grid and its per-frame buffers (point_step + 68 bytes); with
/// scales > 1 the pyramid and the levels' buffers (72 + 24 R bytes); with the uncertainty the
/// sums of the weights (90 bytes); with the hole filling the frame as given and the fill's buffers
/// (40 bytes); and 48 bytes a bandwidth sample. A directory run (`overlapped`) also holds the
/// frame read ahead and the one written behind, each as its loaded points and a PointXYZ cloud
/// (point_step + 16 bytes a pixel). Measured as the peak resident set (/usr/bin/time -v) less a
/// 32 x 24 frame's, on 1280 x 960 active-stereo frames of 16-byte points (bytes a pixel, measured
/// and estimated): one frame 205 / 234, --scales 3 271 / 306, --uncertainty 290 / 324,
/// --fill-holes 64 240 / 274, all three 386 / 434; a directory 256 / 298, --temporal-radius 1
/// 375 / 466 (all three 576 / 692), 2 544 / 634 (all three 765 / 884), 4 763 / 970.
std::uint64_t
frameMemory(const std::vector<Pass>& passes, bool overlapped, std::uint64_t width, std::uint64_t height,
            std::uint64_t point_step)
{
  std::uint64_t per_pixel = 0, fixed = 0;
  for (const Pass& pass : passes) {
    const FilterParameters& p = pass.parameters;
    const std::uint64_t radius = std::uint64_t(pass.radius);
    per_pixel += 150 + (2 * radius + 1) * (point_step + 68);
    if (p.scales > 1)
      per_pixel += 72 + 24 * radius;
    if (p.uncertainty)
      per_pixel += 90;
    if (p.fill_holes > 0)
      per_pixel += 40;
    fixed += 48 * std::uint64_t(std::max(p.bandwidth_samples, 0));
  }
  if (overlapped)
    per_pixel += 2 * (point_step + 16);
  const std::uint64_t pixels = width * height;
  if (pixels > (UINT64_MAX - fixed) / per_pixel)
    return UINT64_MAX;
  return pixels * per_pixel + fixed;
}

/// The passes of the schedule: --pass specs over the filter options, or those options alone.
std::vector<Pass>
passesFrom(const po::variables_map& vm)
{
  Pass base;
  base.parameters = filterParametersFrom(vm);
  base.radius = vm["temporal-radius"].as<int>();
  base.recursive = vm.count("recursive") > 0;
  base.causal = vm.count("causal") > 0 || base.recursive;
  if (base.radius < 0)
    throw UsageError("--temporal-radius must be >= 0, got " + std::to_string(base.radius));
  std::vector<Pass> passes;
  if (vm.count("pass"))
    for (const std::string& spec : vm["pass"].as<std::vector<std::string>>())
      passes.push_back(parsePass(spec, base));
  else
    passes.push_back(base);
  return passes;
}

/// INPUT OUTPUT or --input-dir/--output-dir: the job's mode, its input and output files (outputs
/// of a directory run still with the inputs' extensions), the output directory prepared.
void
framesFrom(const po::variables_map& vm, Job& job)
{
  job.single = vm.count("input") || vm.count("output");
  const bool directory = vm.count("input-dir") || vm.count("output-dir");
  if (job.single == directory)
    throw UsageError("give either INPUT.pcd OUTPUT.pcd or --input-dir DIR --output-dir DIR");
  const bool overwrite = vm.count("overwrite") > 0;
  const std::pair<const char*, const char*> paths[] = {{"input", "INPUT"},
                                                       {"output", "OUTPUT"},
                                                       {"input-dir", "--input-dir"},
                                                       {"output-dir", "--output-dir"},
                                                       {"intrinsics", "--intrinsics"}};
  for (const auto& [option, name] : paths) // refused before any frame is filtered
    if (vm.count(option) && vm[option].as<std::string>().empty())
      throw UsageError(std::string(name) + " is an empty path; give a file or directory name");
  std::error_code ec;
  if (job.single) {
    if (!vm.count("input") || !vm.count("output"))
      throw UsageError("single-frame mode needs INPUT.pcd and OUTPUT.pcd");
    job.inputs.push_back(vm["input"].as<std::string>());
    job.outputs.push_back(vm["output"].as<std::string>());
    if (std::filesystem::is_directory(job.outputs.front(), ec))
      throw InputError("output '" + job.outputs.front() + "' is a directory; give a file name (or use --output-dir)");
  } else {
    if (!vm.count("input-dir") || !vm.count("output-dir"))
      throw UsageError("directory mode needs both --input-dir and --output-dir");
    const std::string in_dir = vm["input-dir"].as<std::string>();
    job.output_dir = vm["output-dir"].as<std::string>();
    job.inputs = listInputFrames(in_dir);
    prepareOutputDirectory(in_dir, job.output_dir, overwrite);
    for (const std::string& in : job.inputs)
      job.outputs.push_back(joinPath(job.output_dir, fileName(in)));
  }
  if (job.resume && (job.single ? std::filesystem::equivalent(job.inputs.front(), job.outputs.front(), ec)
                                : std::filesystem::equivalent(vm["input-dir"].as<std::string>(), job.output_dir, ec)))
    throw UsageError("--resume cannot be used when the output is the input (every frame would count as finished)");
}

/// Every file the job reads: its frames and the intrinsics file.
std::vector<std::string>
inputsOf(const Job& job, const po::variables_map& vm)
{
  std::vector<std::string> inputs = job.inputs;
  if (vm.count("intrinsics"))
    inputs.push_back(vm["intrinsics"].as<std::string>());
  return inputs;
}

Job
jobFrom(const po::variables_map& vm)
{
  Job job;
  job.quiet = vm.count("quiet") > 0;
  job.json = vm.count("json") > 0;
  job.resume = vm.count("resume") > 0;
  job.keep_going = vm.count("keep-going") > 0;
  job.passes = passesFrom(vm);
  framesFrom(vm, job);
  job.intrinsics = depthIntrinsicsFrom(vm);
  const std::vector<Pass> passes = job.passes;
  const bool overlapped = !job.single; // one frame read ahead, one written behind (FrameRun)
  job.budget = memoryBudgetFrom(vm, [passes, overlapped](std::uint64_t w, std::uint64_t h, std::uint64_t step) {
    return frameMemory(passes, overlapped, w, h, step);
  });
  job.output = outputOptionsFrom(vm, job.single, job.inputs.front(), job.single ? job.outputs.front() : std::string(),
                                 job.intrinsics);
  job.output.uncertainty = job.passes.back().parameters.uncertainty; // the last pass's result is written
  if (!job.single)
    for (std::string& output : job.outputs)
      output = replaceExtension(output, job.output.png ? ".png" : ".pcd");
  if (!vm.count("overwrite")) // a link in the output directory may lead to any input frame
    refuseOutputsThatAreInputs(inputsOf(job, vm), job.outputs, " (use --overwrite)");
  job.sharding = shardJobFrom(vm, {reachOf(job.passes), job.single, job.inputs.size(), job.output_dir, kWarmupPerRadius});
  return job;
}

/// The passes as the chain runs them.
std::vector<ChainPass>
chainOf(const std::vector<Pass>& passes)
{
  std::vector<ChainPass> chain;
  for (const Pass& pass : passes)
    chain.push_back({pass.parameters, pass.reach()});
  return chain;
}

/// Filter iterations of a frame through every pass (for the progress display).
int
iterationsPerFrame(const std::vector<Pass>& passes)
{
  int n = 0;
  for (const Pass& p : passes)
    n += p.parameters.iterations;
  return n;
}

/// A frame in flight: the loaded file (all fields) and where its result goes.
struct PendingFrame
{
  LoadedCloud loaded;
  std::string input_path;
  std::string output_path;
  /// Why the frame could not be read (--keep-going: an all-NaN stand-in was pushed in its place,
  /// so that its neighbours' windows stay as they are; nothing is written for it).
  std::string unreadable;
  /// --resume: its output is complete already (a recursive pass still filters it, for the
  /// history of the frames after it, but it is not written again).
  bool finished = false;
  /// --shard: a frame of the halo around the shard, read as a neighbour only; another shard
  /// writes it (and reports it if it cannot be read).
  bool halo = false;
};

/// A frame as the reader thread prepares it: the file, and its points as the filter takes them.
struct ReadFrame
{
  LoadedCloud loaded;
  Cloud::Ptr xyz;
  /// What converting the points threw (an infinite coordinate): thrown after the frame's size is
  /// checked, so that a frame of the wrong size is reported as such, as when read in turn.
  std::exception_ptr xyz_error;
};

/// The writing side of a FrameRun: what becomes of each frame that came out of the chain --
/// written and reported, skipped, or listed as unreadable -- runs as tasks on a writer thread, in
/// frame order, one frame written while the next is filtered. The tasks also keep the summary's
/// records and the progress display.
class ResultWriter
{
public:
  ResultWriter(const Job& job, const po::variables_map& vm, Summary& summary, Progress& progress)
      : job_(job), intrinsics_warning_("range_nlm_denoise", vm), summary_(summary), progress_(progress)
  {
  }

  /// Frame `path` was read: the warning about default intrinsics, if due, comes before anything
  /// of this frame or a later one is reported.
  void frameRead(const std::string& path)
  {
    writer_.post([this, path] { intrinsics_warning_.frameRead(path); }, false);
  }
  /// A frame that could not be read, listed at the end; `counted`: it counts as done for the progress.
  void unreadable(const PendingFrame& frame, bool counted)
  {
    auto record = std::make_pair(fileName(frame.input_path), frame.unreadable);
    writer_.post(
        [this, record, counted] {
          summary_.unreadable.push_back(record);
          if (counted)
            reportProgress();
        },
        false);
  }
  /// --resume: a frame whose output was complete already.
  void skipped(const PendingFrame& frame)
  {
    const std::string name = fileName(frame.output_path);
    writer_.post(
        [this, name] {
          ++summary_.skipped;
          if (!job_.quiet && !job_.json)
            printSkippedLine(name);
          reportProgress();
        },
        false);
  }
  /// A result to write; waits while the one before it is being written.
  void write(const std::shared_ptr<PendingFrame>& frame, const ChainOutput& result)
  {
    writer_.post([this, frame, result] { writeNow(*frame, result); }, true);
  }
  /// Waits until everything posted has run; throws what the first failed task threw.
  void drain() { writer_.drain(); }

private:
  /// On the writer thread: writes one result and reports it.
  void writeNow(PendingFrame& frame, const ChainOutput& result)
  {
    try {
      writeResult(frame.input_path, frame.output_path, frame.loaded, *result.cloud, job_.output,
                  result.info.uncertainty, result.info.filled);
    } catch (const std::bad_alloc&) {
      throw InputError("'" + frame.output_path + "': out of memory while writing the frame");
    }
    const FrameReport report{fileName(frame.output_path), result.info.milliseconds, result.info.bandwidths,
                             result.info.problem, result.info.outliers_moved};
    if (!job_.quiet && !job_.json)
      printFrameLine(report);
    summary_.written.push_back(report);
    reportProgress();
  }

  void reportProgress() { progress_.update(summary_.written.size() + summary_.skipped + summary_.unreadable.size()); }

  const Job& job_;
  DefaultIntrinsicsWarning intrinsics_warning_;
  Summary& summary_;
  Progress& progress_;
  /// Last: destroyed first, it runs the tasks still queued while everything they use is there.
  WriteBehind writer_;
};

/// The frames whose results are to be written, index i for frame reads + i: the shard's frames,
/// but with --resume (once the temporary files an interrupted run left are removed) not those
/// whose output is complete; `summary` then holds the size of the frames, if one could be read.
std::vector<bool>
framesToWrite(const Job& job, Summary& summary)
{
  const FrameRange& reads = job.sharding.plan.reads.front();
  const FrameRange& writes = job.sharding.plan.writes;
  std::vector<bool> wanted(reads.size(), false);
  for (std::size_t f = writes.begin; f < writes.end; ++f)
    wanted[f - reads.begin] = true;
  if (!job.resume || writes.empty())
    return wanted;
  removeTemporaries({job.outputs.begin() + writes.begin, job.outputs.begin() + writes.end});
  FrameSize size;
  const std::vector<bool> finished =
      finishedOutputs(job.inputs, job.outputs, writes, job.output.png, job.intrinsics, job.budget, size);
  summary.width = size.width;
  summary.height = size.height;
  for (std::size_t f = writes.begin; f < writes.end; ++f)
    wanted[f - reads.begin] = !finished[f - writes.begin];
  return wanted;
}

/// The reading side of a FrameRun: the frames of `order` loaded one ahead on a reader thread,
/// each checked against the size of the sequence (that of the first frame read, in the summary).
class FrameReader
{
public:
  FrameReader(const Job& job, const std::vector<std::size_t>& order, Summary& summary, ResultWriter& results)
      : job_(job), order_(order), summary_(summary), results_(results),
        reader_(order_.size(), [this](std::size_t i) { return readFrame(order_[i]); })
  {
  }

  /// Takes frame f, the next of the order, into `frame` and returns its points. A frame that
  /// cannot be read throws InputError, or with --keep-going is marked unreadable (null returned).
  Cloud::Ptr next(std::size_t f, PendingFrame& frame)
  {
    Cloud::Ptr xyz;
    bool loaded = false;
    try {
      try {
        ReadFrame read = reader_.next(); // frame f; throws what loading it threw
        frame.loaded = std::move(read.loaded);
        loaded = true;
        checkSize(frame.loaded, job_.inputs[f]);
        if (read.xyz_error)
          std::rethrow_exception(read.xyz_error);
        xyz = std::move(read.xyz);
      } catch (const std::bad_alloc&) {
        frame.loaded = LoadedCloud();
        throw InputError("'" + job_.inputs[f] +
                         "': out of memory while reading the frame (lower --memory-limit to refuse such frames "
                         "up front, or free memory)");
      }
    } catch (const InputError& e) {
      // Without --keep-going: every frame already out is written (run() waits for the writer);
      // frames whose window reaches this one are not, so that --resume after mending it gives
      // exactly the result of a clean run.
      if (!job_.keep_going)
        throw;
      frame.unreadable = e.what(); // listed at the end
    }
    if (loaded) { // before anything of this frame or a later one is reported
      ++summary_.frames_read;
      results_.frameRead(job_.inputs[f]);
    }
    return xyz;
  }

  /// An all-NaN frame of the sequence's size: in place of an unreadable one it keeps the other
  /// frames' windows as they are and contributes nothing to them.
  Cloud::Ptr standIn() const
  {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    Cloud::Ptr cloud(new Cloud(summary_.width, summary_.height, pcl::PointXYZ(nan, nan, nan)));
    cloud->is_dense = false;
    return cloud;
  }

private:
  /// Loads frame f (on the reader thread): what the filter needs of it, or the exception.
  ReadFrame readFrame(std::size_t f) const
  {
    ReadFrame read;
    read.loaded = loadFrame(job_.inputs[f], job_.intrinsics, job_.budget);
    try {
      read.xyz.reset(new Cloud(xyzFromBlob(read.loaded, job_.inputs[f])));
    } catch (...) {
      read.xyz_error = std::current_exception();
    }
    return read;
  }

  void checkSize(const LoadedCloud& loaded, const std::string& path)
  {
    if (summary_.width == 0) {
      summary_.width = loaded.blob.width;
      summary_.height = loaded.blob.height;
    } else if (loaded.blob.width != summary_.width || loaded.blob.height != summary_.height) {
      throw InputError("'" + path + "': frame is " + std::to_string(loaded.blob.width) + " x " +
                       std::to_string(loaded.blob.height) + " but the sequence is " + std::to_string(summary_.width) +
                       " x " + std::to_string(summary_.height));
    }
  }

  const Job& job_;
  const std::vector<std::size_t> order_;
  Summary& summary_;
  ResultWriter& results_;
  /// Last: its thread uses the members above.
  ReadAhead<ReadFrame> reader_;
};

/// Reads, filters and writes the frames of a job in order, with reading one frame ahead of the
/// temporal windows as they need it. Reading and writing overlap with filtering: a reader thread
/// reads the next frame while the current one is filtered, and a writer thread writes the
/// previous result meanwhile (one frame in flight on each side). Everything the writer does --
/// writing, per-frame lines, warnings, the summary's records -- runs as tasks in frame order, and
/// a failure on either side reaches this thread in the order the frames would have met it when
/// read, filtered and written one after another, so the output, the messages and the exit
/// status are those of that sequential run.
class FrameRun
{
public:
  /// Frames are pushed from the first frame the shard reads on; index i of wanted_ and of the
  /// chain is frame reads_.begin + i (without --shard: every frame, from 0).
  FrameRun(const Job& job, const po::variables_map& vm)
      : job_(job), reads_(job.sharding.plan.reads.front()),
        progress_("range_nlm_denoise", job.sharding.plan.writes.size(), iterationsPerFrame(job.passes), !job.quiet),
        results_(job, vm, summary_, progress_)
  {
  }

  /// Runs to the end; throws InputError (after writing every frame it could) for a frame that
  /// cannot be read, unless the job keeps going.
  Summary run()
  {
    const auto start = std::chrono::steady_clock::now();
    wanted_ = framesToWrite(job_, summary_);
    std::vector<std::size_t> history_begin; // of each recursive pass, counted from reads_.begin
    for (const FrameRange& read : job_.sharding.plan.reads)
      history_begin.push_back(read.begin >= reads_.begin ? read.begin - reads_.begin : 0);
    PassChain chain(chainOf(job_.passes), wanted_, history_begin, &progress_);
    std::vector<std::size_t> read_order; // the frames loaded, in order
    for (std::size_t f = reads_.begin; f < reads_.end; ++f)
      if (chain.inputRead(f - reads_.begin))
        read_order.push_back(f);
    FrameReader reader(job_, read_order, summary_, results_);
    try {
      filterAll(chain, reader);
      summary_.frames_filtered = chain.framesFiltered();
      results_.drain();
    } catch (...) {
      // Every frame before the failure is written first. A failure to write one of them came
      // first in frame order, so it is the one reported.
      std::exception_ptr error = std::current_exception();
      try {
        results_.drain();
      } catch (...) {
        error = std::current_exception();
      }
      progress_.finish();
      std::rethrow_exception(error);
    }
    progress_.finish();
    summary_.wall_ms = millisecondsSince(start);
    return summary_;
  }

private:
  /// The frames of the run through the chain, their results handed to the writer.
  void filterAll(PassChain& chain, FrameReader& reader)
  {
    const FrameRange& writes = job_.sharding.plan.writes;
    std::size_t deferred = 0; // unreadable frames before the sequence's size is known
    for (std::size_t f = reads_.begin; f < reads_.end; ++f) {
      const bool halo = !writes.contains(f);
      if (!chain.inputRead(f - reads_.begin)) { // finished, and no frame still to filter reads it
        pending_.push_back(PendingFrame{LoadedCloud(), job_.inputs[f], job_.outputs[f], "", true, halo});
        finish(filtered([&] { return chain.push(nullptr); }));
        continue;
      }
      PendingFrame frame{LoadedCloud(), job_.inputs[f], job_.outputs[f], "", !wanted_[f - reads_.begin], halo};
      Cloud::Ptr xyz = reader.next(f, frame);
      if (!frame.unreadable.empty() && summary_.width == 0) {
        pending_.push_back(std::move(frame)); // its stand-in needs the sequence's size
        ++deferred;
        continue;
      }
      // Stand-ins for the unreadable frames before the first readable one, now that the size is known.
      for (; deferred > 0; --deferred)
        finish(filtered([&] { return chain.push(reader.standIn()); }));
      if (!frame.unreadable.empty())
        xyz = reader.standIn();
      pending_.push_back(std::move(frame));
      finish(filtered([&] { return chain.push(xyz); }));
    }
    for (; deferred > 0; --deferred) { // nothing could be read at all
      if (!pending_.front().halo)
        results_.unreadable(pending_.front(), false);
      pending_.pop_front();
    }
    finish(filtered([&] { return chain.flush(); }));
  }

  /// Runs a push or flush of the chain; an error of the filter (a parameter that does not fit
  /// the frames) names the oldest frame not yet written, the one being filtered.
  template <typename Step>
  std::vector<ChainOutput> filtered(const Step& step)
  {
    try {
      return step();
    } catch (const std::invalid_argument& e) {
      throw InputError("'" + pending_.front().input_path + "': " + e.what());
    } catch (const std::bad_alloc&) {
      throw InputError("'" + pending_.front().input_path + "': out of memory while filtering the frame (" +
                       std::to_string(summary_.width) + " x " + std::to_string(summary_.height) +
                       "; lower --memory-limit to refuse such frames up front, or free memory)");
    }
  }

  /// Hands the results that came out of the chain, in order, to the writer: each is written (or
  /// recorded as skipped or unreadable) and reported there.
  void finish(const std::vector<ChainOutput>& results)
  {
    for (const ChainOutput& result : results) {
      auto frame = std::make_shared<PendingFrame>(std::move(pending_.front()));
      pending_.pop_front();
      summary_.filtered_ms += result.info.milliseconds; // of every pass, halo frames too
      if (frame->halo)
        continue; // another shard's frame
      if (!frame->unreadable.empty())
        results_.unreadable(*frame, true);
      else if (!result.cloud || frame->finished) // --resume: finished before
        results_.skipped(*frame);
      else
        results_.write(frame, result);
    }
  }

  const Job& job_;
  FrameRange reads_;
  std::vector<bool> wanted_;
  std::deque<PendingFrame> pending_; // pushed into the chain, not yet out of it
  /// Written on the writer thread (width and height on this one); read when the writer is done.
  Summary summary_;
  Progress progress_;
  /// Last: its writer thread uses the members above.
  ResultWriter results_;
};

/// The locks a job holds while it writes (run_lock.h): shards of one recording share the
/// directory and hold their own frames.
struct JobLocks
{
  explicit JobLocks(const Job& job)
      : directory(job.single ? std::filesystem::path(job.outputs.front()).parent_path().string() : job.output_dir,
                  job.sharding.sharded ? false : !job.single || job.resume),
        frames(job.sharding.sharded
                   ? std::make_unique<FrameRangeLock>(job.output_dir, job.sharding.plan.writes, job.inputs)
                   : nullptr)
  {
  }
  OutputDirectoryLock directory;
  std::unique_ptr<FrameRangeLock> frames;
};

/// Parses the command line; false if --help was given (and printed).
bool
parseOptions(int argc, char** argv, po::variables_map& vm)
{
  po::options_description options("Options");
  addOptions(options);
  po::positional_options_description positional;
  positional.add("input", 1).add("output", 1);
  return parseCommandLine(argc, argv, options, positional, vm, kUsage);
}

/// The summary of a finished run; returns the exit status.
int
report(const Summary& summary, const Job& job)
{
  if (job.json)
    printSummaryJson(summary, job.sharding, job.inputs.size(), hasRecursivePass(reachOf(job.passes)));
  return reportEnd(summary, job.quiet || job.json);
}

int
run(int argc, char** argv)
{
  po::variables_map vm;
  if (!parseOptions(argc, argv, vm))
    return 0;
  if (vm.count("input-dir") || wantsBagJob(vm))
    waitPassivelyBetweenFrames(argv);
  if (wantsBagJob(vm))
    return runBagJob(vm);
  const Job job = jobFrom(vm);
  const JobLocks locks(job);
  if (job.sharding.sharded && !job.quiet && !job.json)
    std::cout << printable(describeShard(job.sharding, job.inputs)) << std::endl;
  const Summary summary = FrameRun(job, vm).run();
  return report(summary, job);
}

} // namespace

int
main(int argc, char** argv)
{
  return runTool("range_nlm_denoise", [&] { return run(argc, argv); });
}
