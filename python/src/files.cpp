// Files and pictures through range_nlm::io and range_nlm::eval: PCD frames, 16-bit depth PNGs,
// intrinsics files and renders, with the tools' checked errors (each names the file).
#include "bindings.h"

#include <range_nlm/eval/render.h>
#include <range_nlm/io/pcd_file.h>
#include <range_nlm/io/process_memory.h>

#include <pybind11/stl.h>

#include <cstring>
#include <stdexcept>

namespace range_nlm
{
namespace python
{
namespace
{

/// The colours of a cloud with an `rgb` or `rgba` field (PCL's packing: 0x00RRGGBB in 4 bytes,
/// blue first in memory) as H x W x 3 uint8 (red, green, blue); None without such a field.
py::object
colorsOf(const pcl::PCLPointCloud2& blob)
{
  const pcl::PCLPointField* rgb = nullptr;
  for (const pcl::PCLPointField& f : blob.fields)
    if ((f.name == "rgb" || f.name == "rgba") && f.count == 1 &&
        (f.datatype == pcl::PCLPointField::FLOAT32 || f.datatype == pcl::PCLPointField::UINT32))
      rgb = &f;
  if (!rgb)
    return py::none();
  py::array_t<std::uint8_t> out({py::ssize_t(blob.height), py::ssize_t(blob.width), py::ssize_t(3)});
  std::uint8_t* data = out.mutable_data();
  for (std::uint32_t v = 0; v < blob.height; ++v)
    for (std::uint32_t u = 0; u < blob.width; ++u) {
      std::uint32_t packed;
      std::memcpy(&packed, &blob.data[std::size_t(v) * blob.row_step + std::size_t(u) * blob.point_step + rgb->offset],
                  sizeof packed);
      std::uint8_t* pixel = data + 3 * (std::size_t(v) * blob.width + u);
      pixel[0] = static_cast<std::uint8_t>(packed >> 16);
      pixel[1] = static_cast<std::uint8_t>(packed >> 8);
      pixel[2] = static_cast<std::uint8_t>(packed);
    }
  return std::move(out);
}

py::object
readPcd(const py::handle& path_argument, bool return_viewpoint, bool return_colors)
{
  const std::string path = pathArgument(path_argument, "path");
  io::LoadedCloud loaded;
  Cloud cloud;
  {
    py::gil_scoped_release release;
    loaded = io::loadCloud(path);
    cloud = io::xyzFromBlob(loaded, path);
  }
  py::array points = pointsFromCloud(cloud, 'f');
  if (!return_viewpoint && !return_colors)
    return std::move(points);
  py::list result;
  result.append(points);
  if (return_viewpoint)
    result.append(py::make_tuple(loaded.origin[0], loaded.origin[1], loaded.origin[2]));
  if (return_colors)
    result.append(colorsOf(loaded.blob));
  return py::tuple(result);
}

void
writePcd(const py::handle& path_argument, const py::handle& points, const std::vector<float>& viewpoint)
{
  const std::string path = pathArgument(path_argument, "path");
  if (viewpoint.size() != 3)
    throw py::value_error("range_nlm: viewpoint must be (x, y, z), got " + std::to_string(viewpoint.size()) +
                          " values");
  checkViewpoint({viewpoint[0], viewpoint[1], viewpoint[2]}, "viewpoint"); // as the reader checks VIEWPOINT
  const Cloud::Ptr cloud = cloudFromPoints(points, "points", {viewpoint[0], viewpoint[1], viewpoint[2], 0.0f});
  py::gil_scoped_release release;
  io::saveCloudAtomic(path, *cloud);
}

py::array
readDepth(const py::handle& path_argument)
{
  const std::string path = pathArgument(path_argument, "path");
  DepthImage image;
  {
    py::gil_scoped_release release;
    image = readDepthPng(path);
  }
  py::array_t<std::uint16_t> out({py::ssize_t(image.height), py::ssize_t(image.width)});
  std::memcpy(out.mutable_data(), image.values.data(), image.values.size() * sizeof(std::uint16_t));
  return std::move(out);
}

void
writeDepth(const py::handle& path_argument, const py::handle& depth)
{
  const std::string path = pathArgument(path_argument, "path");
  if (!py::isinstance<py::array_t<std::uint16_t>>(depth) ||
      py::reinterpret_borrow<py::array>(depth).dtype().char_() != 'H' ||
      py::reinterpret_borrow<py::array>(depth).ndim() != 2)
    throw py::type_error("range_nlm: a depth PNG is written from an H x W uint16 array, got " +
                         py::repr(depth.get_type()).cast<std::string>());
  const auto a = py::reinterpret_borrow<py::array_t<std::uint16_t>>(depth);
  DepthImage image;
  image.height = static_cast<int>(a.shape(0));
  image.width = static_cast<int>(a.shape(1));
  image.values.resize(static_cast<std::size_t>(a.size()));
  for (py::ssize_t v = 0; v < a.shape(0); ++v) // any strides
    for (py::ssize_t u = 0; u < a.shape(1); ++u)
      image.values[static_cast<std::size_t>(v * a.shape(1) + u)] = a.at(v, u);
  py::gil_scoped_release release;
  writeDepthPng(path, image);
}

RenderMode
modeNamed(const std::string& mode)
{
  if (mode == "shaded")
    return RenderMode::shaded;
  if (mode == "curvature")
    return RenderMode::curvature;
  throw py::value_error("range_nlm: mode must be 'shaded' or 'curvature', got '" + mode + "'");
}

/// Writes `before` and `after` side by side on one scale (range_nlm_render --before --after);
/// returns the curvature scale used (0 in shaded mode).
float
renderBeforeAfter(const py::handle& before, const py::handle& after, const py::handle& path_argument,
                  const std::string& mode, float curvature_limit)
{
  const std::string path = pathArgument(path_argument, "path");
  RenderParameters parameters;
  parameters.curvature_limit = curvature_limit;
  const Cloud::Ptr a = cloudFromPoints(before, "before", Eigen::Vector4f::Zero());
  const Cloud::Ptr b = cloudFromPoints(after, "after", Eigen::Vector4f::Zero());
  const RenderMode render_mode = modeNamed(mode);
  py::gil_scoped_release release;
  const BeforeAfterImage image =
      range_nlm::renderBeforeAfter(gridFromCloud(*a), gridFromCloud(*b), render_mode, parameters);
  saveRgbPng(path, image.image);
  return image.curvature_limit;
}

/// The points of a depth image, back-projected by the library (depthImageToCloud, depthMapToCloud).
py::array
depthToPoints(const py::handle& depth, const DepthIntrinsics& intrinsics, const py::handle& depth_scale)
{
  FrameFormat format;
  const Cloud::Ptr cloud =
      cloudFromDepth(depth, intrinsics, depthScaleOf(depth, intrinsics, depth_scale), false, format, "depth");
  return pointsFromCloud(*cloud, 'f');
}

void
bindIntrinsics(py::module_& m)
{
  py::class_<DepthIntrinsics>(m, "Intrinsics",
                              "Pinhole intrinsics of a depth camera (pixels) and its depth scale (stored values per "
                              "metre), as range_nlm_denoise --fx ... --depth-scale / --intrinsics take them.")
      .def(py::init([](double fx, double fy, double cx, double cy, double depth_scale, int width, int height) {
             DepthIntrinsics in;
             in.fx = fx, in.fy = fy, in.cx = cx, in.cy = cy, in.depth_scale = depth_scale;
             in.width = width, in.height = height;
             in.validate();
             return in;
           }),
           py::arg("fx") = DepthIntrinsics().fx, py::arg("fy") = DepthIntrinsics().fy,
           py::arg("cx") = DepthIntrinsics().cx, py::arg("cy") = DepthIntrinsics().cy,
           py::arg("depth_scale") = DepthIntrinsics().depth_scale, py::arg("width") = 0, py::arg("height") = 0)
      .def_readwrite("fx", &DepthIntrinsics::fx)
      .def_readwrite("fy", &DepthIntrinsics::fy)
      .def_readwrite("cx", &DepthIntrinsics::cx)
      .def_readwrite("cy", &DepthIntrinsics::cy)
      .def_readwrite("depth_scale", &DepthIntrinsics::depth_scale)
      .def_readwrite("width", &DepthIntrinsics::width)
      .def_readwrite("height", &DepthIntrinsics::height)
      .def_readonly("source", &DepthIntrinsics::source)
      .def("validate", &DepthIntrinsics::validate)
      .def("__repr__", [](const DepthIntrinsics& in) {
        return "range_nlm.Intrinsics(fx=" + py::repr(py::float_(in.fx)).cast<std::string>() +
               ", fy=" + py::repr(py::float_(in.fy)).cast<std::string>() +
               ", cx=" + py::repr(py::float_(in.cx)).cast<std::string>() +
               ", cy=" + py::repr(py::float_(in.cy)).cast<std::string>() +
               ", depth_scale=" + py::repr(py::float_(in.depth_scale)).cast<std::string>() +
               ", width=" + std::to_string(in.width) + ", height=" + std::to_string(in.height) + ")";
      });
  m.def("_depth_to_points", &depthToPoints, py::arg("depth"), py::arg("intrinsics"), py::arg("depth_scale"));
  m.def(
      "read_intrinsics", [](const py::handle& path) { return readIntrinsics(pathArgument(path, "path")); },
      py::arg("path"), "Reads an intrinsics.txt file (fx, fy, cx, cy, depth_scale, width, height; see docs/usage.md).");
}

} // namespace

std::string
pathArgument(const py::handle& value, const char* name)
{
  // os.fspath(), then os.fsencode() for a str: the bytes the operating system is given.
  const py::object path = py::reinterpret_steal<py::object>(PyOS_FSPath(value.ptr()));
  if (!path) {
    PyErr_Clear();
    throw py::type_error("range_nlm: " + std::string(name) + " must be a str, bytes or os.PathLike path, got " +
                         py::str(value.get_type().attr("__name__")).cast<std::string>());
  }
  const py::bytes encoded = PyUnicode_Check(path.ptr())
                                ? py::reinterpret_steal<py::bytes>(PyUnicode_EncodeFSDefault(path.ptr()))
                                : py::reinterpret_borrow<py::bytes>(path);
  if (!encoded)
    throw py::error_already_set();
  std::string text = encoded;
  // The C++ side would end the path at the first NUL and open another file.
  if (text.find('\0') != std::string::npos)
    throw py::value_error("range_nlm: " + std::string(name) +
                          " has an embedded null byte: " + py::repr(path).cast<std::string>());
  return text;
}

void
bindFiles(py::module_& m)
{
  static const py::handle input_error = py::register_exception<io::InputError>(m, "InputError", PyExc_OSError);
  // A message that names a file by a path which is not UTF-8 (a bytes path) goes out with the
  // path's other bytes escaped (\xff), where pybind11's own translation would give an empty one.
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error)
        std::rethrow_exception(error);
    } catch (const py::builtin_exception&) {
      throw;
    } catch (const std::exception& e) {
      const std::string what = e.what();
      const py::object text =
          py::reinterpret_steal<py::object>(PyUnicode_DecodeUTF8(what.data(), py::ssize_t(what.size()), "strict"));
      if (text) // UTF-8: as pybind11 translates it
        throw;
      PyErr_Clear();
      const py::object escaped = py::reinterpret_steal<py::object>(
          PyUnicode_DecodeUTF8(what.data(), py::ssize_t(what.size()), "backslashreplace"));
      const bool value_error = dynamic_cast<const std::invalid_argument*>(&e) ||
                               dynamic_cast<const std::domain_error*>(&e) ||
                               dynamic_cast<const std::length_error*>(&e) || dynamic_cast<const std::range_error*>(&e);
      PyErr_SetObject(dynamic_cast<const io::InputError*>(&e) ? input_error.ptr()
                      : value_error                           ? PyExc_ValueError
                                                              : PyExc_RuntimeError,
                      escaped.ptr());
    }
  });
  bindIntrinsics(m);
  m.def("read_pcd", &readPcd, py::arg("path"), py::arg("return_viewpoint") = false, py::arg("return_colors") = false,
        "Reads an organized PCD file (checked as range_nlm_denoise reads it) as an H x W x 3 float32 array, "
        "NaN where invalid; with return_viewpoint=True also the sensor origin of its VIEWPOINT line, with "
        "return_colors=True also its colours (an rgb or rgba field) as H x W x 3 uint8 red, green, blue, or None "
        "without colours; the extras follow the points in that order.");
  m.def("write_pcd", &writePcd, py::arg("path"), py::arg("points"),
        py::arg("viewpoint") = std::vector<float>{0.0f, 0.0f, 0.0f},
        "Writes an H x W x 3 array as an organized binary PCD file (x, y, z), atomically.");
  m.def("read_depth_png", &readDepth, py::arg("path"), "Reads a 16-bit greyscale PNG as an H x W uint16 array.");
  m.def("write_depth_png", &writeDepth, py::arg("path"), py::arg("depth"),
        "Writes an H x W uint16 array as a 16-bit greyscale PNG, atomically.");
  m.def(
      "prefer_huge_pages",
      [] {
        const io::HeapSetup setup = io::preferHugePagesForBuffers();
        py::dict result;
        result["heap_below_bytes"] = setup.heap_below_bytes;
        result["marked_bytes"] = setup.marked_bytes;
        return result;
      },
      "Keeps the process's frame-sized buffers on a heap that is not given back between calls and is "
      "marked for transparent huge pages (what range_nlm's tools do at start; process-wide, so call it "
      "once, early). Returns the mmap threshold set and the bytes marked, both 0 where the allocator "
      "is not glibc's or refuses.");
  m.def("render_before_after", &renderBeforeAfter, py::arg("before"), py::arg("after"), py::arg("path"),
        py::arg("mode") = "shaded", py::arg("curvature_limit") = 0.0f,
        "Draws two H x W x 3 frames side by side on one scale into a PNG (range_nlm_render --before --after); "
        "returns the curvature scale used (0 in shaded mode).");
}

} // namespace python
} // namespace range_nlm
