/// \file render.h
/// \brief Images of organized range frames: flat shading, mean-curvature colouring and
/// before/after comparisons on one colour scale, written as PNG; curvature-coloured clouds.
///
/// An organized cloud is an image: pixel (u, v) of every rendering is point (u, v) of the cloud
/// (index v * width + u), row 0 at the top, as the sensor delivered it. Clouds are taken to be in
/// the camera frame (x right, y down, z forward), with the sensor at `RenderParameters::viewpoint`.
#pragma once

#include <range_nlm/core/grid.h>
#include <range_nlm/core/pipeline.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace range_nlm
{

/// An 8-bit sRGB colour.
using Rgb = std::array<std::uint8_t, 3>;

/// An 8-bit RGB image, row-major: the colour of pixel (u, v) is rgb[3 * (v * width + u) + {0,1,2}].
struct RgbImage
{
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;

  RgbImage() = default;
  /// A width x height image filled with `fill`.
  RgbImage(int width, int height, const Rgb& fill);
  /// Colour of pixel (u, v); no bounds check beyond an assert.
  Rgb at(int u, int v) const;
  /// Sets pixel (u, v).
  void set(int u, int v, const Rgb& colour);
};

/// Where the light of the flat shading comes from.
enum class Light
{
  /// A headlight at the viewpoint: v_i is the unit ray from point i to the viewpoint, so
  /// intensity falls off toward the image borders even on a fronto-parallel plane.
  view_ray,
  /// A directional light along the optical axis (z): a plane has one intensity everywhere.
  optical_axis
};

/// What a rendering shows.
enum class RenderMode
{
  /// Grey level from |n . v| (see shade()).
  shaded,
  /// Mean curvature on a diverging colour map with a symmetric scale (see curvatureColour()).
  curvature
};

/// Which image(s) the automatic curvature scale of a before/after pair is taken from.
enum class ScaleSource
{
  /// The percentile of |H| over the 'before' frame: noise removed in 'after' shows as paler colour.
  before,
  /// The percentile of |H| over the valid pixels of both frames together.
  both
};

/// Parameters of all renderings. `validate()` is the single place where they are checked.
struct RenderParameters
{
  /// Side of the grid neighbourhood of the plane fit that gives the shading normals
  /// (estimateNormals()), pixels. Odd, 3 ... 31, default 5.
  int normal_window = 5;
  /// Side of the grid neighbourhood of the quadric fit that gives the mean curvature, pixels.
  /// Odd, 5 ... 31, default 7.
  int curvature_window = 7;
  /// Depth-discontinuity test of the curvature fit: neighbour j of point i is used only if
  /// |rho_j - rho_i| <= max_depth_step * rho_i * max(|du|, |dv|), rho = distance from the
  /// viewpoint, (du, dv) the pixel offset. Relative (unitless), > 0, default 0.05 (5 cm per pixel
  /// at 1 m: only real jumps between objects are cut).
  float max_depth_step = 0.05f;
  /// Light direction of the flat shading. Default Light::view_ray.
  Light light = Light::view_ray;
  /// Ambient term of the shading: grey = 255 * (ambient + (1 - ambient) * |n . v|). 0 ... 1,
  /// default 0.1 (surfaces seen edge-on stay distinguishable from a black background).
  float ambient = 0.1f;
  /// Sensor position in cloud coordinates (cloud units). Normals face it; curvature is positive
  /// where the surface bulges toward it (a sphere seen from outside has H = +1/R). Default origin.
  Viewpoint viewpoint = {0.0f, 0.0f, 0.0f};
  /// Half-range of the curvature colour scale, 1 / cloud unit: H = -limit is full blue, +limit full
  /// red. 0 = automatic (the `percentile` of |H|). >= 0, default automatic.
  float curvature_limit = 0.0f;
  /// Percentile of |H| over the valid pixels used as the automatic limit, percent. (0, 100],
  /// default 95 (robust against the few extreme values at depth edges).
  float percentile = 95.0f;
  /// Colour of pixels without a point (NaN). Default black.
  Rgb background = {0, 0, 0};
  /// Colour of valid points for which no normal or curvature could be estimated (too few valid
  /// neighbours). Default mid grey.
  Rgb no_estimate = {128, 128, 128};
  /// Width of the separating strip between the two halves of a before/after image, pixels.
  /// 0 ... 1000, default 8.
  int gap = 8;
  /// Colour of that strip. Default white.
  Rgb gap_colour = {255, 255, 255};
  /// OpenMP threads; 0 = as many as OpenMP offers. Output does not depend on it. 0 ... 1024, default 0.
  int threads = 0;

  /// Throws std::invalid_argument naming the first invalid parameter and its value.
  void validate() const;
};

/// Copies x, y, z of an organized PointXYZ cloud into a Grid (NaN points invalid). Throws
/// std::invalid_argument if the cloud is empty or its width * height is not its size.
Grid
gridFromCloud(const pcl::PointCloud<pcl::PointXYZ>& cloud);

/// Per-point |n_i . v_i| in [0, 1]: n_i from estimateNormals() over `normal_window`, v_i as chosen
/// by `light`. NaN for invalid points and points without a normal.
std::vector<float>
shadingIntensity(const Grid& grid, const RenderParameters& parameters);

/// Per-point mean curvature H, 1 / cloud unit. The neighbours of the point in its
/// `curvature_window` that pass the depth-discontinuity test (`max_depth_step`) give a local frame
/// (their least-squares plane: x, y along it, h along its normal n, oriented toward the viewpoint);
/// a quadric h = a x^2 + b x y + c y^2 + d x + e y + f is fitted to them by least squares, and
///   H = -((1 + e^2) 2a - 2 d e b + (1 + d^2) 2c) / (2 (1 + d^2 + e^2)^(3/2)),
/// the mean curvature of that graph at its origin with the sign convention H = div(n) / 2 for n
/// facing the viewer. NaN for invalid points and where the fit is underdetermined (fewer than 10
/// neighbours or degenerate layout).
std::vector<float>
meanCurvature(const Grid& grid, const RenderParameters& parameters);

/// The `percentile` (percent) of |H| over the finite values of `curvature`, interpolated between
/// order statistics; at least the smallest positive float, so it can divide. 1 if no value is
/// finite. Throws std::invalid_argument if `percentile` is not in (0, 100].
float
curvatureLimit(const std::vector<float>& curvature, float percentile);

/// Grey level of the flat shading for intensity |n . v| in [0, 1]:
/// round(255 * (ambient + (1 - ambient) * intensity)) in R, G and B.
Rgb
shade(float intensity, float ambient);

/// The diverging "cool to warm" colour map (Moreland 2009, the ParaView default) at t in [0, 1]:
/// t = 0 blue (59, 76, 192), t = 0.5 neutral grey (221, 221, 221), t = 1 red (180, 4, 38);
/// piecewise linear through 33 tabulated colours; t is clamped to [0, 1].
Rgb
coolWarm(float t);

/// Colour of mean curvature H on the symmetric scale [-limit, +limit]:
/// coolWarm(0.5 + 0.5 * clamp(H / limit, -1, 1)). `limit` > 0.
Rgb
curvatureColour(float curvature, float limit);

/// Flat-shaded image of a grid (width x height). Throws std::invalid_argument on invalid
/// parameters or an empty grid.
RgbImage
renderShaded(const Grid& grid, const RenderParameters& parameters);

/// Colours precomputed curvature values (one per grid point, e.g. from meanCurvature()) on the
/// scale [-limit, +limit]: background for invalid points, `no_estimate` where H is NaN. Throws
/// std::invalid_argument if the sizes differ or limit <= 0.
RgbImage
curvatureToImage(const Grid& grid, const std::vector<float>& curvature, float limit,
                 const RenderParameters& parameters);

/// Curvature image of a grid on the scale [-limit, +limit] (limit in 1 / cloud unit, > 0).
/// Throws std::invalid_argument on invalid parameters, an empty grid or limit <= 0.
RgbImage
renderCurvature(const Grid& grid, float limit, const RenderParameters& parameters);

/// `left` and `right` next to each other, separated by `gap` columns of `gap_colour`: width
/// left.width + gap + right.width. Throws std::invalid_argument if the heights differ.
RgbImage
sideBySide(const RgbImage& left, const RgbImage& right, int gap, const Rgb& gap_colour);

/// A before/after comparison and the scale it was drawn with.
struct BeforeAfterImage
{
  /// 'before' on the left, 'after' on the right, `gap` columns apart.
  RgbImage image;
  /// Half-range of the curvature scale used for both halves, 1 / cloud unit (0 for shaded mode,
  /// whose scale |n . v| in [0, 1] is absolute).
  float curvature_limit = 0.0f;
};

/// Renders two frames of one size side by side with the same colour scale: in curvature mode
/// `parameters.curvature_limit` if > 0, else the percentile of |H| taken from `scale_source`.
/// Throws std::invalid_argument if the sizes differ or the parameters are invalid.
BeforeAfterImage
renderBeforeAfter(const Grid& before, const Grid& after, RenderMode mode, const RenderParameters& parameters,
                  ScaleSource scale_source = ScaleSource::before);

/// The cloud with x, y, z copied (NaN points stay NaN, rgb 0) and rgb = curvatureColour(H, limit),
/// `no_estimate` where H is NaN; for viewing in pcl_viewer. limit = parameters.curvature_limit if
/// > 0, else the automatic percentile of this cloud; the value used is stored in `*used_limit`
/// if given. Width, height, is_dense, header and sensor pose are copied.
pcl::PointCloud<pcl::PointXYZRGB>
colorizeByCurvature(const pcl::PointCloud<pcl::PointXYZ>& cloud, const RenderParameters& parameters,
                    float* used_limit = nullptr);

/// Writes an 8-bit RGB PNG with libpng (atomically: temporary file, then rename). Throws
/// std::invalid_argument naming the file on failure.
void
saveRgbPng(const std::string& path, const RgbImage& image);

} // namespace range_nlm
