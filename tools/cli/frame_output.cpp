#include "cli/frame_output.h"

#include "cli/cli.h"
#include "io/output_file.h"

#include <pcl/conversions.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iostream>
#include <sstream>
#include <stdexcept>

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
  std::cerr << printable("range_nlm_denoise: warning: '" + output_path + "': " + clampingText(clamping, depth_scale))
            << "\n" << std::flush;
}

/// The mask of the filled points as a 16-bit PNG (65535 where filled), as the depth beside it.
void
writeFilledMask(const std::string& path, const Cloud& result, const std::vector<unsigned char>& filled)
{
  DepthImage mask;
  mask.width = static_cast<int>(result.width);
  mask.height = static_cast<int>(result.height);
  mask.values.resize(filled.size());
  for (std::size_t i = 0; i < filled.size(); ++i)
    mask.values[i] = filled[i] ? 65535 : 0;
  writeDepthPng(path, mask);
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

std::string
uncertaintyImagePath(const std::string& png_output)
{
  const std::string::size_type dot = png_output.rfind('.'), slash = png_output.rfind('/');
  const bool extension = dot != std::string::npos && (slash == std::string::npos || dot > slash);
  return (extension ? png_output.substr(0, dot) : png_output) + "_uncertainty.pfm";
}

void
writeFloatImage(const std::string& path, const std::vector<float>& values, int width, int height)
{
  if (width <= 0 || height <= 0 || values.size() != static_cast<std::size_t>(width) * height)
    throw InputError("'" + path + "': " + std::to_string(values.size()) + " values for a " + std::to_string(width) +
                     " x " + std::to_string(height) + " float image");
  const std::string header = "Pf\n" + std::to_string(width) + " " + std::to_string(height) + "\n-1.0\n";
  std::vector<float> rows(values.size());
  for (int v = 0; v < height; ++v) // PFM stores the bottom row first
    std::copy_n(&values[static_cast<std::size_t>(height - 1 - v) * width], width,
                &rows[static_cast<std::size_t>(v) * width]);
  static_assert(sizeof(float) == 4, "PFM holds 32-bit floats");
  // Through OutputFile, like every output: a temporary file beside it renamed into place once
  // complete (no half-written image ever carries the final name), links followed, devices and
  // FIFOs written directly, directories refused; errors name the file.
  io::detail::OutputFile file(path);
  file.write(header.data(), header.size());
  // Little-endian hosts, as the scale -1.0 says.
  file.write(rows.data(), rows.size() * sizeof(float));
  file.commit();
}

void
setFloatField(pcl::PCLPointCloud2& blob, const std::string& name, const std::vector<float>& values)
{
  const std::size_t points = static_cast<std::size_t>(blob.width) * blob.height;
  if (values.size() != points)
    throw std::invalid_argument("setFloatField: " + std::to_string(values.size()) + " values for " +
                                std::to_string(points) + " points");
  for (const pcl::PCLPointField& f : blob.fields)
    if (f.name == name && f.datatype == pcl::PCLPointField::FLOAT32 && f.count == 1) {
      for (std::size_t i = 0; i < points; ++i)
        std::memcpy(&blob.data[i * blob.point_step + f.offset], &values[i], sizeof(float));
      return;
    }
  pcl::PCLPointCloud2 out = blob;
  out.data.clear();
  pcl::PCLPointField field;
  field.name = name;
  field.offset = blob.point_step;
  field.datatype = pcl::PCLPointField::FLOAT32;
  field.count = 1;
  out.fields.push_back(field);
  out.point_step = blob.point_step + sizeof(float);
  out.row_step = out.point_step * blob.width;
  out.data.resize(static_cast<std::size_t>(out.point_step) * points);
  for (std::size_t i = 0; i < points; ++i) {
    std::memcpy(&out.data[i * out.point_step], &blob.data[i * blob.point_step], blob.point_step);
    std::memcpy(&out.data[i * out.point_step + blob.point_step], &values[i], sizeof(float));
  }
  blob = std::move(out);
}

std::string
filledMaskPath(const std::string& output_path)
{
  const std::size_t dot = output_path.size() >= 4 ? output_path.size() - 4 : output_path.size();
  return output_path.substr(0, dot) + ".filled-mask.png";
}

void
markFilled(pcl::PCLPointCloud2& blob, const std::vector<unsigned char>& filled)
{
  const std::size_t points = std::size_t(blob.width) * blob.height;
  if (filled.size() != points)
    throw std::invalid_argument("the filled mask has " + std::to_string(filled.size()) + " entries for " +
                                std::to_string(points) + " points");
  auto field = std::find_if(blob.fields.begin(), blob.fields.end(),
                            [](const pcl::PCLPointField& f) { return f.name == "filled"; });
  if (field != blob.fields.end() && (field->datatype != pcl::PCLPointField::UINT8 || field->count != 1))
    throw std::invalid_argument("the cloud has a field 'filled' that is not one uint8");
  if (field == blob.fields.end()) {
    // Appended to every point: the other fields keep their bytes and offsets.
    const std::uint32_t step = blob.point_step;
    std::vector<std::uint8_t> data(points * (step + 1), 0);
    for (std::size_t i = 0; i < points; ++i)
      std::copy_n(&blob.data[i * step], step, &data[i * (step + 1)]);
    pcl::PCLPointField f;
    f.name = "filled";
    f.offset = step;
    f.datatype = pcl::PCLPointField::UINT8;
    f.count = 1;
    blob.fields.push_back(f);
    blob.point_step = step + 1;
    blob.row_step = blob.point_step * blob.width;
    blob.data.swap(data);
    field = blob.fields.end() - 1;
  }
  for (std::size_t i = 0; i < points; ++i)
    if (filled[i])
      blob.data[i * blob.point_step + field->offset] = 1;
}

void
writeResult(const std::string& input_path, const std::string& output_path, LoadedCloud& loaded, const Cloud& result,
            const OutputOptions& out, const std::vector<float>& uncertainty,
            const std::vector<unsigned char>& filled)
{
  // A frame passed through unfiltered has no estimate: NaN everywhere.
  std::vector<float> sigma;
  if (out.uncertainty)
    sigma = uncertainty.size() == result.size() ? uncertainty
                                                : std::vector<float>(result.size(), std::nanf(""));
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
    if (out.uncertainty)
      writeFloatImage(uncertaintyImagePath(output_path), sigma, int(result.width), int(result.height));
    if (!filled.empty())
      writeFilledMask(filledMaskPath(output_path), result, filled);
    return;
  }
  if (out.colorize) {
    RenderParameters colour = out.colour;
    colour.viewpoint = {loaded.origin[0], loaded.origin[1], loaded.origin[2]};
    pcl::PointCloud<pcl::PointXYZRGB> coloured = colorizeByCurvature(result, colour);
    coloured.sensor_origin_ = loaded.origin;
    coloured.sensor_orientation_ = loaded.orientation;
    if (!out.uncertainty) {
      saveCloudAtomic(output_path, coloured);
      return;
    }
    pcl::PCLPointCloud2 blob;
    pcl::toPCLPointCloud2(coloured, blob);
    setFloatField(blob, "uncertainty", sigma);
    saveCloudAtomic(output_path, blob, loaded.origin, loaded.orientation);
    return;
  }
  writeXyzToBlob(result, loaded.blob);
  if (out.uncertainty)
    setFloatField(loaded.blob, "uncertainty", sigma);
  if (!filled.empty()) {
    try {
      markFilled(loaded.blob, filled);
    } catch (const std::invalid_argument& e) {
      throw InputError("'" + output_path + "': " + e.what());
    }
  }
  saveCloudAtomic(output_path, loaded.blob, loaded.origin, loaded.orientation);
}

} // namespace tools
} // namespace range_nlm
