// The pieces of the range_nlm Python module (module.cpp puts them together): numpy frames <->
// the library's clouds, the parameter registry as keyword arguments, the filter's entry points,
// the temporal stream, file reading and writing, and renders.
#pragma once

#include <range_nlm/core/pipeline.h>
#include <range_nlm/io/depth_image.h>
#include <range_nlm/parameters.h>
#include <range_nlm/temporal_stream.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

namespace range_nlm
{
namespace python
{

namespace py = pybind11;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Stream = TemporalStream<pcl::PointXYZ>;

/// How a frame came in, so that its result goes out the same way.
struct FrameFormat
{
  /// A depth image (H x W); otherwise points (H x W x 3, NaN = invalid).
  bool depth = false;
  /// numpy's type character of the array: 'f' float32, 'd' float64, 'H' uint16 (depth only).
  char type = 'f';
  /// Depth images: stored values per metre (value / depth_scale = z in metres).
  double depth_scale = 1.0;
  /// Depth images: the result is a depth image of the input's type; false: points (float32).
  bool depth_output = true;
  /// Float depth images: the value of pixels without measurement in the input (0 or NaN), kept
  /// in the output.
  float invalid_value = 0.0f;
  /// Depth images: the frame's points as they came in, for the depth encoding (which may take
  /// the input and the filtered points, as range_nlm_denoise's PNG output does).
  Cloud::ConstPtr input;
};

/// The organized cloud of an H x W x 3 float32 / float64 array with the sensor at `viewpoint`: a
/// C-contiguous array is read in place; a strided view, another byte order or an array-like (a
/// nested list of numbers; integers become float64) is copied first. `type`, if given, is set to
/// the numpy type character of the points read ('f' or 'd'). Throws TypeError / ValueError naming
/// `what` for any other type or shape.
Cloud::Ptr
cloudFromPoints(const py::handle& points, const char* what, const Eigen::Vector4f& viewpoint, char* type = nullptr);
/// A new H x W x 3 array of `type` ('f' or 'd') holding the cloud's points.
py::array
pointsFromCloud(const Cloud& cloud, char type);

/// The cloud of an H x W uint16 or float depth image (any layout, or an array-like of floats)
/// back-projected with `intrinsics` and
/// `depth_scale` (library code: depthImageToCloud / depthMapToCloud); `format` is set to match.
Cloud::Ptr
cloudFromDepth(const py::handle& depth, const DepthIntrinsics& intrinsics, double depth_scale, bool depth_output,
               FrameFormat& format, const char* what);
/// The depth scale of a depth image: `depth_scale` if not None, else the intrinsics' for a
/// uint16 image and 1 (metres) for a float one.
double
depthScaleOf(const py::handle& depth, const DepthIntrinsics& intrinsics, const py::handle& depth_scale);
/// The result of a frame in its input's format: points, or a depth image encoded by the
/// library's cloudToDepthImage (uint16, as range_nlm_denoise writes PNGs) or cloudToDepthValues.
py::object
resultOf(const Cloud& result, const FrameFormat& format);

/// The frame's record as a dict: the bandwidths the filter chose, the time, outliers moved, and
/// why it was passed through unfiltered (range_nlm_denoise --json's keys).
py::dict
infoDict(const Stream::OutputInfo& info);

/// `threads` (> 0) for every OpenMP region the calling thread starts while it exists, also those
/// that do not take the parameter, as range_nlm_denoise --threads sets it; the count before is
/// restored at its end.
class ThreadCount
{
public:
  explicit ThreadCount(int threads);
  ~ThreadCount();
  ThreadCount(const ThreadCount&) = delete;
  ThreadCount& operator=(const ThreadCount&) = delete;

private:
  int before_ = 1;
};

/// The path a path argument names, as Python's open() takes it: a str, bytes or os.PathLike
/// (os.fspath), encoded as os.fsencode does. Throws TypeError for anything else and ValueError
/// for an embedded null byte (which would cut the path short), both naming the argument `name`.
std::string
pathArgument(const py::handle& value, const char* name);

/// Thrown out of a filter run when a Python signal handler raised (Ctrl-C: KeyboardInterrupt);
/// the Python exception is already set, and the module's exception translator lets it through.
struct Interrupted : std::exception
{
  const char* what() const noexcept override { return "range_nlm: interrupted"; }
};

/// Makes the runs of `stream` interruptible while it exists: at the start of every stage (the
/// stream's StageObserver, called on the calling thread between parallel regions) the GIL is
/// taken for a moment and Python's signal handlers run (PyErr_CheckSignals); if one raised, the
/// run stops with Interrupted. The stream keeps no half-filtered result: its next run starts over.
class Interruptible : private StageObserver
{
public:
  explicit Interruptible(Stream& stream);
  ~Interruptible();
  Interruptible(const Interruptible&) = delete;
  Interruptible& operator=(const Interruptible&) = delete;

private:
  void begin(Stage stage, int iteration) override;
  void end(Stage, int) override {}
  Stream& stream_;
};

/// The FilterParameters of a Parameters object, or of None (the recommended setting).
FilterParameters
parametersOf(const py::handle& parameters);

void
bindParameters(py::module_& m);
void
bindFilter(py::module_& m);
void
bindStream(py::module_& m);
void
bindFiles(py::module_& m);

} // namespace python
} // namespace range_nlm
