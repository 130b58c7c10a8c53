// Box-filtered patch similarity (the integral-image idea of fast NL-means, adapted to the
// normal-projected distance). For a shift delta = j - i and D(u) = p_u - p'_{u+delta} (p' the
// candidate frame):
//   Sim(i, i + delta) = n_i^T [ sum_{o in O} D(i+o) D(i+o)^T ] n_i / (valid pairs),
// so the six distinct entries of D D^T and the pair count are box-filtered over the patch once
// per shift for all pixels. Horizontal sums are fresh float sums of P values (no drift);
// vertical sums are running sums in double. Rows are processed in fixed tiles, so the output
// does not depend on the number of threads. Cost per point ~ S^2 (independent of P, up to the
// P adds of the horizontal sums).
#include "kernel_rows.h"

#include <range_nlm/kernel.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace range_nlm
{
namespace detail
{
namespace
{

constexpr int kTileRows = 32;
/// Up to this patch size the vertical box sums are fresh float sums of P rows (cheaper than
/// the double running sums, and exact to float rounding); larger patches use running sums.
constexpr int kMaxDirectPatch = 7;

/// A frame copied into a zero-padded SoA grid; invalid and border points have flag 0 and
/// coordinates 0, so the inner loops need no bounds checks and never see NaN.
struct PaddedFrame
{
  int border = 0;
  int stride = 0; // padded width
  std::vector<float> x, y, z, f;

  PaddedFrame(const Grid& g, int border_) : border(border_), stride(g.width + 2 * border_)
  {
    const std::size_t n = static_cast<std::size_t>(stride) * (g.height + 2 * border);
    x.assign(n, 0.0f);
    y.assign(n, 0.0f);
    z.assign(n, 0.0f);
    f.assign(n, 0.0f);
    for (int v = 0; v < g.height; ++v)
      for (int u = 0; u < g.width; ++u) {
        const int i = v * g.width + u;
        if (!g.valid[i])
          continue;
        const std::size_t k = index(u, v);
        x[k] = g.x[i];
        y[k] = g.y[i];
        z[k] = g.z[i];
        f[k] = 1.0f;
      }
  }
  std::size_t index(int u, int v) const
  {
    return static_cast<std::size_t>(v + border) * stride + (u + border);
  }
  RowPointers row(int u, int v) const
  {
    const std::size_t k = index(u, v);
    return RowPointers{&x[k], &y[k], &z[k], &f[k]};
  }
};

struct Workspace
{
  std::vector<float> prod;  // kChannels x (width + P - 1): per-pixel products of one D row
  std::vector<float> ring;  // (P + 1) x kChannels x width: horizontally summed rows
  std::vector<double> vacc; // kChannels x width: vertical running sums
  std::vector<float> vrow;  // the same as float, for the weight pass
  std::vector<float> num, den;
};

} // namespace

void
computeOffsetsFast(const Grid& center, const NormalField& normals,
                   const std::vector<FrameTerm>& frames, int search_window, int patch_size,
                   int threads, const std::vector<unsigned char>& active,
                   std::vector<float>& offsets)
{
  const RowKernels& kernels = rowKernels();
  const int width = center.width;
  const int height = center.height;
  const int r = search_window / 2;
  const int hp = patch_size / 2;
  const int border = r + hp;

  const PaddedFrame padded_center(center, border);
  // The centre frame's own term reuses padded_center; other frames get their own copy.
  std::vector<std::unique_ptr<PaddedFrame>> padded(frames.size());
  std::vector<const PaddedFrame*> frame_ptr(frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (frames[f].grid == &center) {
      frame_ptr[f] = &padded_center;
    } else {
      padded[f] = std::make_unique<PaddedFrame>(*frames[f].grid, border);
      frame_ptr[f] = padded[f].get();
    }
  }

  // Per point: 1 if the offset is computed (valid, selected, with a normal); normals zeroed
  // elsewhere so that no NaN enters the arithmetic.
  const std::size_t n = center.size();
  std::vector<float> act(n), nx(n), ny(n), nz(n);
  for (std::size_t i = 0; i < n; ++i) {
    const bool ok = center.valid[i] && (active.empty() || active[i]) && std::isfinite(normals.nx[i]) &&
                    std::isfinite(normals.ny[i]) && std::isfinite(normals.nz[i]);
    act[i] = ok ? 1.0f : 0.0f;
    nx[i] = ok ? normals.nx[i] : 0.0f;
    ny[i] = ok ? normals.ny[i] : 0.0f;
    nz[i] = ok ? normals.nz[i] : 0.0f;
  }

  // 1 / d^2 and 1 / s^2 per centre point and frame (constant maps for scalar bandwidths).
  std::vector<std::vector<float>> own_maps;
  own_maps.reserve(2 * frames.size());
  std::vector<const float*> inv_d2(frames.size()), inv_s2(frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (frames[f].inverse_distance2) {
      inv_d2[f] = frames[f].inverse_distance2->data();
    } else {
      own_maps.emplace_back(n, inverseSquare(frames[f].distance_bandwidth));
      inv_d2[f] = own_maps.back().data();
    }
    if (frames[f].inverse_similarity2) {
      inv_s2[f] = frames[f].inverse_similarity2->data();
    } else {
      own_maps.emplace_back(n, inverseSquare(frames[f].similarity_bandwidth));
      inv_s2[f] = own_maps.back().data();
    }
  }

  const bool direct_vertical = patch_size <= kMaxDirectPatch;
  const int tiles = (height + kTileRows - 1) / kTileRows;
  const int plen = width + patch_size - 1;
  const std::size_t row_floats = static_cast<std::size_t>(kChannels) * width;
  (void)threads;
#pragma omp parallel num_threads(threads)
  {
    Workspace ws;
    ws.prod.resize(static_cast<std::size_t>(kChannels) * plen);
    ws.ring.resize(static_cast<std::size_t>(patch_size + 1) * row_floats);
    ws.vacc.resize(row_floats);
    ws.vrow.resize(row_floats);
    ws.num.resize(static_cast<std::size_t>(kTileRows) * width);
    ws.den.resize(static_cast<std::size_t>(kTileRows) * width);
#pragma omp for schedule(dynamic, 1)
    for (int tile = 0; tile < tiles; ++tile) {
      const int y0 = tile * kTileRows;
      const int y1 = std::min(height, y0 + kTileRows);
      std::fill(ws.num.begin(), ws.num.end(), 0.0f);
      std::fill(ws.den.begin(), ws.den.end(), 0.0f);
      for (std::size_t f = 0; f < frames.size(); ++f) {
        const PaddedFrame& cand = *frame_ptr[f];
        const float psi = frames[f].weight;
        for (int dy = -r; dy <= r; ++dy) {
          for (int dx = -r; dx <= r; ++dx) {
            if (!direct_vertical)
              std::fill(ws.vacc.begin(), ws.vacc.end(), 0.0);
            // D rows y0 - hp .. y1 - 1 + hp feed the output rows y0 .. y1 - 1. The ring has
            // P + 1 slots, so row yy - P (leaving the vertical window now) is still held.
            for (int yy = y0 - hp; yy < y1 + hp; ++yy) {
              const int k = yy - (y0 - hp);
              float* slot = &ws.ring[static_cast<std::size_t>(k % (patch_size + 1)) * row_floats];
              const float* leaving =
                  k >= patch_size
                      ? &ws.ring[static_cast<std::size_t>((k - patch_size) % (patch_size + 1)) * row_floats]
                      : nullptr;
              kernels.products(padded_center.row(-hp, yy), cand.row(-hp + dx, yy + dy), width, patch_size,
                               ws.prod.data(), slot);
              const int out_row = yy - hp;
              if (direct_vertical) {
                // Small patches: fresh float sums of the P rows in the window.
                if (out_row >= y0) {
                  const float* rows[kMaxDirectPatch];
                  for (int t = 0; t < patch_size; ++t)
                    rows[t] = &ws.ring[static_cast<std::size_t>((k - t) % (patch_size + 1)) * row_floats];
                  kernels.column_sum(rows, patch_size, row_floats, ws.vrow.data());
                }
              } else {
                kernels.slide(ws.vacc.data(), slot, leaving, out_row >= y0 ? ws.vrow.data() : nullptr, row_floats);
              }
              if (out_row < y0)
                continue;
              const std::size_t base = static_cast<std::size_t>(out_row) * width;
              const std::size_t local = static_cast<std::size_t>(out_row - y0) * width;
              kernels.weights(padded_center.row(0, out_row), cand.row(dx, out_row + dy), &act[base], &nx[base],
                              &ny[base], &nz[base], ws.vrow.data(), width, inv_d2[f] + base, inv_s2[f] + base, psi, &ws.num[local],
                              &ws.den[local]);
            }
          }
        }
      }
      for (int v = y0; v < y1; ++v)
        for (int u = 0; u < width; ++u) {
          const std::size_t i = static_cast<std::size_t>(v) * width + u;
          const std::size_t t = static_cast<std::size_t>(v - y0) * width + u;
          offsets[i] = (act[i] > 0.0f && ws.den[t] > 0.0f) ? ws.num[t] / ws.den[t] : 0.0f;
        }
    }
  }
}

} // namespace detail
} // namespace range_nlm
