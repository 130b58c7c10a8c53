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
  plane,
  /// Depth edges and creases, all planar, at depths 0.8 m - 3 m: floor and back wall (finite
  /// rectangles), a staircase of three steps of uneven height (0.10, 0.22, 0.30 m) turned 30
  /// degrees, a panel tilted 50 degrees to the view and a folded panel with a concave crease.
  steps,
  /// Small features only, all planar: one plate filling the view at about 1.1 m, turned 15 degrees,
  /// whose face carries terraces rising and falling by 2 - 5 mm, ridges 4 mm wide and 2 - 5 mm high,
  /// and a layer 5 mm proud with grooves 6 mm wide and 2 - 5 mm deep. Features of a few noise
  /// sigmas at laser-grade noise, of about one at depth-camera noise.
  ridges
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
  stripes,
  /// Active stereo (Intel RealSense D4xx-like). Depth comes from a disparity d = f B / z (f = fx,
  /// B = stereo_baseline); the measured disparity is
  ///     d' = q(d + scale * stereo_disparity_sigma * n),  n = sqrt(1 - c) w + sqrt(c) g,
  /// with w white N(0, 1) per pixel, g a fresh N(0, 1) field per frame made of white noise blurred
  /// by a Gaussian (sigma = stereo_correlation_length / 2 px) and renormalised to unit variance,
  /// so its autocorrelation is exp(-(lag / stereo_correlation_length)^2); c =
  /// stereo_correlated_share; q rounds to multiples of stereo_subpixel. Then z' = f B / d', so
  /// the depth error is dz ~= z^2 / (f B) * dd and grows with z^2. Sources: Intel, "Tuning depth
  /// cameras for best performance" (RealSense D400 white paper): depth RMS error = z^2 *
  /// subpixel / (f * baseline), subpixel RMS ~0.08 px for a well-textured scene, D435 baseline
  /// 50 mm; Keselman et al., "Intel RealSense Stereoscopic Depth Cameras", CVPR Workshops 2017
  /// (z^2 error growth, sub-pixel disparity estimation). Blob-like, frame-to-frame changing error
  /// as measured on the D435 frames of this project. No quantization of the depth itself.
  stereo,
  /// Structured light (Kinect v1 / Xtion) after Handa, Whelan, McDonald, Davison, "A Benchmark
  /// for RGB-D Visual Odometry, 3D Reconstruction and SLAM", ICRA 2014 (ICL-NUIM; the simkinect
  /// model, github.com/ankurhanda/simkinect): the disparity d = f B / z (B = kinect1_baseline) is
  /// bilinearly sampled at pixel positions shifted by N(0, kinect1_shift_sigma) px in u and v;
  /// a 9x9 block (kinect1_block) is matched against a fixed pseudo-random dot pattern: with m the
  /// mean disparity over the dots of the block, a dot at squared radius r^2 from the centre is an
  /// inlier if |d_dot - m| / (1.44 max(r^2, 1)) < kinect1_block_threshold (simkinect's weights
  /// and 0.1 px), and the pixel is measured only if more than 1/1.2 of the dots are inliers; a
  /// dot without a surface (or whose shifted sample leaves the image) fails the block. So a block
  /// straddling a depth edge, the image border or a pixel without a surface gives no measurement
  /// (NaN). Then disparity noise N(0, scale *
  /// kinect1_disparity_sigma), quantization to kinect1_subpixel (1/8 px), z' = f B / d', rounded
  /// to kinect1_depth_unit (1 mm): banding. Where this differs from simkinect: simkinect
  /// quantizes before the block test and again after the noise, averages over all pixels of the
  /// block (not only the dots), tolerates up to 1/6 of the dots without a surface, measures only
  /// pixels on a dot and copies their value to the neighbours within 3 px; and its N(0, 1/6)
  /// noise is in units of 35130 / depth_cm, about 0.1 px at its f = 480 px, so about 0.017 px.
  /// The default here, 0.05 px, makes the total axial error with the 1/8 px quantization about
  /// the Kinect v1 axial sigma of Nguyen, Izadi and Lovell (3DIMPVT 2012), 1.2 mm + 1.9 mm *
  /// (z - 0.4 m)^2, at 1-2 m (the kinect model).
  kinect1,
  /// Time of flight (Kinect v2 / Azure Kinect-like): range noise N(0, scale * (tof_sigma +
  /// tof_sigma_slope * r)) along the ray, r the range in metres; and mixed ("flying") pixels: a
  /// pixel within tof_edge_band px (Chebyshev) of a depth discontinuity (two hit pixels whose
  /// ranges differ by more than tof_edge_jump of the smaller) becomes, with probability
  /// tof_mixed_probability, a point on its own ray at range (1 - a) r_near + a r_far, a ~ U(0, 1),
  /// r_near and r_far the smallest and largest truth range in its (2 band + 1)^2 window: light
  /// from foreground and background mixed in one pixel. No quantization. Sources: Sabov and
  /// Krueger, "Identification and correction of flying pixels in range camera data", SCCG 2008;
  /// Reynolds et al., "Capturing Time-of-Flight data with confidence", CVPR 2011; Toelgyessy et
  /// al., "Evaluation of the Azure Kinect and Its Comparison to Kinect V1 and Kinect V2",
  /// Sensors 21(2), 2021 (noise growing with distance, a few mm at 1-3 m).
  tof
};

/// Motion of the sequence.
enum class Motion
{
  /// Every frame shows the same scene; only the noise is independent per frame.
  none,
  /// The nearest box translates along +x by SceneOptions::motion_step per frame ("boxes" only).
  moving_box
};

/// Parses "boxes" / "plane" / "steps"; throws std::invalid_argument naming the value otherwise.
SceneType
sceneTypeFromString(const std::string& name);
/// Parses "none" / "kinect" / "laser" / "stripes" / "stereo" / "kinect1" / "tof"; throws
/// std::invalid_argument otherwise.
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
  /// Factor on sigma(z). >= 0. Default: 1 for kinect, 0.25 for laser and stripes. For stereo,
  /// kinect1 and tof a factor (default 1) on their random error: the disparity noise sigma of
  /// stereo and kinect1 (not the pixel shifts), the range sigma of tof.
  std::optional<double> noise_scale;
  /// Amplitude A of the stripe artefact, metres. >= 0, default 0.002.
  double stripe_amplitude = 0.002;
  /// Period of the stripe artefact along the columns, pixels. > 0, default 16.
  double stripe_period = 16.0;

  /// stereo: baseline B, metres. > 0, default 0.05 (RealSense D435).
  double stereo_baseline = 0.05;
  /// stereo: standard deviation of the disparity error, pixels. >= 0, default 0.08 (Intel's
  /// typical subpixel RMS of the D400 series).
  double stereo_disparity_sigma = 0.08;
  /// stereo: share c of the disparity error variance that is spatially correlated. In [0, 1],
  /// default 0.8.
  double stereo_correlated_share = 0.8;
  /// stereo: correlation length L of the correlated part, pixels: its autocorrelation at a lag of
  /// l pixels is exp(-(l / L)^2). In [0, 64], default 4 (0: white, like the rest).
  double stereo_correlation_length = 4.0;
  /// stereo: disparity quantization step, pixels. >= 0, default 1/32 (0 = none).
  double stereo_subpixel = 1.0 / 32.0;

  /// kinect1: baseline between projector and camera B, metres. > 0, default 0.075 (simkinect).
  double kinect1_baseline = 0.075;
  /// kinect1: standard deviation of the pixel shifts in u and v, pixels. >= 0, default 0.5.
  double kinect1_shift_sigma = 0.5;
  /// kinect1: standard deviation of the disparity noise, pixels. >= 0, default 0.05.
  double kinect1_disparity_sigma = 0.05;
  /// kinect1: disparity quantization step, pixels. >= 0, default 1/8 (0 = none).
  double kinect1_subpixel = 0.125;
  /// kinect1: side of the matching block, pixels. Odd, in [1, 31], default 9.
  int kinect1_block = 9;
  /// kinect1: inlier threshold of the block consistency test, pixels (weighted disparity
  /// difference, see NoiseModel::kinect1). > 0, default 0.1.
  double kinect1_block_threshold = 0.1;
  /// kinect1: depth unit the measured depth is rounded to, metres. >= 0, default 0.001 (0 = none).
  double kinect1_depth_unit = 0.001;

  /// tof: range noise sigma at range 0, metres. >= 0, default 0.0015.
  double tof_sigma = 0.0015;
  /// tof: growth of the range noise sigma with range, metres per metre. >= 0, default 0.001.
  double tof_sigma_slope = 0.001;
  /// tof: width of the band at depth discontinuities where mixed pixels occur, pixels. In
  /// [0, 16], default 1 (0 = no mixed pixels).
  int tof_edge_band = 1;
  /// tof: probability that a pixel in the band becomes a mixed pixel. In [0, 1], default 0.5.
  double tof_mixed_probability = 0.5;
  /// tof: a depth discontinuity is a range difference of more than this fraction of the smaller
  /// range between two hit pixels. > 0, default 0.05.
  double tof_edge_jump = 0.05;

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

  /// Seed of all random draws (noise, dropouts, stripe phases). The kinect1 dot pattern is fixed.
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
