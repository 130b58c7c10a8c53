// Stage::outliers: the current frame's isolated outliers moved onto their neighbours' surface.
#include "stages.h"

namespace range_nlm
{

const Grid*
detail::correctOutliersStage(const Grid& input, const NoiseProfile& profile, const FilterParameters& parameters,
                             const Viewpoint& viewpoint, const std::vector<unsigned char>& active,
                             Workspace& workspace)
{
  const int threads = resolveThreads(parameters.threads);
  const bool sized = active.empty() || active.size() == input.size(); // runContiguous reports a mismatch
  if (profile.empty() || !sized)
    return &input;
  const std::vector<IsolatedPoint> found =
      findIsolatedPoints(input, profile, parameters.outlier_sigmas, viewpoint, active, threads,
                         workspace.range_scratch[0]);
  if (found.empty())
    return &input;
  copyGrid(input, workspace.corrected, threads);
  moveIsolatedPoints(workspace.corrected, found, viewpoint);
  workspace.run.outliers_moved = found.size();
  return &workspace.corrected;
}

} // namespace range_nlm
