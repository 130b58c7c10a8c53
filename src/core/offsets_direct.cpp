// The literal evaluation of the filter formula (docs/method.md, "The static filter" and "The
// temporal filter"): for every point and every candidate, the patch similarity is summed pair by
// pair. It is the reference the fast kernel is tested against.
#include "fast_math.h"

#include "internal.h"

#include <algorithm>
#include <cmath>

namespace range_nlm
{
namespace detail
{

int
innerSearch(const std::vector<FrameTerm>& frames, int search_window)
{
  for (const FrameTerm& term : frames)
    if (term.search_window > 0 && term.search_window < search_window)
      return term.search_window;
  return search_window;
}

void
computeOffsetsDirect(const Grid& center, const NormalField& normals,
                     const std::vector<FrameTerm>& frames, int search_window, int patch_size,
                     int threads, const std::vector<unsigned char>& active,
                     std::vector<float>& offsets, const std::vector<float>& patch_gate, OffsetSpread* spread)
{
  const int width = center.width;
  const int height = center.height;
  if (spread) {
    spread->variance.resize(center.size());
    spread->inverse_count.resize(center.size());
  }
  const int hp = patch_size / 2;
  (void)threads;
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads)
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const int i = v * width + u;
      offsets[i] = 0.0f;
      if (spread)
        spread->variance[i] = spread->inverse_count[i] = 0.0f;
      if (!center.valid[i] || (!active.empty() && !active[i]) || !std::isfinite(normals.nx[i]))
        continue;
      const float nx = normals.nx[i], ny = normals.ny[i], nz = normals.nz[i];
      const float px = center.x[i], py = center.y[i], pz = center.z[i];
      // Pixels of the centre patch farther than this from its tangent plane count as holes.
      const bool gated = !patch_gate.empty();
      const double gate = gated ? patch_gate[i] : 0.0;
      double num = 0.0, den = 0.0, num2 = 0.0, den2 = 0.0; // and sum w h^2, sum w^2
      // The frames searched over a smaller window (FrameTerm::search_window) are summed apart and
      // scaled by the centre frame's weight over the whole window relative to its weight over
      // that inner one (the windowed kernel's rule).
      double inner_num = 0.0, inner_den = 0.0, inner_num2 = 0.0, inner_den2 = 0.0;
      double centre_den = 0.0, centre_inner_den = 0.0;
      bool centre_seen = false;
      const int inner_r = innerSearch(frames, search_window) / 2;
      for (const FrameTerm& term : frames) {
        const int r = (term.search_window > 0 ? term.search_window : search_window) / 2;
        const bool inner_term = r < search_window / 2;
        const bool centre_term = !inner_term && term.grid == &center && inner_r < search_window / 2;
        centre_seen = centre_seen || centre_term;
        // Into the sums of its window; the centre frame's weight also into its own two sums.
        double& to_num = inner_term ? inner_num : num;
        double& to_den = inner_term ? inner_den : den;
        double& to_num2 = inner_term ? inner_num2 : num2;
        double& to_den2 = inner_term ? inner_den2 : den2;
        const Grid& g = *term.grid;
        const Grid& c = term.patches ? *term.patches : center; // the centre patch's grid
        const float inv_d2 = term.inverse_distance2 ? (*term.inverse_distance2)[i]
                                                    : inverseSquareInline(term.distance_bandwidth);
        const float inv_s2 = term.inverse_similarity2 ? (*term.inverse_similarity2)[i]
                                                      : inverseSquareInline(term.similarity_bandwidth);
        for (int jv = v - r; jv <= v + r; ++jv) {
          for (int ju = u - r; ju <= u + r; ++ju) {
            if (jv < 0 || jv >= height || ju < 0 || ju >= width)
              continue;
            const int j = jv * width + ju;
            if (!g.valid[j])
              continue;
            double sim_sum = 0.0;
            int pairs = 0;
            for (int ov = -hp; ov <= hp; ++ov) {
              for (int ou = -hp; ou <= hp; ++ou) {
                const int av = v + ov, au = u + ou, bv = jv + ov, bu = ju + ou;
                if (av < 0 || av >= height || au < 0 || au >= width || bv < 0 || bv >= height ||
                    bu < 0 || bu >= width)
                  continue;
                const int a = av * width + au, b = bv * width + bu;
                if (!c.valid[a] || !g.valid[b])
                  continue;
                if (gated && std::fabs((double(c.x[a]) - px) * nx + (double(c.y[a]) - py) * ny +
                                       (double(c.z[a]) - pz) * nz) > gate)
                  continue;
                const double t = (double(c.x[a]) - g.x[b]) * nx + (double(c.y[a]) - g.y[b]) * ny +
                                 (double(c.z[a]) - g.z[b]) * nz;
                sim_sum += t * t;
                ++pairs;
              }
            }
            if (pairs == 0)
              continue;
            const double sim = sim_sum / pairs;
            const double dx = double(px) - g.x[j], dy = double(py) - g.y[j], dz = double(pz) - g.z[j];
            const double dist2 = dx * dx + dy * dy + dz * dz;
            const double h = dx * nx + dy * ny + dz * nz;
            const float arg = static_cast<float>(-(dist2 * inv_d2 + sim * inv_s2));
            const double w = term.weight * expNonPositiveInline(arg);
            to_num += w * h;
            to_den += w;
            to_num2 += w * h * h;
            to_den2 += w * w;
            if (centre_term) {
              centre_den += w;
              if (std::abs(jv - v) <= inner_r && std::abs(ju - u) <= inner_r)
                centre_inner_den += w;
            }
          }
        }
      }
      if (inner_r < search_window / 2) {
        const double scale = centre_seen && centre_inner_den > 0.0 ? centre_den / centre_inner_den : 1.0;
        num += scale * inner_num, den += scale * inner_den;
        num2 += scale * inner_num2, den2 += scale * inner_den2;
      }
      offsets[i] = den > 0.0 ? static_cast<float>(num / den) : 0.0f;
      if (spread && den > 0.0) {
        const double mean = num / den;
        spread->variance[i] = static_cast<float>(std::max(0.0, num2 / den - mean * mean));
        spread->inverse_count[i] = static_cast<float>(den2 / (den * den));
      }
    }
  }
}

} // namespace detail
} // namespace range_nlm
