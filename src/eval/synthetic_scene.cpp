// Analytic ray casting of the synthetic scenes and the depth-sensor noise models.
#include <range_nlm/eval/synthetic_scene.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

namespace range_nlm
{
namespace
{

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

constexpr double kPi = 3.14159265358979323846;

template <typename T>
[[noreturn]] void
fail(const char* name, T value, const char* requirement)
{
  std::ostringstream msg;
  msg << "range_nlm: scene option " << name << " = " << value << " is invalid: " << requirement;
  throw std::invalid_argument(msg.str());
}

double
degreesToRadians(double degrees)
{
  return degrees * kPi / 180.0;
}

/// Slab test of a ray (local coordinates) against the axis-aligned box |q_i| <= half_i.
/// Returns the entry and exit parameters and the axis of the entry face.
bool
slabs(const Vec3& o, const Vec3& d, const Vec3& half, double& t_near, double& t_far, int& near_axis)
{
  t_near = -std::numeric_limits<double>::infinity();
  t_far = std::numeric_limits<double>::infinity();
  near_axis = -1;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-300) {
      if (std::abs(o[i]) > half[i])
        return false;
      continue;
    }
    double t1 = (-half[i] - o[i]) / d[i];
    double t2 = (half[i] - o[i]) / d[i];
    if (t1 > t2)
      std::swap(t1, t2);
    if (t1 > t_near) {
      t_near = t1;
      near_axis = i;
    }
    t_far = std::min(t_far, t2);
    if (t_near > t_far)
      return false;
  }
  return near_axis >= 0;
}

/// Euclidean signed distance to the axis-aligned box |q_i| <= half_i (negative inside).
double
boxSignedDistance(const Vec3& q, const Vec3& half)
{
  const Vec3 excess = q.cwiseAbs() - half;
  const double outside = excess.cwiseMax(0.0).norm();
  const double inside = std::min(excess.maxCoeff(), 0.0);
  return outside + inside;
}

/// Outward normal of the face of the axis-aligned box nearest to q.
Vec3
boxFaceNormal(const Vec3& q, const Vec3& half)
{
  int axis = 0;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    const double gap = std::abs(std::abs(q[i]) - half[i]);
    if (gap < best) {
      best = gap;
      axis = i;
    }
  }
  Vec3 n = Vec3::Zero();
  n[axis] = q[axis] >= 0.0 ? 1.0 : -1.0;
  return n;
}

/// A finite rectangle: centre, two orthonormal in-plane axes, half extents; normal axis_u x axis_v.
class Rectangle final : public Shape
{
public:
  Rectangle(const Vec3& center, const Vec3& axis_u, const Vec3& axis_v, double half_u, double half_v)
      : center_(center), u_(axis_u.normalized()), v_(axis_v.normalized()), half_u_(half_u), half_v_(half_v),
        n_(u_.cross(v_).normalized())
  {}

  bool intersect(const Vec3& origin, const Vec3& direction, double t_min, double& t, Vec3& normal) const override
  {
    const double dn = direction.dot(n_);
    if (std::abs(dn) < 1e-300)
      return false;
    const double hit = (center_ - origin).dot(n_) / dn;
    if (!(hit > t_min))
      return false;
    const Vec3 q = origin + hit * direction - center_;
    if (std::abs(q.dot(u_)) > half_u_ || std::abs(q.dot(v_)) > half_v_)
      return false;
    t = hit;
    normal = n_;
    return true;
  }

  double surfaceDistance(const Vec3& p) const override
  {
    const Vec3 q = p - center_;
    const double a = std::max(std::abs(q.dot(u_)) - half_u_, 0.0);
    const double b = std::max(std::abs(q.dot(v_)) - half_v_, 0.0);
    const double c = q.dot(n_);
    return std::sqrt(a * a + b * b + c * c);
  }

  Vec3 normalAt(const Vec3&) const override { return n_; }
  std::string name() const override { return "rectangle"; }

private:
  Vec3 center_, u_, v_;
  double half_u_, half_v_;
  Vec3 n_;
};

/// An infinite plane n . (p - point) = 0.
class Plane final : public Shape
{
public:
  Plane(const Vec3& point, const Vec3& normal) : point_(point), n_(normal.normalized()) {}

  bool intersect(const Vec3& origin, const Vec3& direction, double t_min, double& t, Vec3& normal) const override
  {
    const double dn = direction.dot(n_);
    if (std::abs(dn) < 1e-300)
      return false;
    const double hit = (point_ - origin).dot(n_) / dn;
    if (!(hit > t_min))
      return false;
    t = hit;
    normal = n_;
    return true;
  }
  double surfaceDistance(const Vec3& p) const override { return std::abs((p - point_).dot(n_)); }
  Vec3 normalAt(const Vec3&) const override { return n_; }
  std::string name() const override { return "plane"; }

private:
  Vec3 point_, n_;
};

/// An oriented box: centre, rotation (columns = local axes), half extents.
class Box final : public Shape
{
public:
  Box(const Vec3& center, const Mat3& rotation, const Vec3& half) : center_(center), r_(rotation), half_(half) {}

  bool intersect(const Vec3& origin, const Vec3& direction, double t_min, double& t, Vec3& normal) const override
  {
    const Vec3 o = r_.transpose() * (origin - center_);
    const Vec3 d = r_.transpose() * direction;
    double t_near, t_far;
    int axis;
    if (!slabs(o, d, half_, t_near, t_far, axis) || !(t_near > t_min))
      return false;
    Vec3 n = Vec3::Zero();
    n[axis] = d[axis] > 0.0 ? -1.0 : 1.0;
    t = t_near;
    normal = r_ * n;
    return true;
  }
  double surfaceDistance(const Vec3& p) const override
  {
    return std::abs(boxSignedDistance(r_.transpose() * (p - center_), half_));
  }
  Vec3 normalAt(const Vec3& p) const override { return r_ * boxFaceNormal(r_.transpose() * (p - center_), half_); }
  std::string name() const override { return "box"; }

private:
  Vec3 center_;
  Mat3 r_;
  Vec3 half_;
};

class Sphere final : public Shape
{
public:
  Sphere(const Vec3& center, double radius) : center_(center), radius_(radius) {}

  bool intersect(const Vec3& origin, const Vec3& direction, double t_min, double& t, Vec3& normal) const override
  {
    // |o + t d - c|^2 = r^2, roots in the numerically stable form.
    const Vec3 oc = origin - center_;
    const double a = direction.squaredNorm();
    const double b = oc.dot(direction);
    const double c = oc.squaredNorm() - radius_ * radius_;
    const double disc = b * b - a * c;
    if (disc < 0.0)
      return false;
    const double q = -(b + std::copysign(std::sqrt(disc), b));
    double t1 = q / a, t2 = (q != 0.0) ? c / q : t1;
    if (t1 > t2)
      std::swap(t1, t2);
    const double hit = t1 > t_min ? t1 : t2;
    if (!(hit > t_min))
      return false;
    t = hit;
    normal = (origin + hit * direction - center_) / radius_;
    return true;
  }
  double surfaceDistance(const Vec3& p) const override { return std::abs((p - center_).norm() - radius_); }
  Vec3 normalAt(const Vec3& p) const override { return (p - center_).normalized(); }
  std::string name() const override { return "sphere"; }

private:
  Vec3 center_;
  double radius_;
};

/// A capped cylinder: centre of the axis segment, unit axis, radius, half height.
class Cylinder final : public Shape
{
public:
  Cylinder(const Vec3& center, const Vec3& axis, double radius, double half_height)
      : center_(center), axis_(axis.normalized()), radius_(radius), half_height_(half_height)
  {}

  bool intersect(const Vec3& origin, const Vec3& direction, double t_min, double& t, Vec3& normal) const override
  {
    const Vec3 o = origin - center_;
    const double oa = o.dot(axis_), da = direction.dot(axis_);
    const Vec3 op = o - oa * axis_, dp = direction - da * axis_;
    double best = std::numeric_limits<double>::infinity();
    Vec3 best_normal = Vec3::Zero();
    // Side: |op + t dp|^2 = r^2 with |oa + t da| <= half height.
    const double a = dp.squaredNorm();
    if (a > 1e-300) {
      const double b = op.dot(dp);
      const double c = op.squaredNorm() - radius_ * radius_;
      const double disc = b * b - a * c;
      if (disc >= 0.0) {
        const double q = -(b + std::copysign(std::sqrt(disc), b));
        const double roots[2] = {q / a, q != 0.0 ? c / q : q / a};
        for (double root : roots) {
          if (root > t_min && root < best && std::abs(oa + root * da) <= half_height_) {
            best = root;
            best_normal = (op + root * dp) / radius_;
          }
        }
      }
    }
    // Caps: planes at +-half height along the axis, within the radius.
    if (std::abs(da) > 1e-300) {
      for (double side : {-1.0, 1.0}) {
        const double root = (side * half_height_ - oa) / da;
        if (root > t_min && root < best && (op + root * dp).squaredNorm() <= radius_ * radius_) {
          best = root;
          best_normal = side * axis_;
        }
      }
    }
    if (!std::isfinite(best))
      return false;
    t = best;
    normal = best_normal.normalized();
    return true;
  }
  double surfaceDistance(const Vec3& p) const override
  {
    const Vec3 q = p - center_;
    const double along = q.dot(axis_);
    const double dr = (q - along * axis_).norm() - radius_;
    const double dh = std::abs(along) - half_height_;
    const double outside = std::hypot(std::max(dr, 0.0), std::max(dh, 0.0));
    const double inside = std::min(std::max(dr, dh), 0.0);
    return std::abs(outside + inside);
  }
  Vec3 normalAt(const Vec3& p) const override
  {
    const Vec3 q = p - center_;
    const double along = q.dot(axis_);
    const Vec3 radial = q - along * axis_;
    if (std::abs(radial.norm() - radius_) < std::abs(std::abs(along) - half_height_))
      return radial.normalized();
    return along >= 0.0 ? axis_ : Vec3(-axis_);
  }
  std::string name() const override { return "cylinder"; }

private:
  Vec3 center_, axis_;
  double radius_, half_height_;
};

/// A panel with fine ridges: a base box (local s in [-Ls, Ls], t in [-Lt, Lt], w in [-D, 0]) and
/// on its w = 0 face a triangular ridge profile w = h(s) = A * tri(s / P), tri rising from 0 at
/// s = 0 to 1 at s = P/2 and back to 0 at s = P; ridges run along t. Ls is a whole number of
/// periods so the profile ends in valleys; the ridges' ends at t = +-Lt are closed by flat faces.
/// Local axes (columns of the rotation): s, t, w (w points out of the ridged face).
class RidgedPanel final : public Shape
{
public:
  RidgedPanel(const Vec3& center, const Mat3& rotation, double half_s, double half_t, double depth,
              double ridge_height, double ridge_period)
      : center_(center), r_(rotation), half_s_(half_s), half_t_(half_t), depth_(depth), height_(ridge_height),
        period_(ridge_period)
  {}

  bool intersect(const Vec3& origin, const Vec3& direction, double t_min, double& t, Vec3& normal) const override
  {
    const Vec3 o = r_.transpose() * (origin - center_);
    const Vec3 d = r_.transpose() * direction;
    double best = std::numeric_limits<double>::infinity();
    Vec3 best_normal = Vec3::Zero();

    // Base box, centred at w = -D/2.
    {
      const Vec3 half(half_s_, half_t_, 0.5 * depth_);
      double t_near, t_far;
      int axis;
      if (slabs(o - Vec3(0, 0, -0.5 * depth_), d, half, t_near, t_far, axis) && t_near > t_min) {
        best = t_near;
        best_normal = Vec3::Zero();
        best_normal[axis] = d[axis] > 0.0 ? -1.0 : 1.0;
      }
    }

    // Ridge facets, only over the part of the ray inside the ridges' bounding box.
    const Vec3 ridge_half(half_s_, half_t_, 0.5 * height_);
    const Vec3 ridge_center(0, 0, 0.5 * height_);
    double t0, t1;
    int axis;
    if (slabs(o - ridge_center, d, ridge_half, t0, t1, axis) && t1 > t_min) {
      const double half_period = 0.5 * period_;
      const double slope = 2.0 * height_ / period_;
      const double s0 = o[0] + t0 * d[0], s1 = o[0] + t1 * d[0];
      const long last_facet = std::lround(2.0 * half_s_ / period_) - 1; // facets -last-1 .. last
      long k_begin = static_cast<long>(std::floor(std::min(s0, s1) / half_period)) - 1;
      long k_end = static_cast<long>(std::floor(std::max(s0, s1) / half_period)) + 1;
      k_begin = std::max(k_begin, -last_facet - 1);
      k_end = std::min(k_end, last_facet);
      const double tolerance = 1e-12;
      for (long k = k_begin; k <= k_end; ++k) {
        // On facet k, h(s) = alpha + beta s.
        const bool rising = (k % 2 + 2) % 2 == 0;
        const double beta = rising ? slope : -slope;
        const double alpha = rising ? -height_ * double(k) : height_ * double(k + 1);
        const double denom = d[2] - beta * d[0];
        if (std::abs(denom) < 1e-300)
          continue;
        const double root = (alpha + beta * o[0] - o[2]) / denom;
        if (!(root > t_min) || root >= best)
          continue;
        const double s = o[0] + root * d[0];
        if (s < k * half_period - tolerance || s > (k + 1) * half_period + tolerance)
          continue;
        if (std::abs(s) > half_s_ || std::abs(o[1] + root * d[1]) > half_t_)
          continue;
        best = root;
        best_normal = Vec3(-beta, 0.0, 1.0).normalized();
      }
      // End faces of the ridges at t = +-Lt, between the base and the profile.
      if (std::abs(d[1]) > 1e-300) {
        for (double side : {-1.0, 1.0}) {
          const double root = (side * half_t_ - o[1]) / d[1];
          if (!(root > t_min) || root >= best)
            continue;
          const double s = o[0] + root * d[0], w = o[2] + root * d[2];
          if (std::abs(s) <= half_s_ && w >= 0.0 && w <= profile(s)) {
            best = root;
            best_normal = Vec3(0.0, side, 0.0);
          }
        }
      }
    }
    if (!std::isfinite(best))
      return false;
    t = best;
    normal = r_ * best_normal;
    return true;
  }

  double surfaceDistance(const Vec3& p) const override
  {
    const Vec3 q = r_.transpose() * (p - center_);
    double distance = std::abs(boxSignedDistance(q - Vec3(0, 0, -0.5 * depth_), Vec3(half_s_, half_t_, 0.5 * depth_)));
    if (std::abs(q[0]) <= half_s_ && std::abs(q[1]) <= half_t_)
      distance = std::min(distance, std::abs(q[2] - profile(q[0])));
    if (std::abs(q[0]) <= half_s_ && q[2] >= 0.0 && q[2] <= profile(q[0]))
      distance = std::min(distance, std::abs(std::abs(q[1]) - half_t_));
    return distance;
  }

  Vec3 normalAt(const Vec3& p) const override
  {
    const Vec3 q = r_.transpose() * (p - center_);
    const Vec3 base_q = q - Vec3(0, 0, -0.5 * depth_);
    const Vec3 base_half(half_s_, half_t_, 0.5 * depth_);
    double best = std::abs(boxSignedDistance(base_q, base_half));
    Vec3 n = boxFaceNormal(base_q, base_half);
    if (std::abs(q[0]) <= half_s_ && std::abs(q[1]) <= half_t_) {
      const double gap = std::abs(q[2] - profile(q[0]));
      if (gap <= best) {
        best = gap;
        const bool rising = std::fmod(std::fmod(q[0], period_) + period_, period_) < 0.5 * period_;
        const double beta = (rising ? 2.0 : -2.0) * height_ / period_;
        n = Vec3(-beta, 0.0, 1.0).normalized();
      }
    }
    if (std::abs(q[0]) <= half_s_ && q[2] >= 0.0 && q[2] <= profile(q[0])) {
      const double gap = std::abs(std::abs(q[1]) - half_t_);
      if (gap < best)
        n = Vec3(0.0, q[1] >= 0.0 ? 1.0 : -1.0, 0.0);
    }
    return r_ * n;
  }
  std::string name() const override { return "ridged panel"; }

private:
  /// h(s) = A * tri(s / P).
  double profile(double s) const
  {
    const double x = s / period_;
    const double frac = x - std::floor(x);
    return height_ * (1.0 - std::abs(2.0 * frac - 1.0));
  }

  Vec3 center_;
  Mat3 r_;
  double half_s_, half_t_, depth_, height_, period_;
};

Mat3
rotation(double yaw_degrees, double pitch_degrees)
{
  return (Eigen::AngleAxisd(degreesToRadians(yaw_degrees), Vec3::UnitY()) *
          Eigen::AngleAxisd(degreesToRadians(pitch_degrees), Vec3::UnitX()))
      .toRotationMatrix();
}

/// The shapes of SceneType::steps. Every surface is planar, so each edge and crease is exact: the
/// risers and treads of the stairs meet in convex and concave creases, the steps end in depth
/// edges against the floor and wall, the tilted panel is seen at a steep angle and the folded
/// panel has one concave crease.
std::vector<std::shared_ptr<const Shape>>
stepsShapes()
{
  std::vector<std::shared_ptr<const Shape>> shapes;
  // Room: floor at y = 0.55 m (seen from 1.2 m on), back wall at z = 3 m; both finite.
  const double floor_y = 0.55, wall_z = 3.0;
  shapes.push_back(std::make_shared<Rectangle>(Vec3(0.1, floor_y, 1.9), Vec3::UnitX(), Vec3::UnitZ(), 1.5, 1.1));
  shapes.push_back(std::make_shared<Rectangle>(Vec3(0.1, -0.2, wall_z), Vec3::UnitY(), Vec3::UnitX(), 0.75, 1.5));
  // Staircase of three steps 0.10, 0.22 and 0.30 m high (uneven risers), treads 0.18 m deep,
  // climbing away from the camera, turned 30 degrees so that risers and treads are seen obliquely.
  const Mat3 stair = rotation(30.0, 0.0);
  const Vec3 foot(-0.35, floor_y, 1.6);
  const double tread = 0.18, half_width = 0.3;
  const double heights[] = {0.10, 0.22, 0.30};
  for (int i = 0; i < 3; ++i) {
    const Vec3 centre = foot + stair * Vec3(0.0, -0.5 * heights[i], (i + 0.5) * tread);
    shapes.push_back(std::make_shared<Box>(centre, stair, Vec3(half_width, 0.5 * heights[i], 0.5 * tread)));
  }
  // Tilted panel at 0.85 m - 1.15 m: turned 50 degrees and pitched 20 degrees. (Each
  // rectangle's normal axis_u x axis_v faces the camera, as the truth normals do.)
  const Mat3 tilt = rotation(-50.0, 20.0);
  shapes.push_back(
      std::make_shared<Rectangle>(Vec3(0.45, 0.0, 1.0), tilt * Vec3::UnitY(), tilt * Vec3::UnitX(), 0.2, 0.18));
  // Folded panel (a dihedral opening toward the camera): two 0.35 m wide halves meeting in a
  // vertical concave crease at x = 0.05 m, z = 1.9 m, each turned 40 degrees.
  const Vec3 hinge(0.05, -0.25, 1.9);
  for (double side : {-1.0, 1.0}) {
    const Vec3 along(side * std::cos(degreesToRadians(40.0)), 0.0, -std::sin(degreesToRadians(40.0)));
    shapes.push_back(std::make_shared<Rectangle>(hinge + 0.175 * along, along, -side * Vec3::UnitY(), 0.175, 0.2));
  }
  return shapes;
}

/// The shapes of SceneType::ridges: one plate filling the view, turned to it, whose front face
/// (local -z, toward the camera) carries every feature, so that all of them are small: boxes on
/// the face (terraces, ridges) or layers of it cut apart (grooves). Every surface is planar and
/// each edge and crease exact.
std::vector<std::shared_ptr<const Shape>>
ridgesShapes()
{
  std::vector<std::shared_ptr<const Shape>> shapes;
  const Vec3 center(0.0, 0.0, 1.1);
  const Mat3 r = rotation(15.0, 8.0);
  // A box spanning local [x0, x1] x [y0, y1] x [z0, z1] of the plate (z = 0: the face).
  auto slab = [&](double x0, double x1, double y0, double y1, double z0, double z1) {
    const Vec3 local(0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1));
    shapes.push_back(
        std::make_shared<Box>(center + r * local, r, Vec3(0.5 * (x1 - x0), 0.5 * (y1 - y0), 0.5 * (z1 - z0))));
  };
  slab(-1.0, 1.0, -0.8, 0.8, 0.0, 0.03);
  const double sizes[] = {0.002, 0.003, 0.004, 0.005};
  // Upper left: terraces rising by 2, 3, 4 and 5 mm and falling by 5, 4, 3 and 2 mm, 45 mm apart.
  double rise = 0.0;
  for (int i = 0; i < 4; ++i) {
    rise += sizes[i];
    slab(-0.5 + 0.045 * i, -0.05 - 0.045 * i, -0.38, -0.03, -rise, 0.0);
  }
  // Upper right: ridges 4 mm wide and 2, 3, 4 and 5 mm high, 60 mm apart.
  for (int i = 0; i < 4; ++i) {
    const double x = 0.08 + 0.06 * i;
    slab(x - 0.002, x + 0.002, -0.38, -0.03, -sizes[i], 0.0);
  }
  // Lower half: a layer 5 mm proud of the face (a 5 mm step along its top edge) with grooves 6 mm
  // wide and 2, 3, 4 and 5 mm deep, 100 mm apart.
  const double layer = 0.005;
  double x = -0.6;
  for (int i = 0; i < 4; ++i) {
    const double g = -0.3 + 0.1 * i;
    slab(x, g - 0.003, 0.03, 0.5, -layer, 0.0);
    if (layer - sizes[i] > 0.0)
      slab(g - 0.003, g + 0.003, 0.03, 0.5, -(layer - sizes[i]), 0.0);
    x = g + 0.003;
  }
  slab(x, 0.6, 0.03, 0.5, -layer, 0.0);
  return shapes;
}

/// Uniform in [0, 1) from the top 53 bits: the same sequence on every platform.
double
uniform(std::mt19937_64& rng)
{
  return double(rng() >> 11) * 0x1.0p-53;
}

/// N(0, 1) from two uniforms (Box-Muller, cosine branch).
double
gaussian(std::mt19937_64& rng)
{
  const double u1 = uniform(rng), u2 = uniform(rng);
  return std::sqrt(-2.0 * std::log(1.0 - u1)) * std::cos(2.0 * kPi * u2);
}

/// Rounds x to a multiple of step; step 0 leaves x unchanged.
double
quantize(double x, double step)
{
  return step > 0.0 ? std::round(x / step) * step : x;
}

/// The random stream of a sensor model: its own stream per frame (seed, frame and model), so the
/// draws of the older models stay as they were.
std::mt19937_64
sensorStream(const SceneOptions& options, int frame)
{
  std::seed_seq seq{std::uint32_t(options.seed & 0xffffffffu), std::uint32_t(options.seed >> 32),
                    std::uint32_t(frame), std::uint32_t(0x5e750000u + unsigned(options.noise))};
  return std::mt19937_64(seq);
}

/// A fresh N(0, 1) field of width x height with autocorrelation exp(-(lag / length)^2): white
/// noise on a padded grid blurred by a separable Gaussian of sigma length / 2 and divided by the
/// blur's L2 norm, so the variance is exactly 1. length 0 gives white noise.
std::vector<double>
correlatedField(int width, int height, double length, std::mt19937_64& rng)
{
  const double sigma = 0.5 * length;
  const int radius = sigma > 0.0 ? int(std::ceil(4.0 * sigma)) : 0;
  std::vector<double> kernel(std::size_t(2 * radius + 1), 1.0);
  if (radius > 0) {
    double sum = 0.0;
    for (int k = -radius; k <= radius; ++k)
      sum += kernel[std::size_t(k + radius)] = std::exp(-0.5 * k * k / (sigma * sigma));
    for (double& w : kernel)
      w /= sum;
  }
  double norm_sq = 0.0;
  for (double w : kernel)
    norm_sq += w * w;
  // 2-D separable kernel: sum of squared weights is (sum_k w_k^2)^2; its root is norm_sq.
  const double renormalise = 1.0 / norm_sq;
  const int pw = width + 2 * radius, ph = height + 2 * radius;
  std::vector<double> white(std::size_t(pw) * ph);
  for (double& x : white)
    x = gaussian(rng);
  std::vector<double> rows(std::size_t(width) * ph);
  for (int y = 0; y < ph; ++y)
    for (int x = 0; x < width; ++x) {
      double acc = 0.0;
      for (int k = 0; k <= 2 * radius; ++k)
        acc += kernel[std::size_t(k)] * white[std::size_t(y) * pw + x + k];
      rows[std::size_t(y) * width + x] = acc;
    }
  std::vector<double> field(std::size_t(width) * height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      double acc = 0.0;
      for (int k = 0; k <= 2 * radius; ++k)
        acc += kernel[std::size_t(k)] * rows[std::size_t(y + k) * width + x];
      field[std::size_t(y) * width + x] = acc * renormalise;
    }
  return field;
}

/// Whether pixel (u, v) carries a dot of the kinect1 projector pattern: a fixed hash of the
/// position, one dot in about three pixels, the same for every seed and frame.
bool
kinectDot(int u, int v)
{
  std::uint64_t h = (std::uint64_t(std::uint32_t(u)) << 32) ^ std::uint32_t(v);
  h += 0x9e3779b97f4a7c15ull;
  h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ull;
  h = (h ^ (h >> 27)) * 0x94d049bb133111ebull;
  h ^= h >> 31;
  return h % 3 == 0;
}

/// Per-pixel inputs of the sensor models.
struct SensorInput
{
  const SceneOptions& options;
  const std::vector<int>& shape_index;
  const std::vector<double>& depth;
  const std::vector<double>& cosine;
  double cx, cy;
};

/// Sets q to the point of pixel (u, v) at depth z, NaN unless z is finite and > 0.
bool
placeOnRay(const SensorInput& in, int u, int v, double z, pcl::PointXYZ& q)
{
  if (!(std::isfinite(z) && z > 0.0))
    return false;
  q.x = float((u - in.cx) / in.options.fx * z);
  q.y = float((v - in.cy) / in.options.fy * z);
  q.z = float(z);
  return true;
}

/// Stereo: disparity-domain noise, partly correlated, quantized. Draws: the correlated field
/// (padded grid, row-major), then per pixel in scan order a white normal (two uniforms) and a
/// dropout uniform, whether or not the pixel is hit.
bool
applyStereo(const SensorInput& in, std::mt19937_64& rng, pcl::PointCloud<pcl::PointXYZ>& noisy)
{
  const SceneOptions& o = in.options;
  const int width = o.width, height = o.height;
  const double fb = o.fx * o.stereo_baseline;
  const double sigma = o.effectiveNoiseScale() * o.stereo_disparity_sigma;
  const double share = o.stereo_correlated_share;
  const std::vector<double> field = share > 0.0 ? correlatedField(width, height, o.stereo_correlation_length, rng)
                                                : std::vector<double>(std::size_t(width) * height, 0.0);
  const double a = std::sqrt(1.0 - share), b = std::sqrt(share);
  const double cos_grazing = std::cos(degreesToRadians(o.grazing_dropout));
  const bool grazing_enabled = o.grazing_dropout < 90.0;
  bool dense = true;
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = std::size_t(v) * width + u;
      const double white = gaussian(rng);
      const double drop = uniform(rng);
      if (in.shape_index[i] < 0 || drop < o.dropout || (grazing_enabled && in.cosine[i] < cos_grazing)) {
        dense = false;
        continue;
      }
      const double d = fb / in.depth[i];
      const double measured = quantize(d + sigma * (a * white + b * field[i]), o.stereo_subpixel);
      if (!(measured > 0.0) || !placeOnRay(in, u, v, fb / measured, noisy[i]))
        dense = false;
    }
  return dense;
}

/// kinect1 (simkinect): shifted bilinear disparity, block consistency against the dot pattern,
/// disparity noise, quantization, depth rounding. Draws: per pixel in scan order two normals
/// (the shifts), then per pixel in scan order a normal (disparity noise) and a dropout uniform.
bool
applyKinect1(const SensorInput& in, std::mt19937_64& rng, pcl::PointCloud<pcl::PointXYZ>& noisy)
{
  const SceneOptions& o = in.options;
  const int width = o.width, height = o.height;
  const double fb = o.fx * o.kinect1_baseline;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> disparity;
  disparity.assign(std::size_t(width) * height, nan);
  for (std::size_t i = 0; i < disparity.size(); ++i)
    if (in.shape_index[i] >= 0)
      disparity[i] = fb / in.depth[i];

  // Bilinear samples at shifted positions; NaN if a corner is outside the image or has no surface.
  std::vector<double> shifted;
  shifted.assign(disparity.size(), nan);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const double x = u + o.kinect1_shift_sigma * gaussian(rng);
      const double y = v + o.kinect1_shift_sigma * gaussian(rng);
      const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
      if (x0 < 0 || y0 < 0 || x0 + 1 >= width || y0 + 1 >= height)
        continue;
      const double fx = x - x0, fy = y - y0;
      const std::size_t i00 = std::size_t(y0) * width + x0, i10 = i00 + 1, i01 = i00 + width, i11 = i01 + 1;
      shifted[std::size_t(v) * width + u] =
          (1.0 - fy) * ((1.0 - fx) * disparity[i00] + fx * disparity[i10]) +
          fy * ((1.0 - fx) * disparity[i01] + fx * disparity[i11]);
    }

  const int half = o.kinect1_block / 2;
  const double cos_grazing = std::cos(degreesToRadians(o.grazing_dropout));
  const bool grazing_enabled = o.grazing_dropout < 90.0;
  bool dense = true;
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = std::size_t(v) * width + u;
      const double noise = gaussian(rng);
      const double drop = uniform(rng);
      if (in.shape_index[i] < 0 || drop < o.dropout || (grazing_enabled && in.cosine[i] < cos_grazing) ||
          !std::isfinite(shifted[i]) || u < half || v < half || u + half >= width || v + half >= height) {
        dense = false;
        continue;
      }
      // Block consistency: mean over the dots, then inliers by weighted difference. A dot without
      // a surface makes the mean meaningless (simkinect: depth 0, an infinite disparity).
      double sum = 0.0;
      int dots = 0;
      bool consistent = true;
      for (int dv = -half; dv <= half; ++dv)
        for (int du = -half; du <= half; ++du)
          if (kinectDot(u + du, v + dv)) {
            ++dots;
            const double s = shifted[std::size_t(v + dv) * width + u + du];
            consistent = consistent && std::isfinite(s);
            sum += s;
          }
      consistent = consistent && dots > 0;
      if (consistent) {
        const int finite = dots;
        const double mean = sum / finite;
        int inliers = 0;
        for (int dv = -half; dv <= half; ++dv)
          for (int du = -half; du <= half; ++du)
            if (kinectDot(u + du, v + dv)) {
              const double s = shifted[std::size_t(v + dv) * width + u + du];
              const double weight = 1.0 / (1.44 * std::max(du * du + dv * dv, 1));
              inliers += std::isfinite(s) && std::abs(s - mean) * weight < o.kinect1_block_threshold;
            }
        consistent = inliers * 1.2 > dots;
      }
      if (!consistent) {
        dense = false;
        continue;
      }
      const double sigma = o.effectiveNoiseScale() * o.kinect1_disparity_sigma;
      const double measured = quantize(shifted[i] + sigma * noise, o.kinect1_subpixel);
      if (!(measured > 0.0) || !placeOnRay(in, u, v, quantize(fb / measured, o.kinect1_depth_unit), noisy[i]))
        dense = false;
    }
  return dense;
}

/// tof: mixed pixels at depth discontinuities, range noise growing with range. Draws: per pixel
/// in scan order a mixing uniform, a mixing fraction uniform, a normal (two uniforms) and a
/// dropout uniform.
bool
applyTof(const SensorInput& in, std::mt19937_64& rng, pcl::PointCloud<pcl::PointXYZ>& noisy)
{
  const SceneOptions& o = in.options;
  const int width = o.width, height = o.height;
  // Range per unit depth of each pixel's ray.
  auto rayLength = [&](int u, int v) {
    const double x = (u - in.cx) / o.fx, y = (v - in.cy) / o.fy;
    return std::sqrt(x * x + y * y + 1.0);
  };
  std::vector<double> range(in.depth.size(), 0.0);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = std::size_t(v) * width + u;
      if (in.shape_index[i] >= 0)
        range[i] = in.depth[i] * rayLength(u, v);
    }
  // Discontinuity seeds: hit pixels with a hit 8-neighbour whose range differs by more than the jump.
  std::vector<unsigned char> seed(range.size(), 0);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = std::size_t(v) * width + u;
      if (in.shape_index[i] < 0)
        continue;
      for (int dv = -1; dv <= 1 && !seed[i]; ++dv)
        for (int du = -1; du <= 1; ++du) {
          const int nu = u + du, nv = v + dv;
          if (nu < 0 || nv < 0 || nu >= width || nv >= height)
            continue;
          const std::size_t j = std::size_t(nv) * width + nu;
          if (in.shape_index[j] >= 0 && std::abs(range[j] - range[i]) > o.tof_edge_jump * std::min(range[i], range[j])) {
            seed[i] = 1;
            break;
          }
        }
    }
  const int band = o.tof_edge_band;
  const double cos_grazing = std::cos(degreesToRadians(o.grazing_dropout));
  const bool grazing_enabled = o.grazing_dropout < 90.0;
  bool dense = true;
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = std::size_t(v) * width + u;
      const double mix = uniform(rng), fraction = uniform(rng);
      const double noise = gaussian(rng);
      const double drop = uniform(rng);
      if (in.shape_index[i] < 0 || drop < o.dropout || (grazing_enabled && in.cosine[i] < cos_grazing)) {
        dense = false;
        continue;
      }
      double r = range[i];
      if (band > 0 && mix < o.tof_mixed_probability) {
        double r_near = r, r_far = r;
        bool near_edge = false;
        for (int dv = -band; dv <= band; ++dv)
          for (int du = -band; du <= band; ++du) {
            const int nu = u + du, nv = v + dv;
            if (nu < 0 || nv < 0 || nu >= width || nv >= height)
              continue;
            const std::size_t j = std::size_t(nv) * width + nu;
            if (in.shape_index[j] < 0)
              continue;
            near_edge = near_edge || seed[j];
            r_near = std::min(r_near, range[j]);
            r_far = std::max(r_far, range[j]);
          }
        if (near_edge)
          r = (1.0 - fraction) * r_near + fraction * r_far;
      }
      const double sigma = o.effectiveNoiseScale() * (o.tof_sigma + o.tof_sigma_slope * r);
      const double measured = r + sigma * noise;
      if (!placeOnRay(in, u, v, measured / rayLength(u, v), noisy[i]))
        dense = false;
    }
  return dense;
}

} // namespace

SceneType
sceneTypeFromString(const std::string& name)
{
  if (name == "boxes")
    return SceneType::boxes;
  if (name == "plane")
    return SceneType::plane;
  if (name == "steps")
    return SceneType::steps;
  if (name == "ridges")
    return SceneType::ridges;
  throw std::invalid_argument("unknown scene '" + name + "' (expected boxes, plane, steps or ridges)");
}

NoiseModel
noiseModelFromString(const std::string& name)
{
  if (name == "none")
    return NoiseModel::none;
  if (name == "kinect")
    return NoiseModel::kinect;
  if (name == "laser")
    return NoiseModel::laser;
  if (name == "stripes")
    return NoiseModel::stripes;
  if (name == "stereo")
    return NoiseModel::stereo;
  if (name == "kinect1")
    return NoiseModel::kinect1;
  if (name == "tof")
    return NoiseModel::tof;
  throw std::invalid_argument("unknown noise model '" + name +
                              "' (expected none, kinect, laser, stripes, stereo, kinect1 or tof)");
}

Motion
motionFromString(const std::string& name)
{
  if (name == "static")
    return Motion::none;
  if (name == "moving")
    return Motion::moving_box;
  throw std::invalid_argument("unknown motion '" + name + "' (expected static or moving)");
}

std::string
toString(SceneType scene)
{
  switch (scene) {
  case SceneType::boxes:
    return "boxes";
  case SceneType::plane:
    return "plane";
  case SceneType::steps:
    return "steps";
  case SceneType::ridges:
    return "ridges";
  }
  return "unknown";
}

std::string
toString(NoiseModel noise)
{
  switch (noise) {
  case NoiseModel::none:
    return "none";
  case NoiseModel::kinect:
    return "kinect";
  case NoiseModel::laser:
    return "laser";
  case NoiseModel::stripes:
    return "stripes";
  case NoiseModel::stereo:
    return "stereo";
  case NoiseModel::kinect1:
    return "kinect1";
  case NoiseModel::tof:
    return "tof";
  }
  return "unknown";
}

std::string
toString(Motion motion)
{
  return motion == Motion::none ? "static" : "moving";
}

double
kinectAxialSigma(double depth, double scale)
{
  const double offset = depth - 0.4;
  return scale * (0.0012 + 0.0019 * offset * offset);
}

double
SceneOptions::principalX() const
{
  return cx ? *cx : 0.5 * (width - 1);
}

double
SceneOptions::principalY() const
{
  return cy ? *cy : 0.5 * (height - 1);
}

double
SceneOptions::effectiveNoiseScale() const
{
  if (noise_scale)
    return *noise_scale;
  return (noise == NoiseModel::kinect || noise == NoiseModel::stereo || noise == NoiseModel::kinect1 ||
          noise == NoiseModel::tof)
             ? 1.0
             : 0.25;
}

void
SceneOptions::validate() const
{
  if (width < 1)
    fail("width", width, "must be at least 1 pixel");
  if (height < 1)
    fail("height", height, "must be at least 1 pixel");
  if (std::int64_t(width) * height > (std::int64_t(1) << 28))
    fail("width * height", std::int64_t(width) * height, "must be at most 2^28 pixels");
  if (!(std::isfinite(fx) && fx > 0.0))
    fail("fx", fx, "must be finite and > 0 pixels");
  if (!(std::isfinite(fy) && fy > 0.0))
    fail("fy", fy, "must be finite and > 0 pixels");
  if (cx && !std::isfinite(*cx))
    fail("cx", *cx, "must be finite");
  if (cy && !std::isfinite(*cy))
    fail("cy", *cy, "must be finite");
  if (!(std::isfinite(plane_depth) && plane_depth > 0.0))
    fail("plane_depth", plane_depth, "must be finite and > 0 metres");
  if (noise_scale && !(std::isfinite(*noise_scale) && *noise_scale >= 0.0))
    fail("noise_scale", *noise_scale, "must be finite and >= 0");
  if (!(std::isfinite(stripe_amplitude) && stripe_amplitude >= 0.0))
    fail("stripe_amplitude", stripe_amplitude, "must be finite and >= 0 metres");
  if (!(std::isfinite(stripe_period) && stripe_period > 0.0))
    fail("stripe_period", stripe_period, "must be finite and > 0 pixels");
  if (!(std::isfinite(stereo_baseline) && stereo_baseline > 0.0))
    fail("stereo_baseline", stereo_baseline, "must be finite and > 0 metres");
  if (!(std::isfinite(stereo_disparity_sigma) && stereo_disparity_sigma >= 0.0))
    fail("stereo_disparity_sigma", stereo_disparity_sigma, "must be finite and >= 0 pixels");
  if (!(stereo_correlated_share >= 0.0 && stereo_correlated_share <= 1.0))
    fail("stereo_correlated_share", stereo_correlated_share, "must be a share of the variance in [0, 1]");
  if (!(stereo_correlation_length >= 0.0 && stereo_correlation_length <= 64.0))
    fail("stereo_correlation_length", stereo_correlation_length, "must be in [0, 64] pixels");
  if (!(std::isfinite(stereo_subpixel) && stereo_subpixel >= 0.0))
    fail("stereo_subpixel", stereo_subpixel, "must be finite and >= 0 pixels (0 = no quantization)");
  if (!(std::isfinite(kinect1_baseline) && kinect1_baseline > 0.0))
    fail("kinect1_baseline", kinect1_baseline, "must be finite and > 0 metres");
  if (!(std::isfinite(kinect1_shift_sigma) && kinect1_shift_sigma >= 0.0 && kinect1_shift_sigma <= 16.0))
    fail("kinect1_shift_sigma", kinect1_shift_sigma, "must be in [0, 16] pixels");
  if (!(std::isfinite(kinect1_disparity_sigma) && kinect1_disparity_sigma >= 0.0))
    fail("kinect1_disparity_sigma", kinect1_disparity_sigma, "must be finite and >= 0 pixels");
  if (!(std::isfinite(kinect1_subpixel) && kinect1_subpixel >= 0.0))
    fail("kinect1_subpixel", kinect1_subpixel, "must be finite and >= 0 pixels (0 = no quantization)");
  if (kinect1_block < 1 || kinect1_block > 31 || kinect1_block % 2 == 0)
    fail("kinect1_block", kinect1_block, "must be odd and in [1, 31] pixels");
  if (!(std::isfinite(kinect1_block_threshold) && kinect1_block_threshold > 0.0))
    fail("kinect1_block_threshold", kinect1_block_threshold, "must be finite and > 0 pixels");
  if (!(std::isfinite(kinect1_depth_unit) && kinect1_depth_unit >= 0.0))
    fail("kinect1_depth_unit", kinect1_depth_unit, "must be finite and >= 0 metres (0 = no rounding)");
  if (!(std::isfinite(tof_sigma) && tof_sigma >= 0.0))
    fail("tof_sigma", tof_sigma, "must be finite and >= 0 metres");
  if (!(std::isfinite(tof_sigma_slope) && tof_sigma_slope >= 0.0))
    fail("tof_sigma_slope", tof_sigma_slope, "must be finite and >= 0 metres per metre");
  if (tof_edge_band < 0 || tof_edge_band > 16)
    fail("tof_edge_band", tof_edge_band, "must be in [0, 16] pixels");
  if (!(tof_mixed_probability >= 0.0 && tof_mixed_probability <= 1.0))
    fail("tof_mixed_probability", tof_mixed_probability, "must be a probability in [0, 1]");
  if (!(std::isfinite(tof_edge_jump) && tof_edge_jump > 0.0))
    fail("tof_edge_jump", tof_edge_jump, "must be finite and > 0 (a fraction of the range)");
  if (!(dropout >= 0.0 && dropout <= 1.0))
    fail("dropout", dropout, "must be a probability in [0, 1]");
  if (!(grazing_dropout > 0.0 && grazing_dropout <= 90.0))
    fail("grazing_dropout", grazing_dropout, "must be an angle in (0, 90] degrees (90 = off)");
  if (frames < 1)
    fail("frames", frames, "must be at least 1");
  if (!std::isfinite(motion_step))
    fail("motion_step", motion_step, "must be finite (metres per frame)");
  if (motion == Motion::moving_box && scene != SceneType::boxes)
    fail("motion", toString(motion), "needs the boxes scene (the plane and steps scenes have nothing to move)");
}

Scene
Scene::build(const SceneOptions& options, int frame)
{
  options.validate();
  if (frame < 0)
    fail("frame", frame, "must be >= 0");
  Scene scene;
  if (options.scene == SceneType::plane) {
    scene.shapes_.push_back(std::make_shared<Plane>(Vec3(0, 0, options.plane_depth), Vec3(0, 0, -1)));
    return scene;
  }
  if (options.scene == SceneType::steps) {
    scene.shapes_ = stepsShapes();
    return scene;
  }
  if (options.scene == SceneType::ridges) {
    scene.shapes_ = ridgesShapes();
    return scene;
  }
  // Room: floor at y = 0.7 m (1.5 m - 3 m deep in view), back wall at z = 3 m; both finite, so
  // the image has invalid regions beside and above them.
  const double floor_y = 0.7, wall_z = 3.0;
  scene.shapes_.push_back(
      std::make_shared<Rectangle>(Vec3(0.1, floor_y, 1.75), Vec3::UnitX(), Vec3::UnitZ(), 1.5, 1.25));
  scene.shapes_.push_back(
      std::make_shared<Rectangle>(Vec3(0.1, -0.25, wall_z), Vec3::UnitY(), Vec3::UnitX(), 0.95, 1.5));
  // Near box (moves in moving sequences): three faces visible, sharp silhouette and creases.
  const double shift = options.motion == Motion::moving_box ? frame * options.motion_step : 0.0;
  scene.moving_shape_ = options.motion == Motion::moving_box ? int(scene.shapes_.size()) : -1;
  scene.shapes_.push_back(
      std::make_shared<Box>(Vec3(-0.32 + shift, -0.06, 1.05), rotation(35.0, -25.0), Vec3(0.12, 0.10, 0.12)));
  // Far box standing on the floor, turned 40 degrees.
  scene.shapes_.push_back(
      std::make_shared<Box>(Vec3(-0.55, floor_y - 0.18, 2.3), rotation(40.0, 0.0), Vec3(0.25, 0.18, 0.2)));
  scene.shapes_.push_back(std::make_shared<Sphere>(Vec3(0.36, -0.12, 1.35), 0.16));
  // Vertical cylinder standing on the floor.
  scene.shapes_.push_back(std::make_shared<Cylinder>(Vec3(0.85, floor_y - 0.4, 2.5), Vec3::UnitY(), 0.15, 0.4));
  // Panel with vertical ridges 3 mm high, 10 mm period, turned 20 degrees; its ridged face (+w)
  // looks toward the camera.
  Mat3 panel;
  const Mat3 turn = rotation(20.0, 0.0);
  panel.col(0) = turn * Vec3::UnitX();
  panel.col(1) = turn * Vec3::UnitY();
  panel.col(2) = turn * -Vec3::UnitZ();
  if (panel.determinant() < 0.0)
    panel.col(0) = -panel.col(0);
  scene.shapes_.push_back(std::make_shared<RidgedPanel>(Vec3(0.0, 0.17, 1.2), panel, 0.15, 0.12, 0.02, 0.003, 0.01));
  return scene;
}

int
Scene::intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min, double& t,
                 Eigen::Vector3d& normal) const
{
  int hit = -1;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < shapes_.size(); ++i) {
    double ti;
    Vec3 ni;
    if (shapes_[i]->intersect(origin, direction, t_min, ti, ni) && ti < best) {
      best = ti;
      normal = ni;
      hit = int(i);
    }
  }
  if (hit >= 0)
    t = best;
  return hit;
}

SyntheticFrame
renderFrame(const SceneOptions& options, int frame)
{
  const Scene scene = Scene::build(options, frame);
  const int width = options.width, height = options.height;
  const double cx = options.principalX(), cy = options.principalY();
  const float nan = std::numeric_limits<float>::quiet_NaN();

  SyntheticFrame out;
  out.truth = pcl::PointCloud<pcl::PointNormal>(width, height);
  out.noisy = pcl::PointCloud<pcl::PointXYZ>(width, height);
  out.shape_index.assign(std::size_t(width) * height, -1);
  // Cosine of the angle between ray and normal per pixel (for grazing dropouts).
  std::vector<double> cosine(out.shape_index.size(), 0.0);
  std::vector<double> depth(out.shape_index.size(), 0.0);

  // Geometry: every pixel is independent, so the result does not depend on the thread count.
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const std::size_t i = std::size_t(v) * width + u;
      const Vec3 d((u - cx) / options.fx, (v - cy) / options.fy, 1.0);
      double t = 0.0;
      Vec3 n;
      const int shape = scene.intersect(Vec3::Zero(), d, 1e-9, t, n);
      pcl::PointNormal& q = out.truth[i];
      if (shape < 0) {
        q.x = q.y = q.z = q.normal_x = q.normal_y = q.normal_z = q.curvature = nan;
        continue;
      }
      if (n.dot(d) > 0.0)
        n = -n;
      const Vec3 p = t * d;
      q.x = float(p.x()), q.y = float(p.y()), q.z = float(p.z());
      q.normal_x = float(n.x()), q.normal_y = float(n.y()), q.normal_z = float(n.z());
      q.curvature = 0.0f;
      out.shape_index[i] = shape;
      cosine[i] = -n.dot(d) / d.norm();
      depth[i] = t;
    }
  }
  out.truth.is_dense = std::find(out.shape_index.begin(), out.shape_index.end(), -1) == out.shape_index.end();

  if (options.noise == NoiseModel::stereo || options.noise == NoiseModel::kinect1 ||
      options.noise == NoiseModel::tof) {
    for (auto& q : out.noisy)
      q.x = q.y = q.z = nan;
    const SensorInput input{options, out.shape_index, depth, cosine, cx, cy};
    std::mt19937_64 rng = sensorStream(options, frame);
    if (options.noise == NoiseModel::stereo)
      out.noisy.is_dense = applyStereo(input, rng, out.noisy);
    else if (options.noise == NoiseModel::kinect1)
      out.noisy.is_dense = applyKinect1(input, rng, out.noisy);
    else
      out.noisy.is_dense = applyTof(input, rng, out.noisy);
    return out;
  }

  // Noise: one random stream per frame, three draws per pixel in scan order whether or not the
  // pixel is hit, so changing dropouts or the scene never reshuffles the noise of other pixels.
  std::seed_seq seq{std::uint32_t(options.seed & 0xffffffffu), std::uint32_t(options.seed >> 32),
                    std::uint32_t(frame)};
  std::mt19937_64 rng(seq);
  const double phase = 2.0 * kPi * uniform(rng);
  const double scale = options.noise == NoiseModel::none ? 0.0 : options.effectiveNoiseScale();
  const double stripe = options.noise == NoiseModel::stripes ? options.stripe_amplitude : 0.0;
  const double cos_grazing = std::cos(degreesToRadians(options.grazing_dropout));
  const bool grazing_enabled = options.grazing_dropout < 90.0;
  bool dense = true;
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const std::size_t i = std::size_t(v) * width + u;
      const double u1 = uniform(rng), u2 = uniform(rng), u3 = uniform(rng);
      pcl::PointXYZ& q = out.noisy[i];
      q.x = q.y = q.z = nan;
      if (out.shape_index[i] < 0 || u3 < options.dropout || (grazing_enabled && cosine[i] < cos_grazing)) {
        dense = false;
        continue;
      }
      const double z = depth[i];
      const double gaussian = std::sqrt(-2.0 * std::log(1.0 - u1)) * std::cos(2.0 * kPi * u2);
      double error = kinectAxialSigma(z, scale) * gaussian;
      if (stripe > 0.0)
        error += stripe * std::sin(2.0 * kPi * u / options.stripe_period + phase);
      if (!(z + error > 0.0)) {
        dense = false;
        continue;
      }
      // Stay on the camera ray: the point at depth z + e.
      const double measured = z + error;
      q.x = float((u - cx) / options.fx * measured);
      q.y = float((v - cy) / options.fy * measured);
      q.z = float(measured);
    }
  }
  out.noisy.is_dense = dense;
  return out;
}

std::vector<SyntheticFrame>
renderSequence(const SceneOptions& options)
{
  options.validate();
  std::vector<SyntheticFrame> frames;
  frames.reserve(options.frames);
  for (int k = 0; k < options.frames; ++k)
    frames.push_back(renderFrame(options, k));
  return frames;
}

} // namespace range_nlm
