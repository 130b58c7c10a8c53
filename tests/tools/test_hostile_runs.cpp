// The tools against a hostile user: outputs that lead back to an input, frames whose header
// announces more memory than the machine has, standard output that cannot be written, file names
// that are not UTF-8 or hold control characters, absurd thread counts and intrinsics. Each test
// asserts the property the user relies on: no input changed, the problem named, the exit status.
#include "test_support.h"

#include <range_nlm/io/pcd_file.h>

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{

class HostileRuns : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() / ("range_nlm_hostile_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "in");
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  /// A small noisy plane, frame `k` of a sequence, saved as `name`.
  void writeFrame(const std::string& name, int k, int w = 32, int h = 24) const
  {
    const auto cloud = test::makeCloud(w, h, test::plane({0.1, 0.0, 1.0}, 1.0), 0.003, 40 + k);
    ASSERT_EQ(pcl::io::savePCDFileBinary(path(name), cloud), 0);
  }
  /// A directory "in" of `n` frames frame_0000.pcd ...
  void writeSequence(int n) const
  {
    for (int k = 0; k < n; ++k)
      writeFrame("in/frame_000" + std::to_string(k) + ".pcd", k);
  }
  /// Ground truth for range_nlm_eval: frame `k` with the plane's normal.
  void writeTruth(const std::string& name, int k) const
  {
    const auto xyz = test::makeCloud(32, 24, test::plane({0.1, 0.0, 1.0}, 1.0), 0.0, 40 + k);
    pcl::PointCloud<pcl::PointNormal> truth(32, 24);
    for (std::size_t i = 0; i < truth.size(); ++i) {
      truth[i].x = xyz[i].x, truth[i].y = xyz[i].y, truth[i].z = xyz[i].z;
      truth[i].normal_x = -0.0995f, truth[i].normal_y = 0.0f, truth[i].normal_z = -0.995f;
    }
    ASSERT_EQ(pcl::io::savePCDFileBinary(path(name), truth), 0);
  }
  static void writeText(const std::string& file, const std::string& text)
  {
    std::ofstream out(file, std::ios::binary);
    out << text;
  }

  fs::path dir_;
};

/// A PNG of a header only: 16-bit greyscale, width x height, no pixel data (a reader that trusts the
/// header allocates width x height before it finds the data missing).
std::string
pngHeaderOnly(std::uint32_t width, std::uint32_t height)
{
  auto chunk = [](const std::string& type, const std::string& data) {
    std::string bytes;
    for (int shift = 24; shift >= 0; shift -= 8)
      bytes += static_cast<char>((data.size() >> shift) & 0xff);
    const std::string body = type + data;
    const uLong crc = crc32(0, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size()));
    bytes += body;
    for (int shift = 24; shift >= 0; shift -= 8)
      bytes += static_cast<char>((crc >> shift) & 0xff);
    return bytes;
  };
  std::string ihdr;
  for (std::uint32_t value : {width, height})
    for (int shift = 24; shift >= 0; shift -= 8)
      ihdr += static_cast<char>((value >> shift) & 0xff);
  ihdr += std::string("\x10\x00\x00\x00\x00", 5); // 16 bits, greyscale, deflate, no filter, no interlace
  return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) + chunk("IDAT", "") + chunk("IEND", "");
}

/// A PCD header announcing 16384 x 16384 points in front of a small body.
const char* const kHugePcd = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
                             "TYPE F F F\nCOUNT 1 1 1\nWIDTH 16384\nHEIGHT 16384\nVIEWPOINT 0 0 0 1 0 0 0\n"
                             "POINTS 268435456\nDATA binary_compressed\n";

} // namespace

// A symbolic link in the output directory that leads to an input frame: the directory run refuses
// it up front, by name, as single-frame mode does, and the input keeps its bytes.
TEST_F(HostileRuns, LinkInTheOutputDirectoryToAnInputIsRefused)
{
  writeSequence(3);
  fs::create_directories(dir_ / "out");
  fs::create_symlink("../in/frame_0002.pcd", dir_ / "out/frame_0002.pcd");
  const std::string before = test::readBytes(path("in/frame_0002.pcd"));
  const std::string args = "--input-dir " + path("in") + " --output-dir " + path("out") + " -q --temporal-radius 1";
  test::CommandResult r = test::runDenoise(args);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("output '" + path("out/frame_0002.pcd") + "' is the input file '" +
                          path("in/frame_0002.pcd") + "'"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(test::readBytes(path("in/frame_0002.pcd")), before);
  EXPECT_FALSE(fs::exists(dir_ / "out/frame_0000.pcd")); // refused before anything is written
  // A hard link is the same file too.
  fs::remove(dir_ / "out/frame_0002.pcd");
  fs::create_hard_link(dir_ / "in/frame_0001.pcd", dir_ / "out/frame_0001.pcd");
  r = test::runDenoise(args);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("'" + path("in/frame_0001.pcd") + "' (the same file, through a link)"), std::string::npos)
      << r.output;
  // --overwrite allows it, as for a single frame.
  r = test::runDenoise(args + " --overwrite");
  EXPECT_EQ(r.status, 0) << r.output;
}

// range_nlm_render's output is one of its inputs (by name, through a symbolic link, as a hard link,
// or a comparison's frame): refused, the input unchanged.
TEST_F(HostileRuns, RenderRefusesAnOutputThatIsItsInput)
{
  writeFrame("in.pcd", 0);
  const std::string before = test::readBytes(path("in.pcd"));
  fs::create_symlink("in.pcd", dir_ / "link.pcd");
  fs::create_hard_link(dir_ / "in.pcd", dir_ / "hard.pcd");
  for (const std::string& output : {path("in.pcd"), path("link.pcd"), path("hard.pcd")}) {
    const test::CommandResult r =
        test::runTool("range_nlm_render", path("in.pcd") + " " + output + " --mode curvature -q");
    EXPECT_EQ(r.status, 1) << output << ": " << r.output;
    EXPECT_NE(r.output.find("output '" + output + "' is the input file"), std::string::npos) << r.output;
    EXPECT_EQ(test::readBytes(path("in.pcd")), before) << output;
  }
  writeFrame("b.pcd", 1);
  fs::copy_file(path("in.pcd"), path("a.png"));
  const std::string image = test::readBytes(path("a.png"));
  const test::CommandResult r =
      test::runTool("range_nlm_render", "--before " + path("b.pcd") + " --after " + path("a.png") + " " +
                                            path("a.png") + " -q");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("is the input file"), std::string::npos) << r.output;
  EXPECT_EQ(test::readBytes(path("a.png")), image);
}

// A 2 kB PNG announcing 32000 x 32000 pixels and a 4 kB PCD header announcing 16384 x 16384 points:
// range_nlm_render and range_nlm_eval refuse them from the header under --memory-limit, as the
// denoise tool does, naming the file and the figure.
TEST_F(HostileRuns, RenderAndEvalRefuseFramesAboveTheMemoryLimit)
{
  writeText(path("bomb.png"), pngHeaderOnly(32000, 32000));
  writeText(path("bomb.pcd"), kHugePcd + std::string(64, '\0'));
  writeFrame("small.pcd", 0);
  const std::string limit = " --memory-limit 4096";
  const std::pair<std::string, std::string> runs[] = {
      {"range_nlm_render", path("bomb.png") + " " + path("out.png")},
      {"range_nlm_render", path("bomb.pcd") + " " + path("out.pcd") + " --mode curvature"},
      {"range_nlm_render", "--before " + path("small.pcd") + " --after " + path("bomb.pcd") + " " + path("out.png")},
      {"range_nlm_eval", "--raw " + path("bomb.png")},
      {"range_nlm_eval", "--raw " + path("small.pcd") + " " + path("bomb.pcd")},
      {"range_nlm_eval", path("bomb.pcd") + " " + path("small.pcd")},
      {"range_nlm_eval", "--jitter " + path("in") + " --json"}};
  fs::copy_file(path("bomb.pcd"), path("in/frame.pcd"));
  for (const auto& [tool, args] : runs) {
    const test::CommandResult r = test::runTool(tool, args + limit);
    EXPECT_EQ(r.status, 1) << tool << " " << args << ": " << r.output;
    EXPECT_NE(r.output.find(" frame needs about"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("more than the limit of 4096 MB (raise it with --memory-limit"), std::string::npos)
        << r.output;
    EXPECT_TRUE(r.output.find("'" + path("bomb.png") + "'") != std::string::npos ||
                r.output.find("'" + path("bomb.pcd") + "'") != std::string::npos ||
                r.output.find("'" + path("in/frame.pcd") + "'") != std::string::npos)
        << r.output;
  }
  EXPECT_FALSE(fs::exists(path("out.png")));
  EXPECT_FALSE(fs::exists(path("out.pcd")));
  const test::CommandResult r = test::runTool("range_nlm_render", path("small.pcd") + " " + path("out.png") + limit);
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(test::runTool("range_nlm_eval", "--raw " + path("small.pcd") + " --memory-limit -1").status, 2);
}

// Standard output that cannot be written -- a full disk (/dev/full), a closed descriptor -- ends
// in exit status 1 and a message, never in an empty summary with status 0.
TEST_F(HostileRuns, StandardOutputWriteErrorsFailTheRun)
{
  writeTruth("gt.pcd", 0);
  writeFrame("in.pcd", 1);
  const std::string tools = std::string(RANGE_NLM_TOOLS_DIR) + "/";
  const std::string runs[] = {
      tools + "range_nlm_eval " + path("gt.pcd") + " " + path("gt.pcd") + " --json",
      tools + "range_nlm_denoise " + path("in.pcd") + " " + path("out.pcd") + " --json",
      tools + "range_nlm_render " + path("in.pcd") + " " + path("out.png")};
  for (const std::string& run : runs) {
    test::CommandResult r = test::runCommand("(" + run + " > /dev/full)"); // stderr still to the test
    EXPECT_EQ(r.status, 1) << run << ": " << r.output;
    EXPECT_NE(r.output.find("error: cannot write standard output: No space left on device"), std::string::npos)
        << r.output;
    r = test::runCommand("(" + run + " >&-)");
    EXPECT_EQ(r.status, 1) << run << ": " << r.output;
    EXPECT_NE(r.output.find("error: cannot write standard output"), std::string::npos) << r.output;
  }
  // The frame written with a closed standard output is a frame, not the summary.
  const test::CommandResult r = test::runTool("range_nlm_eval", path("gt.pcd") + " " + path("out.pcd"));
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("flat mm"), std::string::npos) << r.output;
  // Nothing printed, nothing to fail.
  EXPECT_EQ(test::runCommand("(" + tools + "range_nlm_denoise " + path("in.pcd") + " " + path("out.pcd") +
                             " -q >&-)").status,
            0);
}

// A frame name that is not UTF-8: range_nlm_eval --json stays valid JSON (the bytes become
// U+FFFD, as in the denoise tool's summary).
TEST_F(HostileRuns, EvalJsonOfANameThatIsNotUtf8IsValid)
{
  const std::string name = "bad\xff\xfe name.pcd";
  fs::create_directories(dir_ / "gt");
  writeTruth("gt/" + name, 0);
  writeTruth("in/" + name, 0);
  const test::CommandResult r = test::runTool("range_nlm_eval", path("gt") + " " + path("in") + " --json");
  EXPECT_EQ(r.status, 0) << r.output;
  nlohmann::json summary;
  ASSERT_NO_THROW(summary = test::jsonLine(r.output)) << r.output;
  EXPECT_EQ(summary["frames"][0]["name"], "bad\xef\xbf\xbd\xef\xbf\xbd name.pcd");
}

// Output names of 246 to 255 bytes are legal: the temporary file beside them gets a shorter name
// (within the 255 bytes a name may have), so they are written, and --resume still finds and
// removes what an interrupted run left.
TEST_F(HostileRuns, LongestFileNamesAreWritten)
{
  writeFrame("in.pcd", 0);
  for (std::size_t length : {246u, 250u, 255u}) {
    const std::string name = std::string(length - 4, 'n') + ".pcd";
    const test::CommandResult r = test::runDenoise(path("in.pcd") + " " + path(name) + " -q");
    EXPECT_EQ(r.status, 0) << length << ": " << r.output;
    EXPECT_TRUE(fs::is_regular_file(dir_ / name)) << length;
    EXPECT_LE(io::temporaryPrefix(name).size() + 10, 255u);
  }
  // Names that differ only past the cut keep their temporaries apart.
  EXPECT_NE(io::temporaryPrefix(std::string(251, 'a') + ".pcd"), io::temporaryPrefix(std::string(251, 'a') + ".PCD"));
  // A temporary file an interrupted run left beside a long name goes with --resume.
  const std::string name = std::string(251, 'f') + ".pcd";
  writeFrame("in/" + name, 0);
  fs::create_directories(dir_ / "out");
  const std::string leftover = io::temporaryPrefix(name) + "4242";
  writeText(path("out/" + leftover), "half a frame");
  const test::CommandResult r =
      test::runDenoise("--input-dir " + path("in") + " --output-dir " + path("out") + " -q --resume");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "out" / name));
  EXPECT_FALSE(fs::exists(dir_ / "out" / leftover));
}

// A loop of symbolic links among the frames of --input-dir is an unreadable frame like any other:
// named with the system's reason, skipped with --keep-going (exit status 3), the other frames
// written.
TEST_F(HostileRuns, SymbolicLinkLoopInTheInputIsAnUnreadableFrame)
{
  writeSequence(3);
  fs::create_symlink("frame_0001b.pcd", dir_ / "in/frame_0001a.pcd");
  fs::create_symlink("frame_0001a.pcd", dir_ / "in/frame_0001b.pcd");
  test::CommandResult r = test::runDenoise("--input-dir " + path("in") + " --output-dir " + path("out") + " --json --keep-going");
  EXPECT_EQ(r.status, 3) << r.output;
  EXPECT_EQ(r.output.find("filesystem error"), std::string::npos) << r.output;
  const nlohmann::json summary = test::jsonLine(r.output);
  EXPECT_EQ(summary["frames"], 3);
  ASSERT_EQ(summary["unreadable"].size(), 2u) << r.output;
  EXPECT_EQ(summary["unreadable"][0]["file"], "frame_0001a.pcd");
  EXPECT_NE(summary["unreadable"][0]["error"].get<std::string>().find("Too many levels of symbolic links"),
            std::string::npos)
      << r.output;
  for (int k = 0; k < 3; ++k)
    EXPECT_TRUE(fs::is_regular_file(dir_ / "out" / ("frame_000" + std::to_string(k) + ".pcd")));
  r = test::runDenoise("--input-dir " + path("in") + " --output-dir " + path("out2") + " -q");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("'" + path("in/frame_0001a.pcd") + "'"), std::string::npos) << r.output;
}

// --intrinsics reads at most 1 MB: a character device that never ends is refused quickly, by name.
TEST_F(HostileRuns, IntrinsicsFromAnEndlessDeviceAreRefused)
{
  writeFrame("in.pcd", 0);
  const auto start = std::chrono::steady_clock::now();
  const test::CommandResult r = test::runDenoise(path("in.pcd") + " " + path("out.pcd") + " -q --intrinsics /dev/zero");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10.0);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("'/dev/zero': not an intrinsics file: longer than 1024 kB"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("out.pcd")));
}

// OMP_NUM_THREADS cannot override --threads: 100000 no longer crashes a run with --threads 2 (nor
// one without, which uses the processors), and with 64 a run with --threads 1 starts no thread of
// OpenMP (main, reader and writer threads only).
TEST_F(HostileRuns, OpenMpEnvironmentDoesNotOverrideThreads)
{
  writeSequence(3);
  const std::string tool = std::string(RANGE_NLM_TOOLS_DIR) + "/range_nlm_denoise ";
  const std::string args = "--input-dir " + path("in") + " -q --temporal-radius 1 --output-dir ";
  ASSERT_EQ(test::runDenoise(args + path("plain") + " --threads 2").status, 0);
  test::CommandResult r = test::runCommand("OMP_NUM_THREADS=100000 " + tool + args + path("huge") + " --threads 2");
  EXPECT_EQ(r.status, 0) << r.output;
  for (int k = 0; k < 3; ++k) {
    const std::string name = "frame_000" + std::to_string(k) + ".pcd";
    EXPECT_EQ(test::readBytes(path("huge/" + name)), test::readBytes(path("plain/" + name))) << name;
  }
  r = test::runCommand("OMP_NUM_THREADS=100000 " + tool + args + path("default"));
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("warning: OMP_NUM_THREADS asks for 100000 threads, more than the 1024"), std::string::npos)
      << r.output;

  // The most threads seen while a longer run goes on.
  fs::remove_all(dir_ / "in");
  fs::create_directories(dir_ / "in");
  for (int k = 0; k < 6; ++k)
    writeFrame("in/frame_000" + std::to_string(k) + ".pcd", k, 128, 96);
  ::setenv("OMP_NUM_THREADS", "64", 1);
  const int pid = test::startProcess({tool.substr(0, tool.size() - 1), "--input-dir", path("in"), "--output-dir",
                                      path("one"), "-q", "--temporal-radius", "1", "--threads", "1"},
                                     path("log.txt"));
  ::unsetenv("OMP_NUM_THREADS");
  std::size_t most = 0;
  int status = 0;
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    std::error_code ec;
    std::size_t threads = 0;
    for (auto it = fs::directory_iterator("/proc/" + std::to_string(pid) + "/task", ec);
         !ec && it != fs::directory_iterator(); it.increment(ec))
      ++threads;
    most = std::max(most, threads);
    ::usleep(1000);
  }
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << test::readBytes(path("log.txt"));
  EXPECT_GE(most, 1u);
  EXPECT_LE(most, 3u);
}

// Intrinsics that would give garbage are refused, by option or by file and line: a focal length
// of 1e308 (every x would be -0), a tiny one or a tiny depth scale (infinite coordinates), a
// depth_format that divides by 0, a key given twice.
TEST_F(HostileRuns, IntrinsicsThatGiveGarbageAreRefused)
{
  writeFrame("in.pcd", 0);
  const std::string run = path("in.pcd") + " " + path("out.pcd") + " -q ";
  const std::pair<std::string, std::string> options[] = {
      {"--fx 1e308", "fx must be a positive number of pixels from 1 to 1000000, got 1e+308"},
      {"--fy 1e-300", "fy must be a positive number of pixels from 1 to 1000000, got 1e-300"},
      {"--cx -1e300", "cx must be finite, a number of pixels from -1000000 to 1000000, got -1e+300"},
      {"--depth-scale 1e-300", "depth_scale must be a positive number of values per metre from 0.001 to 1000000000"}};
  for (const auto& [option, message] : options) {
    const test::CommandResult r = test::runDenoise(run + option);
    EXPECT_EQ(r.status, 2) << option << ": " << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << r.output;
  }
  const std::pair<std::string, std::string> files[] = {
      {"fx 500\ndepth_format uint16, value / 0\n", "line 2: depth_format 'uint16, value / 0' divides by 0"},
      {"fx 500\nfy 500\nfx 600\n", "line 3: 'fx' is given twice (first on line 1)"},
      {"depth_format value / 1000\ndepth_format millimetres\n", "line 2: 'depth_format' is given twice"}};
  for (const auto& [text, message] : files) {
    writeText(path("intrinsics.txt"), text);
    const test::CommandResult r = test::runDenoise(run + "--intrinsics " + path("intrinsics.txt"));
    EXPECT_EQ(r.status, 1) << text << ": " << r.output;
    EXPECT_NE(r.output.find("'" + path("intrinsics.txt") + "' " + message), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(path("out.pcd")));
}

// Control characters in a file name are printed as escapes: an error stays one line and cannot
// drive the terminal; the per-frame lines too.
TEST_F(HostileRuns, ControlCharactersInNamesAreEscaped)
{
  writeFrame("in/good\tframe.pcd", 0);
  writeText(path("in/ok\x1b[2J\nframe.pcd"), "not a PCD file");
  test::CommandResult r = test::runDenoise("--input-dir " + path("in") + " --output-dir " + path("out"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output.find('\x1b'), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find('\t'), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("good\\tframe.pcd: "), std::string::npos) << r.output;
  const std::size_t error = r.output.find("range_nlm_denoise: error: '" + path("in/ok\\x1b[2J\\nframe.pcd") + "'");
  ASSERT_NE(error, std::string::npos) << r.output;
  EXPECT_EQ(r.output.find('\n', error), r.output.size() - 1) << r.output; // one line, the last
}

// The last round of small holes: an absurd iteration count, a dilation whose phases cannot hold
// the windows (named as such), an empty output path (refused before any filtering), a --pass key
// given twice, and range_nlm_render writing into a directory a directory run holds.
TEST_F(HostileRuns, ParameterAndPathHolesAreClosed)
{
  writeFrame("in.pcd", 0);
  const std::string run = path("in.pcd") + " " + path("out.pcd") + " -q ";
  test::CommandResult r = test::runDenoise(run + "--iterations 1000000000");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("iterations = 1000000000 is invalid: must be 1 ... 100"), std::string::npos) << r.output;
  r = test::runDenoise(run + "--dilation 1000000");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("dilation = 1000000 is invalid: must be 0 (automatic) ... 64"), std::string::npos)
      << r.output;
  r = test::runDenoise(run + "--dilation 64");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("dilation = 64 splits the cloud (32 x 24) into phases of 0 x 0 pixels"), std::string::npos)
      << r.output;
  r = test::runDenoise(path("in.pcd") + " '' -q");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("OUTPUT is an empty path"), std::string::npos) << r.output;
  r = test::runDenoise(run + "--pass search=9,patch=3,search=11");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("'search' is given twice"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("out.pcd")));

  // A directory run holds its output directory alone (run_lock.h); render waits its turn too.
  fs::create_directories(dir_ / "busy");
  const int fd = ::open(path("busy").c_str(), O_RDONLY | O_DIRECTORY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  r = test::runTool("range_nlm_render", path("in.pcd") + " " + path("busy/out.png") + " -q");
  ::close(fd);
  EXPECT_EQ(r.status, 4) << r.output; // the exit status of a lock conflict
  EXPECT_NE(r.output.find("output directory '" + path("busy") + "' is in use"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("busy/out.png")));
  EXPECT_EQ(test::runTool("range_nlm_render", path("in.pcd") + " " + path("busy/out.png") + " -q").status, 0);
}
