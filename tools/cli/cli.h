// The one helper shared by the range_nlm_* tools and the benchmark: error exits, option parsing,
// filter and depth-image options, sorted frame lists, output directories and progress display.
// Reading and writing frames is range_nlm::io (pcd_file.h, depth_image.h).
#pragma once

#include <range_nlm/io/depth_image.h>
#include <range_nlm/io/pcd_file.h>
#include <range_nlm/core/pipeline.h>
#include <range_nlm/parameters.h>

#include <boost/program_options.hpp>
#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{
using io::LoadedCloud;
using io::loadCloud;
using io::xyzFromBlob;
using io::writeXyzToBlob;
using io::saveCloudAtomic;
using io::isDepthImagePath;
using io::loadFrame;


/// Wrong command line: exit status 2.
struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};
/// Unreadable or invalid input, failed processing: exit status 1.
using io::InputError;
/// Another run holds the output directory or the frames (run_lock.h): exit status 4. Nothing was
/// written; the same command succeeds once the other run has ended.
struct LockConflict : InputError
{
  using InputError::InputError;
};

/// Runs `body` and maps exceptions to one-line messages on stderr and exit statuses
/// (0 success, 1 input/processing error, 2 usage error, 4 LockConflict). Standard output that could not all be
/// written (a full disk, a closed descriptor) turns a success into status 1 with a message.
int
runTool(const std::string& tool, const std::function<int()>& body);

/// For runs over many frames (a directory, a bag): restarts the process (exec of itself, same
/// arguments and process id) with OMP_WAIT_POLICY=passive unless the environment already sets
/// OMP_WAIT_POLICY or GOMP_SPINCOUNT. libgomp's threads otherwise spin between parallel regions
/// and after each frame, taking the cores from the threads that read and write the frames beside
/// the filter (docs/performance.md, "Whole-process time over a directory"); libgomp reads the
/// policy only when it is loaded, hence the restart. Returns (doing nothing) where exec fails.
void
waitPassivelyBetweenFrames(char** argv);

/// `text` with its control characters written as escapes (\n, \t, \r, \xHH): a file name may
/// hold any byte but '/' and NUL, and printed raw it could split a one-line message or drive the
/// terminal. For every file name and message a tool prints as text (JSON escapes its own).
std::string
printable(const std::string& text);

/// Parses argv against `options` (+ positional), throwing UsageError with boost's message.
/// Returns false if --help was given (help text already printed to stdout).
bool
parseCommandLine(int argc, char** argv, const boost::program_options::options_description& options,
                 const boost::program_options::positional_options_description& positional,
                 boost::program_options::variables_map& vm, const std::string& usage);

/// Adds --preset and the option (and flags) of every parameter of the registry
/// (parameter_registry.h): --search-window, --patch, --iterations, --threads, --seed, ...,
/// --direct, --line-of-sight, --along-normal. Each option's value has its field's type.
void
addFilterOptions(boost::program_options::options_description& options);
/// Builds validated FilterParameters from the options added by addFilterOptions: the preset,
/// overridden by every option given. Throws UsageError naming the option or the parameter.
FilterParameters
filterParametersFrom(const boost::program_options::variables_map& vm);

/// The *.pcd files of a directory, sorted by name (with any entry of such a name whose kind
/// cannot be told, e.g. a loop of symbolic links, for reading it to report). Throws InputError if
/// the directory is missing or holds no .pcd file.
std::vector<std::string>
listFrames(const std::string& directory, const std::string& extension = ".pcd");

/// Throws InputError if an output directory is the input directory (unless allowed), or
/// creates it if missing.
void
prepareOutputDirectory(const std::string& input_dir, const std::string& output_dir, bool allow_same);

/// Throws InputError if one of `outputs` is one of `inputs`: the same path, or another path of the
/// same regular file (a symbolic link to it, or a hard link), since writing it would replace the
/// input. `remedy` ends the message, e.g. " (use --overwrite)". Outputs that do not exist yet,
/// devices and FIFOs pass.
void
refuseOutputsThatAreInputs(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs,
                           const std::string& remedy);

/// Joins a directory and a file name.
std::string
joinPath(const std::string& directory, const std::string& name);
/// The file name part of a path.
std::string
fileName(const std::string& path);

/// Progress of a run on stderr with an estimate of the time left. Nothing is shown during the
/// first two seconds (short runs stay silent); after that a line every second, rewritten in place
/// on a terminal, or a line every ten seconds when stderr is a file or a pipe. A ticker thread
/// keeps it going during a long frame. As a StageObserver of the filter it also counts the
/// phases within a frame, so that a single slow frame gets an estimate too.
class Progress : public StageObserver
{
public:
  /// `total` frames, each of `iterations` filter iterations (for the within-frame estimate).
  Progress(std::string tool, std::size_t total, int iterations, bool enabled);
  ~Progress() override;
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// `done` frames are finished.
  void update(std::size_t done);
  /// Stops the display and ends its line.
  void finish();

  void begin(Stage stage, int iteration) override;
  void end(Stage stage, int iteration) override;

private:
  void tick();
  std::string line() const;

  std::string tool_;
  std::size_t total_;
  int iterations_;
  bool enabled_;
  bool terminal_;
  std::chrono::steady_clock::time_point start_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  bool shown_ = false;
  std::size_t done_ = 0;
  double frame_fraction_ = 0.0;
  std::chrono::steady_clock::time_point last_shown_;
  std::thread ticker_;
};

/// Milliseconds since `start`.
double
millisecondsSince(std::chrono::steady_clock::time_point start);

/// Adds the options of 16-bit depth-PNG input: --fx, --fy, --cx, --cy (pixels), --depth-scale
/// (stored values per metre) with the DepthIntrinsics defaults, and --intrinsics FILE.
void
addDepthImageOptions(boost::program_options::options_description& options);
/// Intrinsics from those options: the defaults, overridden by --intrinsics FILE, overridden by
/// every value given explicitly on the command line. Throws UsageError naming the option on an
/// invalid value, InputError naming the file if the intrinsics file is unreadable or invalid.
DepthIntrinsics
depthIntrinsicsFrom(const boost::program_options::variables_map& vm);

/// Prints, once, a warning on stderr that depth PNGs are being read with default intrinsics
/// (values the user gave neither with --intrinsics nor explicitly), naming the first such file
/// and the defaults used. Call frameRead() for every frame read; PCD frames are ignored.
class DefaultIntrinsicsWarning
{
public:
  DefaultIntrinsicsWarning(std::string tool, const boost::program_options::variables_map& vm);
  void frameRead(const std::string& path);

private:
  std::string tool_;
  std::string defaults_; // empty: nothing defaulted, or already warned
};

/// Adds --memory-limit MB (see defaultMemoryLimitMb).
void
addMemoryLimitOption(boost::program_options::options_description& options);
/// The default of --memory-limit: half the machine's physical memory, in MB (4096 if unknown).
std::uint64_t
defaultMemoryLimitMb();
/// The budget of --memory-limit (0 = no limit) with `estimate` of the bytes a frame needs.
/// Throws UsageError for a negative or absurd value.
io::MemoryBudget
memoryBudgetFrom(const boost::program_options::variables_map& vm,
                 std::function<std::uint64_t(std::uint64_t, std::uint64_t, std::uint64_t)> estimate);

/// The value of an option that is an unsigned 64-bit integer (a seed). boost reads "-1" into a
/// std::uint64_t as 2^64 - 1; this refuses a sign (and anything but the digits of a number that
/// fits), naming the option and the value.
struct Unsigned64
{
  std::uint64_t value = 0;
};
/// The reader of an Unsigned64 option; boost::program_options finds it by argument-dependent lookup.
void
validate(boost::any& v, const std::vector<std::string>& values, Unsigned64*, int);
/// An Unsigned64 option's value semantic with default `value` (shown as a number in the help).
boost::program_options::typed_value<Unsigned64>*
unsigned64Value(std::uint64_t value);

/// The frames of an input directory, sorted by name: its *.pcd files if it has any, otherwise
/// its *.png depth images. Throws InputError if the directory is missing or holds neither.
std::vector<std::string>
listInputFrames(const std::string& directory);

/// `path` with its extension replaced by `extension` (e.g. ".png").
std::string
replaceExtension(const std::string& path, const std::string& extension);

} // namespace tools
} // namespace range_nlm
