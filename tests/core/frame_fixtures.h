// Frames shared by the tests of the frame estimates (noise profile and correlation, frame change,
// change masks): generated scenes as grids, and ways to move and compare their points.
#pragma once

#include "core/internal.h"

#include <range_nlm/core/pipeline.h>
#include <range_nlm/eval/synthetic_scene.h>

#include <cmath>
#include <cstring>
#include <vector>

namespace range_nlm::test
{
inline Grid
gridOf(const pcl::PointCloud<pcl::PointXYZ>& c)
{
  return Grid::fromInterleaved(reinterpret_cast<const float*>(c.points.data()), static_cast<int>(c.width),
                               static_cast<int>(c.height), sizeof(pcl::PointXYZ) / sizeof(float));
}

inline SceneOptions
planeScene(const char* noise, int width, int height, int frames = 1)
{
  SceneOptions o;
  o.width = width;
  o.height = height;
  o.fx = o.fy = 525.0 * width / 640;
  o.scene = SceneType::plane;
  o.plane_depth = 1.5;
  o.noise = noiseModelFromString(noise);
  o.frames = frames;
  o.seed = 11;
  return o;
}

inline const Viewpoint kOrigin{0.0f, 0.0f, 0.0f};

/// detail::alongNormals of b against a.
inline std::vector<float>
alongOf(const Grid& a, const NormalField& n, const Grid& b)
{
  std::vector<float> along;
  detail::alongNormals(a, n, b, 1, along);
  return along;
}

/// `g` with every valid point moved along its ray (from the origin) by offset(u) metres.
template <typename Offset>
Grid
alongRays(Grid g, Offset offset)
{
  for (int v = 0; v < g.height; ++v)
    for (int u = 0; u < g.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * g.width + u;
      const float len = std::sqrt(g.x[i] * g.x[i] + g.y[i] * g.y[i] + g.z[i] * g.z[i]);
      if (!g.valid[i] || !(len > 0.0f))
        continue;
      const float f = (len + offset(u)) / len;
      g.x[i] *= f, g.y[i] *= f, g.z[i] *= f;
    }
  return g;
}

inline float
rangeOf(const Grid& g, std::size_t i)
{
  return std::sqrt(g.x[i] * g.x[i] + g.y[i] * g.y[i] + g.z[i] * g.z[i]);
}

/// Whether two grids hold the same bits in every coordinate and flag.
inline bool
sameBits(const Grid& a, const Grid& b)
{
  return a.width == b.width && a.height == b.height && a.valid == b.valid &&
         std::memcmp(a.x.data(), b.x.data(), a.x.size() * sizeof(float)) == 0 &&
         std::memcmp(a.y.data(), b.y.data(), a.y.size() * sizeof(float)) == 0 &&
         std::memcmp(a.z.data(), b.z.data(), a.z.size() * sizeof(float)) == 0;
}
} // namespace range_nlm::test
