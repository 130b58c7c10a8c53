// Box-filtered patch similarity (the integral-image idea of fast NL-means, adapted to the
// normal-projected distance). For a shift delta = j - i and D(u) = p_u - p'_{u+delta} (p' the
// candidate frame):
//   Sim(i, i + delta) = n_i^T [ sum_{o in O} D(i+o) D(i+o)^T ] n_i / (valid pairs),
// so the six distinct entries of D D^T and the pair count are box-filtered over the patch once
// per shift for all pixels. Box sums are fresh float sums of P values in each direction (no
// running-sum drift across depth edges). When the candidate frame is the centre frame, the
// shifts delta and -delta share their sums: D_{-delta}(u) = -D_delta(u - delta), so
// M_{-delta}(i) = M_delta(i - delta), and one box filtering serves both (each pixel with its own
// normal). The image is cut into fixed tiles of rows and columns that fit the caches, so the
// output does not depend on the number of threads.
#include "kernel_rows.h"

#include <range_nlm/kernel.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cmath>
#include <memory>

namespace range_nlm
{
namespace detail
{
namespace
{

constexpr int kTileRows = 32;
/// Tile width for patches up to 7 pixels and beyond (a ring of P rows of box sums stays in the
/// first-level cache); less for very wide search windows.
constexpr int kTileColsSmallPatch = 128;
constexpr int kTileColsLargePatch = 64;
/// Row lengths passed to the row kernels are rounded up to a multiple of this, so that no
/// scalar remainder loop runs (the extra pixels read padding and write unused sums).
constexpr int kVectorPad = 16;

int
roundUp(int n)
{
  return (n + kVectorPad - 1) / kVectorPad * kVectorPad;
}

/// A frame copied into a zero-padded SoA grid; invalid and border points have flag 0 and
/// coordinates 0, so the inner loops need no bounds checks and never see NaN.
struct PaddedFrame
{
  int border = 0;
  int stride = 0; // padded width
  std::vector<float> x, y, z, f;

  PaddedFrame(const Grid& g, int border_, int threads) : border(border_), stride(g.width + 2 * border_)
  {
    // Slack: rows rounded up to whole vectors may read up to 2 x kVectorPad floats past the last
    // padded row.
    const std::size_t n = static_cast<std::size_t>(stride) * (g.height + 2 * border) + 4 * kVectorPad;
    x.assign(n, 0.0f);
    y.assign(n, 0.0f);
    z.assign(n, 0.0f);
    f.assign(n, 0.0f);
    (void)threads;
#pragma omp parallel for schedule(static) num_threads(threads)
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

/// Zeroed floats whose first one is aligned to a cache line (so are all fields kRowStride apart).
class AlignedBuffer
{
public:
  explicit AlignedBuffer(std::size_t n) : storage_(n + kVectorPad, 0.0f)
  {
    const std::uintptr_t address = reinterpret_cast<std::uintptr_t>(storage_.data());
    data_ = storage_.data() + ((64 - address % 64) % 64) / sizeof(float);
  }
  float* data() { return data_; }
  float& operator[](std::size_t i) { return data_[i]; }

private:
  std::vector<float> storage_;
  float* data_ = nullptr;
};

/// Weight sums per pixel: the current frame's sum of w h / s, the sum of w, the sum of w h.
constexpr int kSumFields = 3;

struct Workspace
{
  explicit Workspace(int patch_size)
    : prod(kChannels * std::size_t(kRowStride)), ring(std::size_t(patch_size) * (kRingFields * kRowStride + kRingSlack)),
      rows(patch_size), maps(std::size_t(kTileRows) * kSideFields * kRowStride),
      sums(std::size_t(kTileRows) * kSumFields * kRowStride)
  {
  }
  AlignedBuffer prod;             // kChannels x kRowStride: products of one D row
  AlignedBuffer ring;             // P x kRingFields x kRowStride: box-summed D rows
  std::vector<const float*> rows; // the ring rows of the current vertical window
  AlignedBuffer maps;             // tile rows x kSideFields x kRowStride: staged per-pixel maps
  AlignedBuffer sums;             // tile rows x kSumFields x kRowStride: num / s of a frame, den, num
};

} // namespace

void
computeOffsetsDirect(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
                     int search_window, int patch_size, int threads, const std::vector<unsigned char>& active,
                     std::vector<float>& offsets);

void
computeOffsetsWindowed(const Grid& center, const NormalField& normals, const std::vector<FrameTerm>& frames,
                       int search_window, int patch_size, int threads, const std::vector<unsigned char>& active,
                       std::vector<float>& offsets);

void
computeOffsetsFast(const Grid& center, const NormalField& normals,
                   const std::vector<FrameTerm>& frames, int search_window, int patch_size,
                   int threads, const std::vector<unsigned char>& active,
                   std::vector<float>& offsets)
{
  if (std::getenv("RANGE_NLM_BOX") == nullptr) {
    computeOffsetsWindowed(center, normals, frames, search_window, patch_size, threads, active, offsets);
    return;
  }
  const int width = center.width;
  const int height = center.height;
  const int r = search_window / 2;
  const int hp = patch_size / 2;
  const int border = r + hp;
  // The staged maps and sums start `lead` columns before the tile (r rounded up to whole vectors).
  // A row of box sums spans a tile row and r columns each side, rounded up to whole vectors, its
  // products P - 1 more; all of it must fit in kRowStride.
  const int lead = roundUp(r);
  const int tile_width = std::min(patch_size <= 7 ? kTileColsSmallPatch : kTileColsLargePatch,
                                  kRowStride - 2 * r - (patch_size - 1) - 2 * kVectorPad);
  if (tile_width < 16) {
    // Search windows of about kRowStride pixels and more: only the literal evaluation.
    computeOffsetsDirect(center, normals, frames, search_window, patch_size, threads, active, offsets);
    return;
  }
  const RowKernels& kernels = rowKernels();

  const PaddedFrame padded_center(center, border, threads);
  // The centre frame's own term reuses padded_center; other frames get their own copy.
  std::vector<std::unique_ptr<PaddedFrame>> padded(frames.size());
  std::vector<const PaddedFrame*> frame_ptr(frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (frames[f].grid == &center) {
      frame_ptr[f] = &padded_center;
    } else {
      padded[f] = std::make_unique<PaddedFrame>(*frames[f].grid, border, threads);
      frame_ptr[f] = padded[f].get();
    }
  }

  // Per point: computed or not (valid, selected, with a normal). Normals are zeroed elsewhere so
  // that no NaN enters the arithmetic; the weight sums of such points are formed but not used.
  const std::size_t n = center.size();
  std::vector<unsigned char> act(n);
  std::vector<float> nx(n), ny(n), nz(n);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t i = 0; i < n; ++i) {
    const bool ok = center.valid[i] && (active.empty() || active[i]) && std::isfinite(normals.nx[i]) &&
                    std::isfinite(normals.ny[i]) && std::isfinite(normals.nz[i]);
    act[i] = ok ? 1 : 0;
    nx[i] = ok ? normals.nx[i] : 0.0f;
    ny[i] = ok ? normals.ny[i] : 0.0f;
    nz[i] = ok ? normals.nz[i] : 0.0f;
  }
  // 1 / d^2 and 1 / s^2 per centre point and frame: the frame's map, or its scalar bandwidth.
  std::vector<float> const_d2(frames.size()), const_s2(frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const_d2[f] = inverseSquare(frames[f].distance_bandwidth);
    const_s2[f] = inverseSquare(frames[f].similarity_bandwidth);
  }
  // 1 / s^2 of point i in frame f, bounded below so that s stays finite (s = 1e15 m is no
  // weight at all either way).
  const auto inverseSimilarity = [&](std::size_t f, std::size_t i) {
    const float v = frames[f].inverse_similarity2 ? (*frames[f].inverse_similarity2)[i] : const_s2[f];
    return v > 1e-30f ? v : 1e-30f;
  };

  const int tile_rows = (height + kTileRows - 1) / kTileRows;
  const int tile_cols = (width + tile_width - 1) / tile_width;
  const int tiles = tile_rows * tile_cols;
  constexpr std::size_t kRow = kRowStride;
  const std::size_t slot_floats = kRingFields * kRow + kRingSlack;
#pragma omp parallel num_threads(threads)
  {
    Workspace ws(patch_size);
#pragma omp for schedule(dynamic, 1)
    for (int tile = 0; tile < tiles; ++tile) {
      const int y0 = (tile / tile_cols) * kTileRows;
      const int y1 = std::min(height, y0 + kTileRows);
      const int x0 = (tile % tile_cols) * tile_width;
      const int x1 = std::min(width, x0 + tile_width);
      // Zero the sums of the columns the tile's rows touch (vectors beyond the tile included).
      const std::size_t touched = std::min<std::size_t>(kRow, tile_width + 2 * lead + 2 * kVectorPad);
      for (int v = 0; v < kTileRows; ++v)
        for (int field = 0; field < kSumFields; ++field)
          std::fill_n(&ws.sums[(static_cast<std::size_t>(v) * kSumFields + field) * kRow], touched, 0.0f);
      // Staged data of pixel (u, v): v in the tile, u up to r columns beyond it on either side;
      // column x0 starts a cache line.
      const auto col = [&](int u) { return static_cast<std::size_t>(u - x0 + lead); };
      const auto side = [&](int u, int v) {
        return WeightSide{&ws.maps[static_cast<std::size_t>(v - y0) * kSideFields * kRow + col(u)],
                          &ws.sums[static_cast<std::size_t>(v - y0) * kSumFields * kRow + col(u)]};
      };
      for (std::size_t f = 0; f < frames.size(); ++f) {
        // Stage this frame's per-pixel maps of the tile rows (zero outside the image).
        const std::vector<float>* map_d2 = frames[f].inverse_distance2;
        for (int v = y0; v < y1; ++v) {
          float* out = &ws.maps[static_cast<std::size_t>(v - y0) * kSideFields * kRow];
          for (int u = x0 - r; u < x1 + r; ++u) {
            const std::size_t q = col(u);
            if (u < 0 || u >= width) {
              for (int field = 0; field < kSideFields; ++field)
                out[q + field * kRow] = 0.0f;
              continue;
            }
            const std::size_t i = static_cast<std::size_t>(v) * width + u;
            const float scale = std::sqrt(inverseSimilarity(f, i));
            out[q] = nx[i] * scale;
            out[q + kRow] = ny[i] * scale;
            out[q + 2 * kRow] = nz[i] * scale;
            out[q + 3 * kRow] = map_d2 ? (*map_d2)[i] : const_d2[f];
          }
        }
        const PaddedFrame& cand = *frame_ptr[f];
        const float psi = frames[f].weight;
        const bool paired = &cand == &padded_center;
        for (int dy = -r; dy <= r; ++dy) {
          for (int dx = -r; dx <= r; ++dx) {
            if (paired && (dy < 0 || (dy == 0 && dx < 0)))
              continue; // served by the shift -delta
            if (paired && dy == 0 && dx == 0) {
              // j = i: D = 0, Sim = 0, weight psi, no offset term.
              for (int v = y0; v < y1; ++v)
                for (int u = x0; u < x1; ++u)
                  side(u, v).sums[kRow] += psi * padded_center.f[padded_center.index(u, v)];
              continue;
            }
            // Box sums are needed on rows ya .. y1 - 1 and columns xs .. xe - 1: at the tile's
            // pixels i, and for a pair also at i - delta.
            const int ya = paired ? y0 - dy : y0;
            const int xs = paired ? x0 - std::max(dx, 0) : x0;
            const int xe = paired ? x1 - std::min(dx, 0) : x1;
            for (int yy = ya - hp; yy < y1 + hp; ++yy) {
              const int k = yy - (ya - hp);
              kernels.box_row(padded_center.row(xs - hp, yy), cand.row(xs - hp + dx, yy + dy), roundUp(xe - xs), patch_size,
                              ws.prod.data(), &ws.ring[static_cast<std::size_t>(k % patch_size) * slot_floats]);
              const int y = yy - hp; // the row whose vertical window is now complete
              if (y < ya)
                continue;
              // Side a: pixels (u, y) of the tile with candidates (u + dx, y + dy). Side b: pixels
              // (u + dx, y + dy) of the tile with candidates (u, y), the shift -delta.
              const bool side_a = y >= y0;
              const bool side_b = paired && y + dy < y1;
              const int u0 = side_a ? (side_b ? xs : x0) : x0 - dx;
              const int u1 = side_a ? (side_b ? xe : x1) : x1 - dx;
              for (int t = 0; t < patch_size; ++t)
                ws.rows[t] = &ws.ring[static_cast<std::size_t>((k - t) % patch_size) * slot_floats] + (u0 - xs);
              const BoxRows box{ws.rows.data(), patch_size};
              const WeightSide a = side_a ? side(u0, y) : WeightSide{};
              const WeightSide b = side_b ? side(u0 + dx, y + dy) : WeightSide{};
              kernels.shift_weights(box, roundUp(u1 - u0), psi, side_a ? &a : nullptr, side_b ? &b : nullptr);
            }
          }
        }
        // num += s (sum of w h / s) for this frame's s, then the frame's sum starts again.
        for (int v = y0; v < y1; ++v)
          for (int u = x0; u < x1; ++u) {
            float* sum = side(u, v).sums;
            sum[2 * kRow] += sum[0] / std::sqrt(inverseSimilarity(f, static_cast<std::size_t>(v) * width + u));
            sum[0] = 0.0f;
          }
      }
      for (int v = y0; v < y1; ++v)
        for (int u = x0; u < x1; ++u) {
          const std::size_t i = static_cast<std::size_t>(v) * width + u;
          const WeightSide s = side(u, v);
          offsets[i] = (act[i] && s.sums[kRow] > 0.0f) ? s.sums[2 * kRow] / s.sums[kRow] : 0.0f;
        }
    }
  }
}

} // namespace detail
} // namespace range_nlm
