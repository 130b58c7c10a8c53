// Filtered points put back on their input points' rays: where the ray meets the filtered
// surface's tangent plane at the point (a plane fitted to the filtered points around it).
#include <range_nlm/io/ray_reprojection.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace range_nlm
{
namespace
{

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

bool
isValid(const pcl::PointXYZ& p)
{
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

Eigen::Vector3d
vectorOf(const pcl::PointXYZ& p)
{
  return Eigen::Vector3d(p.x, p.y, p.z);
}

std::string
sizeText(const Cloud& cloud)
{
  return std::to_string(cloud.width) + " x " + std::to_string(cloud.height) + " (" + std::to_string(cloud.size()) +
         " points)";
}

std::string
numberText(double value)
{
  std::ostringstream s;
  s << value;
  return s.str();
}

/// Whether `point` lies within the range gate of a point at range `range` (on its side of a
/// depth edge).
bool
withinRangeGate(const Eigen::Vector3d& point, double range, const RayReprojectionParameters& parameters)
{
  return std::fabs(point.norm() - range) <= parameters.range_gate * range;
}

/// The unit normal of the plane fitted (least squares) to the filtered points of the window
/// around pixel (u, v) whose range is within range_gate of the range of `centre` (the filtered
/// surface on the point's side of a depth edge); zero if fewer than kMinimumFitPoints are.
Eigen::Vector3d
surfaceNormal(const Cloud& filtered, int u, int v, const Eigen::Vector3d& centre,
              const RayReprojectionParameters& parameters)
{
  constexpr int kMinimumFitPoints = 6;
  const int w = static_cast<int>(filtered.width), h = static_cast<int>(filtered.height);
  const int r = parameters.window / 2;
  const double range = centre.norm();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  int count = 0;
  for (int b = std::max(0, v - r); b <= std::min(h - 1, v + r); ++b)
    for (int a = std::max(0, u - r); a <= std::min(w - 1, u + r); ++a) {
      const pcl::PointXYZ& f = filtered[static_cast<std::size_t>(b) * w + a];
      if (!isValid(f))
        continue;
      // Relative to the centre: the moments stay well conditioned far from the origin.
      const Eigen::Vector3d x = vectorOf(f) - centre;
      if (!withinRangeGate(x + centre, range, parameters))
        continue;
      sum += x;
      second += x * x.transpose();
      ++count;
    }
  if (count < kMinimumFitPoints)
    return Eigen::Vector3d::Zero();
  const Eigen::Vector3d mean = sum / count;
  const Eigen::Matrix3d covariance = second / count - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(covariance);
  const Eigen::Vector3d normal = solver.eigenvectors().col(0);
  // A window whose points lie on a line (or on one point) has no plane.
  const Eigen::Vector3d values = solver.eigenvalues();
  if (!(values(1) > 0.0) || !normal.allFinite())
    return Eigen::Vector3d::Zero();
  return normal.normalized();
}

/// surfaceNormal at every pixel whose filtered point is valid (zero elsewhere): a moved point
/// needs its own plane and those of the windows around it.
std::vector<Eigen::Vector3d>
surfaceNormals(const Cloud& filtered, const RayReprojectionParameters& parameters)
{
  const int w = static_cast<int>(filtered.width);
  std::vector<Eigen::Vector3d> normals(filtered.size(), Eigen::Vector3d::Zero());
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(filtered.size());
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t k = 0; k < size; ++k) {
    const std::size_t i = static_cast<std::size_t>(k);
    if (isValid(filtered[i]))
      normals[i] = surfaceNormal(filtered, static_cast<int>(i % w), static_cast<int>(i / w), vectorOf(filtered[i]),
                                 parameters);
  }
  return normals;
}

/// How far the plane n at pixel (u, v) may be turned: the RMS sine of its angle to the planes of
/// the windows half a window away in the 8 directions (those on the point's side of a depth edge,
/// as surfaceNormal gates). On a plane they agree up to the filter's leftover noise; on bumps
/// the filter left, across creases and where a window straddles an edge, they do not. 1 (as
/// uncertain as an orientation can be) if no such window has a plane.
double
planeAngleSpread(const Cloud& filtered, const std::vector<Eigen::Vector3d>& normals, int u, int v,
                 const Eigen::Vector3d& centre, const Eigen::Vector3d& n, const RayReprojectionParameters& parameters)
{
  const int w = static_cast<int>(filtered.width), h = static_cast<int>(filtered.height);
  const int step = parameters.window / 2;
  const double range = centre.norm();
  double sum = 0.0;
  int count = 0;
  for (int b = -1; b <= 1; ++b)
    for (int a = -1; a <= 1; ++a) {
      const int x = u + a * step, y = v + b * step;
      if ((a == 0 && b == 0) || x < 0 || y < 0 || x >= w || y >= h)
        continue;
      const std::size_t j = static_cast<std::size_t>(y) * w + x;
      if (normals[j].isZero() || !withinRangeGate(vectorOf(filtered[j]), range, parameters))
        continue;
      sum += normals[j].cross(n).squaredNorm();
      ++count;
    }
  return count > 0 ? std::sqrt(sum / count) : 1.0;
}

enum class Treatment { on_plane, grazing, unmoved };

/// The factor s that puts the point p (moved by m to p + m) on its ray, s p: where the ray meets
/// the plane through p + m with unit normal n, s = 1 + (n . m) / (n . p), computed as the part of
/// the move along the ray, a = (m . p) / |p|^2, plus the part across it carried onto the ray
/// through the plane, c = (n . m_across) / (n . p) (the same sum, but a move along the ray stays
/// exact whatever the bound and the weight below do). At a grazing angle (|n . p| < min_cos |p|)
/// |n . p| is taken as min_cos |p|, so that the part across the ray moves the point along it by
/// at most |m_across| / min_cos. The carried part is weighted by how far the plane can be
/// trusted: a plane turned by an angle e about p + m moves the crossing along the ray by about
/// L e / cos, L the distance from p + m to the crossing, cos = (n . p) / |p| (bounded as above);
/// with e the plane's angle spread (planeAngleSpread) and C = c |p| the carried move, the weight
/// C^2 / (C^2 + (L e / cos)^2) keeps the crossing where that error is small against the move and
/// falls back smoothly to the part along the ray (the point of the ray nearest to p + m) where it
/// is not. Without a plane (n = 0) only the part along the ray is kept.
double
rayScale(const Eigen::Vector3d& p, const Eigen::Vector3d& m, const Eigen::Vector3d& n, double angle_spread,
         double min_cos, Treatment& treatment)
{
  const double pp = p.squaredNorm(), length = std::sqrt(pp);
  const double along = m.dot(p) / pp;
  const Eigen::Vector3d across = m - along * p;
  double s = 1.0 + along;
  if (n.isZero()) {
    treatment = Treatment::grazing;
  } else {
    const double np = n.dot(p);
    const double least = min_cos * length;
    treatment = std::fabs(np) >= least ? Treatment::on_plane : Treatment::grazing;
    const double cosine = treatment == Treatment::on_plane ? np : (np < 0.0 ? -least : least);
    const double carried = n.dot(across) / cosine;
    const double slide = ((s + carried) * p - (p + m)).norm();
    const double error = slide * angle_spread * length / std::fabs(cosine);
    const double move = carried * length;
    const double weight = move * move / (move * move + error * error);
    if (std::isfinite(weight)) // 0 / 0: nothing carried
      s += weight * carried;
  }
  // Through the camera (a move no filter of a surface makes): the filtered range on the ray.
  return s > 0.0 && std::isfinite(s) ? s : (p + m).norm() / length;
}

} // namespace

void
RayReprojectionParameters::validate() const
{
  if (!(min_cos > 0.0 && min_cos <= 1.0))
    throw std::invalid_argument("ray re-projection: min_cos must be in (0, 1], got " + numberText(min_cos));
  if (window < 3 || window % 2 == 0 || window > 99)
    throw std::invalid_argument("ray re-projection: window must be an odd number of pixels from 3 to 99, got " +
                                std::to_string(window));
  if (!(range_gate > 0.0 && range_gate <= 1.0))
    throw std::invalid_argument("ray re-projection: range_gate must be in (0, 1], got " + numberText(range_gate));
}

Cloud
reprojectOntoRays(const Cloud& input, const Cloud& filtered, const RayReprojectionParameters& parameters,
                  RayReprojectionCounts* counts)
{
  parameters.validate();
  for (const Cloud* cloud : {&input, &filtered})
    if (cloud->empty() || static_cast<std::size_t>(cloud->width) * cloud->height != cloud->size())
      throw std::invalid_argument("ray re-projection: the " + std::string(cloud == &input ? "input" : "filtered") +
                                  " cloud of " + sizeText(*cloud) + " is empty or not organized");
  if (input.width != filtered.width || input.height != filtered.height)
    throw std::invalid_argument("ray re-projection: the filtered cloud is " + sizeText(filtered) + ", its input " +
                                sizeText(input) + "; give the cloud the filter was given");
  Cloud out = filtered;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const int w = static_cast<int>(filtered.width);
  std::size_t on_plane = 0, grazing = 0, unmoved = 0, without_ray = 0;
  bool dense = true;
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(out.size());
  const std::vector<Eigen::Vector3d> normals = surfaceNormals(filtered, parameters);
  // Each point is computed from the clouds as given: the result does not depend on the threads.
#pragma omp parallel for schedule(static) reduction(+ : on_plane, grazing, unmoved, without_ray) reduction(&& : dense)
  for (std::ptrdiff_t k = 0; k < size; ++k) {
    const std::size_t i = static_cast<std::size_t>(k);
    const pcl::PointXYZ& p = input[i];
    const pcl::PointXYZ& q = filtered[i];
    pcl::PointXYZ& o = out[i];
    if (!isValid(q)) {
      o.x = o.y = o.z = nan;
      dense = false;
      continue;
    }
    if (!isValid(p) || (p.x == 0.0f && p.y == 0.0f && p.z == 0.0f)) { // a filled hole: no ray
      ++without_ray;
      continue;
    }
    if (p.x == q.x && p.y == q.y && p.z == q.z) {
      ++unmoved;
      continue;
    }
    const Eigen::Vector3d from = vectorOf(p), to = vectorOf(q);
    const Eigen::Vector3d& normal = normals[i];
    const double spread = normal.isZero() ? 0.0
                                          : planeAngleSpread(filtered, normals, static_cast<int>(i % w),
                                                             static_cast<int>(i / w), to, normal, parameters);
    Treatment treatment;
    const double s = rayScale(from, to - from, normal, spread, parameters.min_cos, treatment);
    ++(treatment == Treatment::on_plane ? on_plane : grazing);
    o.x = static_cast<float>(s * p.x);
    o.y = static_cast<float>(s * p.y);
    o.z = static_cast<float>(s * p.z);
  }
  out.is_dense = dense;
  if (counts != nullptr)
    *counts = RayReprojectionCounts{on_plane, grazing, unmoved, without_ray};
  return out;
}

} // namespace range_nlm
