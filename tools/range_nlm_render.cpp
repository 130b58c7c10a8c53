// range_nlm_render: images of organized range frames (flat shading or mean-curvature colour),
// before/after comparisons on one colour scale, and curvature-coloured clouds for pcl_viewer.
#include "cli/cli.h"
#include "cli/pipeline.h"
#include "cli/run_lock.h"

#include <range_nlm/eval/render.h>

#include <filesystem>
#include <iomanip>
#include <iostream>

namespace po = boost::program_options;
using namespace range_nlm;
using namespace range_nlm::tools;

namespace
{

const char* const kUsage =
    "Usage:\n"
    "  range_nlm_render INPUT OUT.png [--mode shaded|curvature] [options]\n"
    "  range_nlm_render INPUT OUT.pcd --mode curvature [options]\n"
    "  range_nlm_render --before A --after B OUT.png [--mode shaded|curvature] [options]\n"
    "Draws an organized frame as an image, pixel (u, v) = point (u, v): 'shaded' is flat shading\n"
    "with grey = 255 (ambient + (1 - ambient) |n . v|), 'curvature' maps the mean curvature H\n"
    "(1 / cloud unit, > 0 where the surface bulges toward the sensor) to a blue-grey-red scale\n"
    "[-limit, +limit]. With --before/--after both frames are drawn side by side on the same scale.\n"
    "An OUT.pcd is the input as PointXYZRGB coloured by curvature. Inputs are organized PCD files\n"
    "or 16-bit depth PNGs (read with the intrinsics options). Pixels without a point are black,\n"
    "points without an estimate grey.";

struct Frame
{
  std::string path;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  Viewpoint viewpoint = {0.0f, 0.0f, 0.0f};
};

/// Bytes rendering a width x height frame of `point_step`-byte points needs: point_step + 68 a
/// pixel, twice that for a comparison (two frames). Peak resident memory (/usr/bin/time -v) grows
/// from 1280 x 960 to 2560 x 1920 frames of 12-byte points by 78 bytes a pixel for a
/// curvature-coloured PCD (the largest single-frame output), 57 for a shaded PNG and 89 for a
/// shaded comparison.
std::uint64_t
renderMemory(bool comparison, std::uint64_t width, std::uint64_t height, std::uint64_t point_step)
{
  const std::uint64_t per_pixel = (comparison ? 2 : 1) * (point_step + 68);
  const std::uint64_t pixels = width * height;
  return pixels > UINT64_MAX / per_pixel ? UINT64_MAX : pixels * per_pixel;
}

/// The frame at `path`, refused from its header if it would not fit `budget`.
Frame
loadInput(const std::string& path, const DepthIntrinsics& intrinsics, const io::MemoryBudget& budget,
          DefaultIntrinsicsWarning& warning)
{
  Frame frame;
  frame.path = path;
  try {
    const LoadedCloud loaded = loadFrame(path, intrinsics, budget);
    warning.frameRead(path);
    frame.cloud = xyzFromBlob(loaded, path);
    frame.viewpoint = {loaded.origin[0], loaded.origin[1], loaded.origin[2]};
  } catch (const std::bad_alloc&) {
    throw InputError("'" + path + "': out of memory while reading the frame (lower --memory-limit to refuse such "
                     "frames up front, or free memory)");
  }
  return frame;
}

/// Every file the run reads: `frames` and the intrinsics file.
std::vector<std::string>
inputsOf(std::vector<std::string> frames, const po::variables_map& vm)
{
  if (vm.count("intrinsics"))
    frames.push_back(vm["intrinsics"].as<std::string>());
  return frames;
}

/// The directory an output file goes into ("" for the current one), whose lock a render shares
/// with single-frame denoise runs: a directory run of range_nlm_denoise holds it alone.
std::string
parentDirectory(const std::string& path)
{
  return std::filesystem::path(path).parent_path().string();
}

std::string
extensionOf(const std::string& path)
{
  std::string extension;
  const std::size_t dot = path.find_last_of('.');
  const std::size_t slash = path.find_last_of('/');
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash))
    extension = path.substr(dot);
  for (char& c : extension)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

/// RenderParameters from the options; messages name the option.
RenderParameters
renderParametersFrom(const po::variables_map& vm)
{
  RenderParameters p;
  const std::string light = vm["light"].as<std::string>();
  if (light == "view-ray")
    p.light = Light::view_ray;
  else if (light == "axis")
    p.light = Light::optical_axis;
  else
    throw UsageError("--light must be 'view-ray' or 'axis', got '" + light + "'");
  p.normal_window = vm["normal-window"].as<int>();
  p.curvature_window = vm["curvature-window"].as<int>();
  p.max_depth_step = vm["max-depth-step"].as<float>();
  p.curvature_limit = vm["curvature-limit"].as<float>();
  p.percentile = vm["percentile"].as<float>();
  p.gap = vm["gap"].as<int>();
  p.threads = vm["threads"].as<int>();
  try {
    p.validate();
    useThreads(p.threads);
  } catch (const std::invalid_argument& e) {
    // The parameter names of RenderParameters are the option names with '_' for '-'.
    std::string message = e.what();
    const std::size_t end = message.find(' ');
    std::string name = message.substr(0, end);
    for (char& c : name)
      if (c == '_')
        c = '-';
    throw UsageError("--" + name + message.substr(end));
  }
  return p;
}

RenderMode
modeFrom(const po::variables_map& vm)
{
  const std::string mode = vm["mode"].as<std::string>();
  if (mode == "shaded")
    return RenderMode::shaded;
  if (mode == "curvature")
    return RenderMode::curvature;
  throw UsageError("--mode must be 'shaded' or 'curvature', got '" + mode + "'");
}

int
run(int argc, char** argv)
{
  const RenderParameters d;
  po::options_description options("Options");
  // clang-format off
  options.add_options()
    ("help,h", "print this help")
    ("paths", po::value<std::vector<std::string>>(), "INPUT OUT, or OUT alone with --before/--after (positional)")
    ("before", po::value<std::string>(), "'before' frame of a side-by-side comparison (left half) [default: none]")
    ("after", po::value<std::string>(), "'after' frame of a side-by-side comparison (right half) [default: none]")
    ("mode", po::value<std::string>()->default_value("shaded"), "shaded or curvature")
    ("light", po::value<std::string>()->default_value("view-ray"),
     "shading light: view-ray (headlight at the sensor) or axis (along the optical axis)")
    ("normal-window", po::value<int>()->default_value(d.normal_window), "odd side of the normal-estimation neighbourhood, pixels (3 ... 31)")
    ("curvature-window", po::value<int>()->default_value(d.curvature_window), "odd side of the quadric fit of the curvature, pixels (5 ... 31)")
    ("max-depth-step", po::value<float>()->default_value(d.max_depth_step, "0.05"),
     "neighbours of the curvature fit farther than this fraction of the range per pixel step are cut off (depth edges)")
    ("curvature-limit", po::value<float>()->default_value(d.curvature_limit),
     "half-range of the curvature colour scale, 1 / cloud unit (0 = automatic from --percentile)")
    ("percentile", po::value<float>()->default_value(d.percentile), "percentile of |H| used as the automatic scale, percent")
    ("scale-from", po::value<std::string>()->default_value("before"),
     "automatic scale of a comparison from the 'before' frame or from 'both'")
    ("gap", po::value<int>()->default_value(d.gap), "white columns between the halves of a comparison")
    ("threads", po::value<int>()->default_value(d.threads), "OpenMP threads, 0 = all cores")
    ("quiet,q", "print nothing but errors");
  // clang-format on
  addDepthImageOptions(options);
  addMemoryLimitOption(options);
  po::positional_options_description positional;
  positional.add("paths", -1);
  po::variables_map vm;
  if (!parseCommandLine(argc, argv, options, positional, vm, kUsage))
    return 0;

  const RenderMode mode = modeFrom(vm);
  RenderParameters parameters = renderParametersFrom(vm);
  const DepthIntrinsics intrinsics = depthIntrinsicsFrom(vm);
  DefaultIntrinsicsWarning warning("range_nlm_render", vm);
  const std::string scale_from = vm["scale-from"].as<std::string>();
  if (scale_from != "before" && scale_from != "both")
    throw UsageError("--scale-from must be 'before' or 'both', got '" + scale_from + "'");
  const std::vector<std::string> paths =
      vm.count("paths") ? vm["paths"].as<std::vector<std::string>>() : std::vector<std::string>();
  for (const std::string& path : paths)
    if (path.empty())
      throw UsageError("an empty path was given; give a file name");
  const bool comparison = vm.count("before") || vm.count("after");
  const bool quiet = vm.count("quiet") > 0;
  const io::MemoryBudget budget = memoryBudgetFrom(
      vm, [comparison](std::uint64_t w, std::uint64_t h, std::uint64_t step) { return renderMemory(comparison, w, h, step); });

  if (comparison) {
    if (!vm.count("before") || !vm.count("after"))
      throw UsageError("a comparison needs both --before and --after");
    if (paths.size() != 1)
      throw UsageError("with --before/--after give exactly one output path, got " + std::to_string(paths.size()));
    const std::string& output = paths[0];
    if (extensionOf(output) != ".png")
      throw UsageError("output '" + output + "' of a comparison must be a .png file");
    refuseOutputsThatAreInputs(inputsOf({vm["before"].as<std::string>(), vm["after"].as<std::string>()}, vm), {output},
                               "");
    const OutputDirectoryLock lock(parentDirectory(output), false);
    const Frame before = loadInput(vm["before"].as<std::string>(), intrinsics, budget, warning);
    const Frame after = loadInput(vm["after"].as<std::string>(), intrinsics, budget, warning);
    if (before.cloud.width != after.cloud.width || before.cloud.height != after.cloud.height)
      throw InputError("'" + after.path + "' is " + std::to_string(after.cloud.width) + " x " +
                       std::to_string(after.cloud.height) + " but '" + before.path + "' is " +
                       std::to_string(before.cloud.width) + " x " + std::to_string(before.cloud.height) +
                       "; a comparison needs frames of one size");
    parameters.viewpoint = before.viewpoint;
    const BeforeAfterImage result =
        renderBeforeAfter(gridFromCloud(before.cloud), gridFromCloud(after.cloud), mode, parameters,
                          scale_from == "both" ? ScaleSource::both : ScaleSource::before);
    saveRgbPng(output, result.image);
    if (!quiet) {
      std::cout << printable(output) << ": " << result.image.width << " x " << result.image.height;
      if (mode == RenderMode::curvature)
        std::cout << ", curvature scale +-" << std::setprecision(6) << result.curvature_limit << " 1/unit"
                  << (parameters.curvature_limit > 0.0f ? " (given)"
                                                        : " (from the '" + scale_from + "' frame" +
                                                              (scale_from == "both" ? "s" : "") + ")");
      std::cout << std::endl;
    }
    return 0;
  }

  if (paths.size() != 2)
    throw UsageError("give INPUT and OUT (or --before A --after B OUT.png), got " + std::to_string(paths.size()) +
                     " path(s)");
  const std::string& output = paths[1];
  const std::string extension = extensionOf(output);
  if (extension != ".png" && extension != ".pcd")
    throw UsageError("output '" + output + "' must be a .png image or a .pcd cloud");
  if (extension == ".pcd" && mode != RenderMode::curvature)
    throw UsageError("a .pcd output is coloured by curvature; add --mode curvature");
  refuseOutputsThatAreInputs(inputsOf({paths[0]}, vm), {output}, "");
  const OutputDirectoryLock lock(parentDirectory(output), false);
  const Frame frame = loadInput(paths[0], intrinsics, budget, warning);
  parameters.viewpoint = frame.viewpoint;
  float limit = 0.0f;
  std::string size;
  if (extension == ".pcd") {
    const pcl::PointCloud<pcl::PointXYZRGB> coloured = colorizeByCurvature(frame.cloud, parameters, &limit);
    saveCloudAtomic(output, coloured);
    size = std::to_string(coloured.width) + " x " + std::to_string(coloured.height) + " PointXYZRGB";
  } else {
    const Grid grid = gridFromCloud(frame.cloud);
    RgbImage image;
    if (mode == RenderMode::shaded) {
      image = renderShaded(grid, parameters);
    } else {
      const std::vector<float> curvature = meanCurvature(grid, parameters);
      limit = parameters.curvature_limit > 0.0f ? parameters.curvature_limit
                                                : curvatureLimit(curvature, parameters.percentile);
      image = curvatureToImage(grid, curvature, limit, parameters);
    }
    saveRgbPng(output, image);
    size = std::to_string(image.width) + " x " + std::to_string(image.height);
  }
  if (!quiet) {
    std::cout << printable(output) << ": " << size;
    if (mode == RenderMode::curvature)
      std::cout << ", curvature scale +-" << std::setprecision(6) << limit << " 1/unit"
                << (parameters.curvature_limit > 0.0f ? " (given)" : " (automatic)");
    std::cout << std::endl;
  }
  return 0;
}

} // namespace

int
main(int argc, char** argv)
{
  return runTool("range_nlm_render", [&] { return run(argc, argv); });
}
