#include <range_nlm/ros/message_frames.h>

#include <range_nlm/io/depth_image.h>
#include <range_nlm/io/pcd_file.h>
#include <range_nlm/io/ray_reprojection.h>
#include <range_nlm/parameter_registry.h>

#include <sensor_msgs/image_encodings.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace range_nlm_ros
{
namespace
{

constexpr bool kHostBigEndian =
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    true;
#else
    false;
#endif

std::string
sizeText(std::uint32_t width, std::uint32_t height)
{
  return std::to_string(width) + " x " + std::to_string(height);
}

/// A float coordinate field of a PointCloud2, checked against the point step.
struct Coordinate
{
  std::uint32_t offset = 0;
  bool is_double = false;
};

Coordinate
coordinateField(const sensor_msgs::PointCloud2& message, const std::string& name)
{
  for (const sensor_msgs::PointField& field : message.fields) {
    if (field.name != name)
      continue;
    if (field.datatype != sensor_msgs::PointField::FLOAT32 && field.datatype != sensor_msgs::PointField::FLOAT64)
      throw InvalidMessage("field '" + name + "' has datatype " + std::to_string(field.datatype) +
                           "; x, y, z must be FLOAT32 (7) or FLOAT64 (8)");
    const Coordinate c{field.offset, field.datatype == sensor_msgs::PointField::FLOAT64};
    if (std::uint64_t(c.offset) + (c.is_double ? 8 : 4) > message.point_step)
      throw InvalidMessage("field '" + name + "' at offset " + std::to_string(field.offset) +
                           " does not fit point_step " + std::to_string(message.point_step));
    return c;
  }
  throw InvalidMessage("PointCloud2 has no field '" + name + "'");
}

double
readCoordinate(const std::uint8_t* point, const Coordinate& c)
{
  if (c.is_double) {
    double v;
    std::memcpy(&v, point + c.offset, sizeof v);
    return v;
  }
  float v;
  std::memcpy(&v, point + c.offset, sizeof v);
  return v;
}

void
writeCoordinate(std::uint8_t* point, const Coordinate& c, float value)
{
  if (c.is_double) {
    const double v = value;
    std::memcpy(point + c.offset, &v, sizeof v);
  } else {
    std::memcpy(point + c.offset, &value, sizeof value);
  }
}

/// The smallest side of a frame any parameters can filter: the smallest normal window.
int
smallestWindow()
{
  const range_nlm::ParameterEntry* normal = range_nlm::findParameter("normal_window");
  return normal ? static_cast<int>(normal->range.min) : 3;
}

struct CloudLayout
{
  Coordinate x, y, z;
};

CloudLayout
checkedLayout(const sensor_msgs::PointCloud2& message)
{
  if (message.height <= 1)
    throw InvalidMessage("PointCloud2 is unorganized (" + sizeText(message.width, message.height) +
                         "); the filter needs an organized cloud (height > 1, one point per pixel)");
  if (message.width == 0)
    throw InvalidMessage("PointCloud2 is empty (" + sizeText(message.width, message.height) + ")");
  // Before a byte of it is decoded: no parameters filter a frame narrower or lower than the
  // smallest plane fit (a caller that knows its parameters checks their windows too).
  const int smallest = smallestWindow();
  if (message.width < std::uint32_t(smallest) || message.height < std::uint32_t(smallest))
    throw InvalidMessage("PointCloud2 of " + sizeText(message.width, message.height) +
                         " is smaller than the filter's smallest window (" + std::to_string(smallest) + " x " +
                         std::to_string(smallest) + " points for a normal)");
  if (bool(message.is_bigendian) != kHostBigEndian)
    throw InvalidMessage(std::string("PointCloud2 is ") + (message.is_bigendian ? "big" : "little") +
                         "-endian, unlike this host");
  if (std::uint64_t(message.row_step) != std::uint64_t(message.width) * message.point_step)
    throw InvalidMessage("PointCloud2 row_step " + std::to_string(message.row_step) + " is not width " +
                         std::to_string(message.width) + " x point_step " + std::to_string(message.point_step));
  if (std::uint64_t(message.data.size()) != std::uint64_t(message.row_step) * message.height)
    throw InvalidMessage("PointCloud2 data holds " + std::to_string(message.data.size()) + " bytes, not row_step " +
                         std::to_string(message.row_step) + " x height " + std::to_string(message.height));
  // The PCD reader's check: which of two x fields would be the coordinate?
  std::vector<std::string> names;
  std::vector<std::uint64_t> counts;
  for (const sensor_msgs::PointField& field : message.fields) {
    names.push_back(field.name);
    counts.push_back(field.count);
  }
  const std::string problem =
      range_nlm::io::fieldLayoutProblem(names, counts, std::max<std::uint32_t>(1, message.point_step));
  if (!problem.empty())
    throw InvalidMessage("PointCloud2 " + problem);
  return CloudLayout{coordinateField(message, "x"), coordinateField(message, "y"), coordinateField(message, "z")};
}

/// Bytes per pixel of a depth encoding the filter takes (2: 16UC1 millimetres, 4: 32FC1 metres).
int
depthBytes(const std::string& encoding)
{
  if (encoding == sensor_msgs::image_encodings::TYPE_16UC1 || encoding == sensor_msgs::image_encodings::MONO16)
    return 2;
  if (encoding == sensor_msgs::image_encodings::TYPE_32FC1)
    return 4;
  throw InvalidMessage("depth image encoding '" + encoding + "' is not supported (16UC1 millimetres or 32FC1 metres)");
}

void
checkImage(const sensor_msgs::Image& image)
{
  const int bytes = depthBytes(image.encoding);
  if (image.width == 0 || image.height <= 1)
    throw InvalidMessage("depth image of " + sizeText(image.width, image.height) + " is empty or a single row");
  if (bool(image.is_bigendian) != kHostBigEndian)
    throw InvalidMessage(std::string("depth image is ") + (image.is_bigendian ? "big" : "little") +
                         "-endian, unlike this host");
  if (std::uint64_t(image.step) != std::uint64_t(image.width) * bytes)
    throw InvalidMessage("depth image step " + std::to_string(image.step) + " is not width " +
                         std::to_string(image.width) + " x " + std::to_string(bytes) + " bytes (" + image.encoding +
                         ")");
  if (std::uint64_t(image.data.size()) != std::uint64_t(image.step) * image.height)
    throw InvalidMessage("depth image data holds " + std::to_string(image.data.size()) + " bytes, not step " +
                         std::to_string(image.step) + " x height " + std::to_string(image.height));
}

} // namespace

Cloud::Ptr
cloudFromPointCloud2(const sensor_msgs::PointCloud2& message, const range_nlm::FilterParameters* parameters)
{
  const CloudLayout layout = checkedLayout(message);
  if (parameters) {
    try {
      parameters->validateFor(static_cast<int>(std::min<std::uint32_t>(message.width, INT32_MAX)),
                              static_cast<int>(std::min<std::uint32_t>(message.height, INT32_MAX)));
    } catch (const std::invalid_argument& e) {
      throw InvalidMessage("PointCloud2 of " + sizeText(message.width, message.height) + ": " + e.what());
    }
  }
  Cloud::Ptr cloud(new Cloud(message.width, message.height));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const double largest = std::numeric_limits<float>::max();
  // Decoded by the filter's threads; an out-of-range coordinate is reported at the first such
  // pixel in row order, whichever thread met it (the cloud is then dropped whole).
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(cloud->size());
  std::ptrdiff_t bad = n;
  const int threads = range_nlm::threadCount(parameters ? parameters->threads : 0);
  unsigned dense = 1;
  (void)threads;
#pragma omp parallel for schedule(static) reduction(min : bad) reduction(& : dense) num_threads(threads)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const std::uint8_t* p = &message.data[static_cast<std::size_t>(i) * message.point_step];
    const double x = readCoordinate(p, layout.x), y = readCoordinate(p, layout.y), z = readCoordinate(p, layout.z);
    pcl::PointXYZ& q = (*cloud)[i];
    if (std::isnan(x) || std::isnan(y) || std::isnan(z)) {
      q.x = q.y = q.z = nan;
      dense = 0;
      continue;
    }
    if (!(std::fabs(x) <= largest && std::fabs(y) <= largest && std::fabs(z) <= largest)) {
      bad = std::min(bad, i);
      continue;
    }
    q.x = float(x), q.y = float(y), q.z = float(z);
  }
  if (bad < n)
    throw InvalidMessage("PointCloud2 has an infinite (or out of float range) coordinate at pixel (" +
                         std::to_string(bad % message.width) + ", " + std::to_string(bad / message.width) +
                         "); invalid points must be NaN");
  cloud->is_dense = dense != 0;
  return cloud;
}

sensor_msgs::PointCloud2::Ptr
pointCloud2WithXyz(const sensor_msgs::PointCloud2& message, const Cloud& xyz, int threads)
{
  const CloudLayout layout = checkedLayout(message);
  if (xyz.width != message.width || xyz.height != message.height)
    throw InvalidMessage("filtered cloud of " + sizeText(xyz.width, xyz.height) + " for a PointCloud2 of " +
                         sizeText(message.width, message.height));
  // Everything but the data copied as it is; the data copied row by row by the threads, each row
  // followed at once by its new coordinates (one pass over the bytes, not two).
  sensor_msgs::PointCloud2::Ptr out(new sensor_msgs::PointCloud2);
  out->header = message.header;
  out->height = message.height;
  out->width = message.width;
  out->fields = message.fields;
  out->is_bigendian = message.is_bigendian;
  out->point_step = message.point_step;
  out->row_step = message.row_step;
  out->data.resize(message.data.size());
  const std::ptrdiff_t rows = static_cast<std::ptrdiff_t>(message.height);
  const std::size_t width = message.width, row_bytes = message.row_step;
  unsigned dense = 1;
  (void)threads;
#pragma omp parallel for schedule(static) reduction(& : dense) num_threads(range_nlm::threadCount(threads))
  for (std::ptrdiff_t v = 0; v < rows; ++v) {
    std::uint8_t* row = out->data.data() + static_cast<std::size_t>(v) * row_bytes;
    std::memcpy(row, message.data.data() + static_cast<std::size_t>(v) * row_bytes, row_bytes);
    for (std::size_t u = 0; u < width; ++u) {
      std::uint8_t* p = row + u * message.point_step;
      const pcl::PointXYZ& q = xyz[static_cast<std::size_t>(v) * width + u];
      writeCoordinate(p, layout.x, q.x);
      writeCoordinate(p, layout.y, q.y);
      writeCoordinate(p, layout.z, q.z);
      dense &= std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
    }
  }
  out->is_dense = dense != 0;
  return out;
}

Cloud::Ptr
cloudFromDepthImage(const sensor_msgs::Image& image, const sensor_msgs::CameraInfo& info)
{
  checkImage(image);
  if ((info.width != 0 || info.height != 0) && (info.width != image.width || info.height != image.height))
    throw InvalidMessage("CameraInfo is for " + sizeText(info.width, info.height) + " images, the depth image is " +
                         sizeText(image.width, image.height));
  range_nlm::DepthIntrinsics intrinsics;
  intrinsics.fx = info.K[0];
  intrinsics.fy = info.K[4];
  intrinsics.cx = info.K[2];
  intrinsics.cy = info.K[5];
  try {
    intrinsics.validate();
  } catch (const std::invalid_argument& e) {
    throw InvalidMessage(std::string("CameraInfo K: ") + e.what());
  }
  if (depthBytes(image.encoding) == 2) { // millimetres: the library's back-projection
    intrinsics.depth_scale = 1000.0;
    range_nlm::DepthImage depth;
    depth.width = static_cast<int>(image.width);
    depth.height = static_cast<int>(image.height);
    depth.values.resize(std::size_t(image.width) * image.height);
    std::memcpy(depth.values.data(), image.data.data(), depth.values.size() * sizeof(std::uint16_t));
    return Cloud::Ptr(new Cloud(range_nlm::depthImageToCloud(depth, intrinsics)));
  }
  // Metres as floats: the same formula with depth_scale 1.
  Cloud::Ptr cloud(new Cloud(image.width, image.height));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  bool dense = true;
  for (std::uint32_t v = 0; v < image.height; ++v)
    for (std::uint32_t u = 0; u < image.width; ++u) {
      const std::size_t i = std::size_t(v) * image.width + u;
      float value;
      std::memcpy(&value, &image.data[i * 4], sizeof value);
      pcl::PointXYZ& p = (*cloud)[i];
      if (!(value > 0.0f) || !std::isfinite(value)) {
        if (value < 0.0f || std::isinf(value))
          throw InvalidMessage("depth image (32FC1) has depth " + std::to_string(value) + " at pixel (" +
                               std::to_string(u) + ", " + std::to_string(v) + "); invalid pixels must be 0 or NaN");
        p.x = p.y = p.z = nan;
        dense = false;
        continue;
      }
      const double z = value;
      p.x = static_cast<float>((u - intrinsics.cx) * z / intrinsics.fx);
      p.y = static_cast<float>((v - intrinsics.cy) * z / intrinsics.fy);
      p.z = static_cast<float>(z);
    }
  cloud->is_dense = dense;
  return cloud;
}

sensor_msgs::Image::Ptr
depthImageWithZ(const sensor_msgs::Image& image, const Cloud& xyz)
{
  checkImage(image);
  if (xyz.width != image.width || xyz.height != image.height)
    throw InvalidMessage("filtered cloud of " + sizeText(xyz.width, xyz.height) + " for a depth image of " +
                         sizeText(image.width, image.height));
  sensor_msgs::Image::Ptr out(new sensor_msgs::Image);
  out->header = image.header;
  out->height = image.height;
  out->width = image.width;
  out->encoding = image.encoding;
  out->is_bigendian = image.is_bigendian;
  out->step = image.step;
  if (depthBytes(image.encoding) == 2) {
    range_nlm::DepthImage depth;
    try {
      depth = range_nlm::cloudToDepthImage(xyz, 1000.0);
    } catch (const std::invalid_argument& e) {
      throw InvalidMessage(std::string("filtered depth does not fit 16UC1: ") + e.what());
    }
    out->data.resize(depth.values.size() * sizeof(std::uint16_t));
    std::memcpy(out->data.data(), depth.values.data(), out->data.size());
    return out;
  }
  out->data = image.data; // invalid pixels keep their 0 or NaN
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    const pcl::PointXYZ& p = xyz[i];
    float in;
    std::memcpy(&in, &image.data[i * 4], sizeof in);
    const bool valid_in = in > 0.0f && std::isfinite(in);
    const bool valid_out = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    if (valid_out)
      std::memcpy(&out->data[i * 4], &p.z, sizeof p.z);
    else if (valid_in)
      std::memcpy(&out->data[i * 4], &nan, sizeof nan);
  }
  return out;
}

sensor_msgs::Image::Ptr
uncertaintyImage(const std_msgs::Header& header, std::uint32_t width, std::uint32_t height,
                 const std::vector<float>& sigma)
{
  if (sigma.size() != static_cast<std::size_t>(width) * height)
    throw InvalidMessage(std::to_string(sigma.size()) + " uncertainty values for a frame of " +
                         sizeText(width, height));
  sensor_msgs::Image::Ptr out(new sensor_msgs::Image);
  out->header = header;
  out->height = height;
  out->width = width;
  out->encoding = "32FC1";
  out->is_bigendian = 0;
  out->step = width * sizeof(float);
  out->data.resize(sigma.size() * sizeof(float));
  std::memcpy(out->data.data(), sigma.data(), out->data.size());
  return out;
}

sensor_msgs::Image::Ptr
filteredDepthImage(const sensor_msgs::Image& image, const sensor_msgs::CameraInfo& info, const Cloud& filtered)
{
  const Cloud::Ptr input = cloudFromDepthImage(image, info);
  if (filtered.width != input->width || filtered.height != input->height)
    throw InvalidMessage("filtered cloud of " + sizeText(filtered.width, filtered.height) + " for a depth image of " +
                         sizeText(image.width, image.height));
  return depthImageWithZ(image, range_nlm::reprojectOntoRays(*input, filtered));
}

bool
hasValidPoint(const Cloud& cloud)
{
  for (const pcl::PointXYZ& p : cloud)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
      return true;
  return false;
}

std::string
describe(const std_msgs::Header& header)
{
  std::ostringstream s;
  s << "stamp " << header.stamp.sec << "." << std::setw(9) << std::setfill('0') << header.stamp.nsec << ", frame '"
    << header.frame_id << "', seq " << header.seq;
  return s.str();
}

} // namespace range_nlm_ros
