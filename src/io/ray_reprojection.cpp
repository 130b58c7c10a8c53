// Filtered points put back on their input points' rays: where the ray meets the filtered
// surface's tangent plane at the point (a plane fitted to the filtered points around it).
#include <range_nlm/io/ray_reprojection.h>

#include "ray_reprojection_builds.h"

#include "../core/simd/kernels.h"

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

/// Whether a point at range `point_range` lies within the range gate of a point at range `range`
/// (on its side of a depth edge).
bool
withinRangeGate(double point_range, double range, const RayReprojectionParameters& parameters)
{
  return std::fabs(point_range - range) <= parameters.range_gate * range;
}

bool
withinRangeGate(const Eigen::Vector3d& point, double range, const RayReprojectionParameters& parameters)
{
  return withinRangeGate(point.norm(), range, parameters);
}

/// The unit normal of the plane of a window's points from their moments (relative to the centre
/// point): the sum of the points, of their products (x x^T) and their count; zero if fewer than
/// kMinimumFitPoints, or if they lie on a line (or on one point).
Eigen::Vector3d
normalFromMoments(const Eigen::Vector3d& sum, const Eigen::Matrix3d& second, int count)
{
  constexpr int kMinimumFitPoints = 6;
  if (count < kMinimumFitPoints)
    return Eigen::Vector3d::Zero();
  const Eigen::Vector3d mean = sum / count;
  const Eigen::Matrix3d covariance = second / count - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(covariance);
  const Eigen::Vector3d normal = solver.eigenvectors().col(0);
  const Eigen::Vector3d values = solver.eigenvalues();
  if (!(values(1) > 0.0) || !normal.allFinite())
    return Eigen::Vector3d::Zero();
  return normal.normalized();
}

/// The unit normal of the plane fitted (least squares) to the filtered points of the window
/// around pixel (u, v) whose range is within range_gate of the range of `centre` (the filtered
/// surface on the point's side of a depth edge); zero if fewer than kMinimumFitPoints are.
Eigen::Vector3d
surfaceNormal(const Cloud& filtered, int u, int v, const Eigen::Vector3d& centre,
              const RayReprojectionParameters& parameters)
{
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
  return normalFromMoments(sum, second, count);
}

/// The filtered points as planes of doubles (x, y, z), NaN where a point is invalid and in a
/// border of `pad` pixels around the frame, so that every window read stays inside.
struct PaddedPoints
{
  int width = 0, height = 0, pad = 0;
  std::ptrdiff_t stride = 0;
  std::vector<double> x, y, z;

  PaddedPoints(const Cloud& cloud, int border)
    : width(static_cast<int>(cloud.width)), height(static_cast<int>(cloud.height)), pad(border),
      stride(static_cast<std::ptrdiff_t>(cloud.width) + 2 * border)
  {
    const std::size_t size = static_cast<std::size_t>(stride) * (static_cast<std::size_t>(height) + 2 * pad);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    x.assign(size, nan), y.assign(size, nan), z.assign(size, nan);
    const std::ptrdiff_t rows = height;
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t v = 0; v < rows; ++v)
      for (int u = 0; u < width; ++u) {
        const pcl::PointXYZ& p = cloud[static_cast<std::size_t>(v) * width + u];
        if (!isValid(p))
          continue;
        const std::size_t i = index(u, static_cast<int>(v));
        x[i] = p.x, y[i] = p.y, z[i] = p.z;
      }
  }
  std::size_t index(int u, int v) const
  {
    return static_cast<std::size_t>((static_cast<std::ptrdiff_t>(v) + pad) * stride + u + pad);
  }
};

/// Pixels of a row whose windows are summed together (one per vector lane of the widest build).
constexpr int kLanes = 8;

/// surfaceNormal's window sums for the pixels u0 .. u0 + kLanes - 1 of row v, those with `live`
/// set (in the frame, with a valid point), each lane with the operations of surfaceNormal in its
/// order: every window point is visited in turn, and one outside the frame, invalid (NaN) or
/// beyond the range gate adds +0 to sums that start at +0, which is what leaving it out gives.
/// Written so that a vectorizing build takes the lanes as vector lanes; this file is compiled
/// without contraction into fused multiply-adds, so every build gives surfaceNormal's bits.
[[gnu::always_inline]] inline void
laneWindowSums(const PaddedPoints& P, int u0, int v, int r, double range_gate, const bool* live,
               double (*sum)[kLanes], double (*second)[kLanes], int* count)
{
  // Everything a lane reads or adds up in arrays of the lanes' own (no aliasing with the outputs).
  double cx[kLanes], cy[kLanes], cz[kLanes], range[kLanes], gate[kLanes];
  double s0[kLanes], s1[kLanes], s2[kLanes], m00[kLanes], m01[kLanes], m02[kLanes], m11[kLanes], m12[kLanes],
      m22[kLanes];
  double n[kLanes], on[kLanes]; // (counts of at most 99 x 99 points: exact in double)
  const std::size_t centre = P.index(u0, v);
  for (int l = 0; l < kLanes; ++l) {
    cx[l] = P.x[centre + l], cy[l] = P.y[centre + l], cz[l] = P.z[centre + l];
    range[l] = std::sqrt((cx[l] * cx[l] + cy[l] * cy[l]) + cz[l] * cz[l]);
    gate[l] = range_gate * range[l];
    s0[l] = s1[l] = s2[l] = 0.0;
    m00[l] = m01[l] = m02[l] = m11[l] = m12[l] = m22[l] = 0.0;
    n[l] = 0.0;
    on[l] = live[l] ? 1.0 : 0.0;
  }
  const int first = std::max(0, v - r), last = std::min(P.height - 1, v + r);
  for (int b = first; b <= last; ++b)
    for (int a = -r; a <= r; ++a) {
      const std::size_t at = P.index(u0 + a, b);
      const double* __restrict px = P.x.data() + at;
      const double* __restrict py = P.y.data() + at;
      const double* __restrict pz = P.z.data() + at;
#pragma omp simd
      for (int l = 0; l < kLanes; ++l) {
        const double x0 = px[l] - cx[l], x1 = py[l] - cy[l], x2 = pz[l] - cz[l];
        const double q0 = x0 + cx[l], q1 = x1 + cy[l], q2 = x2 + cz[l];
        const double norm = std::sqrt((q0 * q0 + q1 * q1) + q2 * q2);
        // A NaN (invalid or outside the frame) fails the comparison.
        const bool in = on[l] > 0.0 && std::fabs(norm - range[l]) <= gate[l];
        const double y0 = in ? x0 : 0.0, y1 = in ? x1 : 0.0, y2 = in ? x2 : 0.0;
        s0[l] += y0, s1[l] += y1, s2[l] += y2;
        m00[l] += y0 * y0, m01[l] += y0 * y1, m02[l] += y0 * y2;
        m11[l] += y1 * y1, m12[l] += y1 * y2, m22[l] += y2 * y2;
        n[l] += in ? 1.0 : 0.0;
      }
    }
  for (int l = 0; l < kLanes; ++l) {
    sum[0][l] = s0[l], sum[1][l] = s1[l], sum[2][l] = s2[l];
    second[0][l] = m00[l], second[1][l] = m01[l], second[2][l] = m02[l];
    second[3][l] = m11[l], second[4][l] = m12[l], second[5][l] = m22[l];
    count[l] = static_cast<int>(n[l]);
  }
}

using LaneWindowSums = void (*)(const PaddedPoints&, int, int, int, double, const bool*, double (*)[kLanes],
                                double (*)[kLanes], int*);

void
laneWindowSumsBaseline(const PaddedPoints& P, int u0, int v, int r, double range_gate, const bool* live,
                       double (*sum)[kLanes], double (*second)[kLanes], int* count)
{
  laneWindowSums(P, u0, v, r, range_gate, live, sum, second, count);
}

#if defined(__x86_64__)
[[RANGE_NLM_TARGET_AVX2]] void
laneWindowSumsAvx2(const PaddedPoints& P, int u0, int v, int r, double range_gate, const bool* live,
                   double (*sum)[kLanes], double (*second)[kLanes], int* count)
{
  laneWindowSums(P, u0, v, r, range_gate, live, sum, second, count);
}

[[RANGE_NLM_TARGET_AVX512]] void
laneWindowSumsAvx512(const PaddedPoints& P, int u0, int v, int r, double range_gate, const bool* live,
                     double (*sum)[kLanes], double (*second)[kLanes], int* count)
{
  laneWindowSums(P, u0, v, r, range_gate, live, sum, second, count);
}
#endif

/// The ways of taking the windows this CPU runs, slowest first: pixel by pixel (surfaceNormal,
/// the reference; null), then the lane sums of each build.
std::vector<LaneWindowSums>
laneBuilds()
{
  std::vector<LaneWindowSums> all{nullptr, &laneWindowSumsBaseline};
#if defined(__x86_64__)
  if (detail::cpuRunsAvx2())
    all.push_back(&laneWindowSumsAvx2);
  if (detail::cpuRunsAvx512())
    all.push_back(&laneWindowSumsAvx512);
#endif
  return all;
}

LaneWindowSums
fastestLaneBuild()
{
  static const LaneWindowSums fastest = laneBuilds().back();
  return fastest;
}

/// surfaceNormal at every pixel whose filtered point is valid (zero elsewhere): a moved point
/// needs its own plane and those of the windows around it. With `sums` (a lane build) the
/// windows of kLanes pixels of a row are summed together; without, pixel by pixel.
std::vector<Eigen::Vector3d>
surfaceNormals(const Cloud& filtered, const RayReprojectionParameters& parameters, LaneWindowSums sums)
{
  const int w = static_cast<int>(filtered.width);
  std::vector<Eigen::Vector3d> normals(filtered.size(), Eigen::Vector3d::Zero());
  if (!sums) {
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
  const int r = parameters.window / 2;
  // A border of r pixels, and kLanes more for the lanes of a row's last block past its width.
  const PaddedPoints points(filtered, r + kLanes);
  const std::ptrdiff_t rows = static_cast<std::ptrdiff_t>(filtered.height);
#pragma omp parallel for schedule(dynamic, 4)
  for (std::ptrdiff_t row = 0; row < rows; ++row) {
    const int v = static_cast<int>(row);
    double sum[3][kLanes], second[6][kLanes];
    int count[kLanes];
    bool live[kLanes];
    for (int u0 = 0; u0 < w; u0 += kLanes) {
      bool any = false;
      for (int l = 0; l < kLanes; ++l) {
        live[l] = u0 + l < w && isValid(filtered[static_cast<std::size_t>(v) * w + u0 + l]);
        any = any || live[l];
      }
      if (!any)
        continue;
      sums(points, u0, v, r, parameters.range_gate, live, sum, second, count);
      for (int l = 0; l < kLanes; ++l) {
        if (!live[l])
          continue;
        const Eigen::Vector3d s(sum[0][l], sum[1][l], sum[2][l]);
        Eigen::Matrix3d m;
        m << second[0][l], second[1][l], second[2][l], second[1][l], second[3][l], second[4][l], second[2][l],
            second[4][l], second[5][l];
        normals[static_cast<std::size_t>(v) * w + u0 + l] = normalFromMoments(s, m, count[l]);
      }
    }
  }
  return normals;
}

/// How far the plane n at pixel (u, v) may be turned: the RMS sine of its angle to the planes of
/// the windows half a window away in the 8 directions (those on the point's side of a depth edge,
/// as surfaceNormal gates). On a plane they agree up to the filter's leftover noise; on bumps
/// the filter left, across creases and where a window straddles an edge, they do not. 1 (as
/// uncertain as an orientation can be) if no such window has a plane.
double
planeAngleSpread(const Cloud& filtered, const std::vector<Eigen::Vector3d>& normals,
                 const std::vector<double>& ranges, int u, int v, const Eigen::Vector3d& n,
                 const RayReprojectionParameters& parameters)
{
  const int w = static_cast<int>(filtered.width), h = static_cast<int>(filtered.height);
  const int step = parameters.window / 2;
  const double range = ranges[static_cast<std::size_t>(v) * w + u];
  double sum = 0.0;
  int count = 0;
  for (int b = -1; b <= 1; ++b)
    for (int a = -1; a <= 1; ++a) {
      const int x = u + a * step, y = v + b * step;
      if ((a == 0 && b == 0) || x < 0 || y < 0 || x >= w || y >= h)
        continue;
      const std::size_t j = static_cast<std::size_t>(y) * w + x;
      if (normals[j].isZero() || !withinRangeGate(ranges[j], range, parameters))
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

namespace
{

/// reprojectOntoRays with the windows' planes taken by `sums` (see surfaceNormals).
Cloud
reproject(const Cloud& input, const Cloud& filtered, const RayReprojectionParameters& parameters,
          RayReprojectionCounts* counts, LaneWindowSums sums)
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
  const std::vector<Eigen::Vector3d> normals = surfaceNormals(filtered, parameters, sums);
  // Each filtered point's range, once (the plane spread compares its neighbours' with it).
  std::vector<double> ranges(filtered.size(), 0.0);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t k = 0; k < size; ++k)
    if (isValid(filtered[static_cast<std::size_t>(k)]))
      ranges[static_cast<std::size_t>(k)] = vectorOf(filtered[static_cast<std::size_t>(k)]).norm();
  // Each point is computed from the clouds as given: the result does not depend on the threads.
#pragma omp parallel for schedule(dynamic, 2048) reduction(+ : on_plane, grazing, unmoved, without_ray) \
    reduction(&& : dense)
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
                                          : planeAngleSpread(filtered, normals, ranges, static_cast<int>(i % w),
                                                             static_cast<int>(i / w), normal, parameters);
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

} // namespace

Cloud
reprojectOntoRays(const Cloud& input, const Cloud& filtered, const RayReprojectionParameters& parameters,
                  RayReprojectionCounts* counts)
{
  return reproject(input, filtered, parameters, counts, fastestLaneBuild());
}

std::size_t
detail::rayReprojectionBuilds()
{
  return laneBuilds().size();
}

std::vector<Eigen::Vector3d>
detail::surfacePlaneNormalsWithBuild(std::size_t build, const Cloud& filtered,
                                     const RayReprojectionParameters& parameters)
{
  parameters.validate();
  return surfaceNormals(filtered, parameters, laneBuilds().at(build));
}

Cloud
detail::reprojectOntoRaysWithBuild(std::size_t build, const Cloud& input, const Cloud& filtered,
                                   const RayReprojectionParameters& parameters, RayReprojectionCounts* counts)
{
  return reproject(input, filtered, parameters, counts, laneBuilds().at(build));
}

} // namespace range_nlm
