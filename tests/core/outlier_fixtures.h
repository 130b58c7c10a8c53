// Frames shared by the tests of the isolated-outlier step: a noisy plane with and without a step
// edge, noise-free grids of a given depth, and ways to move and compare their points.
#pragma once

#include "core/outliers.h"

#include <range_nlm/core/pipeline.h>
#include <range_nlm/eval/synthetic_scene.h>

#include <cmath>
#include <cstring>
#include <vector>

namespace range_nlm::test
{
inline const Viewpoint kOrigin{0.0f, 0.0f, 0.0f};

inline Grid
gridOf(const pcl::PointCloud<pcl::PointXYZ>& c)
{
  return Grid::fromInterleaved(reinterpret_cast<const float*>(c.points.data()), static_cast<int>(c.width),
                               static_cast<int>(c.height), sizeof(pcl::PointXYZ) / sizeof(float));
}

/// A plane 1.5 m in front of a 320 x 240 camera with Kinect-like noise (about 4 mm there).
inline Grid
noisyPlane()
{
  SceneOptions o;
  o.width = 320;
  o.height = 240;
  o.fx = o.fy = 525.0 * 320 / 640;
  o.scene = SceneType::plane;
  o.plane_depth = 1.5;
  o.noise = noiseModelFromString("kinect");
  o.seed = 5;
  return gridOf(renderSequence(o).front().noisy);
}

inline float
rangeOf(const Grid& g, std::size_t i)
{
  return std::sqrt(g.x[i] * g.x[i] + g.y[i] * g.y[i] + g.z[i] * g.z[i]);
}

/// Moves point i along its ray by `delta` (metres of range).
inline void
pushAlongRay(Grid& g, std::size_t i, float delta)
{
  const float f = (rangeOf(g, i) + delta) / rangeOf(g, i);
  g.x[i] *= f, g.y[i] *= f, g.z[i] *= f;
}

/// The noisy plane with a step edge: columns < 160 half a metre nearer.
inline Grid
stepEdge()
{
  Grid g = noisyPlane();
  for (int v = 0; v < g.height; ++v)
    for (int u = 0; u < 160; ++u)
      pushAlongRay(g, static_cast<std::size_t>(v) * g.width + u, -0.5f);
  return g;
}

inline NoiseProfile
profileOf(const Grid& g)
{
  return detail::estimateNoiseProfile(g, 9, 1000, 42, kOrigin, 1);
}

inline bool
samePoint(const Grid& a, const Grid& b, std::size_t i)
{
  return a.valid[i] == b.valid[i] && std::memcmp(&a.x[i], &b.x[i], sizeof(float)) == 0 &&
         std::memcmp(&a.y[i], &b.y[i], sizeof(float)) == 0 && std::memcmp(&a.z[i], &b.z[i], sizeof(float)) == 0;
}

/// Focal length in pixels of the noise-free grids: adjacent rays 1 / 500 rad apart.
constexpr float kFocal = 500.0f;

/// A noise-free width x height grid, pixel (u, v) at depth z(u, v) on its ray through the centre.
template <typename Depth>
Grid
gridAtDepth(int width, int height, Depth z)
{
  Grid g(width, height);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * width + u;
      const float d = z(u, v);
      g.x[i] = (u - width / 2) * d / kFocal, g.y[i] = (v - height / 2) * d / kFocal, g.z[i] = d;
      g.valid[i] = 1;
    }
  return g;
}

/// The ranges of g's points (0 where invalid), as findIsolatedPoints gives them to its parts.
inline std::vector<float>
rangesOf(const Grid& g)
{
  std::vector<float> rho(g.size(), 0.0f);
  for (std::size_t i = 0; i < g.size(); ++i)
    rho[i] = g.valid[i] ? rangeOf(g, i) : 0.0f;
  return rho;
}

/// A noise profile of one bin: sigma 1 mm at every range.
inline NoiseProfile
flatProfile()
{
  NoiseProfile p;
  p.range = {1.0f};
  p.sigma = {0.001f};
  p.extent = {0.01f};
  return p;
}
} // namespace range_nlm::test
