// The one helper shared by the range_nlm_* tools: error exits, option parsing, sorted frame
// lists, checked loading and atomic saving of PCD files, filter options and progress display.
#pragma once

#include <range_nlm/depth_image.h>
#include <range_nlm/parameters.h>

#include <boost/program_options.hpp>
#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <chrono>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace range_nlm
{
namespace tools
{

/// Wrong command line: exit status 2.
struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};
/// Unreadable or invalid input, failed processing: exit status 1.
struct InputError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// Runs `body` and maps exceptions to one-line messages on stderr and exit statuses
/// (0 success, 1 input/processing error, 2 usage error).
int
runTool(const std::string& tool, const std::function<int()>& body);

/// Parses argv against `options` (+ positional), throwing UsageError with boost's message.
/// Returns false if --help was given (help text already printed to stdout).
bool
parseCommandLine(int argc, char** argv, const boost::program_options::options_description& options,
                 const boost::program_options::positional_options_description& positional,
                 boost::program_options::variables_map& vm, const std::string& usage);

/// Adds --search-window, --patch, --iterations, --threads, --distance-bandwidth,
/// --similarity-bandwidth, --seed, --normal-window, --preset, --direct, --line-of-sight.
void
addFilterOptions(boost::program_options::options_description& options);
/// Builds validated FilterParameters from the options added by addFilterOptions.
FilterParameters
filterParametersFrom(const boost::program_options::variables_map& vm);

/// The *.pcd files of a directory, sorted by name. Throws InputError if the directory is
/// missing or holds no .pcd file.
std::vector<std::string>
listFrames(const std::string& directory, const std::string& extension = ".pcd");

/// Loads a PCD file with checks: exists, non-empty, parsable, has float x, y, z fields,
/// width * height points, organized if `organized`. Errors name the file.
/// A loaded PCD file: all fields plus the sensor pose from its VIEWPOINT line.
struct LoadedCloud
{
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
};
LoadedCloud
loadCloud(const std::string& path, bool organized = true);

/// x, y, z of a blob (FLOAT32 or FLOAT64 fields) as an organized PointXYZ cloud, with the
/// blob's width, height and sensor pose. Throws InputError (naming `path`) on infinite values.
pcl::PointCloud<pcl::PointXYZ>
xyzFromBlob(const LoadedCloud& cloud, const std::string& path);
/// Writes x, y, z back into the blob (all other fields untouched); sets is_dense.
void
writeXyzToBlob(const pcl::PointCloud<pcl::PointXYZ>& xyz, pcl::PCLPointCloud2& blob);

/// Saves binary PCD to a temporary name in the same directory and renames it into place, so no
/// half-written file ever carries the final name. Throws InputError naming the file.
void
saveCloudAtomic(const std::string& path, const pcl::PCLPointCloud2& blob,
                const Eigen::Vector4f& origin = Eigen::Vector4f::Zero(),
                const Eigen::Quaternionf& orientation = Eigen::Quaternionf::Identity());
/// Same for a typed cloud.
template <typename PointT>
void
saveCloudAtomic(const std::string& path, const pcl::PointCloud<PointT>& cloud)
{
  pcl::PCLPointCloud2 blob;
  pcl::toPCLPointCloud2(cloud, blob);
  saveCloudAtomic(path, blob, cloud.sensor_origin_, cloud.sensor_orientation_);
}

/// Throws InputError if an output directory is the input directory (unless allowed), or
/// creates it if missing.
void
prepareOutputDirectory(const std::string& input_dir, const std::string& output_dir, bool allow_same);

/// Joins a directory and a file name.
std::string
joinPath(const std::string& directory, const std::string& name);
/// The file name part of a path.
std::string
fileName(const std::string& path);

/// Progress of a long run: a bar on a terminal (stderr), nothing when quiet or not a terminal.
class Progress
{
public:
  Progress(std::size_t total, bool quiet);
  void update(std::size_t done);
  void finish();

private:
  std::size_t total_;
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
};

/// Milliseconds since `start`.
double
millisecondsSince(std::chrono::steady_clock::time_point start);

/// Adds the options of 16-bit depth-PNG input: --fx, --fy, --cx, --cy (pixels), --depth-scale
/// (stored values per metre) with the DepthIntrinsics defaults, and --intrinsics FILE.
void
addDepthImageOptions(boost::program_options::options_description& options);
/// Intrinsics from those options: the defaults, overridden by --intrinsics FILE, overridden by
/// every value given explicitly on the command line. Throws UsageError naming the option on an
/// invalid value, InputError naming the file if the intrinsics file is unreadable or invalid.
DepthIntrinsics
depthIntrinsicsFrom(const boost::program_options::variables_map& vm);

/// True if `path` ends in ".png" (any case): such inputs are read as 16-bit depth images.
bool
isDepthImagePath(const std::string& path);

/// Loads one organized frame: a PCD file through loadCloud() (all fields), or a 16-bit depth PNG
/// back-projected with `intrinsics` into a blob with fields x, y, z. Errors name the file.
LoadedCloud
loadFrame(const std::string& path, const DepthIntrinsics& intrinsics);

/// The frames of an input directory, sorted by name: its *.pcd files if it has any, otherwise
/// its *.png depth images. Throws InputError if the directory is missing or holds neither.
std::vector<std::string>
listInputFrames(const std::string& directory);

/// `path` with its extension replaced by `extension` (e.g. ".png").
std::string
replaceExtension(const std::string& path, const std::string& extension);

} // namespace tools
} // namespace range_nlm
