/// \file grid.h
/// \brief The PCL-free data the numeric kernel works on: an organized grid of 3-D points.
#pragma once

#include <cstddef>
#include <vector>

namespace range_nlm
{

/// An organized range frame in structure-of-arrays form: point (u, v) is index i = v * width + u.
/// A point is valid when all of x, y, z are finite; invalid points hold NaN in x, y and z.
struct Grid
{
  int width = 0;
  int height = 0;
  std::vector<float> x, y, z;
  /// 1 where the point is valid, 0 where it is NaN.
  std::vector<unsigned char> valid;

  Grid() = default;
  Grid(int w, int h);

  std::size_t size() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
  /// Number of valid points.
  std::size_t countValid() const;

  /// Copies `width * height` points from interleaved memory: point i's x, y, z are the floats at
  /// `data + i * stride_floats + {0, 1, 2}` (the layout of every PCL point type with x, y, z).
  /// Non-finite points become invalid (NaN in x, y and z). Reuses the grid's storage. Returns the
  /// index of the first point with an infinite coordinate, or -1: the filters refuse such input
  /// (an infinity is not a documented invalid marker), the evaluation treats it as invalid.
  std::ptrdiff_t assignInterleaved(const float* data, int width, int height, std::size_t stride_floats);
  /// A new grid from interleaved memory, as assignInterleaved, with infinite points invalid.
  static Grid fromInterleaved(const float* data, int width, int height, std::size_t stride_floats);
  /// Recomputes `valid` from x, y, z and writes NaN into all three coordinates of invalid points.
  void updateValidity();

  /// Becomes a copy of `from` with its validity recomputed as updateValidity does (from's `valid`
  /// is not read), in one parallel pass. Reuses the grid's storage.
  void assignValidated(const Grid& from);
};

/// Unit normals per point of a Grid (NaN where none could be estimated).
struct NormalField
{
  std::vector<float> nx, ny, nz;
  std::size_t size() const { return nx.size(); }
};

} // namespace range_nlm
