// librealsense's hole-filling filter (rs2::hole_filling_filter), reimplemented as a baseline for
// the hole-filling comparison of range_nlm_bench: what users of Intel RealSense depth cameras run
// to close the holes of their depth frames.
//
// Follows IntelRealSense/librealsense src/proc/hole-filling-filter.h and
// src/proc/hole-filling-filter.cpp as of commit cacc8e701a963a44b49fe51911443797e8b3a517 (master,
// July 2025; both files last changed in 296ef40c10eaba75a39a1865e525cf1c42b35fdb, September 2024),
// Apache-2.0. The kernels are the Z16 paths of holes_fill_left, holes_fill_farest and
// holes_fill_nearest, statement for statement. A hole is a depth of 0; the image is scanned once,
// row by row, left to right, in place, so a pixel filled earlier in the scan is a neighbour like
// any other for the pixels after it:
//  - fill from left (RS2_OPTION_HOLES_FILL 0): in every row, from the second column on, a hole
//    takes its left neighbour's value (so a run of holes takes the value left of it). The first
//    column is never filled.
//  - farthest from around (1, the default): in rows 1 .. height - 2, columns 1 .. width - 1, a
//    hole takes the largest of its upper, upper-left, left, lower-left and lower neighbours (0
//    where all are holes). Only those five: the right-hand neighbours are not read. The first and
//    last rows and the first column are never filled.
//  - nearest from around (2): the same pixels and neighbours, but the value starts as the upper
//    neighbour's and is replaced by any of the other four that is not a hole and smaller. An
//    upper neighbour that is a hole starts it at 0, which nothing non-zero is smaller than: such
//    a pixel stays a hole (the source's behaviour, kept).
//
// Deviations, none of which changes an output value of the Z16 path:
//  - Only depth (Z16) frames, as a program gets that calls the filter on its depth frames. The
//    source also fills disparity frames (float; the recommended D400 chain runs it in disparity,
//    where farthest means the smallest disparity, as the filter then compares raw float bits).
//  - Point clouds: the cloud adaptor (HoleFillingFilter::filter) turns z into depth units
//    (round(z / depth_unit); a point whose z rounds to 0 is a hole, as the camera would report it)
//    and puts every filled pixel back on its own ray, which the caller gives as the camera's
//    pinhole intrinsics (a hole has no point of its own to take it from).
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>

namespace range_nlm
{
namespace tools
{
namespace librealsense
{

/// RS2_OPTION_HOLES_FILL, "Hole Filling mode", with the source's enumerator values.
enum class HoleFillingMode
{
  fill_from_left = 0,
  farthest_from_around = 1,
  nearest_from_around = 2
};

/// The name librealsense's option describes a mode by ("Fill from Left", ...).
const char*
toString(HoleFillingMode mode);

/// A pinhole camera whose pixel (u, v) at depth z is ((u - cx) z / fx, (v - cy) z / fy, z): where
/// the cloud adaptor puts a filled pixel.
struct PinholeRays
{
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;
  /// Puts q on the ray of pixel (u, v) at depth z; a depth of 0 or less (a pixel left a hole)
  /// makes it NaN in x, y and z. Whether it was placed.
  bool place(pcl::PointXYZ& q, int u, int v, double z) const;
};

/// The filter's options, with librealsense's names and defaults.
struct HoleFillingParameters
{
  /// RS2_OPTION_HOLES_FILL. Default farthest_from_around (the source's hole_fill_def).
  HoleFillingMode mode = HoleFillingMode::farthest_from_around;
  /// RS2_OPTION_DEPTH_UNITS of the sensor: metres per depth unit, for the cloud adaptor. > 0,
  /// default 0.001 (the D400 series' millimetres).
  double depth_unit = 0.001;

  /// Throws std::invalid_argument naming the parameter and its value if one is out of range.
  void validate() const;
};

/// The filter: no state from frame to frame.
class HoleFillingFilter
{
public:
  /// Throws std::invalid_argument (HoleFillingParameters::validate).
  explicit HoleFillingFilter(const HoleFillingParameters& parameters = {});

  /// Fills the holes of a width x height depth image (row-major, depth units, 0 = no
  /// measurement) in place. Throws std::invalid_argument for a non-positive size.
  void process(std::uint16_t* depth, int width, int height) const;

  /// The same on an organized cloud of points in metres (x right, y down, z forward, camera at
  /// the origin; NaN = no measurement): depth = round(z / depth_unit). A measured point is kept
  /// bit for bit; a filled pixel is its depth * depth_unit on the ray `rays` give it. Holes left
  /// are NaN in x, y and z; is_dense is recomputed. Throws std::invalid_argument (naming the pixel
  /// and value) for an unorganized cloud, a point with a finite z but a non-finite x or y, or a
  /// depth that is negative or above 65535 units (choose a larger depth_unit).
  pcl::PointCloud<pcl::PointXYZ> filter(const pcl::PointCloud<pcl::PointXYZ>& frame, const PinholeRays& rays) const;

  const HoleFillingParameters& parameters() const { return parameters_; }

private:
  HoleFillingParameters parameters_;
};

} // namespace librealsense
} // namespace tools
} // namespace range_nlm
