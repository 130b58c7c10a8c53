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
// A finding becomes a regression test: run the target on it with RANGE_NLM_FUZZ_RECIPE=FILE.pcd
// set, and it writes the decoded cloud as an ascii PCD whose "# range_nlm recipe" comment line
// holds the parameters; tests/test_bad_input.cpp filters every tests/data/fuzz-*.pcd that way and
// runs range_nlm_denoise on every tests/data/fuzz-* file.
#include "fuzz_contract.h"
#include <range_nlm/io/pcd_file.h>

#include <range_nlm/nonlocal_means_filter.h>

#include <fuzzer/FuzzedDataProvider.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

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
    const range_nlm::io::LoadedCloud loaded = range_nlm::io::loadCloud(path, organized);
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

/// Writes a decoded recipe as an ascii PCD with its parameters in a comment line.
void
writeRecipe(const std::string& path, const pcl::PointCloud<pcl::PointXYZ>& cloud,
            const range_nlm::FilterParameters& p)
{
  pcl::PCDWriter().writeASCII(path, cloud, 9);
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  std::ostringstream line;
  line.precision(9);
  line << "# range_nlm recipe search_window=" << p.search_window << " patch_size=" << p.patch_size
       << " normal_window=" << p.normal_window << " normal_presmooth_window=" << p.normal_presmooth_window
       << " iterations=" << p.iterations << " threads=" << p.threads
       << " evaluation=" << (p.evaluation == range_nlm::Evaluation::fast ? "fast" : "direct")
       << " displacement=" << (p.displacement == range_nlm::Displacement::normal ? "normal" : "line_of_sight")
       << " seed=" << p.seed << " distance_bandwidth=" << p.distance_bandwidth
       << " similarity_bandwidth=" << p.similarity_bandwidth << "\n";
  std::ofstream(path, std::ios::trunc) << line.str() << text;
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
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      // A noisy slanted surface seen by a 100-pixel camera, unless the input says otherwise.
      const float z = 1.0f + 0.01f * u + 0.3f * (in.ConsumeIntegral<std::uint8_t>() / 255.0f);
      pcl::PointXYZ& q = (*cloud)[std::size_t(v) * w + u];
      q.x = pointValue(in, (u - 0.5f * w) * z / 100.0f);
      q.y = pointValue(in, (v - 0.5f * h) * z / 100.0f);
      q.z = pointValue(in, z);
      has_inf = has_inf || std::isinf(q.x) || std::isinf(q.y) || std::isinf(q.z);
      has_valid = has_valid || (std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z));
    }
  cloud->is_dense = false;

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
    if (!expect_error && !nothing_to_filter)
      bug(std::string("unexpected std::invalid_argument: ") + e.what());
    return;
  }
  if (expect_error)
    bug("invalid parameters or an infinite coordinate were accepted");
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
  return 0;
}
