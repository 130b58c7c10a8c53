// How a tool writes the result of a frame: into the input's own fields (PCD), as a cloud coloured
// by mean curvature (PCD) or as a 16-bit depth image (PNG), with the options that choose it.
#pragma once

#include <range_nlm/eval/render.h>
#include <range_nlm/io/depth_image.h>
#include <range_nlm/io/pcd_file.h>

#include <boost/program_options/variables_map.hpp>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{

/// How results are written: the input's fields (PCD), curvature colour (PCD) or 16-bit depth (PNG).
struct OutputOptions
{
  bool png = false;
  bool colorize = false;
  RenderParameters colour;
  double depth_scale = DepthIntrinsics().depth_scale;
  /// Also write the per-point uncertainty (FilterParameters::uncertainty): a float field
  /// `uncertainty` after the points' fields of PCD output, a float image
  /// uncertaintyImagePath(output) beside PNG output.
  bool uncertainty = false;
};

/// Where the uncertainty image of a PNG output goes: NAME_uncertainty.pfm beside NAME.png.
std::string
uncertaintyImagePath(const std::string& png_output);

/// Writes `values` (width x height, row 0 at the top) as a little-endian Portable Float Map
/// (PFM, "Pf": one 32-bit float channel, rows stored bottom to top as the format says), NaN
/// where there is no value; atomically as the PCD output. Throws InputError naming the file.
void
writeFloatImage(const std::string& path, const std::vector<float>& values, int width, int height);

/// `blob` with a FLOAT32 field `name` holding `values` (one per point): appended after the
/// other fields, or overwritten where the blob has such a field already.
void
setFloatField(pcl::PCLPointCloud2& blob, const std::string& name, const std::vector<float>& values);

/// From --output-format, --colorize and --curvature-limit; `single`: a single-frame run writing
/// `single_output`, else a directory run whose first input is `first_input`. Throws UsageError
/// naming the option.
OutputOptions
outputOptionsFrom(const boost::program_options::variables_map& vm, bool single, const std::string& first_input,
                  const std::string& single_output, const DepthIntrinsics& intrinsics);

/// Writes `result`, the filtered points of the frame `loaded` read from `input_path`, to
/// `output_path` as `out` says (PCD outputs atomically; the input's other fields are kept, so
/// `loaded` takes the new points). A PNG output puts each point on its pixel's ray, where the ray
/// meets the plane the filter moved the point onto (cloudToDepthImage(input, filtered, ...));
/// `loaded` must still hold the frame's input points then. A PNG depth that filtering moved just past the 16-bit range is
/// clamped, with a warning on stderr, unless the input's depths never fitted (then it throws).
/// With out.uncertainty, `uncertainty` (one value per point, else NaN everywhere: a frame passed
/// through unfiltered) is written too. `filled` (one entry per point, empty when the hole filling
/// is off) marks the points the hole filling gave a range: a PCD output gets a uint8 field
/// `filled` (1 = filled; an input's own `filled` field is kept and added to), a PNG output a mask
/// image beside it (filledMaskPath(output_path), 65535 where filled, 0 elsewhere).
void
writeResult(const std::string& input_path, const std::string& output_path, io::LoadedCloud& loaded,
            const pcl::PointCloud<pcl::PointXYZ>& result, const OutputOptions& out,
            const std::vector<float>& uncertainty = {}, const std::vector<unsigned char>& filled = {});

/// The mask image of the filled points beside a PNG output: "NAME.png" -> "NAME.filled-mask.png".
std::string
filledMaskPath(const std::string& output_path);

/// Sets the uint8 field `filled` of `blob` (appended if it has none) to 1 where `filled` is set,
/// keeping the 1s it already holds.
void
markFilled(pcl::PCLPointCloud2& blob, const std::vector<unsigned char>& filled);

} // namespace tools
} // namespace range_nlm
