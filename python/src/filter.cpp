// denoise() and denoise_depth(): one frame through the library's TemporalStream with radius 0,
// the way range_nlm_denoise filters a single frame, with the GIL released while it filters.
#include "bindings.h"

#include <range_nlm/nonlocal_means_filter.h>
#include <range_nlm/parameter_registry.h>

#include <pybind11/stl.h>

#include <chrono>
#include <memory>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace range_nlm
{
namespace python
{
namespace
{

bool
sameParameters(const FilterParameters& a, const FilterParameters& b)
{
  for (const ParameterEntry& entry : parameterRegistry())
    if (parameterText(entry, a) != parameterText(entry, b))
      return false;
  return true;
}

/// The calling thread's static stream, kept while frames of one size come with one setting:
/// its workspace's buffers are then reused, as range_nlm_denoise reuses them over a directory
/// (allocating and first touching them costs about a sixth of a VGA frame's time). Each thread
/// has its own, so that frames filtered in parallel threads share nothing.
struct CachedStream
{
  std::unique_ptr<Stream> stream;
  FilterParameters parameters;
  std::uint32_t width = 0, height = 0;
};

CachedStream&
staticStream(const FilterParameters& parameters, const Cloud& frame)
{
  thread_local CachedStream cached;
  if (!cached.stream || cached.width != frame.width || cached.height != frame.height ||
      !sameParameters(cached.parameters, parameters)) {
    cached.stream.reset(); // its buffers go before the new ones are taken
    cached.stream = std::make_unique<Stream>(0, TemporalWindow::centred, parameters);
    cached.parameters = parameters;
    cached.width = frame.width;
    cached.height = frame.height;
  }
  return cached;
}

} // namespace

ThreadCount::ThreadCount(int threads)
{
#ifdef _OPENMP
  before_ = omp_get_max_threads();
  if (threads > 0)
    omp_set_num_threads(threads);
#else
  (void)threads;
#endif
}

ThreadCount::~ThreadCount()
{
#ifdef _OPENMP
  omp_set_num_threads(before_);
#endif
}

Interruptible::Interruptible(Stream& stream) : stream_(stream)
{
  stream_.setStageObserver(this);
}

Interruptible::~Interruptible()
{
  stream_.setStageObserver(nullptr);
}

namespace
{
/// Python runs signal handlers on its main thread only: the calls of other threads need not
/// take the GIL to look (they would wait for it while the main thread runs Python code).
unsigned long main_thread = 0;
} // namespace

void
Interruptible::begin(Stage, int)
{
  if (PyThread_get_thread_ident() != main_thread)
    return;
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() != 0)
    throw Interrupted();
}

namespace
{

/// Filters one frame (GIL released; Ctrl-C stops it); returns the result and its record.
std::pair<Cloud::Ptr, Stream::OutputInfo>
filterFrame(const Cloud::Ptr& frame, const FilterParameters& parameters)
{
  py::gil_scoped_release release;
  const ThreadCount threads(parameters.threads);
  CachedStream& cached = staticStream(parameters, *frame);
  try {
    const Interruptible interruptible(*cached.stream); // ends before the stream may go below
    const std::vector<Stream::CloudPtr> out = cached.stream->push(frame);
    return {out.front(), cached.stream->lastOutputs().front()};
  } catch (...) {
    cached.stream.reset(); // a run that failed half-way leaves nothing to reuse
    throw;
  }
}

Eigen::Vector4f
viewpointOf(const py::handle& viewpoint)
{
  if (viewpoint.is_none())
    return Eigen::Vector4f::Zero();
  const std::vector<float> v = viewpoint.cast<std::vector<float>>();
  if (v.size() != 3)
    throw py::value_error("range_nlm: viewpoint must be (x, y, z), got " + std::to_string(v.size()) + " values");
  checkViewpoint({v[0], v[1], v[2]}, "viewpoint");
  return {v[0], v[1], v[2], 0.0f};
}

py::tuple
denoise(const py::handle& points, const py::handle& parameters, const py::handle& viewpoint)
{
  const FilterParameters p = parametersOf(parameters);
  FrameFormat format;
  const Cloud::Ptr frame = cloudFromPoints(points, "points", viewpointOf(viewpoint), &format.type);
  const auto [result, info] = filterFrame(frame, p);
  return py::make_tuple(resultOf(*result, format), infoDict(info));
}

py::tuple
denoiseDepth(const py::handle& depth, const DepthIntrinsics& intrinsics, const py::handle& depth_scale,
             const std::string& output, const py::handle& parameters)
{
  const FilterParameters p = parametersOf(parameters);
  if (output != "depth" && output != "points")
    throw py::value_error("range_nlm: output must be 'depth' or 'points', got '" + output + "'");
  const double scale = depthScaleOf(depth, intrinsics, depth_scale);
  FrameFormat format;
  const Cloud::Ptr frame = cloudFromDepth(depth, intrinsics, scale, output == "depth", format, "depth");
  const auto [result, info] = filterFrame(frame, p);
  return py::make_tuple(resultOf(*result, format), infoDict(info));
}

/// The C++ library's own calls on a frame held in C++, for measuring what calling from Python
/// costs: run() times one NonLocalMeansFilter::filter() (`path` "filter", as a C++ program calls
/// the library) or one TemporalStream::push() of radius 0 ("stream", the call denoise() makes),
/// with the GIL released, and nothing else.
class LibraryTimer
{
public:
  LibraryTimer(const py::handle& points, const py::handle& parameters, const std::string& path)
      : input_(cloudFromPoints(points, "points", Eigen::Vector4f::Zero())), parameters_(parametersOf(parameters)),
        stream_path_(path == "stream")
  {
    if (path != "filter" && path != "stream")
      throw py::value_error("range_nlm: path must be 'filter' or 'stream', got '" + path + "'");
    filter_.setParameters(parameters_);
    filter_.setInputCloud(input_);
    stream_ = std::make_unique<Stream>(0, TemporalWindow::centred, parameters_);
  }
  /// Milliseconds of one call.
  double run()
  {
    py::gil_scoped_release release;
    const ThreadCount threads(parameters_.threads);
    const auto start = std::chrono::steady_clock::now();
    if (stream_path_)
      stream_output_ = stream_->push(input_).front();
    else
      filter_.filter(output_);
    const auto stop = std::chrono::steady_clock::now();
    return std::chrono::duration<double, std::milli>(stop - start).count();
  }
  py::array output() const { return pointsFromCloud(stream_path_ ? *stream_output_ : output_, 'f'); }

private:
  Cloud::Ptr input_;
  FilterParameters parameters_;
  bool stream_path_;
  Cloud output_;
  Stream::CloudPtr stream_output_;
  NonLocalMeansFilter<pcl::PointXYZ> filter_;
  std::unique_ptr<Stream> stream_;
};

} // namespace

double
depthScaleOf(const py::handle& depth, const DepthIntrinsics& intrinsics, const py::handle& depth_scale)
{
  if (!depth_scale.is_none())
    return depth_scale.cast<double>();
  const bool integer = py::isinstance<py::array>(depth) && py::reinterpret_borrow<py::array>(depth).dtype().kind() == 'u';
  return integer ? intrinsics.depth_scale : 1.0;
}

void
bindFilter(py::module_& m)
{
  main_thread = py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error)
        std::rethrow_exception(error);
    } catch (const Interrupted&) {
      if (!PyErr_Occurred()) // set by the signal handler that raised
        PyErr_SetNone(PyExc_KeyboardInterrupt);
    }
  });
  m.def("_denoise", &denoise, py::arg("points"), py::arg("parameters"), py::arg("viewpoint"));
  m.def("_denoise_depth", &denoiseDepth, py::arg("depth"), py::arg("intrinsics"), py::arg("depth_scale"),
        py::arg("output"), py::arg("parameters"));
  py::class_<LibraryTimer>(m, "_LibraryTimer")
      .def(py::init<const py::handle&, const py::handle&, const std::string&>(), py::arg("points"),
           py::arg("parameters"), py::arg("path") = "filter")
      .def("run", &LibraryTimer::run)
      .def("output", &LibraryTimer::output);
}

} // namespace python
} // namespace range_nlm
