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

/// Uniform in [0, 1) from the top 53 bits: the same sequence on every platform.
double
uniform(std::mt19937_64& rng)
{
  return double(rng() >> 11) * 0x1.0p-53;
}

} // namespace

SceneType
sceneTypeFromString(const std::string& name)
{
  if (name == "boxes")
    return SceneType::boxes;
  if (name == "plane")
    return SceneType::plane;
  throw std::invalid_argument("unknown scene '" + name + "' (expected boxes or plane)");
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
  throw std::invalid_argument("unknown noise model '" + name + "' (expected none, kinect, laser or stripes)");
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
  return scene == SceneType::boxes ? "boxes" : "plane";
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
  return noise == NoiseModel::kinect ? 1.0 : 0.25;
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
  if (!(dropout >= 0.0 && dropout <= 1.0))
    fail("dropout", dropout, "must be a probability in [0, 1]");
  if (!(grazing_dropout > 0.0 && grazing_dropout <= 90.0))
    fail("grazing_dropout", grazing_dropout, "must be an angle in (0, 90] degrees (90 = off)");
  if (frames < 1)
    fail("frames", frames, "must be at least 1");
  if (!std::isfinite(motion_step))
    fail("motion_step", motion_step, "must be finite (metres per frame)");
  if (motion == Motion::moving_box && scene != SceneType::boxes)
    fail("motion", toString(motion), "needs the boxes scene (the plane scene has nothing to move)");
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
