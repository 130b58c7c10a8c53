/// \file temporal_stream.h
/// \brief Frame-by-frame temporal filtering for live sensors and long recordings.
#pragma once

#include <range_nlm/core/pipeline.h>
#include <range_nlm/grid_adaptor.h>
#include <range_nlm/parameters.h>
#include <range_nlm/temporal_nonlocal_means_filter.h>

#include <pcl/point_cloud.h>

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace range_nlm
{

/// Which frames are the temporal neighbours of frame t.
enum class TemporalWindow
{
  /// t - r .. t + r (clipped at the sequence's ends): output lags input by r frames.
  centred,
  /// t - r .. t: no output delay.
  causal,
  /// Frame t and the history of the sequence before it (RunningAverage), one neighbour: per pixel a
  /// running average, the newest frame weighted 1 / (2r + 1), that starts over from the filtered
  /// output where the scene or the camera moved. No output delay; like an exponential moving
  /// average that is motion- and edge-aware (the history restarts where a pixel changed, and a
  /// patch that moved is not similar, so it gets no weight); memory and time per frame do not
  /// grow with the sequence. Outputs only start a pixel's history, after that it averages input
  /// frames, so that the filter's own bias does not pile up over the frames. Every frame pushed
  /// is filtered (`wanted` of push() is ignored), since each output may start the next frames'
  /// history, except a null frame (not wanted): it comes out null and ends the history, so the
  /// frame after it is filtered as the first of a sequence (how a run over part of a recording
  /// starts its history at a chosen frame).
  recursive
};

/// Push frames one by one; each filtered frame comes out once its window is complete.
/// A frame that cannot be filtered (UnfilterableFrame: all NaN, or too few valid points for the
/// noise estimate, e.g. a covered lens) comes out unchanged, NaN where it was NaN, and the stream
/// goes on; lastOutputs() says which outputs those were. As a neighbour such a frame contributes
/// nothing.
/// Centred mode (default): the window of frame t is t - r .. t + r (clipped at the sequence
/// start and end), so output lags input by r frames. Causal mode: the window is t - r .. t and
/// every frame comes out as soon as it is pushed. flush() ends the sequence; every pushed frame
/// yields exactly one output frame, in order. At most 2r + 1 (causal: r + 1) frames are held.
/// Each output is the caller's alone until it lets go of it (its last shared pointer is gone, on
/// any thread, also after the stream itself): then its storage may hold a later output of the
/// stream instead of being freed (at most two such clouds are kept), so that a stream at camera
/// rate allocates no frame per frame. A weak pointer to a released output expires as usual.
template <typename PointT>
class TemporalStream
{
public:
  using PointCloud = pcl::PointCloud<PointT>;
  using CloudConstPtr = typename PointCloud::ConstPtr;
  using CloudPtr = typename PointCloud::Ptr;

  /// Throws std::invalid_argument for a negative radius or invalid parameters.
  TemporalStream(int radius, TemporalWindow window, const FilterParameters& parameters);
  /// The same with `causal` choosing TemporalWindow::causal over TemporalWindow::centred.
  TemporalStream(int radius, bool causal, const FilterParameters& parameters)
      : TemporalStream(radius, causal ? TemporalWindow::causal : TemporalWindow::centred, parameters)
  {
  }

  /// Adds the next frame; returns the frames that became ready (zero or one). Throws
  /// std::invalid_argument, leaving the stream as it was (the frame can be skipped), if the
  /// frame's size differs from the first frame's, its point count from width x height, it
  /// holds an infinite coordinate, or its viewpoint (sensor_origin_) is not finite.
  /// With `wanted` false the frame is only a neighbour of the others: it is not filtered and its
  /// output is a null pointer (for resuming a run, or a pass of a schedule whose next pass reads
  /// only some frames). Such a frame may itself be null if no wanted frame's window holds it;
  /// a wanted frame whose window holds a null frame throws std::invalid_argument.
  std::vector<CloudPtr> push(const CloudConstPtr& frame, bool wanted = true);
  /// Filters the frames still waiting for future neighbours, with the windows clipped at the end.
  std::vector<CloudPtr> flush();

  /// Frames currently held in memory (input frames and, in recursive mode, the history).
  std::size_t heldFrames() const { return window_.size() + (history_.empty() ? 0 : 1); }
  /// Psi_k of the last frame produced.
  const std::vector<float>& lastFrameWeights() const { return last_weights_; }
  /// Bandwidths of the current frame of the last frame produced.
  const Bandwidths& lastBandwidths() const { return last_bandwidths_; }
  /// What became of one frame returned by push() or flush().
  struct OutputInfo
  {
    /// Empty if the frame was filtered (or not wanted), else why it was passed through unchanged.
    std::string problem;
    /// Bandwidths of the frame (first iteration); zero if it was not filtered.
    Bandwidths bandwidths;
    /// Time the filter took for it, milliseconds.
    double milliseconds = 0.0;
    /// Its isolated outliers moved onto their neighbours' surface (FilterParameters::outlier_sigmas).
    std::size_t outliers_moved = 0;
    /// With FilterParameters::uncertainty: the per-point standard deviation of the output along
    /// each point's direction of movement, organized like the output (index v * width + u),
    /// metres, NaN for invalid points (as NonLocalMeansFilter::getUncertainty). Empty when off,
    /// or when the frame was passed through unchanged.
    std::vector<float> uncertainty;
    /// Points given a range by the hole filling (FilterParameters::fill_holes): 1 per filled
    /// point, in the cloud's order; empty when the hole filling is off.
    std::vector<unsigned char> filled;
  };
  /// One entry per frame returned by the last push() or flush(), in the same order.
  const std::vector<OutputInfo>& lastOutputs() const { return last_outputs_; }
  /// Told where each phase of every filter run begins and ends (see StageObserver); not owned.
  void setStageObserver(StageObserver* observer) { workspace_.setStageObserver(observer); }

private:
  /// A frame of the window with its grid, converted once, when a window first needs it.
  struct HeldFrame
  {
    CloudConstPtr cloud;
    bool wanted = true; // whether the frame is to be filtered
    bool converted = false;
    Grid grid;
  };

  /// Clouds whose caller let go of them, for the next outputs (shared with their deleters).
  struct OutputPool
  {
    std::mutex mutex;
    std::vector<std::unique_ptr<PointCloud>> spare;
  };
  /// The deleter of an output: its storage back to the pool if the pool is still there and holds
  /// fewer than two, else freed.
  struct RecycleOutput
  {
    std::weak_ptr<OutputPool> pool;
    void operator()(PointCloud* cloud) const;
  };
  /// An output cloud: a spare one (its points still there, to be overwritten) or a new one.
  CloudPtr newOutput();

  CloudPtr filterAt(std::size_t t);
  /// Frame t's grid, converted on first use; `position` is its index in the window being filtered
  /// (for the error message).
  const Grid& gridOf(std::size_t t, std::size_t position);
  /// Recursive mode: frame t enters the history, with the last run's output as where its pixels'
  /// histories start if `filtered`.
  void remember(std::size_t t, bool filtered);
  void dropBefore(std::size_t t);

  int radius_;
  bool causal_;
  bool recursive_ = false;
  RunningAverage history_; // recursive mode: the running average of the frames so far
  Grid start_grid_;        // recursive mode: the filtered output, where a pixel's history starts
  /// 1 / weight of the newest frame in the history: 2r + 1, the centred window's frame count.
  int historyLength() const;
  FilterParameters parameters_;
  std::deque<HeldFrame> window_; // frames first_ .. first_ + size - 1
  Grid spare_grid_;              // the storage of a dropped frame's grid, for the next frame
  std::size_t first_ = 0;        // sequence index of window_.front()
  std::uint32_t width_ = 0, height_ = 0; // size of the first frame pushed
  std::size_t pushed_ = 0;
  std::size_t emitted_ = 0;
  std::vector<float> last_weights_;
  Bandwidths last_bandwidths_;
  std::vector<OutputInfo> last_outputs_;
  /// One workspace for the whole sequence, so that its buffers are reused from frame to frame.
  FilterWorkspace workspace_;
  std::shared_ptr<OutputPool> pool_ = std::make_shared<OutputPool>();
};

/// Batch form: filters a whole sequence with the same windows as TemporalStream.
template <typename PointT>
std::vector<typename pcl::PointCloud<PointT>::Ptr>
filterSequence(const std::vector<typename pcl::PointCloud<PointT>::ConstPtr>& frames, int radius,
               TemporalWindow window, const FilterParameters& parameters);
/// The same with `causal` choosing TemporalWindow::causal over TemporalWindow::centred.
template <typename PointT>
std::vector<typename pcl::PointCloud<PointT>::Ptr>
filterSequence(const std::vector<typename pcl::PointCloud<PointT>::ConstPtr>& frames, int radius,
               bool causal, const FilterParameters& parameters);

} // namespace range_nlm

#ifdef RANGE_NLM_HEADER_ONLY
#include <range_nlm/impl/temporal_stream.hpp>
#endif
