// The history of the recursive temporal window: a motion-aware running average of the input frames.
#include "internal.h"
#include "tuned.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace range_nlm
{

namespace
{
/// Pixel i's history starts over (at(i)) from start's point (counted as `started` frames) where
/// start has one, else from the frame's (counted as 1); it is empty where the frame has no point.
/// The history's arrays must have the frame's size. Branch-free, so that a loop of it vectorizes.
struct StartOver
{
  StartOver(RunningAverage& history, const Grid& frame, const Grid* start, std::uint16_t started)
      : hx(history.average.x.data()), hy(history.average.y.data()), hz(history.average.z.data()),
        hv(history.average.valid.data()), count(history.count.data()), fx(frame.x.data()), fy(frame.y.data()),
        fz(frame.z.data()), fv(frame.valid.data()), has_start(start != nullptr),
        // (Without a start the frame stands in for it, never chosen.)
        sx(start ? start->x.data() : fx), sy(start ? start->y.data() : fy), sz(start ? start->z.data() : fz),
        sv(start ? start->valid.data() : fv), started(started)
  {
  }

  void at(std::ptrdiff_t i) const
  {
    const bool valid = fv[i] != 0;
    const bool from_start = has_start && valid && sv[i] != 0;
    hx[i] = from_start ? sx[i] : fx[i];
    hy[i] = from_start ? sy[i] : fy[i];
    hz[i] = from_start ? sz[i] : fz[i];
    hv[i] = fv[i];
    count[i] = from_start ? started : static_cast<std::uint16_t>(valid ? 1 : 0);
  }

  float* __restrict hx;
  float* __restrict hy;
  float* __restrict hz;
  unsigned char* __restrict hv;
  std::uint16_t* __restrict count;
  const float* __restrict fx;
  const float* __restrict fy;
  const float* __restrict fz;
  const unsigned char* __restrict fv;
  bool has_start;
  const float* __restrict sx;
  const float* __restrict sy;
  const float* __restrict sz;
  const unsigned char* __restrict sv;
  std::uint16_t started;
};

/// Every pixel's history starts over.
void
restart(RunningAverage& history, const Grid& frame, const Grid* start, std::uint16_t started, int threads)
{
  Grid& h = history.average;
  h.width = frame.width;
  h.height = frame.height;
  const std::size_t n = frame.size();
  h.x.resize(n);
  h.y.resize(n);
  h.z.resize(n);
  h.valid.resize(n);
  history.count.resize(n);
  const StartOver over(history, frame, start, started);
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n);
  // (A copy per thread, whose pointers the compiler keeps in registers.)
#pragma omp parallel for simd schedule(static) num_threads(threads) firstprivate(over)
  for (std::ptrdiff_t i = 0; i < size; ++i)
    over.at(i);
}

} // namespace

void
updateRunningAverage(RunningAverage& history, const Grid& frame, const Grid* start, const Viewpoint& viewpoint,
                     int max_count, int search_window, int samples, std::uint64_t seed, int threads,
                     const NoiseProfile* known, const FrameOffset* known_change)
{
  if (start && (start->width != frame.width || start->height != frame.height))
    throw std::invalid_argument("range_nlm: the filtered frame that starts the history is " +
                                std::to_string(start->width) + " x " + std::to_string(start->height) +
                                " but the frame is " + std::to_string(frame.width) + " x " +
                                std::to_string(frame.height));
  threads = detail::resolveThreads(threads);
  max_count = std::max(1, std::min(max_count, static_cast<int>(std::numeric_limits<std::uint16_t>::max())));
  const std::uint16_t started = static_cast<std::uint16_t>(std::max(1, max_count - 1));
  if (history.empty() || history.average.width != frame.width || history.average.height != frame.height ||
      frame.countValid() == 0 || history.average.countValid() == 0) {
    restart(history, frame, start, started, threads);
    return;
  }
  const FrameOffset change =
      known_change ? *known_change : detail::analyseFrameChange(frame, history.average, viewpoint, threads);
  if (change.change == FrameChange::motion) {
    restart(history, frame, start, started, threads);
    return;
  }
  const std::size_t n = frame.size();
  RunningAverage::Buffers& buffers = history.buffers;
  std::vector<float>& rho_f = buffers.rho_frame;
  std::vector<float>& rho_h = buffers.rho_history;
  detail::rangesOf(frame, viewpoint, threads, rho_f);
  detail::rangesOf(history.average, viewpoint, threads, rho_h);
  NoiseProfile estimated;
  if (!known || known->empty()) {
    try {
      estimated = detail::estimateNoiseProfile(frame, search_window, samples, seed, viewpoint, threads);
    } catch (const UnfilterableFrame&) {
      // Too few points to tell noise from change (a nearly covered lens): start over from the frame.
      restart(history, frame, start, started, threads);
      return;
    }
  }
  const NoiseProfile& profile = known && !known->empty() ? *known : estimated;
  // (Every element of the maps below is written before it is read: resized, not cleared.)
  std::vector<float>& sigma = buffers.sigma;
  sigma.resize(n);
  detail::interpolateProfile(profile.range, profile.sigma, rho_f.data(), sigma.data(), n, threads);
  // Differences to the history levelled to the frame (NaN where either has no point), and the
  // noise sigma of each: the frame's, with the history's share 1 / count of it.
  const bool offset = change.change == FrameChange::offset && change.range_offset.size() == n;
  std::vector<float>& along = buffers.along;
  std::vector<float>& noise = buffers.noise;
  std::vector<float>& ratios = buffers.ratios;
  along.resize(n);
  noise.resize(n);
  ratios.resize(n);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::ptrdiff_t size = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::ptrdiff_t i = 0; i < size; ++i) {
    const bool both = frame.valid[i] && history.average.valid[i] && history.count[i] > 0 && sigma[i] > 0.0f;
    const float level = offset ? change.range_offset[i] : 0.0f;
    noise[i] = sigma[i] * std::sqrt(1.0f + 1.0f / std::max<float>(1.0f, history.count[i]));
    along[i] = both ? rho_h[i] - level - rho_f[i] : nan;
    ratios[i] = both ? std::fabs(along[i]) / noise[i] : -1.0f;
  }
  std::size_t counted = 0;
  const float median = detail::medianOfNonNegative(ratios.data(), nullptr, n, threads, &counted);
  const float ratio = counted >= 64 ? std::max(1.0f, 1.4826f * median) : 1.0f;
  // The history starts over at fewer frame-to-frame sigmas than the filter's own test of change
  // (detail::kChangeSigmas): a history that starts over needlessly starts from the filtered frame,
  // which costs little, but one that averages a surface that moved keeps it where it was.
  std::vector<unsigned char>& changed = buffers.changed;
  detail::markChangedPixels(along, frame.width, frame.height, noise.data(), tuned::kHistoryChangeSigmas * ratio,
                            threads, changed);
  Grid& h = history.average;
  const StartOver over(history, frame, start, started);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::ptrdiff_t i = 0; i < size; ++i) {
    if (!frame.valid[i] || !h.valid[i] || history.count[i] == 0 || changed[i] || !(rho_f[i] > 0.0f)) {
      over.at(i);
      continue;
    }
    const int count = std::min(static_cast<int>(history.count[i]) + 1, max_count);
    const float r = rho_h[i] + (rho_f[i] - rho_h[i]) / static_cast<float>(count);
    const float t = r / rho_f[i];
    h.x[i] = viewpoint[0] + (frame.x[i] - viewpoint[0]) * t;
    h.y[i] = viewpoint[1] + (frame.y[i] - viewpoint[1]) * t;
    h.z[i] = viewpoint[2] + (frame.z[i] - viewpoint[2]) * t;
    history.count[i] = static_cast<std::uint16_t>(count);
  }
}

} // namespace range_nlm
