// The public handle of a filter run's buffers.
#include "workspace.h"

namespace range_nlm
{

FilterWorkspace::FilterWorkspace() : workspace_(std::make_unique<Workspace>()) {}

FilterWorkspace::~FilterWorkspace() = default;

FilterWorkspace::FilterWorkspace(const FilterWorkspace& other)
    : workspace_(std::make_unique<Workspace>(*other.workspace_))
{
}

FilterWorkspace::FilterWorkspace(FilterWorkspace&& other) noexcept = default;

FilterWorkspace&
FilterWorkspace::operator=(const FilterWorkspace& other)
{
  if (this != &other)
    workspace_ = std::make_unique<Workspace>(*other.workspace_);
  return *this;
}

FilterWorkspace&
FilterWorkspace::operator=(FilterWorkspace&& other) noexcept = default;

const FilterRun&
FilterWorkspace::result() const
{
  return workspace_->run;
}

const NoiseProfile&
FilterWorkspace::currentProfile() const
{
  return workspace_->current_profile;
}

const FrameOffset*
FilterWorkspace::frameChange(int k) const
{
  const std::vector<FrameOffset>& changes = workspace_->frame_changes;
  return k >= 0 && static_cast<std::size_t>(k) < changes.size() ? &changes[static_cast<std::size_t>(k)] : nullptr;
}

std::vector<Grid>&
FilterWorkspace::inputs()
{
  return workspace_->inputs;
}

void
FilterWorkspace::setStageObserver(StageObserver* observer)
{
  workspace_->observer = observer;
}

void
runFilter(const std::vector<const Grid*>& frames, int center, const FilterParameters& parameters,
          const Viewpoint& viewpoint, const std::vector<unsigned char>& active, FilterWorkspace& workspace)
{
  runFilter(frames, center, parameters, viewpoint, active, *workspace.workspace_);
}

} // namespace range_nlm
