// range_nlm_denoise on broken, hostile and unusual input: every bad file gives one line that names
// the file and the problem, exit status 1 and no output; every file PCL's writer makes still loads.
#include "test_support.h"
#include "fuzz/fuzz_contract.h"

#include <range_nlm/nonlocal_means_filter.h>

#include <pcl/io/pcd_io.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;
using namespace range_nlm;

namespace
{
using Result = test::CommandResult;


std::string
readBytes(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

void
writeBytes(const std::string& path, const std::string& bytes)
{
  std::ofstream(path, std::ios::binary) << bytes;
}

/// A PCD header for x y z (or `fields`), WIDTH w, HEIGHT h.
std::string
header(long long w, long long h, const std::string& data, const std::string& fields = "x y z", const std::string& size = "4 4 4",
       const std::string& type = "F F F", const std::string& count = "1 1 1", long long points = -1)
{
  std::ostringstream s;
  s << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " << fields << "\nSIZE " << size
    << "\nTYPE " << type << "\nCOUNT " << count << "\nWIDTH " << w << "\nHEIGHT " << h
    << "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << (points < 0 ? w * h : points) << "\nDATA "
    << data << "\n";
  return s.str();
}

constexpr int kWidth = 16, kHeight = 12;

/// A slanted plane with a little noise, kWidth x kHeight.
pcl::PointCloud<pcl::PointXYZ>
plane()
{
  return test::makeCloud(kWidth, kHeight, test::plane({0.1, 0.0, 1.0}, 1.0), 0.002, 7);
}

std::string
binaryBody(const pcl::PointCloud<pcl::PointXYZ>& cloud)
{
  std::string body;
  for (const auto& p : cloud) {
    const float v[3] = {p.x, p.y, p.z};
    body.append(reinterpret_cast<const char*>(v), sizeof v);
  }
  return body;
}

std::string
asciiBody(const pcl::PointCloud<pcl::PointXYZ>& cloud)
{
  std::ostringstream s;
  s.precision(9);
  for (const auto& p : cloud)
    s << p.x << " " << p.y << " " << p.z << "\n";
  return s.str();
}

class BadInput : public ::testing::Test
{
protected:
  void SetUp() override
  {
    dir_ = fs::temp_directory_path() / ("range_nlm_bad_input_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  /// Runs the tool on `name` (single-frame mode) and checks the error contract: status 1, one
  /// line naming the file and containing `problem`, no output file and no temporary file.
  void expectRejected(const std::string& name, const std::string& problem)
  {
    SCOPED_TRACE(name);
    const std::string out = path("out_" + name);
    const Result r = test::runDenoise(path(name) + " " + out);
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find("'" + path(name) + "'"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(problem), std::string::npos) << "expected '" << problem << "' in: " << r.output;
    EXPECT_FALSE(fs::exists(out));
    for (const auto& entry : fs::directory_iterator(dir_))
      EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  }
  fs::path dir_;
};
} // namespace

TEST_F(BadInput, MissingAndEmptyFiles)
{
  expectRejected("missing.pcd", "file does not exist");
  writeBytes(path("empty.pcd"), "");
  expectRejected("empty.pcd", "file is empty");
  fs::create_directories(path("dir.pcd"));
  expectRejected("dir.pcd", "not a regular file");
}

TEST_F(BadInput, TruncatedOrMalformedHeader)
{
  const std::string good = header(kWidth, kHeight, "binary") + binaryBody(plane());
  writeBytes(path("cut_in_line.pcd"), good.substr(0, good.find("HEIGHT") + 3));
  expectRejected("cut_in_line.pcd", "truncated PCD header (it ends inside the line 'HEI')");
  writeBytes(path("no_data_line.pcd"), good.substr(0, good.find("POINTS")));
  expectRejected("no_data_line.pcd", "truncated PCD header (no DATA line)");
  writeBytes(path("not_pcd.pcd"), std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16));
  expectRejected("not_pcd.pcd", "malformed PCD header: unexpected line '?PNG?'");

  auto variant = [&](const std::string& name, const std::string& from, const std::string& to) {
    std::string text = good;
    const std::size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    writeBytes(path(name), text);
  };
  variant("width_text.pcd", "WIDTH 16", "WIDTH sixteen");
  expectRejected("width_text.pcd", "WIDTH value 'sixteen' is not a non-negative integer");
  variant("width_negative.pcd", "WIDTH 16", "WIDTH -16");
  expectRejected("width_negative.pcd", "WIDTH value '-16' is not a non-negative integer");
  variant("size_count.pcd", "SIZE 4 4 4", "SIZE 4 4");
  expectRejected("size_count.pcd", "SIZE has 2 values for 3 fields");
  variant("size_odd.pcd", "SIZE 4 4 4", "SIZE 4 3 4");
  expectRejected("size_odd.pcd", "field 'y' has SIZE 3");
  variant("type_unknown.pcd", "TYPE F F F", "TYPE F Q F");
  expectRejected("type_unknown.pcd", "field 'y' has TYPE 'Q'");
  variant("float_size.pcd", "SIZE 4 4 4\nTYPE F F F", "SIZE 4 2 4\nTYPE F F F");
  expectRejected("float_size.pcd", "field 'y' has TYPE F with SIZE 2");
  variant("count_zero.pcd", "COUNT 1 1 1", "COUNT 1 0 1");
  expectRejected("count_zero.pcd", "field 'y' has COUNT 0");
  variant("size_first.pcd", "FIELDS x y z\nSIZE 4 4 4", "SIZE 4 4 4\nFIELDS x y z");
  expectRejected("size_first.pcd", "SIZE line before the FIELDS line");
  variant("twice.pcd", "FIELDS x y z", "FIELDS x y x");
  expectRejected("twice.pcd", "field 'x' appears twice");
  variant("points.pcd", "POINTS 192", "POINTS 100");
  expectRejected("points.pcd", "POINTS 100 but WIDTH x HEIGHT = 192");
  variant("data_kind.pcd", "DATA binary", "DATA binary_packed");
  expectRejected("data_kind.pcd", "DATA must be ascii, binary or binary_compressed, got 'binary_packed'");
  variant("viewpoint.pcd", "VIEWPOINT 0 0 0 1 0 0 0", "VIEWPOINT 0 0 nan 1 0 0 0");
  expectRejected("viewpoint.pcd", "VIEWPOINT value 'nan' is not a finite number");
  variant("viewpoint_short.pcd", "VIEWPOINT 0 0 0 1 0 0 0", "VIEWPOINT 0 0 0");
  expectRejected("viewpoint_short.pcd", "VIEWPOINT needs 7 values");
  variant("blank_line.pcd", "VERSION 0.7\n", "VERSION 0.7\n \t\n");
  expectRejected("blank_line.pcd", "a line holds only blanks");
  variant("unknown_key.pcd", "VERSION 0.7", "VERSION 0.7\nCOLOUR red");
  expectRejected("unknown_key.pcd", "unexpected line 'COLOUR red'");
  // Control characters of the file never reach the terminal.
  variant("control.pcd", "VERSION 0.7", "VERSION 0.7\nW\x1b[2J\x07 1");
  expectRejected("control.pcd", "unexpected line 'W?[2J? 1'");
}

TEST_F(BadInput, TruncatedOrMalformedBinaryBody)
{
  const std::string body = binaryBody(plane());
  writeBytes(path("short.pcd"), header(kWidth, kHeight, "binary") + body.substr(0, body.size() - 5));
  expectRejected("short.pcd", "truncated PCD body (binary: 2299 of 2304 bytes for 192 points)");
  writeBytes(path("no_body.pcd"), header(kWidth, kHeight, "binary"));
  expectRejected("no_body.pcd", "truncated PCD body (binary: 0 of 2304 bytes");
  std::string unterminated = header(kWidth, kHeight, "binary");
  unterminated.pop_back();
  writeBytes(path("unterminated.pcd"), unterminated);
  expectRejected("unterminated.pcd", "truncated PCD header (DATA line not terminated)");
}

TEST_F(BadInput, TruncatedOrMalformedAsciiBody)
{
  const std::string body = asciiBody(plane());
  auto lines = [&](std::size_t n) {
    std::size_t at = 0;
    for (std::size_t i = 0; i < n; ++i)
      at = body.find('\n', at) + 1;
    return body.substr(0, at);
  };
  writeBytes(path("few.pcd"), header(kWidth, kHeight, "ascii") + lines(100));
  expectRejected("few.pcd", "truncated PCD body (ascii: 100 of 192 points)");
  writeBytes(path("cut.pcd"), header(kWidth, kHeight, "ascii") + lines(100) + "0.25 0.5");
  expectRejected("cut.pcd", "truncated PCD body (ascii: point 101 of 192 is cut off)");
  writeBytes(path("word.pcd"), header(kWidth, kHeight, "ascii") + lines(3) + "0.1 abc 1\n" + lines(192).substr(lines(4).size()));
  expectRejected("word.pcd", "ascii: point 4, field 'y': 'abc' is not a valid number");
  writeBytes(path("hex.pcd"), header(kWidth, kHeight, "ascii") + lines(3) + "0x1p3 0 1\n" + lines(192).substr(lines(4).size()));
  expectRejected("hex.pcd", "ascii: point 4, field 'x': '0x1p3' is not a valid number");
  writeBytes(path("two.pcd"), header(kWidth, kHeight, "ascii") + lines(5) + "0.1 0.2\n" + lines(192).substr(lines(6).size()));
  expectRejected("two.pcd", "ascii: point 6 has 2 values, expected 3");
  writeBytes(path("more.pcd"), header(kWidth, kHeight, "ascii") + body + "1 2 3\n");
  expectRejected("more.pcd", "ascii: more than the 192 points of the header");
  writeBytes(path("label.pcd"), header(kWidth, kHeight, "ascii", "x y z label", "4 4 4 1", "F F F U", "1 1 1 1") +
                                    "0 0 1 256\n");
  expectRejected("label.pcd", "field 'label': '256' is not a valid integer of its TYPE and SIZE");
}

TEST_F(BadInput, TruncatedOrMalformedCompressedBody)
{
  pcl::io::savePCDFileBinaryCompressed(path("good.pcd"), plane());
  const std::string good = readBytes(path("good.pcd"));
  const std::size_t body = good.find("DATA binary_compressed\n") + std::strlen("DATA binary_compressed\n");
  std::uint32_t compressed = 0;
  std::memcpy(&compressed, good.data() + body, 4);
  ASSERT_GT(compressed, 8u);

  writeBytes(path("no_sizes.pcd"), good.substr(0, body + 5));
  expectRejected("no_sizes.pcd", "truncated PCD body (binary_compressed: no size record)");
  writeBytes(path("short.pcd"), good.substr(0, body + 8 + compressed / 2));
  expectRejected("short.pcd", "truncated PCD body (binary_compressed: " + std::to_string(compressed / 2) + " of " +
                                  std::to_string(compressed) + " compressed bytes)");
  std::string text = good;
  const std::uint32_t wrong = 4000000000u;
  std::memcpy(&text[body + 4], &wrong, 4);
  writeBytes(path("announces.pcd"), text);
  expectRejected("announces.pcd", "binary_compressed: announces 4000000000 bytes, WIDTH x HEIGHT points need 2304");
  text = good;
  std::fill(text.begin() + body + 8, text.begin() + body + 8 + compressed, '\xff');
  writeBytes(path("garbage.pcd"), text);
  expectRejected("garbage.pcd", "corrupt binary_compressed PCD body");
  text = good;
  const std::uint32_t tiny = 4;
  std::memcpy(&text[body], &tiny, 4);
  writeBytes(path("ratio.pcd"), text);
  expectRejected("ratio.pcd", "4 compressed bytes cannot hold 2304");
}

TEST_F(BadInput, MissingOrUnusableCoordinates)
{
  const std::string body = binaryBody(plane());
  writeBytes(path("abc.pcd"), header(kWidth, kHeight, "binary", "a b c") + body);
  expectRejected("abc.pcd", "PCD has no 'x' field");
  writeBytes(path("xy.pcd"), header(kWidth, kHeight, "binary", "x y w") + body);
  expectRejected("xy.pcd", "PCD has no 'z' field");
  writeBytes(path("int_x.pcd"), header(kWidth, kHeight, "binary", "x y z", "4 4 4", "I F F") + body);
  expectRejected("int_x.pcd", "field 'x' is not a single float");
  writeBytes(path("vector_z.pcd"), header(kWidth, kHeight, "binary", "x y z", "4 4 4", "F F F", "1 1 2") + body +
                                       std::string(4 * kWidth * kHeight, '\0'));
  expectRejected("vector_z.pcd", "field 'z' is not a single float");
}

TEST_F(BadInput, UnusableSizes)
{
  const std::string body = binaryBody(plane());
  writeBytes(path("row.pcd"), header(kWidth * kHeight, 1, "binary") + body);
  expectRejected("row.pcd", "cloud is not organized (height 1)");
  writeBytes(path("list.pcd"),
             "VERSION .6\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 192\nDATA binary\n" + body);
  expectRejected("list.pcd", "cloud is not organized (height 1)");
  writeBytes(path("zero_width.pcd"), header(0, kHeight, "binary") + body);
  expectRejected("zero_width.pcd", "cloud has zero width or height (0 x 12)");
  writeBytes(path("zero_height.pcd"), header(kWidth, 0, "binary") + body);
  expectRejected("zero_height.pcd", "cloud has zero width or height (16 x 0)");
  // Sizes that would make a reader allocate gigabytes before it finds the body missing.
  writeBytes(path("huge.pcd"), header(4000000000LL, 1, "binary") + body);
  expectRejected("huge.pcd", "absurd size 4000000000 x 1 (more than 268435456 points)");
  writeBytes(path("huge2.pcd"), header(4000000000LL, 4000000000LL, "binary", "x y z", "4 4 4", "F F F", "1 1 1", 0) + body);
  expectRejected("huge2.pcd", "absurd size 4000000000 x 4000000000");
  writeBytes(path("huge_ascii.pcd"), header(20000, 20000, "ascii") + asciiBody(plane()));
  expectRejected("huge_ascii.pcd", "absurd size 20000 x 20000");
  writeBytes(path("huge_point.pcd"), header(kWidth, kHeight, "binary", "x y z big", "4 4 4 8", "F F F F", "1 1 1 200000") + body);
  expectRejected("huge_point.pcd", "a point would take more than 1048576 bytes");
  std::string digits = header(kWidth, kHeight, "binary") + body;
  digits.replace(digits.find("WIDTH 16"), 8, "WIDTH 99999999999999999999999");
  writeBytes(path("huge_digits.pcd"), digits);
  expectRejected("huge_digits.pcd", "WIDTH value '99999999999999999999999' is not a non-negative integer");
  // A frame that fits the header but not the filter's windows.
  writeBytes(path("tiny.pcd"), header(3, 2, "ascii") + "0 0 1\n1 0 1\n2 0 1\n0 1 1\n1 1 1\n2 1 1\n");
  expectRejected("tiny.pcd", "is larger than the cloud (3 x 2)");
}

TEST_F(BadInput, NonFiniteValues)
{
  auto cloud = plane();
  cloud.at(3, 2).y = std::numeric_limits<float>::infinity();
  writeBytes(path("inf.pcd"), header(kWidth, kHeight, "binary") + binaryBody(cloud));
  expectRejected("inf.pcd", "infinite coordinate at pixel (3, 2); invalid points must be NaN");
  writeBytes(path("inf_ascii.pcd"), header(kWidth, kHeight, "ascii") + asciiBody(cloud));
  expectRejected("inf_ascii.pcd", "infinite coordinate at pixel (3, 2)");
  // 1e39 does not fit a float: it reads as infinity.
  std::string ascii = asciiBody(plane());
  ascii.replace(0, ascii.find(' '), "1e39");
  writeBytes(path("overflow.pcd"), header(kWidth, kHeight, "ascii") + ascii);
  expectRejected("overflow.pcd", "infinite coordinate at pixel (0, 0)");
  // Doubles beyond the float range would become infinite in the filter.
  std::ostringstream doubles;
  for (int i = 0; i < kWidth * kHeight; ++i)
    doubles << (i == 20 ? "1e300" : "0.5") << " 0.25 1\n";
  writeBytes(path("double.pcd"), header(kWidth, kHeight, "ascii", "x y z", "8 8 8") + doubles.str());
  expectRejected("double.pcd", "coordinate outside the float range at pixel (4, 1)");
}

TEST_F(BadInput, SequenceAndDirectoryProblems)
{
  fs::create_directories(path("seq"));
  writeBytes(path("seq/a.pcd"), header(kWidth, kHeight, "binary") + binaryBody(plane()));
  writeBytes(path("seq/b.pcd"), header(kWidth, kHeight, "binary") + binaryBody(plane()));
  const auto other = test::makeCloud(20, 12, test::plane({0.0, 0.0, 1.0}, 1.0), 0.002, 8);
  writeBytes(path("seq/c.pcd"), header(20, 12, "binary") + binaryBody(other));
  Result r = test::runDenoise("--input-dir " + path("seq") + " --output-dir " + path("seq_out"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("range_nlm_denoise: error: '" + path("seq/c.pcd") +
                          "': frame is 20 x 12 but the sequence is 16 x 12\n"),
            std::string::npos)
      << r.output;
  EXPECT_TRUE(fs::exists(path("seq_out/a.pcd")));
  EXPECT_TRUE(fs::exists(path("seq_out/b.pcd")));
  EXPECT_FALSE(fs::exists(path("seq_out/c.pcd")));

  // A broken frame in the middle of a temporal run: nothing is written for it or after it, and
  // what was written is complete.
  fs::create_directories(path("broken"));
  for (const char* name : {"f0.pcd", "f1.pcd", "f3.pcd", "f4.pcd"})
    writeBytes(path("broken/") + name, header(kWidth, kHeight, "binary") + binaryBody(plane()));
  writeBytes(path("broken/f2.pcd"), header(kWidth, kHeight, "binary") + binaryBody(plane()).substr(0, 100));
  r = test::runDenoise("--input-dir " + path("broken") + " --output-dir " + path("broken_out") + " --temporal-radius 1");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("'" + path("broken/f2.pcd") + "': truncated PCD body"), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1 + 1) << r.output; // f0's report + the error
  pcl::PointCloud<pcl::PointXYZ> written;
  EXPECT_EQ(pcl::io::loadPCDFile(path("broken_out/f0.pcd"), written), 0);
  for (const char* name : {"f1.pcd", "f2.pcd", "f3.pcd", "f4.pcd"})
    EXPECT_FALSE(fs::exists(path("broken_out/") + name)) << name;

  fs::create_directories(path("empty"));
  writeBytes(path("empty/notes.txt"), "no frames here\n");
  r = test::runDenoise("--input-dir " + path("empty") + " --output-dir " + path("empty_out"));
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output, "range_nlm_denoise: error: input directory '" + path("empty") +
                          "' holds no .pcd frame and no .png depth image\n");
  EXPECT_FALSE(fs::exists(path("empty_out")));

  r = test::runDenoise("--input-dir " + path("nowhere") + " --output-dir " + path("nowhere_out"));
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output, "range_nlm_denoise: error: input directory '" + path("nowhere") + "' does not exist\n");

  // The output directory is the input directory: refused, unless --overwrite.
  fs::create_directories(path("same"));
  writeBytes(path("same/a.pcd"), header(kWidth, kHeight, "binary") + binaryBody(plane()));
  const std::string before = readBytes(path("same/a.pcd"));
  r = test::runDenoise("--input-dir " + path("same") + " --output-dir " + path("same") + "/.");
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.output, "range_nlm_denoise: error: output directory '" + path("same") +
                          "/.' is the input directory; refusing to overwrite the input (use --overwrite)\n");
  EXPECT_EQ(readBytes(path("same/a.pcd")), before);
  r = test::runDenoise("--input-dir " + path("same") + " --output-dir " + path("same") + " --overwrite --quiet");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(readBytes(path("same/a.pcd")), before);
  pcl::PointCloud<pcl::PointXYZ> overwritten;
  EXPECT_EQ(pcl::io::loadPCDFile(path("same/a.pcd"), overwritten), 0);
  EXPECT_EQ(overwritten.size(), std::size_t(kWidth * kHeight));
}

TEST_F(BadInput, EveryFilePclWritesStillLoads)
{
  // Padding, colour, normals, NaN, every DATA kind, comments, CRLF and double precision.
  auto xyz = plane();
  xyz.at(5, 5).x = xyz.at(5, 5).y = xyz.at(5, 5).z = std::numeric_limits<float>::quiet_NaN();
  xyz.is_dense = false;
  pcl::PointCloud<pcl::PointXYZRGBA> rgba(kWidth, kHeight);
  pcl::PointCloud<pcl::PointNormal> normals(kWidth, kHeight);
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    rgba[i].x = normals[i].x = xyz[i].x;
    rgba[i].y = normals[i].y = xyz[i].y;
    rgba[i].z = normals[i].z = xyz[i].z;
    rgba[i].rgba = 0xff102030u + std::uint32_t(i);
    normals[i].normal_z = -1.0f;
    normals[i].curvature = 0.01f;
  }
  rgba.is_dense = normals.is_dense = false;
  std::vector<std::string> files;
  auto add = [&](const std::string& name) {
    files.push_back(name);
    return path(name);
  };
  pcl::io::savePCDFileASCII(add("xyz_ascii.pcd"), xyz);
  pcl::io::savePCDFileBinary(add("xyz_binary.pcd"), xyz);
  pcl::io::savePCDFileBinaryCompressed(add("xyz_compressed.pcd"), xyz);
  pcl::io::savePCDFileASCII(add("rgba_ascii.pcd"), rgba);
  pcl::io::savePCDFileBinary(add("rgba_binary.pcd"), rgba);
  pcl::io::savePCDFileBinaryCompressed(add("rgba_compressed.pcd"), rgba);
  pcl::io::savePCDFileASCII(add("normal_ascii.pcd"), normals);
  pcl::io::savePCDFileBinary(add("normal_binary.pcd"), normals);
  pcl::io::savePCDFileBinaryCompressed(add("normal_compressed.pcd"), normals);
  std::string crlf = header(kWidth, kHeight, "ascii");
  for (std::size_t at = crlf.find('\n'); at != std::string::npos; at = crlf.find('\n', at + 2))
    crlf.replace(at, 1, "\r\n");
  writeBytes(add("crlf_comment.pcd"), "# written by hand\n" + crlf + asciiBody(xyz) + "\n\n");
  std::ostringstream doubles;
  doubles.precision(17);
  for (const auto& p : xyz)
    doubles << double(p.x) << "\t" << double(p.y) << "  " << double(p.z) << " 7\r\n";
  writeBytes(add("double_ascii.pcd"),
             header(kWidth, kHeight, "ascii", "x y z _", "8 8 8 4", "F F F F", "1 1 1 1") + doubles.str());

  for (const std::string& name : files) {
    SCOPED_TRACE(name);
    const Result r = test::runDenoise(path(name) + " " + path("out_" + name) + " --quiet");
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(r.output, "");
    pcl::PCLPointCloud2 out;
    ASSERT_EQ(pcl::io::loadPCDFile(path("out_" + name), out), 0);
    ASSERT_EQ(out.width, std::uint32_t(kWidth));
    ASSERT_EQ(out.height, std::uint32_t(kHeight));
    const auto z = std::find_if(out.fields.begin(), out.fields.end(), [](const auto& f) { return f.name == "z"; });
    ASSERT_NE(z, out.fields.end());
    for (std::size_t i = 0; i < xyz.size(); ++i) {
      const std::uint8_t* p = &out.data[i * out.point_step + z->offset];
      double value;
      if (z->datatype == pcl::PCLPointField::FLOAT64) {
        std::memcpy(&value, p, sizeof value);
      } else {
        float f;
        std::memcpy(&f, p, sizeof f);
        value = f;
      }
      EXPECT_EQ(std::isnan(value), std::isnan(xyz[i].z)) << i;
      EXPECT_TRUE(std::isnan(value) || std::fabs(value - xyz[i].z) < 0.05) << i;
    }
  }
}

namespace
{
using fuzz::tooSparseForNoiseEstimate;

/// Filters a recipe written by fuzz/fuzz_pcd_filter (RANGE_NLM_FUZZ_RECIPE) and checks the
/// contract the fuzzer checks: std::invalid_argument exactly for bad parameters or data, finite
/// points stay finite, invalid points come out NaN in x, y and z.
void
expectFilterContract(const fs::path& recipe)
{
  std::ifstream in(recipe);
  std::string first;
  std::getline(in, first);
  const std::string tag = "# range_nlm recipe ";
  ASSERT_EQ(first.rfind(tag, 0), 0u) << "no recipe line";
  FilterParameters p = FilterParameters::recommended();
  std::istringstream words(first.substr(tag.size()));
  for (std::string item; words >> item;) {
    const std::string key = item.substr(0, item.find('=')), value = item.substr(item.find('=') + 1);
    if (key == "search_window")
      p.search_window = std::stoi(value);
    else if (key == "patch_size")
      p.patch_size = std::stoi(value);
    else if (key == "normal_window")
      p.normal_window = std::stoi(value);
    else if (key == "normal_presmooth_window")
      p.normal_presmooth_window = std::stoi(value);
    else if (key == "iterations")
      p.iterations = std::stoi(value);
    else if (key == "threads")
      p.threads = std::stoi(value);
    else if (key == "evaluation")
      p.evaluation = value == "fast" ? Evaluation::fast : Evaluation::direct;
    else if (key == "displacement")
      p.displacement = value == "normal" ? Displacement::normal : Displacement::line_of_sight;
    else if (key == "seed")
      p.seed = std::stoull(value);
    else if (key == "distance_bandwidth")
      p.distance_bandwidth = std::strtof(value.c_str(), nullptr);
    else if (key == "similarity_bandwidth")
      p.similarity_bandwidth = std::strtof(value.c_str(), nullptr);
    else
      FAIL() << "unknown recipe key " << key;
  }
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  ASSERT_EQ(pcl::io::loadPCDFile(recipe.string(), *cloud), 0);
  bool has_inf = false, has_valid = false;
  for (const auto& q : *cloud) {
    has_inf = has_inf || std::isinf(q.x) || std::isinf(q.y) || std::isinf(q.z);
    has_valid = has_valid || (std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z));
  }
  bool valid_parameters = true;
  try {
    p.validateFor(int(cloud->width), int(cloud->height));
  } catch (const std::invalid_argument&) {
    valid_parameters = false;
  }
  const bool expect_error = !valid_parameters || has_inf || !has_valid || cloud->height < 2;
  NonLocalMeansFilter<pcl::PointXYZ> filter;
  filter.setParameters(p);
  filter.setInputCloud(cloud);
  pcl::PointCloud<pcl::PointXYZ> out;
  try {
    filter.filter(out);
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    const bool nothing_to_filter =
        (what.find("no valid point") != std::string::npos || what.find("cannot estimate the noise") != std::string::npos) &&
        tooSparseForNoiseEstimate(*cloud);
    EXPECT_TRUE(expect_error || nothing_to_filter) << what;
    return;
  }
  ASSERT_FALSE(expect_error);
  ASSERT_EQ(out.size(), cloud->size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto &a = (*cloud)[i], &b = out[i];
    if (std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z))
      EXPECT_TRUE(std::isfinite(b.x) && std::isfinite(b.y) && std::isfinite(b.z)) << "point " << i;
    else
      EXPECT_TRUE(std::isnan(b.x) && std::isnan(b.y) && std::isnan(b.z)) << "point " << i;
  }
}
} // namespace

TEST_F(BadInput, FuzzFindingsStayFixed)
{
  // What fuzz/fuzz_pcd_filter once failed on: the raw inputs (fuzz-*.bin), which the tool must
  // reject like any bad file, and the clouds they decode to (fuzz-*.pcd), which must filter
  // within the contract.
  //  - fuzz-exp-of-nan: huge coordinates and a huge distance bandwidth made the fast exponential's
  //    argument NaN, and its exponent then overflowed a left shift of an int (undefined
  //    behaviour; the AddressSanitizer + UndefinedBehaviorSanitizer build aborts on it).
  //  - fuzz-window-of-one: a 1 x 1 search window (valid: it moves nothing) made the noise estimate
  //    of a perfectly valid cloud throw, as no 1 x 1 window holds the 4 points of a plane fit.
  const fs::path data = fs::path(RANGE_NLM_SOURCE_DIR) / "tests" / "data";
  int inputs = 0, recipes = 0;
  for (const auto& entry : fs::directory_iterator(data)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("fuzz-", 0) != 0)
      continue;
    SCOPED_TRACE(name);
    if (entry.path().extension() == ".pcd") {
      ++recipes;
      expectFilterContract(entry.path());
    } else {
      ++inputs;
      fs::copy_file(entry.path(), path(name));
      expectRejected(name, ""); // one line naming the file, status 1, no output
    }
  }
  EXPECT_GE(inputs, 1);
  EXPECT_GE(recipes, 1);
}
