// range_nlm_denoise: filters one organized PCD frame, or every frame of a directory (optionally
// with the temporal filter, in one or several passes), keeping every field of the input.
#include "cli/cli.h"

#include <range_nlm/eval/render.h>
#include <range_nlm/temporal_nonlocal_means_filter.h>
#include <range_nlm/temporal_stream.h>

#include <nlohmann/json.hpp>

#ifdef RANGE_NLM_WITH_ROS
#include <range_nlm/ros/bag_filter.h>
#endif

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

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
    "3 done with --keep-going but some frames were skipped.\n"
    "With --input-bag every sensor_msgs/PointCloud2 message of --topic is filtered (static or\n"
    "temporal, one pass) and every other message copied unchanged, with its record time; no ROS\n"
    "master is needed (builds with ROS support only).";

/// One filter pass of a schedule: parameters and temporal radius.
struct Pass
{
  FilterParameters parameters;
  int radius = 0;
  bool causal = false;
  /// Neighbours are the last `radius` filtered outputs (TemporalWindow::recursive).
  bool recursive = false;
};

Pass
parsePass(const std::string& spec, const Pass& base)
{
  Pass pass = base;
  std::stringstream ss(spec);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos)
      throw UsageError("--pass '" + spec + "': expected key=value items, got '" + item + "'");
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    int v = 0;
    try {
      std::size_t used = 0;
      v = std::stoi(value, &used);
      if (used != value.size())
        throw std::invalid_argument(value);
    } catch (const std::exception&) {
      throw UsageError("--pass '" + spec + "': '" + key + "' needs an integer, got '" + value + "'");
    }
    if (key == "search")
      pass.parameters.search_window = v;
    else if (key == "patch")
      pass.parameters.patch_size = v;
    else if (key == "radius")
      pass.radius = v;
    else if (key == "iterations")
      pass.parameters.iterations = v;
    else if (key == "normal")
      pass.parameters.normal_window = v;
    else
      throw UsageError("--pass '" + spec + "': unknown key '" + key +
                       "' (expected search, patch, radius, iterations, normal)");
  }
  try {
    pass.parameters.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError("--pass '" + spec + "': " + e.what());
  }
  if (pass.radius < 0)
    throw UsageError("--pass '" + spec + "': radius must be >= 0");
  return pass;
}

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

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
};

struct FrameReport
{
  std::string name;
  double milliseconds = 0.0;
  Bandwidths bandwidths;
  /// Why it was written unchanged (empty: filtered).
  std::string unfiltered;
};

/// The frames a pass reads to filter the `needed` ones.
std::vector<bool>
framesRead(const Pass& pass, const std::vector<bool>& needed)
{
  std::vector<bool> read(needed.size(), false);
  if (pass.recursive && pass.radius > 0) { // every output carries the history before it
    const auto last = std::find(needed.rbegin(), needed.rend(), true);
    std::fill(read.begin(), read.begin() + (needed.rend() - last), true);
    return read;
  }
  const std::size_t r = static_cast<std::size_t>(pass.radius);
  for (std::size_t t = 0; t < needed.size(); ++t)
    if (needed[t])
      for (std::size_t k = t >= r ? t - r : 0; k <= (pass.causal ? t : std::min(t + r, needed.size() - 1)); ++k)
        read[k] = true;
  return read;
}

/// What became of one input frame that came out of the chain.
struct ChainOutput
{
  Cloud::ConstPtr cloud; // null: not wanted (--resume: finished before)
  TemporalStream<pcl::PointXYZ>::OutputInfo info; // of the first pass
};

/// The chain of passes, each a TemporalStream, feeding the next.
class PassChain
{
public:
  /// `wanted[t]`: the result of frame t is to be written. From the last pass back, each pass
  /// filters only the frames that the next one reads.
  PassChain(const std::vector<Pass>& passes, const std::vector<bool>& wanted, StageObserver* observer)
  {
    std::vector<std::vector<bool>> needed(passes.size());
    std::vector<bool> next = wanted;
    for (std::size_t level = passes.size(); level-- > 0;) {
      needed[level] = next;
      next = framesRead(passes[level], next);
    }
    inputs_read_ = next;
    for (std::size_t level = 0; level < passes.size(); ++level) {
      const TemporalWindow window = passes[level].recursive ? TemporalWindow::recursive
                                    : passes[level].causal  ? TemporalWindow::causal
                                                            : TemporalWindow::centred;
      levels_.push_back({std::make_unique<TemporalStream<pcl::PointXYZ>>(passes[level].radius, window,
                                                                          passes[level].parameters),
                         needed[level], 0, {}});
      levels_.back().stream->setStageObserver(observer);
    }
  }
  /// False if no result depends on input frame t: it need not even be loaded.
  bool inputRead(std::size_t t) const { return inputs_read_[t]; }
  /// Pushes a frame through every pass; returns the finished frames in order.
  std::vector<ChainOutput> push(const Cloud::ConstPtr& frame) { return feed(0, {{frame, {}}}, false); }
  std::vector<ChainOutput> flush() { return feed(0, {}, true); }

private:
  /// One pass: its stream and which of its frames the next pass (or the output) reads.
  struct Level
  {
    std::unique_ptr<TemporalStream<pcl::PointXYZ>> stream;
    std::vector<bool> needed;
    std::size_t pushed = 0;
    std::deque<TemporalStream<pcl::PointXYZ>::OutputInfo> carried;
  };

  std::vector<ChainOutput> feed(std::size_t level, const std::vector<ChainOutput>& in, bool flush)
  {
    Level& l = levels_[level];
    std::vector<ChainOutput> out;
    // Frames come out of every pass in order: the k-th output is the k-th input, whose record
    // from the earlier passes is carried along (first problem, first pass's bandwidths, time).
    auto take = [&](const std::vector<TemporalStream<pcl::PointXYZ>::CloudPtr>& ready) {
      for (std::size_t i = 0; i < ready.size(); ++i) {
        ChainOutput o{ready[i], l.stream->lastOutputs()[i]};
        const TemporalStream<pcl::PointXYZ>::OutputInfo before = l.carried.front();
        l.carried.pop_front();
        if (level > 0) {
          o.info.milliseconds += before.milliseconds;
          o.info.bandwidths = before.bandwidths;
          if (!before.problem.empty())
            o.info.problem = before.problem;
        }
        out.push_back(o);
      }
    };
    for (const ChainOutput& f : in) {
      l.carried.push_back(f.info);
      take(l.stream->push(f.cloud, l.needed[l.pushed++]));
    }
    if (flush)
      take(l.stream->flush());
    if (level + 1 == levels_.size())
      return out;
    return feed(level + 1, out, flush);
  }
  std::vector<Level> levels_;
  std::vector<bool> inputs_read_;
};

/// For --resume: removes the temporary files an interrupted run left beside `outputs`
/// (".NAME.tmpPID", see saveCloudAtomic). The caller holds the output directory exclusively
/// (OutputDirectoryLock), so no running range_nlm_denoise can own one of them.
void
removeTemporaries(const std::vector<std::string>& outputs)
{
  namespace fs = std::filesystem;
  std::vector<std::string> prefixes;
  for (const std::string& output : outputs)
    prefixes.push_back("." + fileName(output) + ".tmp");
  std::error_code ec;
  const fs::path dir = fs::path(outputs.front()).parent_path();
  for (const auto& entry : fs::directory_iterator(dir.empty() ? fs::path(".") : dir, ec)) {
    const std::string name = entry.path().filename().string();
    for (const std::string& prefix : prefixes)
      if (name.size() > prefix.size() && name.compare(0, prefix.size(), prefix) == 0 &&
          name.find_first_not_of("0123456789", prefix.size()) == std::string::npos) {
        fs::remove(entry.path(), ec);
        break;
      }
  }
}

/// Holds the directory a run writes into, so that runs cannot trip over each other's files: a
/// directory run, and any run with --resume (which removes temporary files), holds it
/// exclusively; a single-frame run shares it with other single-frame runs. A run that cannot get
/// the lock is refused with a message. An flock on the directory itself, so no file is left
/// behind; the kernel releases it however the process ends.
class OutputDirectoryLock
{
public:
  OutputDirectoryLock(const std::string& directory, bool exclusive)
  {
    const std::string dir = directory.empty() ? "." : directory;
    fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd_ < 0)
      throw InputError("cannot open output directory '" + dir + "': " + std::strerror(errno));
    if (::flock(fd_, (exclusive ? LOCK_EX : LOCK_SH) | LOCK_NB) != 0) {
      const int error = errno;
      ::close(fd_);
      fd_ = -1;
      if (error == EWOULDBLOCK)
        throw InputError("output directory '" + dir +
                         "' is in use by another range_nlm_denoise run; wait for it to end or write elsewhere");
      throw InputError("cannot lock output directory '" + dir + "': " + std::strerror(error));
    }
  }
  ~OutputDirectoryLock()
  {
    if (fd_ >= 0)
      ::close(fd_);
  }
  OutputDirectoryLock(const OutputDirectoryLock&) = delete;
  OutputDirectoryLock& operator=(const OutputDirectoryLock&) = delete;

private:
  int fd_ = -1;
};

/// For --resume: `path` holds a complete output of a width x height frame.
bool
isFinishedOutput(const std::string& path, bool png, const DepthIntrinsics& intrinsics, unsigned width,
                 unsigned height)
{
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    return false;
  try {
    if (png) {
      const Cloud cloud = loadDepthPng(path, intrinsics);
      return cloud.width == width && cloud.height == height;
    }
    const LoadedCloud loaded = loadCloud(path);
    return loaded.blob.width == width && loaded.blob.height == height;
  } catch (const std::exception&) {
    return false;
  }
}

/// How results are written: the input's fields (PCD), curvature colour (PCD) or 16-bit depth (PNG).
struct OutputOptions
{
  bool png = false;
  bool colorize = false;
  RenderParameters colour;
  double depth_scale = DepthIntrinsics().depth_scale;
};

OutputOptions
outputOptionsFrom(const po::variables_map& vm, bool single, const std::string& first_input,
                  const std::string& single_output, const DepthIntrinsics& intrinsics)
{
  OutputOptions out;
  const std::string format = vm["output-format"].as<std::string>();
  if (format == "png" || format == "pcd")
    out.png = format == "png";
  else if (format == "auto")
    out.png = isDepthImagePath(single ? single_output : first_input);
  else
    throw UsageError("--output-format must be 'pcd', 'png' or 'auto', got '" + format + "'");
  if (single && out.png != isDepthImagePath(single_output))
    throw UsageError("output '" + single_output + "' does not match --output-format " + format +
                     " (a PNG output must end in .png, a PCD output must not)");
  if (vm.count("colorize")) {
    const std::string what = vm["colorize"].as<std::string>();
    if (what != "curvature")
      throw UsageError("--colorize supports only 'curvature', got '" + what + "'");
    if (out.png)
      throw UsageError("--colorize writes PCD clouds; it cannot be combined with PNG output");
    out.colorize = true;
    out.colour.curvature_limit = vm["curvature-limit"].as<float>();
    try {
      out.colour.validate();
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--curvature-limit: ") + e.what());
    }
  }
  out.depth_scale = intrinsics.depth_scale;
  return out;
}

void
writeResult(PendingFrame& frame, const Cloud& result, const OutputOptions& out)
{
  if (out.png) {
    saveDepthPng(frame.output_path, result, out.depth_scale);
    return;
  }
  if (out.colorize) {
    RenderParameters colour = out.colour;
    colour.viewpoint = {frame.loaded.origin[0], frame.loaded.origin[1], frame.loaded.origin[2]};
    pcl::PointCloud<pcl::PointXYZRGB> coloured = colorizeByCurvature(result, colour);
    coloured.sensor_origin_ = frame.loaded.origin;
    coloured.sensor_orientation_ = frame.loaded.orientation;
    saveCloudAtomic(frame.output_path, coloured);
    return;
  }
  writeXyzToBlob(result, frame.loaded.blob);
  saveCloudAtomic(frame.output_path, frame.loaded.blob, frame.loaded.origin, frame.loaded.orientation);
}

/// Everything a run needs, from the command line, checked.
struct Job
{
  std::vector<Pass> passes;
  bool single = false;
  std::vector<std::string> inputs, outputs;
  std::string output_dir; // directory mode
  DepthIntrinsics intrinsics;
  OutputOptions output;
  bool resume = false, keep_going = false, quiet = false, json = false;
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
    ("recursive", "temporal neighbours are the last R filtered outputs: no output delay, the whole history carried "
                  "along at the cost of R frames (implies --causal)")
    ("pass", po::value<std::vector<std::string>>(), "a pass of a schedule, repeatable: search=S,patch=P,radius=R[,iterations=N][,normal=W]")
    ("input-bag", po::value<std::string>(), "rosbag whose --topic PointCloud2 messages are filtered (other topics copied)")
    ("output-bag", po::value<std::string>(), "rosbag written with the filtered messages (same topics and record times)")
    ("topic", po::value<std::string>(), "topic of organized sensor_msgs/PointCloud2 messages to filter (with --input-bag)")
    ("overwrite", "allow the output to be the input (file or directory)")
    ("resume", "skip frames whose output already exists and is a complete frame of the input's size "
               "(temporal runs still read them as neighbours); removes temporary files an interrupted run left")
    ("keep-going", "skip frames that cannot be read (listed at the end, exit status 3) instead of stopping")
    ("quiet,q", "print nothing but errors (no per-frame lines, no progress)")
    ("json", "print a JSON summary instead of per-frame lines")
    ("colorize", po::value<std::string>(),
     "'curvature': write PointXYZRGB coloured by mean curvature instead of the input's fields [default: keep the fields]")
    ("curvature-limit", po::value<float>()->default_value(0.0f),
     "half-range of the --colorize colour scale, 1 / cloud unit (0 = 95th percentile of |H| of each frame)")
    ("output-format", po::value<std::string>()->default_value("auto"),
     "pcd or png (16-bit depth = round(z * --depth-scale); x, y are not stored, so use --line-of-sight); "
     "auto = png for an OUTPUT.png, else the format of the input");
  // clang-format on
  addFilterOptions(options);
  addDepthImageOptions(options);
}

Job
jobFrom(const po::variables_map& vm)
{
  Job job;
  job.quiet = vm.count("quiet") > 0;
  job.json = vm.count("json") > 0;
  job.resume = vm.count("resume") > 0;
  job.keep_going = vm.count("keep-going") > 0;
  Pass base;
  base.parameters = filterParametersFrom(vm);
  base.radius = vm["temporal-radius"].as<int>();
  base.recursive = vm.count("recursive") > 0;
  base.causal = vm.count("causal") > 0 || base.recursive;
  if (base.radius < 0)
    throw UsageError("--temporal-radius must be >= 0, got " + std::to_string(base.radius));
  if (vm.count("pass"))
    for (const std::string& spec : vm["pass"].as<std::vector<std::string>>())
      job.passes.push_back(parsePass(spec, base));
  else
    job.passes.push_back(base);

  job.single = vm.count("input") || vm.count("output");
  const bool directory = vm.count("input-dir") || vm.count("output-dir");
  if (job.single == directory)
    throw UsageError("give either INPUT.pcd OUTPUT.pcd or --input-dir DIR --output-dir DIR");
  const bool overwrite = vm.count("overwrite") > 0;
  std::error_code ec;
  if (job.single) {
    if (!vm.count("input") || !vm.count("output"))
      throw UsageError("single-frame mode needs INPUT.pcd and OUTPUT.pcd");
    job.inputs.push_back(vm["input"].as<std::string>());
    job.outputs.push_back(vm["output"].as<std::string>());
    if (std::filesystem::is_directory(job.outputs.front(), ec))
      throw InputError("output '" + job.outputs.front() + "' is a directory; give a file name (or use --output-dir)");
    if (std::filesystem::equivalent(job.inputs.front(), job.outputs.front(), ec) && !overwrite)
      throw InputError("output '" + job.outputs.front() + "' is the input file; refusing to overwrite the input (use --overwrite)");
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
  job.intrinsics = depthIntrinsicsFrom(vm);
  job.output = outputOptionsFrom(vm, job.single, job.inputs.front(), job.single ? job.outputs.front() : std::string(),
                                 job.intrinsics);
  if (!job.single)
    for (std::string& output : job.outputs)
      output = replaceExtension(output, job.output.png ? ".png" : ".pcd");
  return job;
}

/// What a run did, for the summary and the exit status.
struct Summary
{
  std::vector<FrameReport> written;
  std::size_t skipped = 0; // --resume: complete output existed
  std::vector<std::pair<std::string, std::string>> unreadable; // file, error
  unsigned width = 0, height = 0;
  double wall_ms = 0.0;
};

/// Reads, filters and writes the frames of a job in order, with reading one frame ahead of the
/// temporal windows as they need it.
class FrameRun
{
public:
  explicit FrameRun(const Job& job)
      : job_(job), wanted_(job.inputs.size(), true),
        progress_("range_nlm_denoise", job.inputs.size(), iterationsPerFrame(job.passes), !job.quiet)
  {
  }

  /// Runs to the end; throws InputError (after writing every frame it could) for a frame that
  /// cannot be read, unless the job keeps going.
  Summary run()
  {
    const auto start = std::chrono::steady_clock::now();
    if (job_.resume) {
      removeTemporaries(job_.outputs);
      resumeFrom();
    }
    PassChain chain(job_.passes, wanted_, &progress_);
    std::size_t deferred = 0; // unreadable frames before the sequence's size is known
    for (std::size_t f = 0; f < job_.inputs.size(); ++f) {
      if (!chain.inputRead(f)) { // finished, and no frame still to filter reads it
        pending_.push_back(PendingFrame{LoadedCloud(), job_.inputs[f], job_.outputs[f], "", true});
        finish(filtered([&] { return chain.push(nullptr); }));
        continue;
      }
      PendingFrame frame{LoadedCloud(), job_.inputs[f], job_.outputs[f], "", !wanted_[f]};
      Cloud::Ptr xyz;
      try {
        frame.loaded = loadFrame(job_.inputs[f], job_.intrinsics);
        checkSize(frame.loaded, job_.inputs[f]);
        xyz.reset(new Cloud(xyzFromBlob(frame.loaded, job_.inputs[f])));
      } catch (const InputError& e) {
        if (!job_.keep_going) {
          // Every frame already out is written; frames whose window reaches this one are not, so
          // that --resume after mending it gives exactly the result of a clean run.
          progress_.finish();
          throw;
        }
        frame.unreadable = e.what(); // listed at the end
      }
      if (!frame.unreadable.empty() && summary_.width == 0) {
        pending_.push_back(std::move(frame)); // its stand-in needs the sequence's size
        ++deferred;
        continue;
      }
      // Stand-ins for the unreadable frames before the first readable one, now that the size is known.
      for (; deferred > 0; --deferred)
        finish(filtered([&] { return chain.push(standIn()); }));
      if (!frame.unreadable.empty())
        xyz = standIn();
      pending_.push_back(std::move(frame));
      finish(filtered([&] { return chain.push(xyz); }));
    }
    for (; deferred > 0; --deferred) { // nothing could be read at all
      summary_.unreadable.emplace_back(fileName(pending_.front().input_path), pending_.front().unreadable);
      pending_.pop_front();
    }
    finish(filtered([&] { return chain.flush(); }));
    progress_.finish();
    summary_.wall_ms = millisecondsSince(start);
    return summary_;
  }

private:
  static int iterationsPerFrame(const std::vector<Pass>& passes)
  {
    int n = 0;
    for (const Pass& p : passes)
      n += p.parameters.iterations;
    return n;
  }

  /// Runs a push or flush of the chain; an error of the filter (a parameter that does not fit
  /// the frames) names the oldest frame not yet written, the one being filtered.
  template <typename Step>
  std::vector<ChainOutput> filtered(const Step& step)
  {
    try {
      return step();
    } catch (const std::invalid_argument& e) {
      progress_.finish();
      throw InputError("'" + pending_.front().input_path + "': " + e.what());
    }
  }

  /// --resume: which outputs are complete already.
  void resumeFrom()
  {
    for (std::size_t f = 0; f < job_.inputs.size(); ++f) {
      if (summary_.width == 0) {
        try {
          const LoadedCloud first = loadFrame(job_.inputs[f], job_.intrinsics);
          summary_.width = first.blob.width;
          summary_.height = first.blob.height;
        } catch (const InputError&) {
          continue; // reported when the frame's turn comes
        }
      }
      wanted_[f] = !isFinishedOutput(job_.outputs[f], job_.output.png, job_.intrinsics, summary_.width,
                                     summary_.height);
    }
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

  /// An all-NaN frame of the sequence's size: in place of an unreadable one it keeps the other
  /// frames' windows as they are and contributes nothing to them.
  Cloud::Ptr standIn() const
  {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    Cloud::Ptr cloud(new Cloud(summary_.width, summary_.height, pcl::PointXYZ(nan, nan, nan)));
    cloud->is_dense = false;
    return cloud;
  }

  void finish(const std::vector<ChainOutput>& results)
  {
    for (const ChainOutput& result : results) {
      PendingFrame frame = std::move(pending_.front());
      pending_.pop_front();
      const std::string name = fileName(frame.output_path);
      if (!frame.unreadable.empty()) {
        summary_.unreadable.emplace_back(fileName(frame.input_path), frame.unreadable);
      } else if (!result.cloud || frame.finished) { // --resume: finished before
        ++summary_.skipped;
        if (!job_.quiet && !job_.json)
          std::cout << name << ": skipped (complete output exists)" << std::endl;
      } else {
        writeResult(frame, *result.cloud, job_.output);
        FrameReport report{name, result.info.milliseconds, result.info.bandwidths, result.info.problem};
        if (!job_.quiet && !job_.json) {
          if (report.unfiltered.empty())
            std::cout << name << ": " << std::fixed << std::setprecision(1) << report.milliseconds << " ms, d = "
                      << std::setprecision(6) << report.bandwidths.distance << ", s = " << report.bandwidths.similarity
                      << std::endl;
          else
            std::cout << name << ": not filtered, written unchanged (" << report.unfiltered << ")" << std::endl;
        }
        summary_.written.push_back(report);
      }
      progress_.update(summary_.written.size() + summary_.skipped + summary_.unreadable.size());
    }
  }

  const Job& job_;
  std::vector<bool> wanted_;
  Progress progress_;
  std::deque<PendingFrame> pending_;
  Summary summary_;
};

void
printJson(const Summary& s)
{
  nlohmann::json out;
  double total = 0.0;
  std::size_t unfiltered = 0;
  nlohmann::json outputs = nlohmann::json::array();
  for (const FrameReport& r : s.written) {
    total += r.milliseconds;
    nlohmann::json o = {{"file", r.name},
                        {"ms", r.milliseconds},
                        {"distance_bandwidth", r.bandwidths.distance},
                        {"similarity_bandwidth", r.bandwidths.similarity},
                        {"filtered", r.unfiltered.empty()}};
    if (!r.unfiltered.empty()) {
      o["reason"] = r.unfiltered;
      ++unfiltered;
    }
    outputs.push_back(o);
  }
  nlohmann::json unreadable = nlohmann::json::array();
  for (const auto& u : s.unreadable)
    unreadable.push_back({{"file", u.first}, {"error", u.second}});
  out["frames"] = s.written.size();
  out["skipped"] = s.skipped;
  out["unfiltered"] = unfiltered;
  out["unreadable"] = unreadable;
  out["width"] = s.width;
  out["height"] = s.height;
  out["filter_ms_total"] = total;
  out["wall_ms"] = s.wall_ms;
  out["outputs"] = outputs;
  // Non-finite numbers (an infinite bandwidth) become null; invalid UTF-8 in a file name is
  // replaced rather than ending the run.
  std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << std::endl;
}

/// --input-bag: filters one topic of a rosbag (ros/, range_nlm_ros::filterBag).
int
runBag(const po::variables_map& vm)
{
#ifndef RANGE_NLM_WITH_ROS
  (void)vm;
  throw UsageError("--input-bag: this range_nlm_denoise was built without ROS support (install the ROS packages "
                   "of scripts/setup.sh and rebuild)");
#else
  for (const char* other : {"input", "output", "input-dir", "output-dir"})
    if (vm.count(other))
      throw UsageError(std::string("--input-bag cannot be combined with ") +
                       (std::string(other).find("dir") == std::string::npos ? "INPUT/OUTPUT files" : "--input-dir/--output-dir"));
  for (const char* needed : {"input-bag", "output-bag", "topic"})
    if (!vm.count(needed))
      throw UsageError("bag mode needs --input-bag, --output-bag and --topic (missing --" + std::string(needed) + ")");
  for (const char* unsupported : {"pass", "resume", "colorize"})
    if (vm.count(unsupported))
      throw UsageError(std::string("--") + unsupported + " is not supported with --input-bag");
  if (vm["output-format"].as<std::string>() != "auto")
    throw UsageError("--output-format is not supported with --input-bag (the bag keeps the messages' layout)");
  range_nlm_ros::BagFilterOptions options;
  options.input_bag = vm["input-bag"].as<std::string>();
  options.output_bag = vm["output-bag"].as<std::string>();
  options.topic = vm["topic"].as<std::string>();
  options.keep_going = vm.count("keep-going") > 0;
  options.settings.parameters = filterParametersFrom(vm);
  options.settings.temporal_radius = vm["temporal-radius"].as<int>();
  if (options.settings.temporal_radius < 0)
    throw UsageError("--temporal-radius must be >= 0, got " + std::to_string(options.settings.temporal_radius));
  options.settings.window = vm.count("recursive") ? TemporalWindow::recursive
                            : vm.count("causal")  ? TemporalWindow::causal
                                                  : TemporalWindow::centred;
  const bool quiet = vm.count("quiet") > 0, json = vm.count("json") > 0;
  std::unique_ptr<Progress> progress;
  const auto start = std::chrono::steady_clock::now();
  range_nlm_ros::BagFilterReport report;
  try {
    report = range_nlm_ros::filterBag(options, [&](std::size_t done, std::size_t total) {
      if (!progress)
        progress = std::make_unique<Progress>("range_nlm_denoise", total, options.settings.parameters.iterations,
                                              !quiet && !json);
      progress->update(done);
    });
  } catch (const range_nlm_ros::BagError& e) {
    if (progress)
      progress->finish();
    throw InputError(e.what());
  }
  if (progress)
    progress->finish();
  std::size_t unfiltered = 0;
  double total_ms = 0.0;
  for (const auto& frame : report.frames) {
    unfiltered += !frame.unfiltered.empty();
    total_ms += frame.milliseconds;
  }
  if (json) {
    nlohmann::json out;
    nlohmann::json invalid = nlohmann::json::array();
    for (const auto& i : report.invalid)
      invalid.push_back({{"message", i.first}, {"error", i.second}});
    out["frames"] = report.frames.size();
    out["unfiltered"] = unfiltered;
    out["invalid"] = invalid;
    out["copied"] = report.copied;
    out["restarts"] = report.restarts;
    out["filter_ms_total"] = total_ms;
    out["wall_ms"] = millisecondsSince(start);
    std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << std::endl;
  } else if (!quiet) {
    for (const auto& frame : report.frames)
      if (frame.unfiltered.empty())
        std::cout << frame.message << ": " << std::fixed << std::setprecision(1) << frame.milliseconds << " ms"
                  << std::endl;
      else
        std::cout << frame.message << ": not filtered, written unchanged (" << frame.unfiltered << ")" << std::endl;
    std::cout << options.output_bag << ": " << report.frames.size() << " message(s) of " << options.topic
              << " filtered (" << unfiltered << " unchanged), " << report.copied << " other message(s) copied"
              << std::endl;
  }
  if (!report.invalid.empty()) {
    std::cerr << "range_nlm_denoise: " << report.invalid.size() << " message(s) of " << options.topic
              << " are not organized clouds and were copied unchanged:\n";
    for (const auto& i : report.invalid)
      std::cerr << "  " << i.first << ": " << i.second << "\n";
    std::cerr << std::flush;
    return 3;
  }
  return 0;
#endif
}

int
run(int argc, char** argv)
{
  po::options_description options("Options");
  addOptions(options);
  po::positional_options_description positional;
  positional.add("input", 1).add("output", 1);
  po::variables_map vm;
  if (!parseCommandLine(argc, argv, options, positional, vm, kUsage))
    return 0;
  if (vm.count("input-bag") || vm.count("output-bag") || vm.count("topic"))
    return runBag(vm);
  const Job job = jobFrom(vm);
  const OutputDirectoryLock lock(job.single ? std::filesystem::path(job.outputs.front()).parent_path().string()
                                             : job.output_dir,
                                  !job.single || job.resume);
  FrameRun frames(job);
  const Summary summary = frames.run();
  if (job.json)
    printJson(summary);
  std::size_t unfiltered = 0;
  for (const FrameReport& r : summary.written)
    unfiltered += !r.unfiltered.empty();
  if (!job.quiet && !job.json && summary.written.size() + summary.skipped > 1 && unfiltered > 0)
    std::cout << unfiltered << " frame(s) could not be filtered and were written unchanged" << std::endl;
  if (!summary.unreadable.empty()) {
    std::cerr << "range_nlm_denoise: " << summary.unreadable.size() << " frame(s) could not be read and were skipped:\n";
    for (const auto& u : summary.unreadable)
      std::cerr << "  " << u.second << "\n"; // the message names the file
    std::cerr << std::flush;
    return 3;
  }
  return 0;
}

} // namespace

int
main(int argc, char** argv)
{
  return runTool("range_nlm_denoise", [&] { return run(argc, argv); });
}
