// FilterParameters::reuse_estimates: what describes the sensor -- the current frame's noise profile
// and the automatic dilation -- carried from one call to the next on the frames of a stream, and
// estimated afresh when a sparse check of the frame says that the sensor's noise or the frame's
// ranges changed (docs/method.md, "Estimates carried in a stream").
#include "stages.h"

#include "../workspace.h"

#include <algorithm>
#include <cmath>

namespace range_nlm
{
namespace detail
{
namespace
{

/// Share of the carried frame's sampled ranges outside its [low, high] range quantiles.
constexpr double kOutsideShare = 2.0 * tuned::kReuseRangeTail;

/// Spacing of the check's lattice: about tuned::kReuseCheckColumns columns across the frame.
int
latticeStep(int width)
{
  return std::max(1, width / tuned::kReuseCheckColumns);
}

/// The robust scale (detail::robustMean) of |1/z_a - 2/z_c + 1/z_b| z_c^2 over the triples at `lag`
/// pixels along the rows and columns of the lattice, and the standard error of its logarithm: the
/// triples are dealt into kReuseCheckGroups groups by lattice position, and the spread of the
/// groups' log scales over sqrt(groups) is the error of the whole sample's. So the error is
/// measured, whatever the noise's correlation, tails or the scene's structure do to it.
Scale
secondDifferenceScale(const Grid& frame, int lag, int step, std::vector<float>& scratch)
{
  constexpr int groups = tuned::kReuseCheckGroups;
  std::vector<float> grouped[groups];
  scratch.clear();
  const int w = frame.width, h = frame.height;
  auto add = [&](std::size_t a, std::size_t c, std::size_t b, int group) {
    if (!(frame.valid[a] && frame.valid[b] && frame.valid[c]))
      return;
    const float za = frame.z[a], zb = frame.z[b], zc = frame.z[c];
    if (!(za > 0.0f && zb > 0.0f && zc > 0.0f))
      return;
    const float value = std::fabs(1.0f / za - 2.0f / zc + 1.0f / zb) * zc * zc;
    scratch.push_back(value);
    grouped[group].push_back(value);
  };
  for (int v = step / 2, row = 0; v < h; v += step, ++row)
    for (int u = step / 2, column = 0; u < w; u += step, ++column) {
      const std::size_t c = static_cast<std::size_t>(v) * w + u;
      const int group = (row + column) % groups;
      if (u >= lag && u + lag < w)
        add(c - lag, c, c + lag, group);
      if (v >= lag && v + lag < h)
        add(c - static_cast<std::size_t>(lag) * w, c, c + static_cast<std::size_t>(lag) * w, group);
    }
  Scale out;
  out.samples = scratch.size();
  if (scratch.size() < static_cast<std::size_t>(tuned::kNoiseCorrelationMinTriples))
    return out;
  out.scale = robustMean(scratch);
  double sum = 0.0, sum2 = 0.0;
  int used = 0;
  for (std::vector<float>& g : grouped) {
    const float scale = g.size() >= 2 ? robustMean(g) : 0.0f;
    if (!(scale > 0.0f))
      continue;
    const double l = std::log(double(scale));
    sum += l, sum2 += l * l, ++used;
  }
  if (used < 2 || !(out.scale > 0.0f)) {
    out.scale = 0.0f;
    return out;
  }
  const double variance = std::max(0.0, (sum2 - sum * sum / used) / (used - 1));
  out.log_error = static_cast<float>(std::sqrt(variance / used));
  return out;
}

/// The range quantiles of the valid points of the lattice, and their count.
void
rangeQuantiles(const Grid& frame, const Viewpoint& viewpoint, int step, std::vector<float>& rho, EstimateSignature& s)
{
  rho.clear();
  for (int v = step / 2; v < frame.height; v += step)
    for (int u = step / 2; u < frame.width; u += step) {
      const std::size_t i = static_cast<std::size_t>(v) * frame.width + u;
      if (!frame.valid[i])
        continue;
      const float dx = frame.x[i] - viewpoint[0], dy = frame.y[i] - viewpoint[1], dz = frame.z[i] - viewpoint[2];
      rho.push_back(std::sqrt(dx * dx + dy * dy + dz * dz));
    }
  s.range_samples = rho.size();
  if (rho.empty())
    return;
  const auto at = [&](double q) {
    const std::size_t k = std::min(rho.size() - 1, static_cast<std::size_t>(q * double(rho.size() - 1) + 0.5));
    std::nth_element(rho.begin(), rho.begin() + static_cast<std::ptrdiff_t>(k), rho.end());
    return rho[k];
  };
  s.range_low = at(tuned::kReuseRangeTail);
  s.range_high = at(1.0 - tuned::kReuseRangeTail);
}

/// Whether two scales differ by no more than their measured errors allow.
bool
scalesAgree(const Scale& a, const Scale& b)
{
  if (!(a.scale > 0.0f) || !(b.scale > 0.0f))
    return !(a.scale > 0.0f) && !(b.scale > 0.0f); // both unmeasured agree; one measured does not
  const double error = std::sqrt(double(a.log_error) * a.log_error + double(b.log_error) * b.log_error);
  return std::fabs(std::log(double(a.scale) / double(b.scale))) <= tuned::kReuseTestSigmas * error;
}

/// The parameters the carried estimates depend on are the same.
bool
sameEstimateParameters(const FilterParameters& a, const FilterParameters& b)
{
  return a.search_window == b.search_window && a.patch_size == b.patch_size && a.normal_window == b.normal_window &&
         a.normal_presmooth_window == b.normal_presmooth_window && a.bandwidth_samples == b.bandwidth_samples &&
         a.seed == b.seed && a.dilation == b.dilation && a.bandwidth_model == b.bandwidth_model;
}

} // namespace

EstimateSignature
estimateSignature(const Grid& frame, const Viewpoint& viewpoint, std::vector<float> (&scratch)[4], int threads)
{
  EstimateSignature s;
  s.width = frame.width;
  s.height = frame.height;
  s.viewpoint = viewpoint;
  const int step = latticeStep(frame.width), lag = dilationReferenceLag(frame.width);
  // Four independent parts, each with a scratch of its own, so the result does not depend on the
  // threads that take them.
  (void)threads;
#pragma omp parallel for schedule(dynamic, 1) num_threads(std::max(1, std::min(threads, 4)))
  for (int part = 0; part < 4; ++part) {
    if (part == 0)
      s.near = secondDifferenceScale(frame, 1, step, scratch[0]);
    else if (part == 1)
      s.half = secondDifferenceScale(frame, std::max(1, lag / 2), step, scratch[1]);
    else if (part == 2)
      s.far = secondDifferenceScale(frame, lag, step, scratch[2]);
    else
      rangeQuantiles(frame, viewpoint, step, scratch[3], s);
  }
  return s;
}

bool
carriedEstimatesHold(const CarriedEstimates& carried, const EstimateSignature& now, const Grid& frame,
                     const FilterParameters& parameters)
{
  const EstimateSignature& then = carried.signature;
  if (!carried.valid || carried.frames >= tuned::kReuseMaxFrames || now.width != then.width ||
      now.height != then.height || now.viewpoint != then.viewpoint ||
      !sameEstimateParameters(carried.parameters, parameters))
    return false;
  // The noise at the pixel scale and at the dilation's lags: the sensor's noise, its strength and
  // correlation (the second differences of inverse depth vanish on planes and are blind to smooth
  // offsets along the rays).
  if (!scalesAgree(now.near, then.near) || !scalesAgree(now.half, then.half) || !scalesAgree(now.far, then.far))
    return false;
  // The ranges: the profile holds its edge bins' values beyond them, so the frame's ranges must lie
  // where the carried frame's did. Outside its quantiles lie kOutsideShare of its sample; more than
  // that share plus what the sampling allows means the ranges moved.
  if (now.range_samples == 0 || then.range_samples == 0)
    return false;
  const int step = latticeStep(frame.width);
  std::size_t outside = 0;
  for (int v = step / 2; v < frame.height; v += step)
    for (int u = step / 2; u < frame.width; u += step) {
      const std::size_t i = static_cast<std::size_t>(v) * frame.width + u;
      if (!frame.valid[i])
        continue;
      const float dx = frame.x[i] - now.viewpoint[0], dy = frame.y[i] - now.viewpoint[1],
                  dz = frame.z[i] - now.viewpoint[2];
      const float rho = std::sqrt(dx * dx + dy * dy + dz * dz);
      outside += rho < then.range_low || rho > then.range_high;
    }
  const double n = double(now.range_samples);
  const double allowed = kOutsideShare + tuned::kReuseTestSigmas * std::sqrt(kOutsideShare * (1.0 - kOutsideShare) / n);
  return double(outside) <= allowed * n;
}

EstimateSignature
takeCarriedEstimates(const Grid& frame, const FilterParameters& parameters, const Viewpoint& viewpoint,
                     Workspace& workspace)
{
  workspace.known_dilation = 0;
  workspace.chosen_dilation = 0;
  workspace.run.estimates_reused = false;
  workspace.profiles = nullptr;
  if (!parameters.reuse_estimates || frame.countValid() == 0) {
    workspace.estimates = CarriedEstimates();
    forgetFrameProfiles(workspace);
    return EstimateSignature();
  }
  const EstimateSignature signature = estimateSignature(frame, viewpoint, workspace.signature_scratch, resolveThreads(parameters.threads));
  CarriedEstimates& carried = workspace.estimates;
  if (carriedEstimatesHold(carried, signature, frame, parameters)) {
    workspace.current_profile = carried.profile;
    workspace.known_dilation = carried.dilation;
    workspace.run.estimates_reused = true;
    ++carried.frames;
  } else {
    // Estimates made afresh for the current frame, for the other frames too: what the profiles
    // were kept for (the dilation's phases, the sensor) may have changed with it.
    forgetFrameProfiles(workspace);
  }
  workspace.carried_profiles.resize(std::max<std::size_t>(1, workspace.carried_profiles.size()));
  workspace.profiles = &workspace.carried_profiles.front();
  return signature;
}

void
forgetFrameProfiles(Workspace& workspace)
{
  workspace.carried_profiles.clear();
  workspace.carried_neighbours.clear();
}

void
checkNeighbourProfiles(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
                       const Viewpoint& viewpoint, Workspace& workspace)
{
  if (!workspace.profiles)
    return; // nothing carried in this call
  for (int k = 0; k < static_cast<int>(frames.size()); ++k) {
    if (k == center || !frames[k])
      continue;
    const int offset = k - center;
    auto slot = std::find_if(workspace.carried_neighbours.begin(), workspace.carried_neighbours.end(),
                             [offset](const CarriedNeighbour& n) { return n.offset == offset; });
    if (slot == workspace.carried_neighbours.end())
      slot = workspace.carried_neighbours.insert(slot, CarriedNeighbour{offset, CarriedEstimates()});
    const Grid& frame = *frames[k];
    const EstimateSignature signature = frame.countValid() > 0
                                            ? estimateSignature(frame, viewpoint, workspace.signature_scratch, resolveThreads(parameters.threads))
                                            : EstimateSignature();
    CarriedEstimates& check = slot->check;
    if (signature.width > 0 && carriedEstimatesHold(check, signature, frame, parameters)) {
      ++check.frames;
      continue;
    }
    // The frame at this place of the window is not the one the profiles were kept for.
    for (std::vector<CarriedProfile>& list : workspace.carried_profiles)
      list.erase(std::remove_if(list.begin(), list.end(), [offset](const CarriedProfile& c) { return c.offset == offset; }),
                 list.end());
    check = CarriedEstimates();
    if (signature.width > 0) {
      check.valid = true;
      check.signature = signature;
      check.parameters = parameters;
      check.frames = 1;
    }
  }
}

const NoiseProfile*
carriedProfile(const Workspace& workspace, int offset, int iteration)
{
  if (!workspace.profiles)
    return nullptr;
  for (const CarriedProfile& c : *workspace.profiles)
    if (c.offset == offset && c.iteration == iteration)
      return &c.profile;
  return nullptr;
}

void
keepProfile(Workspace& workspace, int offset, int iteration, const NoiseProfile& profile)
{
  if (workspace.profiles)
    workspace.profiles->push_back(CarriedProfile{offset, iteration, profile});
}

void
keepEstimates(const EstimateSignature& signature, const FilterParameters& parameters, Workspace& workspace)
{
  workspace.known_dilation = 0;
  if (signature.width == 0 || workspace.run.estimates_reused)
    return;
  CarriedEstimates& carried = workspace.estimates;
  carried.valid = true;
  carried.signature = signature;
  carried.parameters = parameters;
  carried.profile = workspace.current_profile;
  carried.dilation = workspace.chosen_dilation;
  carried.frames = 1;
}

} // namespace detail
} // namespace range_nlm
