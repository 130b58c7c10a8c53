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
};

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
void
writeResult(const std::string& input_path, const std::string& output_path, io::LoadedCloud& loaded,
            const pcl::PointCloud<pcl::PointXYZ>& result, const OutputOptions& out);

} // namespace tools
} // namespace range_nlm
