/// \file pcd_file.h
/// \brief Checked reading and atomic writing of organized frames: PCD files (any field layout,
/// every field kept) and 16-bit depth PNGs. Every error names the file.
#pragma once

#include <range_nlm/io/depth_image.h>
#include <range_nlm/io/memory_budget.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace range_nlm
{
namespace io
{

/// A file that cannot be read or written, or whose contents are invalid. The message names the
/// file and the problem.
struct InputError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// A loaded PCD file: all fields plus the sensor pose from its VIEWPOINT line.
struct LoadedCloud
{
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
};
/// Loads a PCD file with checks: exists, non-empty, parsable, has float x, y, z fields,
/// width * height points, organized if `organized`, and a size that fits `budget` (from the
/// header, before the body is read). The whole header and the body's size are validated before
/// PCL decodes the body. Errors name the file.
LoadedCloud
loadCloud(const std::string& path, bool organized = true, const MemoryBudget& budget = MemoryBudget());

/// x, y, z of a blob (FLOAT32 or FLOAT64 fields) as an organized PointXYZ cloud, with the
/// blob's width, height and sensor pose. Throws InputError (naming `path`) on infinite values.
pcl::PointCloud<pcl::PointXYZ>
xyzFromBlob(const LoadedCloud& cloud, const std::string& path);
/// Writes x, y, z back into the blob (all other fields untouched); sets is_dense.
void
writeXyzToBlob(const pcl::PointCloud<pcl::PointXYZ>& xyz, pcl::PCLPointCloud2& blob);

/// Saves binary PCD (the bytes PCL's PCDWriter::writeBinary writes for the blob with its fields
/// packed: no padding, so no `_` fields that PCL's converters cannot read) with write(2), every return
/// checked: to a temporary name in the same directory (temporaryPrefix), fsynced and renamed into place, so no
/// half-written file ever carries the final name and a full disk gives an error, never SIGBUS.
/// A symbolic link is followed (its target is replaced, the link stays); a character device
/// (/dev/null) or FIFO is written directly; a directory, block device or socket is refused.
/// Throws InputError naming the file (and the system's reason, e.g. "No space left on device");
/// the temporary file is removed on every failure.
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

/// The name of the temporary file saveCloudAtomic (and writeDepthPng) writes for an output named
/// `file_name`, less the process id that follows it: ".NAME.tmp", or for a name too long for that
/// (the whole must stay within 255 bytes) the name cut short, "~" and a hash of the whole name.
std::string
temporaryPrefix(const std::string& file_name);

/// True if `path` ends in ".png" (any case): such inputs are read as 16-bit depth images.
bool
isDepthImagePath(const std::string& path);

/// Loads one organized frame: a PCD file through loadCloud() (all fields), or a 16-bit depth PNG
/// back-projected with `intrinsics` into a blob with fields x, y, z. Either is refused before its
/// body is decoded if its size does not fit `budget`. Errors name the file.
LoadedCloud
loadFrame(const std::string& path, const DepthIntrinsics& intrinsics, const MemoryBudget& budget = MemoryBudget());

/// The first problem of a point layout's fields (their names in order, each with its element
/// count), as a PCD header or a PointCloud2 message gives them: a name other than "_" (PCD's
/// padding) that appears twice ("field 'x' appears twice"), or a count of 0 or above `max_count`
/// ("field 'x' has COUNT 0"). Empty if there is none. A reader that took the first of two x
/// fields, or read an x of no elements, would read another field's bytes as coordinates.
std::string
fieldLayoutProblem(const std::vector<std::string>& names, const std::vector<std::uint64_t>& counts,
                   std::uint64_t max_count);

} // namespace io
} // namespace range_nlm
