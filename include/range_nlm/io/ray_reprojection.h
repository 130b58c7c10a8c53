/// \file ray_reprojection.h
/// \brief Filtered points put back on their pixels' rays, for outputs that hold one range per
/// pixel (depth images).
///
/// A depth image stores one depth per pixel; a reader puts the point on the pixel's ray, the
/// line from the camera centre (the origin of the cloud's frame) through the input point p. A
/// frame filtered alone moves p along its normal to p', off that ray; keeping only the z of p'
/// (cloudToDepthImage(cloud, ...)) throws away the part of the move across the ray.
/// reprojectOntoRays puts each moved point where its pixel's ray meets the tangent plane of the
/// filtered surface at p': with that plane's unit normal n and the move m = p' - p, the ray
/// through p meets it at
///   s p,  s = (n . p') / (n . p) = 1 + (n . m) / (n . p),
/// a move of (n . m) / cos along the ray, cos = (n . p) / |p|. The point keeps its height above
/// the filtered surface's plane, so a plane seen at any angle keeps the residual the filter left.
///
/// The normal n is the least-squares plane of the filtered points in a small window around the
/// pixel (those on the point's side of a depth edge: ranges within `range_gate` of its own).
/// For a single move along the filter's normal, m / |m| would give that normal exactly; but the
/// default's second pass (normals re-estimated on the first pass's output), an outlier moved along
/// its ray and then along its normal, and a multiscale run's coarse range corrections all add
/// moves in other directions, and a plane perpendicular to their sum is tilted against the
/// surface the filter left (docs/method.md, "Depth images: the move re-projected onto the
/// rays"). A move along the ray (--line-of-sight, temporal runs) is on the ray already: s p is
/// then p' (up to rounding) whatever n is.
///
/// The move is split into its part along the ray, kept as it is, and its part across the ray,
/// m_across, which the plane carries onto the ray as a move C = (n . m_across) / cos along it.
/// How far that can be trusted depends on the plane: turned by an angle e about p', it moves
/// the crossing along the ray by about L e / |cos|, L the distance from p' to the crossing. e is
/// estimated from the planes of the windows half a window away (the RMS sine of their angles to
/// n, on the point's side of a depth edge): they agree on a plane, and differ where the surface
/// bends within a window, where the filter left bumps and where a window straddles an edge or a
/// crease. The carried move is weighted by C^2 / (C^2 + (L e / cos)^2): in full where its error
/// is small against it, falling back smoothly to the part along the ray (the point of the ray
/// nearest to p') where it is not (docs/method.md, "How far the plane is trusted").
///
/// Where the ray meets the plane at a grazing angle (|cos| < min_cos), a small error of n would
/// move the point far along its ray: |cos| is taken as min_cos there, so that the part across
/// the ray moves the point along its ray by at most |m_across| / min_cos (as the filter's own
/// line-of-sight move is bounded): a point moves along its ray by at most
/// |m| sqrt(1 + 1 / min_cos^2), 3.5 |m| at the default. Where no plane fits (fewer than 6 points
/// on the point's side, or all on a line) only the part along the ray is kept.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstddef>

namespace range_nlm
{

/// How reprojectOntoRays finds the filtered surface's plane and when it falls back.
struct RayReprojectionParameters
{
  /// Smallest |cos| between the plane's normal and the ray taken: below, the part of the move
  /// across the ray moves the point along it by at most |m_across| / min_cos. In (0, 1],
  /// default 0.3 (a ray at most about 72 degrees from the normal; docs/method.md says why).
  double min_cos = 0.3;
  /// Side of the square window of filtered points the plane is fitted to, pixels; the planes it
  /// is compared with are those of the windows window / 2 pixels away. Odd, 3 ... 99, default 5.
  int window = 5;
  /// Points of the window whose range differs from the point's by more than this fraction of it
  /// are left out of the fit (the other side of a depth edge). In (0, 1], default 0.05.
  double range_gate = 0.05;

  /// Throws std::invalid_argument naming the first field out of its range and its value.
  void validate() const;
};

/// What reprojectOntoRays did, point by point.
struct RayReprojectionCounts
{
  /// Moved points put where their ray meets the filtered surface's plane (the part of the move
  /// across the ray carried as far as the plane is trusted).
  std::size_t on_plane = 0;
  /// Moved points at a grazing angle (bounded move) or without a plane (nearest point of the ray).
  std::size_t grazing = 0;
  /// Valid points that did not move: they keep their place.
  std::size_t unmoved = 0;
  /// Points valid in `filtered` only (a hole the filter filled) or whose input is the origin:
  /// no ray, kept as they are.
  std::size_t without_ray = 0;
};

/// `filtered` with every point that moved put on the ray through the origin and its input point
/// (see the file comment), computed in double: point i becomes s * input[i]. A point that did not
/// move keeps its place; a point invalid (a NaN or infinite coordinate) in `filtered` is NaN in x,
/// y and z; a point valid only in `filtered` (a filled hole), or whose input is the origin, has no
/// ray and is kept as it is. The result is organized like `filtered`, with its header, sensor
/// origin and orientation, and `is_dense` recomputed; it does not depend on the thread count (the
/// points are computed in parallel, each from the two clouds as given). `counts`, if given, receives how each point was treated.
/// Throws std::invalid_argument if the two clouds differ in width or height, either is empty or
/// not organized (width * height != size), or a parameter is out of its range.
pcl::PointCloud<pcl::PointXYZ>
reprojectOntoRays(const pcl::PointCloud<pcl::PointXYZ>& input, const pcl::PointCloud<pcl::PointXYZ>& filtered,
                  const RayReprojectionParameters& parameters = RayReprojectionParameters(),
                  RayReprojectionCounts* counts = nullptr);

} // namespace range_nlm
