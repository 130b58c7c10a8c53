// Stream: the library's TemporalStream for sequences of numpy frames, as range_nlm_denoise
// --input-dir runs it for one temporal pass.
#include "bindings.h"

#include <pybind11/stl.h>

#include <deque>
#include <mutex>
#include <optional>

namespace range_nlm
{
namespace python
{
namespace
{

TemporalWindow
windowNamed(const std::string& mode)
{
  if (mode == "centred" || mode == "centered")
    return TemporalWindow::centred;
  if (mode == "causal")
    return TemporalWindow::causal;
  if (mode == "recursive")
    return TemporalWindow::recursive;
  throw py::value_error("range_nlm: mode must be 'centred', 'causal' or 'recursive', got '" + mode + "'");
}

/// A TemporalStream with the format of every frame still inside it, so that each result goes
/// out as its frame came in. One call at a time: a second thread waits (the GIL is released
/// while frames are filtered).
class PythonStream
{
public:
  PythonStream(int radius, const std::string& mode, const std::optional<DepthIntrinsics>& intrinsics,
               const py::handle& depth_scale, const std::string& output, const py::handle& parameters)
      : stream_(radius, windowNamed(mode), parametersOf(parameters)), threads_(parametersOf(parameters).threads),
        intrinsics_(intrinsics),
        depth_scale_(py::reinterpret_borrow<py::object>(depth_scale)), depth_output_(output == "depth")
  {
    if (output != "depth" && output != "points")
      throw py::value_error("range_nlm: output must be 'depth' or 'points', got '" + output + "'");
  }

  /// The frames that became ready (none or one) in their input's format.
  py::list push(const py::handle& frame)
  {
    FrameFormat format;
    Cloud::Ptr cloud;
    const std::string what = "frame " + std::to_string(pushed_);
    // An array-like is taken as numpy.asarray reads it, so that its dimensions tell a depth image.
    const py::object array = !intrinsics_ || py::isinstance<py::array>(frame)
                                 ? py::reinterpret_borrow<py::object>(frame)
                                 : py::module_::import("numpy").attr("asarray")(frame);
    if (intrinsics_ && py::isinstance<py::array>(array) && py::reinterpret_borrow<py::array>(array).ndim() == 2)
      cloud = cloudFromDepth(array, *intrinsics_, depthScaleOf(array, *intrinsics_, depth_scale_), depth_output_,
                             format, what.c_str());
    else
      cloud = cloudFromPoints(frame, what.c_str(), Eigen::Vector4f::Zero(), &format.type);
    return run([&] { return stream_.push(cloud); }, &format);
  }

  /// The frames still waiting for their future neighbours (centred window), in order.
  py::list flush()
  {
    return run([&] { return stream_.flush(); }, nullptr);
  }

  py::list lastInfo() const
  {
    py::list list;
    for (const Stream::OutputInfo& info : infos_)
      list.append(infoDict(info));
    return list;
  }
  std::size_t heldFrames() const { return stream_.heldFrames(); }

private:
  /// Runs `step` (a push of a frame of `format`, or a flush) with the GIL released and the
  /// stream to itself; returns its frames in their input's format.
  template <typename Step>
  py::list run(const Step& step, const FrameFormat* format)
  {
    std::vector<Stream::CloudPtr> ready;
    std::vector<FrameFormat> taken;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(busy_);
      const ThreadCount threads(threads_);
      if (!broken_.empty())
        throw std::runtime_error(broken_);
      const std::size_t held = stream_.heldFrames();
      try {
        const Interruptible interruptible(stream_);
        ready = step();
      } catch (const Interrupted&) {
        // Stopped in the run of the first frame this call filters: the stream is as it was
        // before that run, with a pushed frame held (its result comes with the next call) and
        // the run done again by the next push or flush. Stopped in a later run, the frames
        // filtered before it are lost.
        if (stream_.lastOutputs().size() > 1)
          broken_ = "range_nlm: the stream cannot go on after an interruption that lost filtered frames";
        else if (format)
          takeIn(*format);
        throw;
      } catch (const std::exception& e) {
        // A refused frame leaves the stream as it was; a run that failed half-way does not.
        if (stream_.heldFrames() != held)
          broken_ = std::string("range_nlm: the stream cannot go on after an earlier failure: ") + e.what();
        throw;
      }
      if (format)
        takeIn(*format);
      for (std::size_t k = 0; k < ready.size(); ++k) {
        taken.push_back(formats_.front());
        formats_.pop_front();
      }
      infos_ = stream_.lastOutputs();
    }
    py::list out;
    for (std::size_t k = 0; k < ready.size(); ++k)
      out.append(resultOf(*ready[k], taken[k]));
    return out;
  }

  void takeIn(const FrameFormat& format)
  {
    formats_.push_back(format);
    ++pushed_;
  }

  Stream stream_;
  int threads_;
  std::optional<DepthIntrinsics> intrinsics_;
  py::object depth_scale_;
  bool depth_output_;
  std::deque<FrameFormat> formats_; // of the frames pushed and not yet out
  std::vector<Stream::OutputInfo> infos_;
  std::size_t pushed_ = 0;
  std::string broken_; // why the stream cannot go on, if it cannot
  std::mutex busy_;
};

} // namespace

void
bindStream(py::module_& m)
{
  py::class_<PythonStream>(m, "_Stream")
      .def(py::init<int, const std::string&, const std::optional<DepthIntrinsics>&, const py::handle&,
                    const std::string&, const py::handle&>(),
           py::arg("radius"), py::arg("mode"), py::arg("intrinsics"), py::arg("depth_scale"), py::arg("output"),
           py::arg("parameters"))
      .def("push", &PythonStream::push, py::arg("frame"))
      .def("flush", &PythonStream::flush)
      .def("last_info", &PythonStream::lastInfo)
      .def_property_readonly("held_frames", &PythonStream::heldFrames);
}

} // namespace python
} // namespace range_nlm
