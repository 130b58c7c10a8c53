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

#include <range_nlm/io/memory_budget.h>

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
  /// Valid ranges: every back-projected point of a 16-bit image is then a finite float that is
  /// not rounded to 0 (a focal length of 1e308 would make every x -0, a tiny one infinite).
  static constexpr double kMinFocalLength = 1.0, kMaxFocalLength = 1e6;
  static constexpr double kMaxPrincipalPoint = 1e6;
  static constexpr double kMinDepthScale = 1e-3, kMaxDepthScale = 1e9;

  /// Focal length along x, pixels, 1 ... 1e6; default 525.
  double fx = 525.0;
  /// Focal length along y, pixels, 1 ... 1e6; default 525.
  double fy = 525.0;
  /// Principal point, column, pixels, -1e6 ... 1e6; default 319.5.
  double cx = 319.5;
  /// Principal point, row, pixels, -1e6 ... 1e6; default 239.5.
  double cy = 239.5;
  /// Stored values per metre: z [m] = value / depth_scale, 1e-3 ... 1e9; default 5000 (TUM
  /// RGB-D); 1000 for millimetre images (RealSense, Azure Kinect).
  double depth_scale = 5000.0;
  /// Image size the intrinsics belong to, pixels; 0 = not known (any size is accepted). Set
  /// from the `width` / `height` lines of an intrinsics file; depthImageToCloud refuses an image
  /// of another size.
  int width = 0;
  int height = 0;
  /// The intrinsics file these values came from (named in messages); empty if none.
  std::string source;

  /// Throws std::invalid_argument naming the first invalid field and its value.
  void validate() const;
};

/// Reads an `intrinsics.txt` file: one `key value` pair per line, `#` starts a comment, blank
/// lines are skipped; a file longer than 1 MB is refused. Numeric keys: `fx`, `fy`, `cx`, `cy`
/// (pixels), `depth_scale` (values per metre), `width` and `height` (positive integers: the image
/// size the intrinsics belong to, checked against every image read with them). A `depth_format`
/// line is free text; when there is no `depth_scale` line, the scale is taken from it if it says
/// `value / N` (scale N > 0) or `millimetres`/`millimeters` (scale 1000). The free-text keys
/// `sensor`, `distortion`, `note`, `notes`, `comment`, `comments` and `source` are documentation
/// and not read. Any other key is refused (a misspelt `depth_scale` must not silently leave the
/// default in place), and so is a key given twice. Missing keys keep their value from `defaults`;
/// `source` is set to `path`.
/// Throws std::invalid_argument naming the file (and line) if it cannot be read or is too long, a
/// key is unknown or repeated, a numeric value does not parse, `depth_format` divides by 0, or the
/// result fails DepthIntrinsics::validate().
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
/// and colour type found), or if the size its header announces does not fit `budget` (checked
/// with a point step of 16 bytes, an organized PointXYZ cloud, before any pixel is decoded).
DepthImage
readDepthPng(const std::string& path, const io::MemoryBudget& budget = io::MemoryBudget());

/// Writes a 16-bit greyscale PNG, first to a temporary file in the same directory, then renamed
/// into place (a symbolic link is followed and kept; a character device or FIFO is written
/// directly; see io::saveCloudAtomic). Throws std::invalid_argument naming the file if the image
/// is inconsistent or the file cannot be written (e.g. "No space left on device"); no partial
/// file is left.
void
writeDepthPng(const std::string& path, const DepthImage& image);

/// Back-projects a depth image with `intrinsics` (see the file comment). The result is organized
/// (width x height), `is_dense` is true only if no pixel is 0. Throws std::invalid_argument if
/// the intrinsics are invalid, the image is empty, or the intrinsics give a width and height
/// other than the image's (the message gives both sizes and the intrinsics file).
pcl::PointCloud<pcl::PointXYZ>
depthImageToCloud(const DepthImage& image, const DepthIntrinsics& intrinsics);

/// How many valid points cloudToDepthImage clamped into the 16-bit range.
struct DepthClamping
{
  /// Points deeper than 65535.5 / depth_scale metres, stored as 65535.
  std::size_t above = 0;
  /// Points nearer than 0.5 / depth_scale metres (or at z <= 0), stored as 1 (0 means "no
  /// measurement", which they are not).
  std::size_t below = 0;
};

/// What `clamping` counts, in words for a warning ("N pixel(s) filtered to more than ... m ...");
/// empty if nothing was clamped.
std::string
clampingText(const DepthClamping& clamping, double depth_scale);

/// Encodes the z of an organized cloud as depth values round(z * depth_scale); NaN points give 0.
/// x and y are not stored (a reader recomputes them from the intrinsics), so this is right for
/// points that lie on their pixels' rays already; for a filtered frame use the form below, which
/// takes the filter's input too. A valid point whose
/// value falls outside 1 ... 65535 (z <= 0, or z >= 65535.5 / depth_scale metres) is clamped to
/// that range and counted in `*clamping` if `clamping` is given (a filtered depth image close to
/// the sensor's largest value can move a little beyond it); without `clamping` it is an error:
/// std::invalid_argument naming the pixel and its z. Also throws if `depth_scale` is not a
/// positive finite number, or if the cloud is empty or its width * height is not its size.
DepthImage
cloudToDepthImage(const pcl::PointCloud<pcl::PointXYZ>& cloud, double depth_scale,
                  DepthClamping* clamping = nullptr);

/// A floating-point depth map (e.g. a float32 image in metres, as Open3D and numpy hold them)
/// back-projected exactly as depthImageToCloud back-projects a 16-bit image: `values[v * width +
/// u] / depth_scale` is the depth z in metres; 0, a negative or a non-finite value marks a pixel
/// without measurement (NaN in x, y and z). Throws std::invalid_argument as depthImageToCloud does,
/// and if `values` does not hold width x height values.
pcl::PointCloud<pcl::PointXYZ>
depthMapToCloud(const std::vector<float>& values, int width, int height, const DepthIntrinsics& intrinsics);

/// The depths a depth image stores for an organized cloud, before any encoding: z * depth_scale
/// per point, NaN where the point is invalid. cloudToDepthImage rounds exactly these values into
/// 16 bits; a floating-point depth map takes them as they are. Throws std::invalid_argument as
/// cloudToDepthImage does for the scale and the cloud's size.
std::vector<double>
cloudToDepthValues(const pcl::PointCloud<pcl::PointXYZ>& cloud, double depth_scale);
/// The depth image of a filtered frame: each point of `filtered` first put on the ray of its
/// pixel, the ray through the origin and the point of `input`, where that ray meets the plane
/// the filter moved the point onto (reprojectOntoRays in ray_reprojection.h, with its
/// `min_cos`), then encoded as cloudToDepthImage(cloud, depth_scale, clamping) does. This is
/// the encoding for any filtered frame: the single-cloud form above keeps only z, which drops
/// the part of a move along the normal that runs across the ray. `input` is the cloud the filter
/// was given (for a depth image, depthImageToCloud's result). Throws std::invalid_argument as
/// reprojectOntoRays and cloudToDepthImage do (sizes, depth scale, a depth out of range).
DepthImage
cloudToDepthImage(const pcl::PointCloud<pcl::PointXYZ>& input, const pcl::PointCloud<pcl::PointXYZ>& filtered,
                  double depth_scale, DepthClamping* clamping = nullptr);

/// readDepthPng + depthImageToCloud; errors name the file.
pcl::PointCloud<pcl::PointXYZ>
loadDepthPng(const std::string& path, const DepthIntrinsics& intrinsics,
             const io::MemoryBudget& budget = io::MemoryBudget());

/// cloudToDepthImage(cloud, ...) + writeDepthPng (z as it is); errors name the file.
void
saveDepthPng(const std::string& path, const pcl::PointCloud<pcl::PointXYZ>& cloud, double depth_scale,
             DepthClamping* clamping = nullptr);

/// cloudToDepthImage(input, filtered, ...) + writeDepthPng: the filtered frame as a depth PNG,
/// each point on its pixel's ray; errors name the file.
void
saveDepthPng(const std::string& path, const pcl::PointCloud<pcl::PointXYZ>& input,
             const pcl::PointCloud<pcl::PointXYZ>& filtered, double depth_scale, DepthClamping* clamping = nullptr);

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
  /// The file's own format, before the expansions above: its bit depth and colour type as stored,
  /// e.g. "16-bit greyscale", "8-bit palette", "1-bit greyscale", "16-bit RGBA".
  std::string format;
  std::vector<std::uint8_t> bytes;
};
/// Reads any PNG with libpng. Throws std::invalid_argument naming the file on any failure,
/// including a size (from the header, before decoding) that does not fit `budget` with
/// `point_step` bytes a pixel.
PngPixels
readPng(const std::string& path, const io::MemoryBudget& budget = io::MemoryBudget(),
        std::uint64_t point_step = 0);
/// Writes `pixels` (channels 1 or 3, bit depth 8 or 16) with libpng, atomically (temporary file
/// then rename). Throws std::invalid_argument naming the file on any failure. Shared by the
/// depth-image and rendering code.
void
writePng(const std::string& path, const PngPixels& pixels);
} // namespace detail

} // namespace range_nlm
