/// \file synthetic_scene.h
/// \brief Organized range frames of analytic scenes, ray-cast through a pinhole camera, with exact
/// ground truth (points and normals) and depth-sensor noise models. Used to measure the filter.
///
/// Camera: at the origin, looking down +z, x to the right, y down. Pixel (u, v) sees the ray
/// d = ((u - cx) / fx, (v - cy) / fy, 1); a hit at depth z is the point z * d. All lengths are
/// metres, all angles degrees.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace range_nlm
{

/// Which scene is rendered.
enum class SceneType
{
  /// Floor and back wall (finite rectangles, NaN beyond them), two oriented boxes, a sphere, a
  /// capped cylinder and a panel with 3 mm high, 10 mm period ridges, at depths 0.8 m - 3 m.
  boxes,
  /// One infinite fronto-parallel plane at SceneOptions::plane_depth (for calibration and tests).
  plane
};

/// Depth-sensor noise added to the noisy frame. The depth error e moves a point along its camera
/// ray so that its depth z becomes z + e.
enum class NoiseModel
{
  /// No noise (dropouts still apply).
  none,
  /// Kinect-class axial noise: e ~ N(0, sigma(z)), sigma(z) = scale * (1.2 mm + 1.9 mm * (z - 0.4 m)^2).
  kinect,
  /// The kinect model with a default scale of 0.25 (laser-grade noise).
  laser,
  /// Structured-light stripe artefacts: e = A sin(2 pi u / period + phase_k) + N(0, sigma(z)),
  /// a sinusoid along the image columns u whose phase_k is drawn per frame; default scale 0.25.
  stripes
};

/// Motion of the sequence.
enum class Motion
{
  /// Every frame shows the same scene; only the noise is independent per frame.
  none,
  /// The nearest box translates along +x by SceneOptions::motion_step per frame ("boxes" only).
  moving_box
};

/// Parses "boxes" / "plane"; throws std::invalid_argument naming the value otherwise.
SceneType
sceneTypeFromString(const std::string& name);
/// Parses "none" / "kinect" / "laser" / "stripes"; throws std::invalid_argument otherwise.
NoiseModel
noiseModelFromString(const std::string& name);
/// Parses "static" / "moving"; throws std::invalid_argument otherwise.
Motion
motionFromString(const std::string& name);
std::string
toString(SceneType scene);
std::string
toString(NoiseModel noise);
std::string
toString(Motion motion);

/// Kinect-class axial noise sigma(z) = scale * (1.2 mm + 1.9 mm * (z - 0.4 m)^2), metres, for a
/// depth z in metres.
double
kinectAxialSigma(double depth, double scale = 1.0);

/// Everything that determines a rendered sequence. Same options, same frames (bit for bit).
struct SceneOptions
{
  /// Image width, pixels. >= 1, default 640.
  int width = 640;
  /// Image height, pixels. >= 1, default 480.
  int height = 480;
  /// Focal lengths, pixels. > 0, default 525 (Kinect-class VGA).
  double fx = 525.0;
  double fy = 525.0;
  /// Principal point, pixels. Default (width - 1) / 2 and (height - 1) / 2.
  std::optional<double> cx;
  std::optional<double> cy;

  /// Scene to render. Default boxes.
  SceneType scene = SceneType::boxes;
  /// Depth of the plane of SceneType::plane, metres. > 0, default 1.5.
  double plane_depth = 1.5;

  /// Noise model. Default kinect.
  NoiseModel noise = NoiseModel::kinect;
  /// Factor on sigma(z). >= 0. Default: 1 for kinect, 0.25 for laser and stripes.
  std::optional<double> noise_scale;
  /// Amplitude A of the stripe artefact, metres. >= 0, default 0.002.
  double stripe_amplitude = 0.002;
  /// Period of the stripe artefact along the columns, pixels. > 0, default 16.
  double stripe_period = 16.0;

  /// Probability that a pixel is dropped (NaN in the noisy frame), independently per pixel and
  /// frame. In [0, 1], default 0.
  double dropout = 0.0;
  /// A pixel is dropped when the angle between its ray and the surface normal exceeds this,
  /// degrees. In (0, 90]; 90 (default) never drops.
  double grazing_dropout = 90.0;

  /// Number of frames of a sequence. >= 1, default 1.
  int frames = 1;
  /// Motion of the sequence. Default none (static scene).
  Motion motion = Motion::none;
  /// Translation of the moving box per frame along +x, metres. Finite, default 0.01 (about five
  /// noise sigmas at its depth of 1 m).
  double motion_step = 0.01;

  /// Seed of all random draws (noise, dropouts, stripe phases).
  std::uint64_t seed = 1;

  /// (width - 1) / 2 unless cx is given.
  double principalX() const;
  /// (height - 1) / 2 unless cy is given.
  double principalY() const;
  /// noise_scale, or the default of the noise model.
  double effectiveNoiseScale() const;
  /// Throws std::invalid_argument naming the first invalid option and its value.
  void validate() const;
};

/// One analytic object of a scene.
class Shape
{
public:
  virtual ~Shape() = default;

  /// Nearest intersection of the ray origin + t * direction with t > t_min. On a hit returns true
  /// and sets t and the outward unit normal at the hit point.
  virtual bool intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                         double& t, Eigen::Vector3d& normal) const = 0;
  /// How far p is from the surface, metres: 0 on the surface; the Euclidean distance for planes,
  /// rectangles, boxes, spheres and cylinders; for the ridged panel the smallest of the distance
  /// to its base box, the offset along the panel normal to the ridged face and the distance to
  /// the ridges' end faces. Computed independently of intersect().
  virtual double surfaceDistance(const Eigen::Vector3d& p) const = 0;
  /// Outward unit normal of the face nearest to the surface point p (computed independently of
  /// intersect()).
  virtual Eigen::Vector3d normalAt(const Eigen::Vector3d& p) const = 0;
  /// Short name, e.g. "sphere".
  virtual std::string name() const = 0;
};

/// A set of shapes as seen in one frame.
class Scene
{
public:
  /// The scene of `options` at frame `frame` (the moving box is displaced by frame * motion_step).
  /// Throws std::invalid_argument if the options are invalid.
  static Scene build(const SceneOptions& options, int frame);

  /// Nearest hit over all shapes of the ray origin + t * direction, t > t_min. Returns the index
  /// of the shape hit (-1 for none) and sets t and the outward unit normal.
  int intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min, double& t,
                Eigen::Vector3d& normal) const;

  const std::vector<std::shared_ptr<const Shape>>& shapes() const { return shapes_; }
  /// Index of the moving box in shapes(), -1 if nothing moves.
  int movingShape() const { return moving_shape_; }

private:
  std::vector<std::shared_ptr<const Shape>> shapes_;
  int moving_shape_ = -1;
};

/// One rendered frame.
struct SyntheticFrame
{
  /// The noisy measurement: organized width x height, NaN where nothing was hit or a pixel was
  /// dropped; sensor at the origin.
  pcl::PointCloud<pcl::PointXYZ> noisy;
  /// Exact hit points and unit normals oriented toward the camera; NaN (all fields) where the ray
  /// hits nothing. Dropouts do not apply to the truth.
  pcl::PointCloud<pcl::PointNormal> truth;
  /// Index into Scene::shapes() of the shape seen by each pixel, -1 where nothing is hit.
  std::vector<int> shape_index;
};

/// Renders frame `frame` (0-based) of the sequence described by `options`: the same frame as
/// element `frame` of renderSequence(options). Throws std::invalid_argument on invalid options
/// or a negative frame index.
SyntheticFrame
renderFrame(const SceneOptions& options, int frame = 0);

/// Renders options.frames frames with independent noise per frame.
std::vector<SyntheticFrame>
renderSequence(const SceneOptions& options);

} // namespace range_nlm
