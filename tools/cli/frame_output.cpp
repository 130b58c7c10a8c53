#include "cli/frame_output.h"

#include "cli/cli.h"

#include <cmath>
#include <iostream>
#include <sstream>

namespace po = boost::program_options;

namespace range_nlm
{
namespace tools
{
namespace
{

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

/// True if every valid point of the input frame has a depth that a 16-bit depth image of `scale`
/// can hold (always so for a depth-PNG input).
bool
depthsFit(const Cloud& input, const std::string& input_path, double scale)
{
  if (isDepthImagePath(input_path))
    return true;
  for (const pcl::PointXYZ& p : input)
    if (std::isfinite(p.z) && !(std::round(double(p.z) * scale) >= 1.0 && std::round(double(p.z) * scale) <= 65535.0))
      return false;
  return true;
}

void
warnClamping(const std::string& output_path, const DepthClamping& clamping, double depth_scale)
{
  std::ostringstream warning;
  warning << "range_nlm_denoise: warning: '" << output_path << "': ";
  if (clamping.above > 0)
    warning << clamping.above << " pixel(s) filtered to more than " << 65535.0 / depth_scale
            << " m (65535 / depth scale " << depth_scale << ") stored as 65535";
  if (clamping.above > 0 && clamping.below > 0)
    warning << "; ";
  if (clamping.below > 0)
    warning << clamping.below << " pixel(s) filtered to less than " << 0.5 / depth_scale << " m stored as 1";
  std::cerr << printable(warning.str()) << "\n" << std::flush;
}

} // namespace

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
writeResult(const std::string& input_path, const std::string& output_path, LoadedCloud& loaded, const Cloud& result,
            const OutputOptions& out)
{
  if (out.png) {
    // A depth the input could hold that filtering moved just past the 16-bit range (a frame near
    // the sensor's largest value) is clamped, with a warning; an input whose depths never fitted
    // is refused (a smaller --depth-scale is needed).
    // Each point goes onto its pixel's ray where the ray meets the plane the filter moved it onto
    // (a depth image holds one range per pixel; z alone would drop the move across the ray).
    const Cloud input = xyzFromBlob(loaded, input_path);
    DepthClamping clamping;
    saveDepthPng(output_path, input, result, out.depth_scale,
                 depthsFit(input, input_path, out.depth_scale) ? &clamping : nullptr);
    if (clamping.above > 0 || clamping.below > 0)
      warnClamping(output_path, clamping, out.depth_scale);
    return;
  }
  if (out.colorize) {
    RenderParameters colour = out.colour;
    colour.viewpoint = {loaded.origin[0], loaded.origin[1], loaded.origin[2]};
    pcl::PointCloud<pcl::PointXYZRGB> coloured = colorizeByCurvature(result, colour);
    coloured.sensor_origin_ = loaded.origin;
    coloured.sensor_orientation_ = loaded.orientation;
    saveCloudAtomic(output_path, coloured);
    return;
  }
  writeXyzToBlob(result, loaded.blob);
  saveCloudAtomic(output_path, loaded.blob, loaded.origin, loaded.orientation);
}

} // namespace tools
} // namespace range_nlm
