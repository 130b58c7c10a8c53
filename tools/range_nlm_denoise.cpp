// range_nlm_denoise: filters one organized PCD frame, or every frame of a directory (optionally
// with the temporal filter, in one or several passes), keeping every field of the input.
#include "cli/cli.h"
#include "cli/passes.h"
#include "cli/pipeline.h"
#include "cli/shard.h"

#include <range_nlm/eval/render.h>
#include <range_nlm/temporal_nonlocal_means_filter.h>
#include <range_nlm/temporal_stream.h>

#include <nlohmann/json.hpp>

#ifdef RANGE_NLM_WITH_ROS
#include <range_nlm/ros/bag_filter.h>
#endif

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <exception>
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
    "3 done with --keep-going but some frames were skipped.\n"
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

struct FrameReport
{
  std::string name;
  double milliseconds = 0.0;
  Bandwidths bandwidths;
  /// Why it was written unchanged (empty: filtered).
  std::string unfiltered;
  /// Isolated outliers moved onto their neighbours' surface (all passes).
  std::size_t outliers_moved = 0;
};

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
  /// filters only the frames that the next one reads. A recursive pass at `level` starts its
  /// history at frame `history_begin[level]` (0: the whole history).
  PassChain(const std::vector<Pass>& passes, const std::vector<bool>& wanted,
            const std::vector<std::size_t>& history_begin, StageObserver* observer)
  {
    std::vector<std::vector<bool>> needed(passes.size());
    std::vector<bool> next = wanted;
    for (std::size_t level = passes.size(); level-- > 0;) {
      needed[level] = next;
      next = framesRead(passes[level].reach(), next, history_begin[level]);
    }
    inputs_read_ = next;
    for (std::size_t level = 0; level < passes.size(); ++level) {
      levels_.push_back({std::make_unique<TemporalStream<pcl::PointXYZ>>(passes[level].radius, passes[level].window(),
                                                                          passes[level].parameters),
                         needed[level], 0, 0, {}});
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
    std::size_t pushed = 0, emitted = 0;
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
        // A recursive pass filters frames nothing needs too (its history); passed on as null, the
        // next recursive pass starts its own history exactly where the plan says.
        ChainOutput o{l.needed[l.emitted++] ? ready[i] : nullptr, l.stream->lastOutputs()[i]};
        const TemporalStream<pcl::PointXYZ>::OutputInfo before = l.carried.front();
        l.carried.pop_front();
        if (level > 0) {
          o.info.milliseconds += before.milliseconds;
          o.info.outliers_moved += before.outliers_moved;
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
/// (OutputDirectoryLock), or with --shard those outputs (FrameRangeLock), so no running
/// range_nlm_denoise can own one of them.
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

/// Holds the frames a --shard run writes, so that shards of one recording can write into one
/// output directory at once while two runs that would write the same frame cannot: an exclusive
/// lock on the byte range [first frame, last frame + 1) of OUTPUT_DIR/.range_nlm_denoise.lock,
/// frame indices in the input's name order. Any two overlapping shards conflict, whatever their
/// N. Open file description locks (F_OFD_SETLK; the kernel releases them however the process
/// ends) are POSIX record locks, which NFS passes to the server, so shards on different nodes of
/// a cluster exclude each other on a shared file system too. The file stays (empty) behind.
class FrameRangeLock
{
public:
  static constexpr const char* kFileName = ".range_nlm_denoise.lock";

  FrameRangeLock(const std::string& directory, const FrameRange& frames, const std::vector<std::string>& inputs)
  {
    if (frames.empty())
      return; // writes nothing
    const std::string path = joinPath(directory, kFileName);
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd_ < 0)
      throw InputError("cannot open the lock file '" + path + "' of the shards: " + std::strerror(errno));
    struct flock range = {};
    range.l_type = F_WRLCK;
    range.l_whence = SEEK_SET;
    range.l_start = static_cast<off_t>(frames.begin);
    range.l_len = static_cast<off_t>(frames.size());
    int command = F_OFD_SETLK;
    int result = ::fcntl(fd_, command, &range);
    if (result != 0 && errno == EINVAL) { // no open file description locks: the process's own
      command = F_SETLK;
      result = ::fcntl(fd_, command, &range);
    }
    if (result == 0)
      return;
    const int error = errno;
    struct flock holder = range;
    const bool known = ::fcntl(fd_, command == F_OFD_SETLK ? F_OFD_GETLK : F_GETLK, &holder) == 0 &&
                       holder.l_type != F_UNLCK;
    ::close(fd_);
    fd_ = -1;
    if (error != EAGAIN && error != EACCES)
      throw InputError("cannot lock frames in '" + path + "': " + std::strerror(error));
    std::string message = "frames " + describe(frames, inputs) + " of output directory '" + directory +
                          "' are being written by another range_nlm_denoise run";
    if (known) {
      const std::size_t first = static_cast<std::size_t>(holder.l_start);
      const std::size_t end = holder.l_len == 0 ? inputs.size() : first + static_cast<std::size_t>(holder.l_len);
      message += " (holding frames " + describe({first, std::min(end, inputs.size())}, inputs) + ")";
    }
    throw InputError(message + "; wait for it to end, or give each run its own shard");
  }
  ~FrameRangeLock()
  {
    if (fd_ >= 0)
      ::close(fd_);
  }
  FrameRangeLock(const FrameRangeLock&) = delete;
  FrameRangeLock& operator=(const FrameRangeLock&) = delete;

private:
  static std::string describe(const FrameRange& frames, const std::vector<std::string>& inputs)
  {
    std::string text = std::to_string(frames.begin) + ".." + std::to_string(frames.end - 1);
    if (frames.end <= inputs.size() && !frames.empty())
      text += " (" + fileName(inputs[frames.begin]) + " .. " + fileName(inputs[frames.end - 1]) + ")";
    return text;
  }
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

/// True if every valid point of the loaded input frame has a depth that a 16-bit depth image of
/// `scale` can hold (always so for a depth-PNG input).
bool
depthsFit(const PendingFrame& frame, double scale)
{
  if (isDepthImagePath(frame.input_path))
    return true;
  const Cloud input = xyzFromBlob(frame.loaded, frame.input_path);
  for (const pcl::PointXYZ& p : input)
    if (std::isfinite(p.z) && !(std::round(double(p.z) * scale) >= 1.0 && std::round(double(p.z) * scale) <= 65535.0))
      return false;
  return true;
}

void
writeResult(PendingFrame& frame, const Cloud& result, const OutputOptions& out)
{
  if (out.png) {
    // A depth the input could hold that filtering moved just past the 16-bit range (a frame near
    // the sensor's largest value) is clamped, with a warning; an input whose depths never fitted
    // is refused (a smaller --depth-scale is needed).
    DepthClamping clamping;
    saveDepthPng(frame.output_path, result, out.depth_scale, depthsFit(frame, out.depth_scale) ? &clamping : nullptr);
    if (clamping.above > 0 || clamping.below > 0) {
      std::ostringstream warning;
      warning << "range_nlm_denoise: warning: '" << frame.output_path << "': ";
      if (clamping.above > 0)
        warning << clamping.above << " pixel(s) filtered to more than " << 65535.0 / out.depth_scale
                << " m (65535 / depth scale " << out.depth_scale << ") stored as 65535";
      if (clamping.above > 0 && clamping.below > 0)
        warning << "; ";
      if (clamping.below > 0)
        warning << clamping.below << " pixel(s) filtered to less than " << 0.5 / out.depth_scale
                << " m stored as 1";
      std::cerr << warning.str() << "\n" << std::flush;
    }
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
  io::MemoryBudget budget;
  OutputOptions output;
  bool resume = false, keep_going = false, quiet = false, json = false;
  /// The frames written and read (directory mode; without --shard: every frame, shard 0 of 1).
  bool sharded = false;
  Shard shard;
  std::size_t warmup = kWholeHistory;
  ShardPlan plan;
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
    ("pass", po::value<std::vector<std::string>>(), "a pass of a schedule, repeatable: search=S,patch=P,radius=R[,iterations=N][,normal=W]")
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
     "pcd or png (16-bit depth = round(z * --depth-scale); x, y are not stored, so use --line-of-sight); "
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

/// Bytes a width x height frame of `point_step`-byte points needs in a run of `passes`: per pass,
/// the filter's buffers (about 106 bytes a pixel) and 2R + 1 frames in flight, each held as the
/// loaded points, a PointXYZ cloud and the filter's grid (point_step + 44 bytes a pixel).
/// Measured with /usr/bin/time -v on 640 x 480 frames of 16-byte points: 166 bytes a pixel
/// above the tool's baseline for one static pass, 282 with --temporal-radius 1. A directory run
/// (`overlapped`) also holds the frame read ahead and the one written behind, each as its loaded
/// points and a PointXYZ cloud (point_step + 16 bytes a pixel; measured: 47 bytes a pixel more
/// than one frame at a time, static or temporal).
std::uint64_t
frameMemory(const std::vector<Pass>& passes, bool overlapped, std::uint64_t width, std::uint64_t height,
            std::uint64_t point_step)
{
  std::uint64_t per_pixel = 0;
  for (const Pass& pass : passes)
    per_pixel += 106 + (2 * std::uint64_t(pass.radius) + 1) * (point_step + 44);
  if (overlapped)
    per_pixel += 2 * (point_step + 16);
  const std::uint64_t pixels = width * height;
  return pixels > UINT64_MAX / per_pixel ? UINT64_MAX : pixels * per_pixel;
}

/// --shard and --shard-warmup: the frames this run writes and reads.
void
shardFrom(const po::variables_map& vm, Job& job)
{
  job.sharded = vm.count("shard") > 0;
  bool recursive = false;
  std::size_t radius = 0;
  for (const Pass& pass : job.passes)
    if (pass.recursive && pass.radius > 0) {
      recursive = true;
      radius = std::max(radius, static_cast<std::size_t>(pass.radius));
    }
  if (vm.count("shard-warmup")) {
    const std::string text = vm["shard-warmup"].as<std::string>();
    if (!job.sharded)
      throw UsageError("--shard-warmup " + text + " needs --shard");
    if (!recursive)
      throw UsageError("--shard-warmup " + text +
                       " applies to --recursive runs only (other schedules are cut exactly, without warm-up)");
    if (text == "all") {
      job.warmup = kWholeHistory;
    } else {
      try {
        std::size_t used = 0;
        const long long v = std::stoll(text, &used);
        if (used != text.size() || v < 0)
          throw std::invalid_argument(text);
        job.warmup = static_cast<std::size_t>(v);
      } catch (const std::exception&) {
        throw UsageError("--shard-warmup must be a number of frames >= 0 or 'all', got '" + text + "'");
      }
    }
  } else if (job.sharded) {
    job.warmup = kWarmupPerRadius * radius;
  }
  if (job.sharded) {
    if (job.single)
      throw UsageError("--shard cuts a directory of frames; give --input-dir and --output-dir");
    job.shard = parseShard(vm["shard"].as<std::string>(), [](const char* name) { return std::getenv(name); });
    std::error_code ec;
    if (std::filesystem::equivalent(vm["input-dir"].as<std::string>(), job.output_dir, ec))
      throw UsageError("--shard cannot write into the input directory: a shard would read frames another shard has "
                       "already filtered as its neighbours");
  }
  job.plan = planShard(job.inputs.size(), job.shard, reachOf(job.passes), job.warmup);
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
  const std::vector<Pass> passes = job.passes;
  const bool overlapped = !job.single; // one frame read ahead, one written behind (FrameRun)
  job.budget = memoryBudgetFrom(vm, [passes, overlapped](std::uint64_t w, std::uint64_t h, std::uint64_t step) {
    return frameMemory(passes, overlapped, w, h, step);
  });
  job.output = outputOptionsFrom(vm, job.single, job.inputs.front(), job.single ? job.outputs.front() : std::string(),
                                 job.intrinsics);
  if (!job.single)
    for (std::string& output : job.outputs)
      output = replaceExtension(output, job.output.png ? ".png" : ".pcd");
  shardFrom(vm, job);
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

/// A frame as the reader thread prepares it: the file, and its points as the filter takes them.
struct ReadFrame
{
  LoadedCloud loaded;
  Cloud::Ptr xyz;
  /// What converting the points threw (an infinite coordinate): thrown after the frame's size is
  /// checked, so that a frame of the wrong size is reported as such, as when read in turn.
  std::exception_ptr xyz_error;
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
      : job_(job), reads_(job.plan.reads.front()), intrinsics_warning_("range_nlm_denoise", vm),
        wanted_(reads_.size(), false),
        progress_("range_nlm_denoise", job.plan.writes.size(), iterationsPerFrame(job.passes), !job.quiet)
  {
    for (std::size_t f = job.plan.writes.begin; f < job.plan.writes.end; ++f)
      wanted_[f - reads_.begin] = true;
  }

  /// Runs to the end; throws InputError (after writing every frame it could) for a frame that
  /// cannot be read, unless the job keeps going.
  Summary run()
  {
    const auto start = std::chrono::steady_clock::now();
    const FrameRange& writes = job_.plan.writes;
    if (job_.resume && !writes.empty()) {
      removeTemporaries({job_.outputs.begin() + writes.begin, job_.outputs.begin() + writes.end});
      resumeFrom();
    }
    std::vector<std::size_t> history_begin; // of each recursive pass, counted from reads_.begin
    for (const FrameRange& read : job_.plan.reads)
      history_begin.push_back(read.begin >= reads_.begin ? read.begin - reads_.begin : 0);
    PassChain chain(job_.passes, wanted_, history_begin, &progress_);
    std::vector<std::size_t> read_order; // the frames loaded, in order
    for (std::size_t f = reads_.begin; f < reads_.end; ++f)
      if (chain.inputRead(f - reads_.begin))
        read_order.push_back(f);
    WriteBehind writer;
    ReadAhead<ReadFrame> reader(read_order.size(), [&](std::size_t i) { return readFrame(read_order[i]); });
    writer_ = &writer;
    try {
      filterAll(chain, reader);
      writer.drain();
    } catch (...) {
      // Every frame before the failure is written first. A failure to write one of them came
      // first in frame order, so it is the one reported.
      std::exception_ptr error = std::current_exception();
      try {
        writer.drain();
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
  void filterAll(PassChain& chain, ReadAhead<ReadFrame>& reader)
  {
    const FrameRange& writes = job_.plan.writes;
    std::size_t deferred = 0; // unreadable frames before the sequence's size is known
    for (std::size_t f = reads_.begin; f < reads_.end; ++f) {
      const bool halo = !writes.contains(f);
      if (!chain.inputRead(f - reads_.begin)) { // finished, and no frame still to filter reads it
        pending_.push_back(PendingFrame{LoadedCloud(), job_.inputs[f], job_.outputs[f], "", true, halo});
        finish(filtered([&] { return chain.push(nullptr); }));
        continue;
      }
      PendingFrame frame{LoadedCloud(), job_.inputs[f], job_.outputs[f], "", !wanted_[f - reads_.begin], halo};
      Cloud::Ptr xyz;
      bool loaded = false;
      try {
        try {
          ReadFrame read = reader.next(); // frame f; throws what loading it threw
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
        const std::string path = job_.inputs[f];
        writer_->post([this, path] { intrinsics_warning_.frameRead(path); }, false);
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
      if (!pending_.front().halo) {
        auto record = std::make_pair(fileName(pending_.front().input_path), pending_.front().unreadable);
        writer_->post([this, record] { summary_.unreadable.push_back(record); }, false);
      }
      pending_.pop_front();
    }
    finish(filtered([&] { return chain.flush(); }));
  }

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
      throw InputError("'" + pending_.front().input_path + "': " + e.what());
    } catch (const std::bad_alloc&) {
      throw InputError("'" + pending_.front().input_path + "': out of memory while filtering the frame (" +
                       std::to_string(summary_.width) + " x " + std::to_string(summary_.height) +
                       "; lower --memory-limit to refuse such frames up front, or free memory)");
    }
  }

  /// --resume: which outputs are complete already.
  void resumeFrom()
  {
    for (std::size_t f = job_.plan.writes.begin; f < job_.plan.writes.end; ++f) {
      if (summary_.width == 0) {
        try {
          const LoadedCloud first = loadFrame(job_.inputs[f], job_.intrinsics, job_.budget);
          summary_.width = first.blob.width;
          summary_.height = first.blob.height;
        } catch (const InputError&) {
          continue; // reported when the frame's turn comes
        }
      }
      wanted_[f - reads_.begin] = !isFinishedOutput(job_.outputs[f], job_.output.png, job_.intrinsics, summary_.width,
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

  /// Hands the results that came out of the chain, in order, to the writer: each is written (or
  /// recorded as skipped or unreadable) and reported there.
  void finish(const std::vector<ChainOutput>& results)
  {
    for (const ChainOutput& result : results) {
      auto frame = std::make_shared<PendingFrame>(std::move(pending_.front()));
      pending_.pop_front();
      if (frame->halo)
        continue; // another shard's frame
      if (!frame->unreadable.empty()) {
        auto record = std::make_pair(fileName(frame->input_path), frame->unreadable);
        writer_->post(
            [this, record] {
              summary_.unreadable.push_back(record);
              reportProgress();
            },
            false);
      } else if (!result.cloud || frame->finished) { // --resume: finished before
        const std::string name = fileName(frame->output_path);
        writer_->post(
            [this, name] {
              ++summary_.skipped;
              if (!job_.quiet && !job_.json)
                std::cout << name << ": skipped (complete output exists)" << std::endl;
              reportProgress();
            },
            false);
      } else {
        writer_->post([this, frame, result] { write(*frame, result); }, true);
      }
    }
  }

  /// On the writer thread: writes one result and reports it.
  void write(PendingFrame& frame, const ChainOutput& result)
  {
    try {
      writeResult(frame, *result.cloud, job_.output);
    } catch (const std::bad_alloc&) {
      throw InputError("'" + frame.output_path + "': out of memory while writing the frame");
    }
    const std::string name = fileName(frame.output_path);
    FrameReport report{name, result.info.milliseconds, result.info.bandwidths, result.info.problem,
                       result.info.outliers_moved};
    if (!job_.quiet && !job_.json) {
      if (report.unfiltered.empty())
        std::cout << name << ": " << std::fixed << std::setprecision(1) << report.milliseconds << " ms, d = "
                  << std::setprecision(6) << report.bandwidths.distance << ", s = " << report.bandwidths.similarity
                  << (report.outliers_moved > 0 ? ", " + std::to_string(report.outliers_moved) + " outliers moved"
                                                : std::string())
                  << std::endl;
      else
        std::cout << name << ": not filtered, written unchanged (" << report.unfiltered << ")" << std::endl;
    }
    summary_.written.push_back(report);
    reportProgress();
  }

  void reportProgress() { progress_.update(summary_.written.size() + summary_.skipped + summary_.unreadable.size()); }

  const Job& job_;
  FrameRange reads_;
  DefaultIntrinsicsWarning intrinsics_warning_;
  std::vector<bool> wanted_;
  Progress progress_;
  std::deque<PendingFrame> pending_; // pushed into the chain, not yet out of it
  /// Written on the writer thread (width and height on this one); read when the writer is done.
  Summary summary_;
  WriteBehind* writer_ = nullptr; // during run()
};

/// What a shard writes and reads, for the first line of its output.
std::string
shardLine(const Job& job)
{
  const ShardPlan& plan = job.plan;
  std::ostringstream line;
  line << "shard " << job.shard.index << "/" << job.shard.count << ": ";
  if (plan.writes.empty()) {
    line << "no frames to write (" << job.inputs.size() << " frames, " << job.shard.count << " shards)";
    return line.str();
  }
  auto name = [&](std::size_t f) { return fileName(job.inputs[f]); };
  line << "frames " << plan.writes.begin << ".." << plan.writes.end - 1 << " of " << job.inputs.size() << " ("
       << name(plan.writes.begin) << " .. " << name(plan.writes.end - 1) << "), reading frames "
       << plan.reads.front().begin << ".." << plan.reads.front().end - 1;
  return line.str();
}

void
printJson(const Summary& s, const Job& job)
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
                        {"outliers_moved", r.outliers_moved},
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
  if (job.sharded) {
    const ShardPlan& plan = job.plan;
    out["shard"] = {{"index", job.shard.index},
                    {"count", job.shard.count},
                    {"sequence_frames", job.inputs.size()},
                    {"first_frame", plan.writes.begin},
                    {"frames", plan.writes.size()},
                    {"first_frame_read", plan.reads.front().begin},
                    {"frames_read", plan.reads.front().size()}};
    const bool recursive = std::any_of(job.passes.begin(), job.passes.end(),
                                       [](const Pass& p) { return p.recursive && p.radius > 0; });
    if (recursive)
      out["shard"]["warmup"] = job.warmup == kWholeHistory ? nlohmann::json("all") : nlohmann::json(job.warmup);
  }
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
  // Shards of one recording share the directory and hold their own frames.
  const OutputDirectoryLock lock(job.single ? std::filesystem::path(job.outputs.front()).parent_path().string()
                                             : job.output_dir,
                                  job.sharded ? false : !job.single || job.resume);
  std::unique_ptr<FrameRangeLock> frames_lock;
  if (job.sharded) {
    frames_lock = std::make_unique<FrameRangeLock>(job.output_dir, job.plan.writes, job.inputs);
    if (!job.quiet && !job.json)
      std::cout << shardLine(job) << std::endl;
  }
  FrameRun frames(job, vm);
  const Summary summary = frames.run();
  if (job.json)
    printJson(summary, job);
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
