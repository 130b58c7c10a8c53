// numpy frames <-> the library's organized clouds. Depth images go through the library's own
// conversions (depthImageToCloud, cloudToDepthImage, ...), the ones range_nlm_denoise uses.
#include "bindings.h"

#include <range_nlm/io/ray_reprojection.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

namespace range_nlm
{
namespace python
{
namespace
{

std::string
typeName(const py::handle& value)
{
  return py::str(value.get_type().attr("__name__")).cast<std::string>();
}

std::string
shapeText(const py::array& a)
{
  std::string text = "(";
  for (py::ssize_t k = 0; k < a.ndim(); ++k)
    text += (k ? ", " : "") + std::to_string(a.shape(k));
  return text + (a.ndim() == 1 ? ",)" : ")");
}

/// The array `value`, checked: a numpy array, or anything numpy.asarray takes (a list, a tuple,
/// an object with __array__), of `ndim` dimensions (the last of size `last` if `last` > 0), not
/// empty, of one of `types` (numpy type characters). An array-like of integers becomes
/// `integers_as` (0: refused by its type). A C-contiguous, aligned array of native byte order is
/// returned as it is (read in place); any other (a strided view, a transposed or byte-swapped
/// array) is copied into one.
py::array
checkedArray(const py::handle& value, const char* what, int ndim, py::ssize_t last, const char* layout,
             const std::string& types, const char* type_names, char integers_as = 0)
{
  const py::module_ numpy = py::module_::import("numpy");
  py::array a;
  if (py::isinstance<py::array>(value)) {
    a = py::reinterpret_borrow<py::array>(value);
  } else {
    try {
      a = numpy.attr("asarray")(value);
    } catch (const py::error_already_set& e) {
      throw py::type_error("range_nlm: " + std::string(what) + " must be a numpy array or an array-like (" + layout +
                           "), got " + typeName(value) + " (numpy.asarray: " + e.what() + ")");
    }
    const char kind = a.dtype().kind();
    if (kind == 'O' || kind == 'U' || kind == 'S' || kind == 'V')
      throw py::type_error("range_nlm: " + std::string(what) + " must be a numpy array or an array-like of numbers (" +
                           layout + "), got " + typeName(value) + " that numpy reads as " +
                           py::str(a.dtype()).cast<std::string>() + " of shape " + shapeText(a));
    if (integers_as != 0 && (kind == 'i' || kind == 'u' || kind == 'b'))
      a = a.attr("astype")(std::string(1, integers_as));
  }
  if (a.ndim() != ndim || (last > 0 && a.shape(ndim - 1) != last) || a.size() == 0)
    throw py::value_error("range_nlm: " + std::string(what) + " must be " + layout + ", got shape " + shapeText(a));
  const char type = a.dtype().char_();
  const bool native = a.dtype().attr("isnative").cast<bool>();
  if (types.find(type) == std::string::npos) {
    const char kind = a.dtype().kind();
    // Integers other than uint16 for a depth image: raw sensor units or metres cannot be told.
    const bool depth_integers = types.find('H') != std::string::npos && (kind == 'i' || kind == 'u' || kind == 'b');
    throw py::type_error("range_nlm: " + std::string(what) + " must be " + type_names + ", got " +
                         py::str(a.dtype()).cast<std::string>() +
                         (py::isinstance<py::array>(value) ? "" : " (the array numpy makes of the " + typeName(value) +
                                                                      ")") +
                         (depth_integers ? "; give numpy.asarray(depth, dtype=numpy.uint16) for raw sensor values, "
                                           "floats for metres"
                                         : ""));
  }
  if (!native || !(a.flags() & py::array::c_style) || !(a.flags() & py::detail::npy_api::NPY_ARRAY_ALIGNED_))
    a = numpy.attr("ascontiguousarray")(a, a.dtype().attr("newbyteorder")("="));
  return a;
}

template <typename Scalar>
void
copyPoints(const Scalar* data, Cloud& cloud)
{
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    pcl::PointXYZ& p = cloud[i];
    p.x = static_cast<float>(data[3 * i]);
    p.y = static_cast<float>(data[3 * i + 1]);
    p.z = static_cast<float>(data[3 * i + 2]);
  }
}

template <typename Scalar>
py::array
pointsArray(const Cloud& cloud)
{
  py::array_t<Scalar> out({static_cast<py::ssize_t>(cloud.height), static_cast<py::ssize_t>(cloud.width),
                           py::ssize_t(3)});
  Scalar* data = out.mutable_data();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    data[3 * i] = cloud[i].x;
    data[3 * i + 1] = cloud[i].y;
    data[3 * i + 2] = cloud[i].z;
  }
  return std::move(out);
}

/// Warns (RuntimeWarning) as range_nlm_denoise does when filtering moved depths out of 16 bits.
void
warnClamping(const DepthClamping& clamping, double depth_scale)
{
  if (clamping.above == 0 && clamping.below == 0)
    return;
  const std::string warning = "range_nlm: " + clampingText(clamping, depth_scale);
  if (PyErr_WarnEx(PyExc_RuntimeWarning, warning.c_str(), 1) != 0)
    throw py::error_already_set();
}

} // namespace

Cloud::Ptr
cloudFromPoints(const py::handle& points, const char* what, const Eigen::Vector4f& viewpoint, char* type)
{
  const py::array a = checkedArray(points, what, 3, 3, "an organized H x W x 3 array of points (NaN = invalid)",
                                   "fd", "float32 or float64", 'd');
  if (type)
    *type = a.dtype().char_();
  Cloud::Ptr cloud(new Cloud(static_cast<std::uint32_t>(a.shape(1)), static_cast<std::uint32_t>(a.shape(0))));
  if (a.dtype().char_() == 'f')
    copyPoints(static_cast<const float*>(a.data()), *cloud);
  else
    copyPoints(static_cast<const double*>(a.data()), *cloud);
  cloud->sensor_origin_ = viewpoint;
  cloud->is_dense = false;
  return cloud;
}

py::array
pointsFromCloud(const Cloud& cloud, char type)
{
  return type == 'd' ? pointsArray<double>(cloud) : pointsArray<float>(cloud);
}

Cloud::Ptr
cloudFromDepth(const py::handle& depth, const DepthIntrinsics& intrinsics, double depth_scale, bool depth_output,
               FrameFormat& format, const char* what)
{
  const py::array a = checkedArray(depth, what, 2, 0, "an H x W depth image", "Hfd", "uint16, float32 or float64");
  DepthIntrinsics scaled = intrinsics;
  scaled.depth_scale = depth_scale;
  format.depth = true;
  format.type = a.dtype().char_();
  format.depth_scale = depth_scale;
  format.depth_output = depth_output;
  const int height = static_cast<int>(a.shape(0)), width = static_cast<int>(a.shape(1));
  const std::size_t count = static_cast<std::size_t>(a.size());
  if (format.type == 'H') {
    DepthImage image;
    image.width = width;
    image.height = height;
    image.values.resize(count);
    std::memcpy(image.values.data(), a.data(), count * sizeof(std::uint16_t));
    const Cloud::Ptr cloud(new Cloud(depthImageToCloud(image, scaled)));
    format.input = cloud;
    return cloud;
  }
  std::vector<float> values(count);
  bool nan_marks_invalid = false;
  for (std::size_t i = 0; i < count; ++i) {
    values[i] = format.type == 'f' ? static_cast<const float*>(a.data())[i]
                                   : static_cast<float>(static_cast<const double*>(a.data())[i]);
    nan_marks_invalid = nan_marks_invalid || std::isnan(values[i]);
  }
  format.invalid_value = nan_marks_invalid ? std::numeric_limits<float>::quiet_NaN() : 0.0f;
  const Cloud::Ptr cloud(new Cloud(depthMapToCloud(values, width, height, scaled)));
  format.input = cloud;
  return cloud;
}

py::object
resultOf(const Cloud& result, const FrameFormat& format)
{
  if (!format.depth)
    return pointsFromCloud(result, format.type);
  if (!format.depth_output)
    return pointsFromCloud(result, 'f');
  const py::ssize_t height = result.height, width = result.width;
  if (format.type == 'H') {
    // A depth image's input always fitted 16 bits, so a depth filtering moved just past them is
    // clamped with a warning, as range_nlm_denoise's PNG output does.
    DepthClamping clamping;
    const DepthImage image = cloudToDepthImage(*format.input, result, format.depth_scale, &clamping);
    warnClamping(clamping, format.depth_scale);
    py::array_t<std::uint16_t> out({height, width});
    std::memcpy(out.mutable_data(), image.values.data(), image.values.size() * sizeof(std::uint16_t));
    return std::move(out);
  }
  // Each point on its pixel's ray first, as the 16-bit encoding does.
  const std::vector<double> depths = cloudToDepthValues(reprojectOntoRays(*format.input, result), format.depth_scale);
  auto fill = [&](auto out) {
    auto* data = out.mutable_data();
    for (std::size_t i = 0; i < depths.size(); ++i)
      data[i] = std::isnan(depths[i]) ? format.invalid_value : depths[i];
    return py::object(std::move(out));
  };
  return format.type == 'f' ? fill(py::array_t<float>({height, width})) : fill(py::array_t<double>({height, width}));
}

py::dict
infoDict(const Stream::OutputInfo& info)
{
  py::dict d;
  d["filtered"] = info.problem.empty();
  d["reason"] = info.problem.empty() ? py::object(py::none()) : py::object(py::str(info.problem));
  d["distance_bandwidth"] = info.bandwidths.distance;
  d["similarity_bandwidth"] = info.bandwidths.similarity;
  d["mu_d"] = info.bandwidths.mu_d;
  d["sigma_s"] = info.bandwidths.sigma_s;
  d["outliers_moved"] = info.outliers_moved;
  d["ms"] = info.milliseconds;
  return d;
}

} // namespace python
} // namespace range_nlm
