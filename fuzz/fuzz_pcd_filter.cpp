// libFuzzer target over the PCD-reading and filtering path.
//
// Each input is used twice:
//  1. as a file: written to a temporary path and read with io::loadCloud + io::xyzFromBlob.
//     InputError (with a one-line message naming the file) is the documented failure; any other
//     exception, a crash or a sanitizer report is a bug. A cloud that loads must be consistent.
//  2. as a recipe: decoded into a small organized cloud (w, h in 1 .. 24; NaN, Inf, huge and
//     ordinary points) and random parameters (odd, even and zero windows, 1 or 2 iterations, fast
//     or direct evaluation), filtered with NonLocalMeansFilter<pcl::PointXYZ>. std::invalid_argument
//     is the documented failure, and exactly for invalid parameters, an infinite coordinate, a
//     single row (not organized) or a cloud with nothing to filter (no valid point, or too few
//     valid points with valid neighbours to estimate the noise). Otherwise every finite input point must come out finite, every
//     invalid input point (any coordinate NaN) must come out NaN in x, y and z.
//
//  3. as a 16-bit depth PNG: written to a temporary .png path and read with io::loadFrame. Again
//     InputError naming the file is the only documented failure; a frame that loads is organized,
//     its points finite or NaN in all three coordinates.
//  4. as a sequence: decoded into a few small frames whose sizes and validity change from frame to
//     frame (all-NaN frames, an infinity, another size), pushed through a TemporalStream with a
//     random radius and mode. A refused push (std::invalid_argument) must be exactly a frame of
//     another size or with an infinity, and leave the stream going; every accepted frame comes
//     out once, in order, with the pixel rule above; a frame with nothing to filter comes out
//     unchanged with its reason.
//
// A finding becomes a regression test: run the target on it with RANGE_NLM_FUZZ_RECIPE=FILE.pcd
// set, and it writes the decoded cloud as an ascii PCD whose "# range_nlm recipe" comment line
// holds the parameters; tests/test_bad_input.cpp filters every tests/data/fuzz-*.pcd that way and
// runs range_nlm_denoise on every tests/data/fuzz-* file.
#include "fuzz_contract.h"
#include "io/output_file.h"
#include <range_nlm/core/pipeline.h>
#include <range_nlm/io/pcd_file.h>

#include <range_nlm/nonlocal_means_filter.h>
#include <range_nlm/temporal_stream.h>

#include <fuzzer/FuzzedDataProvider.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unistd.h>

namespace
{
using range_nlm::fuzz::tooSparseForNoiseEstimate;
using range_nlm::io::InputError;

[[noreturn]] void
bug(const std::string& what)
{
  std::fprintf(stderr, "fuzz_pcd_filter: %s\n", what.c_str());
  std::abort();
}

const std::string&
temporaryPath()
{
  static const std::string path =
      (std::filesystem::temp_directory_path() / ("fuzz_pcd_filter_" + std::to_string(::getpid()) + ".pcd")).string();
  return path;
}

/// The reader's memory check as the tool uses it, with a limit well inside the fuzzer's RSS limit
/// (a header may announce 2^28 points in front of a tiny body).
const range_nlm::io::MemoryBudget&
budget()
{
  static const range_nlm::io::MemoryBudget b = [] {
    range_nlm::io::MemoryBudget m;
    m.limit_bytes = std::uint64_t(512) << 20;
    m.setting = "--memory-limit";
    return m;
  }();
  return b;
}

void
readAsFile(const std::uint8_t* data, std::size_t size)
{
  const std::string& path = temporaryPath();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  const bool organized = size % 2 == 0;
  try {
    const range_nlm::io::LoadedCloud loaded = range_nlm::io::loadCloud(path, organized, budget());
    const pcl::PCLPointCloud2& blob = loaded.blob;
    if (blob.width == 0 || blob.height == 0 || (organized && blob.height < 2) ||
        blob.data.size() != std::size_t(blob.width) * blob.height * blob.point_step)
      bug("loadCloud accepted an inconsistent cloud");
    const pcl::PointCloud<pcl::PointXYZ> cloud = range_nlm::io::xyzFromBlob(loaded, path);
    if (cloud.width != blob.width || cloud.height != blob.height)
      bug("xyzFromBlob changed the size");
    for (const pcl::PointXYZ& p : cloud) {
      const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
      const bool nan = std::isnan(p.x) && std::isnan(p.y) && std::isnan(p.z);
      if (!finite && !nan)
        bug("xyzFromBlob returned a point that is neither finite nor all NaN");
    }
  } catch (const InputError& e) {
    const std::string message = e.what();
    if (message.empty() || message.find('\n') != std::string::npos || message.find(path) == std::string::npos)
      bug("InputError message is not one line naming the file: " + message);
  }
}

float
pointValue(FuzzedDataProvider& in, float ordinary)
{
  switch (in.ConsumeIntegralInRange<int>(0, 9)) {
  case 0:
    return std::numeric_limits<float>::quiet_NaN();
  case 1:
    return in.ConsumeBool() ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity();
  case 2:
    return in.ConsumeFloatingPoint<float>(); // anything, huge values included
  case 3:
    return ordinary * (in.ConsumeBool() ? 1e6f : 1e-6f);
  default:
    return ordinary;
  }
}

/// Writes a decoded recipe as an ascii PCD with its parameters in a comment line (PCL's ascii
/// writer into a scratch file, then the whole file through OutputFile, as every output).
void
writeRecipe(const std::string& path, const pcl::PointCloud<pcl::PointXYZ>& cloud,
            const range_nlm::FilterParameters& p)
{
  const std::string scratch = temporaryPath() + ".recipe";
  pcl::PCDWriter().writeASCII(scratch, cloud, 9);
  std::ifstream in(scratch);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  in.close();
  std::remove(scratch.c_str());
  std::ostringstream line;
  line.precision(9);
  line << "# range_nlm recipe search_window=" << p.search_window << " patch_size=" << p.patch_size
       << " normal_window=" << p.normal_window << " normal_presmooth_window=" << p.normal_presmooth_window
       << " iterations=" << p.iterations << " threads=" << p.threads
       << " evaluation=" << (p.evaluation == range_nlm::Evaluation::fast ? "fast" : "direct")
       << " displacement=" << (p.displacement == range_nlm::Displacement::normal ? "normal" : "line_of_sight")
       << " seed=" << p.seed << " distance_bandwidth=" << p.distance_bandwidth
       << " similarity_bandwidth=" << p.similarity_bandwidth << "\n";
  range_nlm::io::detail::writeWholeFile(path, line.str() + text);
}

void
filterAsRecipe(const std::uint8_t* data, std::size_t size)
{
  FuzzedDataProvider in(data, size);
  const int w = in.ConsumeIntegralInRange<int>(1, 24);
  const int h = in.ConsumeIntegralInRange<int>(1, 24);
  range_nlm::FilterParameters p = range_nlm::FilterParameters::recommended();
  p.search_window = in.ConsumeIntegralInRange<int>(-1, 11);
  p.patch_size = in.ConsumeIntegralInRange<int>(-1, 9);
  p.normal_window = in.ConsumeIntegralInRange<int>(0, 7);
  p.normal_presmooth_window = in.ConsumeIntegralInRange<int>(-1, 7);
  p.iterations = in.ConsumeIntegralInRange<int>(1, 2);
  p.threads = in.ConsumeIntegralInRange<int>(0, 2);
  p.evaluation = in.ConsumeBool() ? range_nlm::Evaluation::fast : range_nlm::Evaluation::direct;
  p.displacement = in.ConsumeBool() ? range_nlm::Displacement::normal : range_nlm::Displacement::line_of_sight;
  p.seed = in.ConsumeIntegral<std::uint8_t>();
  if (in.ConsumeBool())
    p.distance_bandwidth = in.ConsumeFloatingPoint<float>();
  if (in.ConsumeBool())
    p.similarity_bandwidth = in.ConsumeFloatingPoint<float>();

  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>(w, h));
  bool has_inf = false, has_valid = false;
  float largest = 0.0f; // over the points whose x, y and z are all finite
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      // A noisy slanted surface seen by a 100-pixel camera, unless the input says otherwise.
      const float z = 1.0f + 0.01f * u + 0.3f * (in.ConsumeIntegral<std::uint8_t>() / 255.0f);
      pcl::PointXYZ& q = (*cloud)[std::size_t(v) * w + u];
      q.x = pointValue(in, (u - 0.5f * w) * z / 100.0f);
      q.y = pointValue(in, (v - 0.5f * h) * z / 100.0f);
      q.z = pointValue(in, z);
      has_inf = has_inf || std::isinf(q.x) || std::isinf(q.y) || std::isinf(q.z);
      const bool valid = std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
      has_valid = has_valid || valid;
      if (valid)
        largest = std::max({largest, std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)});
    }
  cloud->is_dense = false;
  // The filter refuses a cloud whose float arithmetic would overflow or underflow (checkCoordinateScale).
  const bool out_of_scale =
      has_valid && (largest < range_nlm::kSmallestLargestCoordinate || largest > range_nlm::kLargestCoordinate);

  bool valid_parameters = true;
  try {
    p.validateFor(w, h);
  } catch (const std::invalid_argument&) {
    valid_parameters = false;
  }
  // A single row is not an organized cloud for PCL (height 1 means unorganized).
  const bool expect_error = !valid_parameters || has_inf || !has_valid || h < 2;
  if (const char* dump = std::getenv("RANGE_NLM_FUZZ_RECIPE"))
    writeRecipe(dump, *cloud, p);

  range_nlm::NonLocalMeansFilter<pcl::PointXYZ> filter;
  filter.setParameters(p);
  filter.setInputCloud(cloud);
  pcl::PointCloud<pcl::PointXYZ> out;
  try {
    filter.filter(out);
  } catch (const std::invalid_argument& e) {
    // A cloud whose valid points have (almost) no valid neighbours has nothing to filter.
    const bool nothing_to_filter = (std::strstr(e.what(), "no valid point") != nullptr ||
                                    std::strstr(e.what(), "cannot estimate the noise") != nullptr) &&
                                   tooSparseForNoiseEstimate(*cloud);
    const bool refused_for_scale = out_of_scale && std::strstr(e.what(), "coordinates reach") != nullptr;
    if (!expect_error && !nothing_to_filter && !refused_for_scale)
      bug(std::string("unexpected std::invalid_argument: ") + e.what());
    return;
  }
  if (expect_error)
    bug("invalid parameters or an infinite coordinate were accepted");
  if (out_of_scale)
    bug("coordinates reaching " + std::to_string(largest) + " were filtered instead of refused");
  if (out.width != cloud->width || out.height != cloud->height)
    bug("the output has another size");
  for (std::size_t i = 0; i < out.size(); ++i) {
    const pcl::PointXYZ &a = (*cloud)[i], &b = out[i];
    const bool valid_in = std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
    if (valid_in && !(std::isfinite(b.x) && std::isfinite(b.y) && std::isfinite(b.z)))
      bug("finite point " + std::to_string(i) + " (" + std::to_string(a.x) + ", " + std::to_string(a.y) + ", " +
          std::to_string(a.z) + ") came out non-finite (" + std::to_string(b.x) + ", " + std::to_string(b.y) +
          ", " + std::to_string(b.z) + ")");
    if (!valid_in && !(std::isnan(b.x) && std::isnan(b.y) && std::isnan(b.z)))
      bug("invalid point " + std::to_string(i) + " did not come out NaN in x, y and z");
  }
}
void
readAsDepthImage(const std::uint8_t* data, std::size_t size)
{
  static const std::string path =
      (std::filesystem::temp_directory_path() / ("fuzz_depth_" + std::to_string(::getpid()) + ".png")).string();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    range_nlm::DepthIntrinsics intrinsics;
    intrinsics.depth_scale = 1000.0;
    const range_nlm::io::LoadedCloud loaded = range_nlm::io::loadFrame(path, intrinsics, budget());
    const pcl::PointCloud<pcl::PointXYZ> cloud = range_nlm::io::xyzFromBlob(loaded, path);
    if (cloud.height < 2 || cloud.size() != std::size_t(cloud.width) * cloud.height)
      bug("loadFrame accepted a depth image that is not an organized frame");
    for (const pcl::PointXYZ& p : cloud) {
      const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
      const bool nan = std::isnan(p.x) && std::isnan(p.y) && std::isnan(p.z);
      if (!finite && !nan)
        bug("a depth image gave a point that is neither finite nor all NaN");
    }
  } catch (const InputError& e) {
    const std::string message = e.what();
    if (message.empty() || message.find('\n') != std::string::npos || message.find(path) == std::string::npos)
      bug("InputError message of a depth image is not one line naming the file: " + message);
  }
}

void
streamAsSequence(const std::uint8_t* data, std::size_t size)
{
  using Cloud = pcl::PointCloud<pcl::PointXYZ>;
  FuzzedDataProvider in(data, size);
  const int radius = in.ConsumeIntegralInRange<int>(0, 2);
  const bool causal = in.ConsumeBool();
  range_nlm::FilterParameters p = range_nlm::FilterParameters::recommended();
  p.search_window = 3;
  p.patch_size = 3;
  p.normal_window = 3;
  p.normal_presmooth_window = 3;
  p.iterations = 1;
  p.threads = 1;
  range_nlm::TemporalStream<pcl::PointXYZ> stream(radius, causal, p);
  const int frames = in.ConsumeIntegralInRange<int>(1, 6);
  int width = 0, height = 0, accepted = 0, emitted = 0;
  std::vector<Cloud::ConstPtr> inputs; // accepted frames, in order
  auto check = [&](const std::vector<Cloud::Ptr>& ready) {
    if (stream.lastOutputs().size() != ready.size())
      bug("lastOutputs() does not match the frames returned");
    for (std::size_t r = 0; r < ready.size(); ++r, ++emitted) {
      const Cloud& a = *inputs.at(static_cast<std::size_t>(emitted));
      const Cloud& b = *ready[r];
      if (b.width != a.width || b.height != a.height)
        bug("a streamed frame came out with another size");
      const bool passed_through = !stream.lastOutputs()[r].problem.empty();
      for (std::size_t i = 0; i < a.size(); ++i) {
        const bool valid_in = std::isfinite(a[i].x) && std::isfinite(a[i].y) && std::isfinite(a[i].z);
        const bool finite_out = std::isfinite(b[i].x) && std::isfinite(b[i].y) && std::isfinite(b[i].z);
        if (valid_in != finite_out || (!valid_in && !(std::isnan(b[i].x) && std::isnan(b[i].y) && std::isnan(b[i].z))))
          bug("a streamed frame broke the NaN-in, NaN-out rule at point " + std::to_string(i));
        if (passed_through && valid_in && (a[i].x != b[i].x || a[i].y != b[i].y || a[i].z != b[i].z))
          bug("a frame passed through was changed");
      }
    }
  };
  for (int k = 0; k < frames; ++k) {
    const int w = in.ConsumeIntegralInRange<int>(3, 12);
    const int h = in.ConsumeIntegralInRange<int>(3, 12);
    const int mode = in.ConsumeIntegralInRange<int>(0, 5); // 0 all NaN, 1 an infinity, else ordinary
    Cloud::Ptr cloud(new Cloud(w, h));
    bool has_inf = false;
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) {
        const float z = 1.0f + 0.01f * u + 0.02f * (in.ConsumeIntegral<std::uint8_t>() / 255.0f);
        pcl::PointXYZ& q = (*cloud)[std::size_t(v) * w + u];
        q = pcl::PointXYZ((u - 0.5f * w) * z / 100.0f, (v - 0.5f * h) * z / 100.0f, z);
        if (mode == 0 || in.ConsumeIntegralInRange<int>(0, 15) == 0)
          q.x = q.y = q.z = std::numeric_limits<float>::quiet_NaN();
      }
    if (mode == 1) {
      (*cloud)[0].z = std::numeric_limits<float>::infinity();
      has_inf = true;
    }
    cloud->is_dense = false;
    const bool other_size = accepted > 0 && (w != width || h != height);
    std::vector<Cloud::Ptr> ready;
    try {
      ready = stream.push(cloud);
    } catch (const range_nlm::UnfilterableFrame& e) {
      bug(std::string("TemporalStream let an UnfilterableFrame out: ") + e.what());
    } catch (const std::invalid_argument& e) {
      const std::string message = e.what();
      // The window of a few pixels may also be too small for the parameters: a documented refusal
      // of the whole stream.
      if (message.find("larger than the cloud") != std::string::npos)
        return;
      if (!other_size && !has_inf)
        bug("TemporalStream refused a frame of the sequence's size without an infinity: " + message);
      continue;
    }
    if (other_size || has_inf)
      bug("TemporalStream accepted a frame of another size or with an infinity");
    if (accepted == 0)
      width = w, height = h;
    ++accepted;
    inputs.push_back(cloud);
    check(ready);
  }
  try {
    check(stream.flush());
  } catch (const std::invalid_argument& e) {
    if (std::string(e.what()).find("larger than the cloud") == std::string::npos)
      bug(std::string("flush threw: ") + e.what());
    return;
  }
  if (emitted != accepted)
    bug("TemporalStream did not give one output per accepted frame");
}

} // namespace

extern "C" int
LLVMFuzzerInitialize(int*, char***)
{
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS); // PCL would print on every bad file
  return 0;
}

extern "C" int
LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  readAsFile(data, size);
  filterAsRecipe(data, size);
  readAsDepthImage(data, size);
  streamAsSequence(data, size);
  return 0;
}
