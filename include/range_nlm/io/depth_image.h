/// \file depth_image.h
/// \brief 16-bit depth images (TUM RGB-D, RealSense, Azure Kinect PNGs) <-> organized clouds.
///
/// A depth image stores one unsigned 16-bit value per pixel; value / depth_scale is the depth z
/// in metres along the optical axis and 0 marks a pixel without measurement. With pinhole
/// intrinsics (fx, fy, cx, cy in pixels) pixel (u, v) of depth z is the point
///   x = (u - cx) z / fx,  y = (v - cy) z / fy,  z,
/// in the camera frame (x right, y down, z forward), so the cloud is organized like the image:
/// point (u, v) is index v * width + u. Pixels of value 0 become NaN in x, y and z.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace range_nlm
{

/// Pinhole intrinsics of a depth camera and the encoding of its depth values.
/// The defaults are the common ROS/TUM RGB-D values for a 640 x 480 Kinect v1 frame.
struct DepthIntrinsics
{
  /// Focal length along x, pixels. > 0, default 525.
  double fx = 525.0;
  /// Focal length along y, pixels. > 0, default 525.
  double fy = 525.0;
  /// Principal point, column, pixels. Finite, default 319.5.
  double cx = 319.5;
  /// Principal point, row, pixels. Finite, default 239.5.
  double cy = 239.5;
  /// Stored values per metre: z [m] = value / depth_scale. > 0; default 5000 (TUM RGB-D);
  /// 1000 for millimetre images (RealSense, Azure Kinect).
  double depth_scale = 5000.0;

  /// Throws std::invalid_argument naming the first invalid field and its value.
  void validate() const;
};

/// Reads an `intrinsics.txt` file: one `key value` pair per line, `#` starts a comment, blank
/// lines are skipped. Numeric keys: `fx`, `fy`, `cx`, `cy` (pixels), `depth_scale` (values per
/// metre); `width` and `height` are checked to be positive integers. A `depth_format` line is free
/// text; when there is no `depth_scale` line, the scale is taken from it if it says
/// `value / N` (scale N) or `millimetres`/`millimeters` (scale 1000). Other keys (e.g. lens
/// distortion coefficients) are ignored. Missing keys keep their value from `defaults`.
/// Throws std::invalid_argument naming the file (and line) if it cannot be read, a numeric value
/// does not parse, or the result fails DepthIntrinsics::validate().
DepthIntrinsics
readIntrinsics(const std::string& path, const DepthIntrinsics& defaults = DepthIntrinsics());

/// A single-channel 16-bit image, row-major: `values[v * width + u]`.
struct DepthImage
{
  int width = 0;
  int height = 0;
  std::vector<std::uint16_t> values;
};

/// Reads a 16-bit greyscale PNG (any interlacing). Throws std::invalid_argument naming the file
/// if it is missing, not a PNG, damaged, or not 16-bit greyscale (the message gives the bit depth
/// and colour type found).
DepthImage
readDepthPng(const std::string& path);

/// Writes a 16-bit greyscale PNG, first to a temporary file in the same directory, then renamed
/// into place. Throws std::invalid_argument naming the file if the image is inconsistent or the
/// file cannot be written.
void
writeDepthPng(const std::string& path, const DepthImage& image);

/// Back-projects a depth image with `intrinsics` (see the file comment). The result is organized
/// (width x height), `is_dense` is true only if no pixel is 0. Throws std::invalid_argument if
/// the intrinsics are invalid or the image is empty.
pcl::PointCloud<pcl::PointXYZ>
depthImageToCloud(const DepthImage& image, const DepthIntrinsics& intrinsics);

/// Encodes the z of an organized cloud as depth values round(z * depth_scale); NaN points give 0.
/// x and y are not stored (a reader recomputes them from the intrinsics). Throws
/// std::invalid_argument naming the pixel and its z if a valid point's value would fall outside
/// 1 ... 65535 (z <= 0, or z >= 65535.5 / depth_scale metres), if `depth_scale` is not a
/// positive finite number, or if the cloud is empty or its width * height is not its size.
DepthImage
cloudToDepthImage(const pcl::PointCloud<pcl::PointXYZ>& cloud, double depth_scale);

/// readDepthPng + depthImageToCloud; errors name the file.
pcl::PointCloud<pcl::PointXYZ>
loadDepthPng(const std::string& path, const DepthIntrinsics& intrinsics);

/// cloudToDepthImage + writeDepthPng; errors name the file.
void
saveDepthPng(const std::string& path, const pcl::PointCloud<pcl::PointXYZ>& cloud, double depth_scale);

namespace detail
{
/// Raw PNG pixels as libpng delivers them: `bytes` holds `height` rows of
/// `width * channels * bit_depth / 8` bytes, 16-bit samples big-endian.
struct PngPixels
{
  int width = 0;
  int height = 0;
  /// 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA (palette images are expanded to RGB).
  int channels = 0;
  /// 8 or 16 (lower depths are expanded to 8).
  int bit_depth = 0;
  std::vector<std::uint8_t> bytes;
};
/// Reads any PNG with libpng. Throws std::invalid_argument naming the file on any failure.
PngPixels
readPng(const std::string& path);
/// Writes `pixels` (channels 1 or 3, bit depth 8 or 16) with libpng, atomically (temporary file
/// then rename). Throws std::invalid_argument naming the file on any failure. Shared by the
/// depth-image and rendering code.
void
writePng(const std::string& path, const PngPixels& pixels);
} // namespace detail

} // namespace range_nlm
