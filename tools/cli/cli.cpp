#include "cli/cli.h"
#include "cli/pipeline.h"

#include <range_nlm/io/process_memory.h>
#include <range_nlm/parameter_registry.h>

#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <type_traits>
#include <variant>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;
namespace po = boost::program_options;

namespace range_nlm
{
namespace tools
{

namespace
{
/// Keeps descriptors 0, 1 and 2 taken. One that was closed (`tool >&-`) would go to the first file
/// the tool opens, and text meant for standard output would land in an output frame; /dev/null
/// opened read-only takes its place instead, so that writing to it fails and is reported.
void
reserveStandardDescriptors()
{
  for (int fd = 0; fd <= 2; ++fd) {
    if (::fcntl(fd, F_GETFD) >= 0 || errno != EBADF)
      continue;
    // The descriptors below fd are taken (by now), so open() returns fd itself.
    const int reserved = ::open("/dev/null", O_RDONLY);
    if (reserved >= 0 && reserved != fd)
      ::close(reserved);
  }
}

/// OMP_NUM_THREADS above the thread limit of the tools (FilterParameters::max_threads, as for
/// --threads) would have every parallel region that does not give its own count start that many
/// threads (100000 ends in SIGSEGV): the processor count takes its place, with a warning.
void
limitEnvironmentThreads(const std::string& tool)
{
  const int asked = defaultThreads();
  if (asked <= FilterParameters::max_threads)
    return;
  const int processors = static_cast<int>(
      std::min<unsigned>(std::max(1u, std::thread::hardware_concurrency()), FilterParameters::max_threads));
  useThreads(processors);
  std::cerr << tool << ": warning: OMP_NUM_THREADS asks for " << asked << " threads, more than the "
            << FilterParameters::max_threads << " a tool may use; " << processors
            << " (the processors) are used where --threads does not say\n";
}

/// The exit status of `body`, with its exceptions as one-line messages on stderr.
int
statusOf(const std::string& tool, const std::function<int()>& body)
{
  try {
    return body();
  } catch (const UsageError& e) {
    std::cerr << tool << ": usage error: " << printable(e.what()) << " (see " << tool << " --help)\n";
    return 2;
  } catch (const po::error& e) {
    std::cerr << tool << ": usage error: " << printable(e.what()) << " (see " << tool << " --help)\n";
    return 2;
  } catch (const LockConflict& e) {
    std::cerr << tool << ": error: " << printable(e.what()) << "\n";
    return 4;
  } catch (const std::bad_alloc&) {
    std::cerr << tool << ": error: out of memory (lower --memory-limit to refuse large frames up front, or free "
                         "memory)\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << tool << ": error: " << printable(e.what()) << "\n";
    return 1;
  }
}

/// std::cout's buffer: written with write(2), every return checked and the first error's errno
/// kept, since stdio has forgotten why a write failed by the time the tool ends.
class CheckedOutput : public std::streambuf
{
public:
  CheckedOutput() { setp(buffer_, buffer_ + sizeof buffer_); }
  /// The errno of the first write that failed, 0 if none did.
  int error() const { return error_; }

protected:
  int_type overflow(int_type c) override
  {
    if (sync() != 0)
      return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override
  {
    const char* p = pbase();
    bool ok = true;
    while (ok && p < pptr()) {
      const ssize_t n = ::write(STDOUT_FILENO, p, static_cast<std::size_t>(pptr() - p));
      if (n < 0 && errno == EINTR)
        continue;
      ok = n > 0;
      if (!ok && error_ == 0)
        error_ = n < 0 ? errno : ENOSPC;
      p += ok ? n : 0;
    }
    setp(buffer_, buffer_ + sizeof buffer_); // what could not be written is dropped
    return ok ? 0 : -1;
  }

private:
  char buffer_[4096];
  int error_ = 0;
};

/// `status`, or 1 if what the tool printed on standard output could not all be written (a full
/// disk, a closed descriptor): a summary redirected to a file must not be lost silently.
int
checkStandardOutput(const std::string& tool, int status, const CheckedOutput& output)
{
  std::cout.flush();
  const bool c_flushed = std::fflush(stdout) == 0 && !std::ferror(stdout); // anything printed with stdio
  if (output.error() == 0 && c_flushed && std::cout.good())
    return status;
  std::cerr << tool << ": error: cannot write standard output"
            << (output.error() != 0 ? std::string(": ") + std::strerror(output.error()) : std::string()) << "\n";
  return status == 0 || status == 3 ? 1 : status;
}
} // namespace

std::string
printable(const std::string& text)
{
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const unsigned char byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte != 0x7f) {
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c == '\r') {
      out += "\\r";
    } else {
      char escape[5];
      std::snprintf(escape, sizeof escape, "\\x%02x", byte);
      out += escape;
    }
  }
  return out;
}

void
waitPassivelyBetweenFrames(char** argv)
{
  if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT"))
    return; // the user's (or the calling tool's) choice
  if (::setenv("OMP_WAIT_POLICY", "passive", 1) != 0)
    return;
  std::cout.flush();
  std::cerr.flush();
  ::execv("/proc/self/exe", argv);
  ::unsetenv("OMP_WAIT_POLICY"); // exec failed: run on as started
}

int
runTool(const std::string& tool, const std::function<int()>& body)
{
  reserveStandardDescriptors();
  // Before the first frame's buffers (io/process_memory.h).
  io::preferHugePagesForBuffers();
  limitEnvironmentThreads(tool);
  // PCL's own console messages would add lines to our one-line errors.
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  // A FIFO output whose reader went away then fails a write with EPIPE, reported with the file's
  // name, instead of killing the tool silently.
  ::signal(SIGPIPE, SIG_IGN);
  CheckedOutput output;
  std::streambuf* const original = std::cout.rdbuf(&output);
  const int status = checkStandardOutput(tool, statusOf(tool, body), output);
  std::cout.rdbuf(original); // `output` ends here; the stream is flushed again at exit
  return status;
}

bool
parseCommandLine(int argc, char** argv, const po::options_description& options,
                 const po::positional_options_description& positional, po::variables_map& vm,
                 const std::string& usage)
{
  po::store(po::command_line_parser(argc, argv).options(options).positional(positional).run(), vm);
  if (vm.count("help")) {
    std::cout << usage << "\n\n" << options << "\n";
    return false;
  }
  po::notify(vm);
  return true;
}

namespace
{
/// A value for the help: 0 as what it stands for.
std::string
helpValue(const ParameterEntry& entry, const FilterParameters& p)
{
  const std::string text = parameterText(entry, p);
  return entry.zero_means && text == "0" ? entry.zero_means : text;
}

/// The entry's help with the presets' values: "[default: v]" where they all agree, else
/// "[default: v; live: w; paper: x]".
std::string
optionHelp(const ParameterEntry& entry)
{
  std::string help = entry.help;
  if (entry.cli_always)
    return help;
  const std::string recommended = helpValue(entry, FilterParameters::recommended());
  const std::string live = helpValue(entry, FilterParameters::live());
  const std::string paper = helpValue(entry, FilterParameters::paper());
  return help + (recommended == paper && recommended == live
                     ? " [default: " + recommended + "]"
                     : " [default: " + recommended + "; live: " + live + "; paper: " + paper + "]");
}

/// The option of an entry, its value of the field's own type (an enumerator by name).
void
addOption(po::options_description& options, const ParameterEntry& entry)
{
  const FilterParameters d = FilterParameters::recommended();
  const std::string help = optionHelp(entry);
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(d.*member)>;
        if constexpr (std::is_enum_v<T>) {
          options.add_options()(entry.cli_option, po::value<std::string>(), help.c_str());
        } else if constexpr (std::is_same_v<T, std::uint64_t>) {
          auto* value = entry.cli_always ? unsigned64Value(d.*member) : po::value<Unsigned64>();
          options.add_options()(entry.cli_option, value, help.c_str());
        } else {
          auto* value = po::value<T>();
          if (entry.cli_always)
            value->default_value(d.*member);
          options.add_options()(entry.cli_option, value, help.c_str());
        }
      },
      entry.field);
}

/// Sets the entry's field from its option.
void
setFromOption(const po::variables_map& vm, const ParameterEntry& entry, FilterParameters& p)
{
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_enum_v<T>) {
          const std::string text = vm[entry.cli_option].as<std::string>();
          const int value = choiceValue(entry, text);
          if (value < 0)
            throw UsageError("--" + std::string(entry.cli_option) + " '" + text + "' is invalid: expected " +
                             choiceList(entry));
          p.*member = static_cast<T>(value);
        } else if constexpr (std::is_same_v<T, std::uint64_t>) {
          p.*member = vm[entry.cli_option].as<Unsigned64>().value;
        } else {
          p.*member = vm[entry.cli_option].as<T>();
        }
      },
      entry.field);
}

/// Sets an enumerated field from the one of its flags that was given.
void
setFromSwitches(const po::variables_map& vm, const ParameterEntry& entry, FilterParameters& p)
{
  const ParameterSwitch* given = nullptr;
  for (const ParameterSwitch& flag : entry.cli_switches) {
    if (!vm.count(flag.name))
      continue;
    if (given)
      throw UsageError("--" + std::string(given->name) + " and --" + flag.name + " contradict each other: give one");
    given = &flag;
  }
  if (given)
    setChoice(entry, p, given->on);
}
} // namespace

void
addFilterOptions(po::options_description& options)
{
  options.add_options()("preset", po::value<std::string>()->default_value("default"),
                        "parameter preset: 'default' (the most accurate, for recorded data), 'live' (for a live "
                        "camera's frame rate) or 'paper' (the literal method); options below override it");
  for (const ParameterEntry& entry : parameterRegistry()) {
    if (entry.cli_option)
      addOption(options, entry);
    for (const ParameterSwitch& flag : entry.cli_switches)
      options.add_options()(flag.name, flag.help);
  }
}

FilterParameters
filterParametersFrom(const po::variables_map& vm)
{
  FilterParameters p;
  try {
    p = FilterParameters::preset(vm["preset"].as<std::string>());
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  for (const ParameterEntry& entry : parameterRegistry()) {
    if (entry.cli_option && vm.count(entry.cli_option))
      setFromOption(vm, entry, p);
    setFromSwitches(vm, entry, p);
  }
  for (const ParameterEntry& entry : parameterRegistry())
    if (entry.explicit_positive && entry.cli_option && vm.count(entry.cli_option) && !isPositive(entry, p))
      throw UsageError("--" + std::string(entry.cli_option) + " " + parameterText(entry, p) +
                       ": a bandwidth given on the command line must be a positive number (omit it for automatic)");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  useThreads(p.threads); // also for the parallel regions that do not take the parameter
  return p;
}

namespace
{
/// The files of `directory` ending in `extension` (not hidden), unsorted; throws InputError if
/// the directory is missing, is not a directory, or cannot be listed, saying why.
std::vector<std::string>
framesIn(const std::string& directory, const std::string& extension)
{
  struct stat status;
  if (::stat(directory.c_str(), &status) != 0) {
    const int error = errno;
    if (error == ENOENT)
      throw InputError("input directory '" + directory + "' does not exist");
    throw InputError("cannot read input directory '" + directory + "': " + std::strerror(error));
  }
  if (!S_ISDIR(status.st_mode))
    throw InputError("input directory '" + directory + "' is not a directory");
  std::error_code ec;
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(directory, ec)) {
    // An entry whose kind cannot be told (a loop of symbolic links) is kept: reading it then
    // names it and says why, and --keep-going skips it like any unreadable frame.
    std::error_code kind_error;
    if (!entry.is_regular_file(kind_error) && !kind_error)
      continue;
    const std::string name = entry.path().filename().string();
    if (name.size() > extension.size() &&
        name.compare(name.size() - extension.size(), extension.size(), extension) == 0 &&
        name[0] != '.')
      files.push_back(entry.path().string());
  }
  if (ec)
    throw InputError("cannot read input directory '" + directory + "': " + ec.message());
  return files;
}
} // namespace

std::vector<std::string>
listFrames(const std::string& directory, const std::string& extension)
{
  std::vector<std::string> files = framesIn(directory, extension);
  if (files.empty())
    throw InputError("input directory '" + directory + "' holds no " + extension + " frame");
  std::sort(files.begin(), files.end());
  return files;
}

void
prepareOutputDirectory(const std::string& input_dir, const std::string& output_dir, bool allow_same)
{
  std::error_code ec;
  if (fs::exists(output_dir, ec)) {
    if (!fs::is_directory(output_dir, ec))
      throw InputError("output '" + output_dir + "' exists and is not a directory");
    if (!input_dir.empty() && fs::equivalent(input_dir, output_dir, ec) && !allow_same)
      throw InputError("output directory '" + output_dir +
                       "' is the input directory; refusing to overwrite the input (use --overwrite)");
    return;
  }
  fs::create_directories(output_dir, ec);
  if (ec)
    throw InputError("cannot create output directory '" + output_dir + "': " + ec.message());
}

void
refuseOutputsThatAreInputs(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs,
                           const std::string& remedy)
{
  // A file is its device and inode: that sees through symbolic links and hard links alike.
  std::map<std::pair<dev_t, ino_t>, const std::string*> files;
  struct stat st;
  for (const std::string& input : inputs)
    if (::stat(input.c_str(), &st) == 0 && S_ISREG(st.st_mode))
      files.emplace(std::make_pair(st.st_dev, st.st_ino), &input);
  for (const std::string& output : outputs) {
    if (::stat(output.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
      continue;
    const auto found = files.find(std::make_pair(st.st_dev, st.st_ino));
    if (found == files.end())
      continue;
    const std::string& input = *found->second;
    throw InputError("output '" + output + "' is the input file" +
                     (input == output ? std::string() : " '" + input + "' (the same file, through a link)") +
                     "; refusing to overwrite the input" + remedy);
  }
}

std::string
joinPath(const std::string& directory, const std::string& name)
{
  return (fs::path(directory) / name).string();
}

std::string
fileName(const std::string& path)
{
  return fs::path(path).filename().string();
}

namespace
{
/// Share of a default filter iteration's time spent before each phase begins (range_nlm_bench
/// --breakdown on a VGA frame), for the estimate within a frame.
double
stageStart(Stage stage)
{
  switch (stage) {
  case Stage::outliers:
  case Stage::dilation:
  case Stage::pyramid:
  case Stage::neighbour_frames:
  case Stage::bandwidths:
    return 0.0;
  case Stage::noise_maps:
    return 0.06;
  case Stage::presmoothing:
    return 0.09;
  case Stage::normals:
    return 0.26;
  case Stage::frame_terms:
    return 0.58;
  case Stage::offsets:
    return 0.64;
  case Stage::displacement:
    return 0.98;
  case Stage::hole_filling:
    return 0.99;
  }
  return 0.0;
}

std::string
duration(double seconds)
{
  std::ostringstream s;
  if (seconds < 90)
    s << static_cast<long>(std::lround(seconds)) << " s";
  else if (seconds < 5400)
    s << static_cast<long>(std::lround(seconds / 60)) << " min";
  else
    s << std::fixed << std::setprecision(1) << seconds / 3600 << " h";
  return s.str();
}
} // namespace

Progress::Progress(std::string tool, std::size_t total, int iterations, bool enabled)
    : tool_(std::move(tool)), total_(total), iterations_(std::max(1, iterations)), enabled_(enabled && total > 0),
      terminal_(::isatty(2) != 0), start_(std::chrono::steady_clock::now())
{
  if (enabled_)
    ticker_ = std::thread([this] { tick(); });
}

Progress::~Progress()
{
  finish();
}

void
Progress::update(std::size_t done)
{
  std::lock_guard<std::mutex> lock(mutex_);
  done_ = done;
  frame_fraction_ = 0.0;
}

void
Progress::begin(Stage stage, int iteration)
{
  std::lock_guard<std::mutex> lock(mutex_);
  frame_fraction_ = std::min(0.999, (iteration + stageStart(stage)) / iterations_);
}

void
Progress::end(Stage, int)
{
}

std::string
Progress::line() const
{
  const double elapsed = millisecondsSince(start_) / 1000.0;
  const double done = std::min(static_cast<double>(total_), done_ + frame_fraction_);
  std::ostringstream out;
  out << tool_ << ": ";
  if (total_ > 1)
    out << done_ << "/" << total_ << " frames, ";
  out << static_cast<int>(100.0 * done / total_) << " %, " << duration(elapsed) << " elapsed";
  if (done > 0.0)
    out << ", about " << duration(elapsed * (total_ - done) / done) << " left";
  return out.str();
}

void
Progress::tick()
{
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    wake_.wait_for(lock, std::chrono::milliseconds(250));
    if (stop_)
      break;
    const auto now = std::chrono::steady_clock::now();
    if (now - start_ < std::chrono::seconds(2))
      continue;
    if (shown_ && now - last_shown_ < std::chrono::seconds(terminal_ ? 1 : 10))
      continue;
    const std::string text = line();
    std::cerr << (terminal_ ? "\r" + text + "\033[K" : text + "\n") << std::flush;
    shown_ = true;
    last_shown_ = now;
  }
}

void
Progress::finish()
{
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stop_)
      return;
    stop_ = true;
  }
  wake_.notify_all();
  if (ticker_.joinable())
    ticker_.join();
  if (shown_ && terminal_)
    std::cerr << "\n" << std::flush;
}

double
millisecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void
addDepthImageOptions(po::options_description& options)
{
  const DepthIntrinsics d;
  // clang-format off
  options.add_options()
    ("fx", po::value<double>()->default_value(d.fx), "depth PNG input: focal length along x, pixels")
    ("fy", po::value<double>()->default_value(d.fy), "depth PNG input: focal length along y, pixels")
    ("cx", po::value<double>()->default_value(d.cx), "depth PNG input: principal point column, pixels")
    ("cy", po::value<double>()->default_value(d.cy), "depth PNG input: principal point row, pixels")
    ("depth-scale", po::value<double>()->default_value(d.depth_scale),
     "depth PNG values per metre: z = value / scale (TUM 5000, RealSense/Azure 1000)")
    ("intrinsics", po::value<std::string>(),
     "intrinsics.txt with fx, fy, cx, cy and the depth scale; options given explicitly override it [default: none]");
  // clang-format on
}

DepthIntrinsics
depthIntrinsicsFrom(const po::variables_map& vm)
{
  DepthIntrinsics intrinsics;
  if (vm.count("intrinsics")) {
    try {
      intrinsics = readIntrinsics(vm["intrinsics"].as<std::string>());
    } catch (const std::invalid_argument& e) {
      throw InputError(e.what());
    }
  }
  const std::pair<const char*, double*> fields[] = {{"fx", &intrinsics.fx},
                                                    {"fy", &intrinsics.fy},
                                                    {"cx", &intrinsics.cx},
                                                    {"cy", &intrinsics.cy},
                                                    {"depth-scale", &intrinsics.depth_scale}};
  for (const auto& field : fields) {
    if (!vm.count(field.first))
      continue;
    if (!vm[field.first].defaulted() || !vm.count("intrinsics"))
      *field.second = vm[field.first].as<double>();
  }
  try {
    intrinsics.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string(e.what()) + " (check --fx, --fy, --cx, --cy, --depth-scale and --intrinsics)");
  }
  return intrinsics;
}

DefaultIntrinsicsWarning::DefaultIntrinsicsWarning(std::string tool, const po::variables_map& vm)
    : tool_(std::move(tool))
{
  if (vm.count("intrinsics"))
    return;
  const char* const keys[] = {"fx", "fy", "cx", "cy", "depth-scale"};
  for (const char* key : keys)
    if (vm.count(key) && vm[key].defaulted()) {
      std::ostringstream value;
      value << vm[key].as<double>();
      defaults_ += std::string(defaults_.empty() ? "" : ", ") + key + " " + value.str();
    }
}

void
DefaultIntrinsicsWarning::frameRead(const std::string& path)
{
  if (defaults_.empty() || !isDepthImagePath(path))
    return;
  std::cerr << tool_ << ": warning: '" << printable(path) << "' and any other depth PNG are read with default intrinsics ("
            << defaults_ << ": a 640 x 480 Kinect v1 / TUM RGB-D camera); give --intrinsics FILE or the options "
            << "for your camera, or the depths and positions are wrong\n"
            << std::flush;
  defaults_.clear();
}

void
addMemoryLimitOption(po::options_description& options)
{
  options.add_options()("memory-limit", po::value<long long>()->default_value(static_cast<long long>(defaultMemoryLimitMb())),
                        "MB a frame may need (estimated from its file header before it is decoded; a larger frame "
                        "is refused); 0 = no limit [default: half the physical memory]");
}

std::uint64_t
defaultMemoryLimitMb()
{
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0)
    return 4096;
  return std::max<std::uint64_t>(1, std::uint64_t(pages) * std::uint64_t(page) / 2 / (1024 * 1024));
}

io::MemoryBudget
memoryBudgetFrom(const po::variables_map& vm,
                 std::function<std::uint64_t(std::uint64_t, std::uint64_t, std::uint64_t)> estimate)
{
  const long long mb = vm["memory-limit"].as<long long>();
  if (mb < 0 || mb > (1ll << 40))
    throw UsageError("--memory-limit must be 0 (no limit) or a number of MB up to 2^40, got " + std::to_string(mb));
  io::MemoryBudget budget;
  budget.limit_bytes = std::uint64_t(mb) * 1024 * 1024;
  budget.setting = "--memory-limit";
  budget.estimate = std::move(estimate);
  return budget;
}

void
validate(boost::any& v, const std::vector<std::string>& values, Unsigned64*, int)
{
  po::validators::check_first_occurrence(v);
  const std::string& text = po::validators::get_single_string(values);
  std::uint64_t value = 0;
  bool ok = !text.empty() && text.size() <= 20;
  for (const char c : text)
    ok = ok && c >= '0' && c <= '9';
  if (ok) {
    errno = 0;
    value = std::strtoull(text.c_str(), nullptr, 10);
    ok = errno == 0;
  }
  if (!ok) {
    po::error_with_option_name error("the argument ('%value%') for option '%canonical_option%' is invalid: "
                                     "expected an integer from 0 to 18446744073709551615");
    error.set_substitute("value", text);
    throw error;
  }
  v = boost::any(Unsigned64{value});
}

po::typed_value<Unsigned64>*
unsigned64Value(std::uint64_t value)
{
  return po::value<Unsigned64>()->default_value(Unsigned64{value}, std::to_string(value));
}

std::vector<std::string>
listInputFrames(const std::string& directory)
{
  std::vector<std::string> files = framesIn(directory, ".pcd");
  if (files.empty())
    files = framesIn(directory, ".png");
  if (files.empty())
    throw InputError("input directory '" + directory + "' holds no .pcd frame and no .png depth image");
  std::sort(files.begin(), files.end());
  return files;
}

std::string
replaceExtension(const std::string& path, const std::string& extension)
{
  return fs::path(path).replace_extension(extension).string();
}

} // namespace tools
} // namespace range_nlm
