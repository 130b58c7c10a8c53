/// \file message_stream.h
/// \brief TemporalStream for message streams: each frame carries a tag (its message) out with
/// its result, and a frame of another size starts a new temporal window.
#pragma once

#include <range_nlm/parameters.h>
#include <range_nlm/temporal_stream.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <deque>
#include <memory>
#include <string>
#include <vector>

namespace range_nlm_ros
{

/// What the nodelet and the bag filter do with a stream of frames; the names are those of
/// range_nlm_denoise's options.
struct StreamSettings
{
  range_nlm::FilterParameters parameters = range_nlm::FilterParameters::recommended();
  /// r: frames on each side (0 = every frame filtered alone). >= 0.
  int temporal_radius = 0;
  /// Which frames are neighbours; see range_nlm::TemporalWindow.
  range_nlm::TemporalWindow window = range_nlm::TemporalWindow::centred;

  /// Throws std::invalid_argument naming the first invalid setting and its value.
  void validate() const
  {
    parameters.validate();
    if (temporal_radius < 0)
      throw std::invalid_argument("temporal_radius must be >= 0, got " + std::to_string(temporal_radius));
  }
};

/// A range_nlm::TemporalStream<pcl::PointXYZ> whose frames carry a `Tag` (e.g. the message they
/// came from) to their output. Frames come out in order, each once its window is complete (at
/// once in causal and recursive windows, r frames later in a centred one).
template <typename Tag>
class TaggedStream
{
public:
  using Cloud = pcl::PointCloud<pcl::PointXYZ>;
  struct Output
  {
    Tag tag;
    Cloud::Ptr cloud;
    /// Empty if filtered, else why the frame came out unchanged (e.g. too few valid points).
    std::string problem;
    double milliseconds = 0.0;
    /// Bandwidths the filter chose for it (first iteration); zero if it was not filtered.
    range_nlm::Bandwidths bandwidths;
    /// With range_nlm::FilterParameters::uncertainty: its per-point standard deviation along
    /// the moves, metres, row-major, NaN at invalid points; empty otherwise.
    std::vector<float> uncertainty;
    /// 1 per point the hole filling gave a range (FilterParameters::fill_holes); empty when off.
    std::vector<unsigned char> filled;
  };

  /// Throws std::invalid_argument for invalid settings.
  explicit TaggedStream(const StreamSettings& settings) : settings_(settings)
  {
    settings_.validate();
    restart();
  }

  /// Adds a frame. A frame of another size than the frames before it first ends their window
  /// (the frames still waiting come out first, filtered with the window clipped there) and then
  /// starts a new one; restarted() says so. Throws std::invalid_argument, with the stream as it
  /// was, if the frame is smaller than the windows or the stream refuses it.
  std::vector<Output> push(const Cloud::ConstPtr& frame, const Tag& tag)
  {
    restarted_ = false;
    settings_.parameters.validateFor(static_cast<int>(frame->width), static_cast<int>(frame->height));
    std::vector<Output> out;
    if (started_ && (frame->width != width_ || frame->height != height_)) {
      out = flush();
      restarted_ = true;
    }
    collect(stream_->push(frame), out, &tag);
    started_ = true;
    width_ = frame->width;
    height_ = frame->height;
    return out;
  }

  /// Ends the sequence: the frames still waiting come out; the next frame starts a new window.
  std::vector<Output> flush()
  {
    std::vector<Output> out;
    collect(stream_->flush(), out, nullptr);
    restart();
    return out;
  }

  /// The filter's parameters (a frame too small for their windows is refused by push()).
  const range_nlm::FilterParameters& parameters() const { return settings_.parameters; }
  /// The last push() started a new window because the frame size changed.
  bool restarted() const { return restarted_; }
  /// Width and height of the current window's frames (0 before the first frame).
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }

private:
  void restart()
  {
    stream_ = std::make_unique<range_nlm::TemporalStream<pcl::PointXYZ>>(settings_.temporal_radius, settings_.window,
                                                                         settings_.parameters);
    started_ = false;
    width_ = height_ = 0;
  }

  // The tag of the frame just pushed joins the queue only once the stream has accepted the frame.
  void collect(const std::vector<Cloud::Ptr>& ready, std::vector<Output>& out, const Tag* pushed)
  {
    if (pushed)
      tags_.push_back(*pushed);
    const auto& infos = stream_->lastOutputs();
    for (std::size_t i = 0; i < ready.size(); ++i) {
      out.push_back(Output{tags_.front(), ready[i], infos[i].problem, infos[i].milliseconds, infos[i].bandwidths,
                           infos[i].uncertainty, infos[i].filled});
      tags_.pop_front();
    }
  }

  StreamSettings settings_;
  std::unique_ptr<range_nlm::TemporalStream<pcl::PointXYZ>> stream_;
  std::deque<Tag> tags_;
  bool started_ = false;
  bool restarted_ = false;
  std::uint32_t width_ = 0, height_ = 0;
};

} // namespace range_nlm_ros
