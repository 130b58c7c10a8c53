// Box-filtered patch similarity (the integral-image idea of fast NL-means, adapted to the
// normal-projected distance). For a shift delta = j - i and D(u) = p_u - p'_{u+delta} (p' the
// candidate frame):
//   Sim(i, i + delta) = n_i^T [ sum_{o in O} D(i+o) D(i+o)^T ] n_i / (valid pairs),
// so the six distinct entries of D D^T and the pair count are box-filtered over the patch once
// per shift for all pixels. Horizontal sums are direct float sums of P values (no drift);
// vertical sums are running sums in double. Rows are processed in fixed tiles, so the output
// does not depend on the number of threads.
#include "kernel_math.h"

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
constexpr int kChannels = 7; // xx, xy, xz, yy, yz, zz, count

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
};

struct Workspace
{
  std::vector<float> prod;  // kChannels x (width + P - 1): per-pixel products of one D row
  std::vector<float> ring;  // P x kChannels x width: horizontally summed rows
  std::vector<double> vacc; // kChannels x width: vertical running sums
  std::vector<float> num, den;
};

/// Products of one D row (candidate row shifted by (dx, dy)) and their horizontal box sums.
__attribute__((target_clones("avx2", "default"))) void
rowProducts(const PaddedFrame& c, const PaddedFrame& k, int width, int row, int dx, int dy,
            int patch, float* prod, float* out)
{
  const int hp = patch / 2;
  const int plen = width + patch - 1;
  const std::size_t a0 = c.index(-hp, row);
  const std::size_t b0 = k.index(-hp + dx, row + dy);
  const float* cx = &c.x[a0];
  const float* cy = &c.y[a0];
  const float* cz = &c.z[a0];
  const float* cf = &c.f[a0];
  const float* kx = &k.x[b0];
  const float* ky = &k.y[b0];
  const float* kz = &k.z[b0];
  const float* kf = &k.f[b0];
  float* p0 = prod;
  float* p1 = prod + plen;
  float* p2 = prod + 2 * plen;
  float* p3 = prod + 3 * plen;
  float* p4 = prod + 4 * plen;
  float* p5 = prod + 5 * plen;
  float* p6 = prod + 6 * plen;
  for (int t = 0; t < plen; ++t) {
    const float m = cf[t] * kf[t];
    const float ex = (cx[t] - kx[t]) * m;
    const float ey = (cy[t] - ky[t]) * m;
    const float ez = (cz[t] - kz[t]) * m;
    p0[t] = ex * ex;
    p1[t] = ex * ey;
    p2[t] = ex * ez;
    p3[t] = ey * ey;
    p4[t] = ey * ez;
    p5[t] = ez * ez;
    p6[t] = m;
  }
  for (int ch = 0; ch < kChannels; ++ch) {
    const float* p = prod + ch * plen;
    float* o = out + ch * width;
    for (int u = 0; u < width; ++u) {
      float s = 0.0f;
      for (int t = 0; t < patch; ++t)
        s += p[u + t];
      o[u] = s;
    }
  }
}

/// Weights of one output row for one shift, accumulated into num/den.
__attribute__((target_clones("avx2", "default"))) void
rowWeights(const PaddedFrame& c, const PaddedFrame& k, const float* active, const float* nx,
           const float* ny, const float* nz, const double* vacc, int width, int row, int dx,
           int dy, float inv_d2, float inv_s2, float psi, float* num, float* den)
{
  const std::size_t a0 = c.index(0, row);
  const std::size_t b0 = k.index(dx, row + dy);
  const float* cx = &c.x[a0];
  const float* cy = &c.y[a0];
  const float* cz = &c.z[a0];
  const float* kx = &k.x[b0];
  const float* ky = &k.y[b0];
  const float* kz = &k.z[b0];
  const float* kf = &k.f[b0];
  const double* mxx = vacc;
  const double* mxy = vacc + width;
  const double* mxz = vacc + 2 * width;
  const double* myy = vacc + 3 * width;
  const double* myz = vacc + 4 * width;
  const double* mzz = vacc + 5 * width;
  const double* cnt = vacc + 6 * width;
  for (int u = 0; u < width; ++u) {
    const float a = nx[u], b = ny[u], g = nz[u];
    const float quad = a * a * float(mxx[u]) + b * b * float(myy[u]) + g * g * float(mzz[u]) +
                       2.0f * (a * b * float(mxy[u]) + a * g * float(mxz[u]) + b * g * float(myz[u]));
    const float pairs = float(cnt[u]);
    const float use = (pairs > 0.5f ? 1.0f : 0.0f) * active[u] * kf[u];
    const float sim = std::max(quad, 0.0f) / std::max(pairs, 1.0f);
    const float ex = cx[u] - kx[u];
    const float ey = cy[u] - ky[u];
    const float ez = cz[u] - kz[u];
    const float dist2 = ex * ex + ey * ey + ez * ez;
    const float h = ex * a + ey * b + ez * g;
    const float arg = -(dist2 * inv_d2 + sim * inv_s2);
    const float w = use * psi * expNonPositiveInline(arg);
    num[u] += w * h;
    den[u] += w;
  }
}

} // namespace

void
computeOffsetsFast(const Grid& center, const NormalField& normals,
                   const std::vector<FrameTerm>& frames, int search_window, int patch_size,
                   int threads, const std::vector<unsigned char>& active,
                   std::vector<float>& offsets)
{
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

  const int tiles = (height + kTileRows - 1) / kTileRows;
  const int plen = width + patch_size - 1;
  (void)threads;
#pragma omp parallel num_threads(threads)
  {
    Workspace ws;
    ws.prod.resize(static_cast<std::size_t>(kChannels) * plen);
    ws.ring.resize(static_cast<std::size_t>(patch_size) * kChannels * width);
    ws.vacc.resize(static_cast<std::size_t>(kChannels) * width);
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
        const float inv_d2 = inverseSquareInline(frames[f].distance_bandwidth);
        const float inv_s2 = inverseSquareInline(frames[f].similarity_bandwidth);
        const float psi = frames[f].weight;
        for (int dy = -r; dy <= r; ++dy) {
          for (int dx = -r; dx <= r; ++dx) {
            std::fill(ws.vacc.begin(), ws.vacc.end(), 0.0);
            // D rows y0 - hp .. y1 - 1 + hp feed the output rows y0 .. y1 - 1.
            for (int yy = y0 - hp; yy < y1 + hp; ++yy) {
              float* slot = &ws.ring[static_cast<std::size_t>((yy - (y0 - hp)) % patch_size) *
                                     kChannels * width];
              if (yy - (y0 - hp) >= patch_size) {
                for (std::size_t q = 0; q < static_cast<std::size_t>(kChannels) * width; ++q)
                  ws.vacc[q] -= slot[q];
              }
              rowProducts(padded_center, cand, width, yy, dx, dy, patch_size, ws.prod.data(), slot);
              for (std::size_t q = 0; q < static_cast<std::size_t>(kChannels) * width; ++q)
                ws.vacc[q] += slot[q];
              const int out_row = yy - hp;
              if (out_row >= y0) {
                const std::size_t base = static_cast<std::size_t>(out_row) * width;
                rowWeights(padded_center, cand, &act[base], &nx[base], &ny[base], &nz[base],
                           ws.vacc.data(), width, out_row, dx, dy, inv_d2, inv_s2, psi,
                           &ws.num[static_cast<std::size_t>(out_row - y0) * width],
                           &ws.den[static_cast<std::size_t>(out_row - y0) * width]);
              }
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
