// 16-bit depth PNGs <-> organized clouds, the intrinsics.txt reader and the libpng wrappers.
#include <range_nlm/io/depth_image.h>
#include <range_nlm/io/pcd_file.h>
#include <range_nlm/io/ray_reprojection.h>

#include "output_file.h"

#include <png.h>

#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

namespace range_nlm
{

namespace
{

std::string
quoted(const std::string& path)
{
  return "'" + path + "'";
}

std::string
numberText(double value)
{
  std::ostringstream s;
  s.precision(10);
  s << value;
  return s.str();
}

// ---- libpng plumbing ------------------------------------------------------------------------
// libpng reports errors by longjmp. Every object with a destructor lives in the caller-owned
// context (constructed before setjmp), so a jump skips no destructor; the caller turns the
// recorded message into an exception after libpng has returned.

struct PngContext
{
  char message[256] = {0};
  std::FILE* file = nullptr;
  io::detail::OutputFile* output = nullptr; // writing
  png_structp png = nullptr;
  png_infop info = nullptr;
  detail::PngPixels pixels;
  std::vector<png_bytep> rows;
  // Reading: the memory bound checked from the header, and why it refused the image.
  const io::MemoryBudget* budget = nullptr;
  std::uint64_t point_step = 0;
  std::string refusal;
};

/// The name of a colour type of a PNG header (IHDR), as stored in the file.
const char*
colorTypeName(int color_type)
{
  switch (color_type) {
  case PNG_COLOR_TYPE_GRAY:
    return "greyscale";
  case PNG_COLOR_TYPE_GRAY_ALPHA:
    return "greyscale + alpha";
  case PNG_COLOR_TYPE_RGB:
    return "RGB";
  case PNG_COLOR_TYPE_RGB_ALPHA:
    return "RGBA";
  case PNG_COLOR_TYPE_PALETTE:
    return "palette";
  default:
    return "unknown colour type";
  }
}

void
onPngError(png_structp png, png_const_charp message)
{
  auto* context = static_cast<PngContext*>(png_get_error_ptr(png));
  std::snprintf(context->message, sizeof context->message, "%s", message);
  png_longjmp(png, 1);
}

void
onPngWrite(png_structp png, png_bytep data, png_size_t size)
{
  auto* context = static_cast<PngContext*>(png_get_io_ptr(png));
  const int error = context->output->tryWrite(data, size);
  if (error != 0)
    png_error(png, std::strerror(error));
}

void
onPngFlush(png_structp)
{
}

void
onPngWarning(png_structp, png_const_charp)
{
  // Warnings (e.g. an unknown ancillary chunk) do not affect the pixels.
}

bool
readPngPixels(PngContext& context)
{
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &context, onPngError, onPngWarning);
  if (png == nullptr) {
    std::snprintf(context.message, sizeof context.message, "libpng cannot allocate a reader");
    return false;
  }
  context.png = png;
  context.info = png_create_info_struct(png);
  if (context.info == nullptr) {
    std::snprintf(context.message, sizeof context.message, "libpng cannot allocate image info");
    return false;
  }
  if (setjmp(png_jmpbuf(png)))
    return false;
  png_init_io(png, context.file);
  png_read_info(png, context.info);
  if (context.budget != nullptr) {
    context.refusal = context.budget->refusal(png_get_image_width(png, context.info),
                                              png_get_image_height(png, context.info), context.point_step);
    if (!context.refusal.empty())
      return false;
  }
  const int color_type = png_get_color_type(png, context.info);
  const int bit_depth = png_get_bit_depth(png, context.info);
  context.pixels.format = std::to_string(bit_depth) + "-bit " + colorTypeName(color_type);
  if (color_type == PNG_COLOR_TYPE_PALETTE)
    png_set_palette_to_rgb(png);
  if (bit_depth < 8)
    png_set_expand(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, context.info);
  detail::PngPixels& pixels = context.pixels;
  pixels.width = static_cast<int>(png_get_image_width(png, context.info));
  pixels.height = static_cast<int>(png_get_image_height(png, context.info));
  pixels.channels = png_get_channels(png, context.info);
  pixels.bit_depth = png_get_bit_depth(png, context.info);
  const std::size_t row_bytes = png_get_rowbytes(png, context.info);
  if (row_bytes * static_cast<std::size_t>(pixels.height) > (std::size_t(1) << 31)) {
    std::snprintf(context.message, sizeof context.message, "image of %d x %d pixels is too large", pixels.width,
                  pixels.height);
    return false;
  }
  pixels.bytes.resize(row_bytes * static_cast<std::size_t>(pixels.height));
  context.rows.resize(static_cast<std::size_t>(pixels.height));
  for (int v = 0; v < pixels.height; ++v)
    context.rows[v] = pixels.bytes.data() + row_bytes * static_cast<std::size_t>(v);
  png_read_image(png, context.rows.data());
  png_read_end(png, nullptr);
  return true;
}

bool
writePngPixels(PngContext& context, const detail::PngPixels& pixels)
{
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &context, onPngError, onPngWarning);
  if (png == nullptr) {
    std::snprintf(context.message, sizeof context.message, "libpng cannot allocate a writer");
    return false;
  }
  context.png = png;
  context.info = png_create_info_struct(png);
  if (context.info == nullptr) {
    std::snprintf(context.message, sizeof context.message, "libpng cannot allocate image info");
    return false;
  }
  if (setjmp(png_jmpbuf(png)))
    return false;
  png_set_write_fn(png, &context, onPngWrite, onPngFlush);
  png_set_IHDR(png, context.info, static_cast<png_uint_32>(pixels.width), static_cast<png_uint_32>(pixels.height),
               pixels.bit_depth, pixels.channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, context.info);
  png_write_image(png, context.rows.data());
  png_write_end(png, nullptr);
  return true;
}

void
destroyReader(PngContext& context)
{
  if (context.png != nullptr)
    png_destroy_read_struct(&context.png, context.info != nullptr ? &context.info : nullptr, nullptr);
  if (context.file != nullptr)
    std::fclose(context.file);
  context.file = nullptr;
}

} // namespace

void
DepthIntrinsics::validate() const
{
  // The bounds keep every back-projected coordinate of a 16-bit image a finite float that is not
  // rounded to 0: (65535 + |c|) * z / f with z up to 65535 / depth_scale, and down to 1 / depth_scale.
  auto within = [](const char* name, double value, double low, double high, const char* what) {
    if (!(std::isfinite(value) && value >= low && value <= high))
      throw std::invalid_argument(std::string("depth intrinsics: ") + name + " must be " + what + " from " +
                                  numberText(low) + " to " + numberText(high) + ", got " + numberText(value));
  };
  within("fx", fx, kMinFocalLength, kMaxFocalLength, "a positive number of pixels");
  within("fy", fy, kMinFocalLength, kMaxFocalLength, "a positive number of pixels");
  within("cx", cx, -kMaxPrincipalPoint, kMaxPrincipalPoint, "finite, a number of pixels");
  within("cy", cy, -kMaxPrincipalPoint, kMaxPrincipalPoint, "finite, a number of pixels");
  within("depth_scale", depth_scale, kMinDepthScale, kMaxDepthScale, "a positive number of values per metre");
}

namespace
{
/// Largest intrinsics file read: a few lines of `key value` with comments are far below it, and
/// a device or a pipe that never ends (/dev/zero) is refused instead of read for ever.
constexpr std::size_t kMaxIntrinsicsBytes = 1 << 20;

/// The text of an intrinsics file, at most kMaxIntrinsicsBytes.
std::string
intrinsicsText(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::invalid_argument(quoted(path) + ": cannot open intrinsics file");
  std::string text(kMaxIntrinsicsBytes + 1, '\0');
  in.read(&text[0], static_cast<std::streamsize>(text.size()));
  if (in.bad())
    throw std::invalid_argument(quoted(path) + ": read error");
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxIntrinsicsBytes)
    throw std::invalid_argument(quoted(path) + ": not an intrinsics file: longer than " +
                                std::to_string(kMaxIntrinsicsBytes / 1024) +
                                " kB (an intrinsics file is a few lines of 'key value')");
  return text;
}

bool
isFreeTextKey(const std::string& key)
{
  return key == "sensor" || key == "distortion" || key == "note" || key == "notes" || key == "comment" ||
         key == "comments" || key == "source";
}

/// The depth scale a `depth_format` line gives: N for "value / N", 1000 for millimetres, 0 if it
/// says neither. Throws if N is not a positive finite number (a scale of 0 is no scale).
double
depthFormatScale(const std::string& value, const std::string& where)
{
  static const std::regex divided(R"(value\s*/\s*([0-9]+(\.[0-9]*)?))");
  std::smatch match;
  if (std::regex_search(value, match, divided)) {
    const double scale = std::strtod(match[1].str().c_str(), nullptr);
    if (!(std::isfinite(scale) && scale > 0.0))
      throw std::invalid_argument(where + ": depth_format '" + value + "' divides by " + match[1].str() +
                                  "; the depth scale must be a positive number");
    return scale;
  }
  if (value.find("millimetre") != std::string::npos || value.find("millimeter") != std::string::npos)
    return 1000.0;
  return 0.0;
}
} // namespace

DepthIntrinsics
readIntrinsics(const std::string& path, const DepthIntrinsics& defaults)
{
  std::istringstream in(intrinsicsText(path));
  DepthIntrinsics result = defaults;
  bool have_scale = false;
  double format_scale = 0.0;
  std::map<std::string, int> first_line; // of each key
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos)
      line.erase(hash);
    std::istringstream fields(line);
    std::string key;
    if (!(fields >> key))
      continue;
    std::string value;
    std::getline(fields, value);
    const std::size_t first = value.find_first_not_of(" \t\r");
    value = first == std::string::npos ? std::string() : value.substr(first);
    while (!value.empty() && (value.back() == ' ' || value.back() == '\t' || value.back() == '\r'))
      value.pop_back();
    const std::string where = quoted(path) + " line " + std::to_string(line_number);
    const auto seen = first_line.emplace(key, line_number);
    if (!seen.second && !isFreeTextKey(key)) // which of the two was meant is a guess
      throw std::invalid_argument(where + ": '" + key + "' is given twice (first on line " +
                                  std::to_string(seen.first->second) + "); give it once");
    if (key == "depth_format") {
      format_scale = depthFormatScale(value, where);
      continue;
    }
    const bool numeric = key == "fx" || key == "fy" || key == "cx" || key == "cy" || key == "depth_scale" ||
                         key == "width" || key == "height";
    if (isFreeTextKey(key))
      continue;
    if (!numeric)
      throw std::invalid_argument(where + ": unknown key '" + key +
                                  "' (known: fx, fy, cx, cy, depth_scale, width, height, depth_format; free text: "
                                  "sensor, distortion, note, notes, comment, comments, source)");
    const char* begin = value.c_str();
    char* end = nullptr;
    errno = 0;
    const double number = std::strtod(begin, &end);
    if (value.empty() || end != begin + value.size() || errno == ERANGE || !std::isfinite(number))
      throw std::invalid_argument(where + ": '" + key + "' needs a number, got '" + value + "'");
    if (key == "fx")
      result.fx = number;
    else if (key == "fy")
      result.fy = number;
    else if (key == "cx")
      result.cx = number;
    else if (key == "cy")
      result.cy = number;
    else if (key == "depth_scale") {
      result.depth_scale = number;
      have_scale = true;
    } else if (!(number >= 1.0 && number <= 1e9 && number == std::floor(number)))
      throw std::invalid_argument(where + ": '" + key + "' must be a positive integer, got '" + value + "'");
    else
      (key == "width" ? result.width : result.height) = static_cast<int>(number);
  }
  result.source = path;
  if (!have_scale && format_scale > 0.0)
    result.depth_scale = format_scale;
  try {
    result.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(quoted(path) + ": " + e.what());
  }
  return result;
}

namespace detail
{

PngPixels
readPng(const std::string& path, const io::MemoryBudget& budget, std::uint64_t point_step)
{
  PngContext context;
  context.budget = &budget;
  context.point_step = point_step;
  context.file = std::fopen(path.c_str(), "rb");
  if (context.file == nullptr)
    throw std::invalid_argument(quoted(path) + ": cannot open PNG file: " + std::strerror(errno));
  unsigned char signature[8] = {0};
  const std::size_t got = std::fread(signature, 1, sizeof signature, context.file);
  if (got != sizeof signature || png_sig_cmp(signature, 0, sizeof signature) != 0) {
    std::fclose(context.file);
    throw std::invalid_argument(quoted(path) + ": not a PNG file (bad signature)");
  }
  std::rewind(context.file);
  bool ok = false;
  try {
    ok = readPngPixels(context);
  } catch (...) {
    destroyReader(context);
    throw;
  }
  destroyReader(context);
  if (!context.refusal.empty())
    throw std::invalid_argument(quoted(path) + ": " + context.refusal);
  if (!ok)
    throw std::invalid_argument(quoted(path) + ": damaged PNG file: " + context.message);
  return std::move(context.pixels);
}

void
writePng(const std::string& path, const PngPixels& pixels)
{
  if (pixels.width <= 0 || pixels.height <= 0)
    throw std::invalid_argument(quoted(path) + ": cannot write an empty image (" + std::to_string(pixels.width) +
                                " x " + std::to_string(pixels.height) + ")");
  if ((pixels.channels != 1 && pixels.channels != 3) || (pixels.bit_depth != 8 && pixels.bit_depth != 16))
    throw std::invalid_argument(quoted(path) + ": unsupported PNG layout (" + std::to_string(pixels.channels) +
                                " channels, " + std::to_string(pixels.bit_depth) + " bits)");
  const std::size_t row_bytes =
      static_cast<std::size_t>(pixels.width) * static_cast<std::size_t>(pixels.channels) * (pixels.bit_depth / 8);
  if (pixels.bytes.size() != row_bytes * static_cast<std::size_t>(pixels.height))
    throw std::invalid_argument(quoted(path) + ": pixel buffer holds " + std::to_string(pixels.bytes.size()) +
                                " bytes, the image needs " + std::to_string(row_bytes * pixels.height));

  PngContext context;
  context.rows.resize(static_cast<std::size_t>(pixels.height));
  for (int v = 0; v < pixels.height; ++v)
    context.rows[v] = const_cast<png_bytep>(pixels.bytes.data() + row_bytes * static_cast<std::size_t>(v));
  try {
    // Temporary file + rename for a regular file, directly to a device or FIFO (see OutputFile).
    io::detail::OutputFile output(path);
    context.output = &output;
    bool ok = false;
    try {
      ok = writePngPixels(context, pixels);
    } catch (const std::bad_alloc&) {
      std::snprintf(context.message, sizeof context.message, "out of memory");
    }
    if (context.png != nullptr)
      png_destroy_write_struct(&context.png, context.info != nullptr ? &context.info : nullptr);
    if (!ok)
      throw std::invalid_argument(quoted(path) + ": cannot write PNG file: " + context.message +
                                  (std::strcmp(context.message, std::strerror(ENOSPC)) == 0
                                       ? " (the disk is full; nothing was written under this name)"
                                       : ""));
    output.commit();
  } catch (const io::InputError& e) {
    throw std::invalid_argument(e.what());
  }
}

} // namespace detail

DepthImage
readDepthPng(const std::string& path, const io::MemoryBudget& budget)
{
  detail::PngPixels pixels = detail::readPng(path, budget, sizeof(pcl::PointXYZ));
  if (pixels.channels != 1 || pixels.bit_depth != 16)
    throw std::invalid_argument(quoted(path) + ": not a 16-bit greyscale depth PNG (found " + pixels.format + ")");
  DepthImage image;
  image.width = pixels.width;
  image.height = pixels.height;
  image.values.resize(static_cast<std::size_t>(pixels.width) * static_cast<std::size_t>(pixels.height));
  for (std::size_t i = 0; i < image.values.size(); ++i)
    image.values[i] = static_cast<std::uint16_t>((pixels.bytes[2 * i] << 8) | pixels.bytes[2 * i + 1]);
  return image;
}

void
writeDepthPng(const std::string& path, const DepthImage& image)
{
  if (image.values.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height))
    throw std::invalid_argument(quoted(path) + ": depth image of " + std::to_string(image.width) + " x " +
                                std::to_string(image.height) + " holds " + std::to_string(image.values.size()) +
                                " values");
  detail::PngPixels pixels;
  pixels.width = image.width;
  pixels.height = image.height;
  pixels.channels = 1;
  pixels.bit_depth = 16;
  pixels.bytes.resize(2 * image.values.size());
  for (std::size_t i = 0; i < image.values.size(); ++i) {
    pixels.bytes[2 * i] = static_cast<std::uint8_t>(image.values[i] >> 8);
    pixels.bytes[2 * i + 1] = static_cast<std::uint8_t>(image.values[i] & 0xff);
  }
  detail::writePng(path, pixels);
}

namespace
{

/// Back-projects width x height depth values (`value / depth_scale` metres; 0, negative or
/// non-finite: no measurement) with `intrinsics`: the one place 16-bit images and floating-point
/// depth maps become clouds.
template <typename Value>
pcl::PointCloud<pcl::PointXYZ>
backProject(const Value* values, std::size_t count, int width, int height, const DepthIntrinsics& intrinsics)
{
  intrinsics.validate();
  if (width <= 0 || height <= 0 || count != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    throw std::invalid_argument("depth image: " + std::to_string(width) + " x " + std::to_string(height) + " with " +
                                std::to_string(count) + " values is empty or inconsistent");
  if ((intrinsics.width > 0 && intrinsics.width != width) || (intrinsics.height > 0 && intrinsics.height != height))
    throw std::invalid_argument("image is " + std::to_string(width) + " x " + std::to_string(height) +
                                " pixels but the intrinsics" +
                                (intrinsics.source.empty() ? std::string() : " in " + quoted(intrinsics.source)) +
                                " are for " + std::to_string(intrinsics.width) + " x " +
                                std::to_string(intrinsics.height) +
                                " (give the intrinsics of this camera and resolution)");
  pcl::PointCloud<pcl::PointXYZ> cloud(static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  bool dense = true;
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * width + u;
      pcl::PointXYZ& p = cloud[i];
      const Value value = values[i];
      if (!(value > 0) || !std::isfinite(static_cast<double>(value))) {
        p.x = p.y = p.z = nan;
        dense = false;
        continue;
      }
      const double z = value / intrinsics.depth_scale;
      p.x = static_cast<float>((u - intrinsics.cx) * z / intrinsics.fx);
      p.y = static_cast<float>((v - intrinsics.cy) * z / intrinsics.fy);
      p.z = static_cast<float>(z);
    }
  cloud.is_dense = dense;
  return cloud;
}

} // namespace

pcl::PointCloud<pcl::PointXYZ>
depthImageToCloud(const DepthImage& image, const DepthIntrinsics& intrinsics)
{
  return backProject(image.values.data(), image.values.size(), image.width, image.height, intrinsics);
}

pcl::PointCloud<pcl::PointXYZ>
depthMapToCloud(const std::vector<float>& values, int width, int height, const DepthIntrinsics& intrinsics)
{
  return backProject(values.data(), values.size(), width, height, intrinsics);
}

std::vector<double>
cloudToDepthValues(const pcl::PointCloud<pcl::PointXYZ>& cloud, double depth_scale)
{
  if (!(std::isfinite(depth_scale) && depth_scale > 0.0))
    throw std::invalid_argument("depth_scale must be a positive number, got " + numberText(depth_scale));
  if (cloud.empty() || static_cast<std::size_t>(cloud.width) * cloud.height != cloud.size())
    throw std::invalid_argument("cannot encode a " + std::to_string(cloud.width) + " x " +
                                std::to_string(cloud.height) + " cloud of " + std::to_string(cloud.size()) +
                                " points as a depth image (empty or not organized)");
  std::vector<double> values(cloud.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const pcl::PointXYZ& p = cloud[i];
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
      values[i] = static_cast<double>(p.z) * depth_scale;
  }
  return values;
}

std::string
clampingText(const DepthClamping& clamping, double depth_scale)
{
  std::ostringstream text;
  if (clamping.above > 0)
    text << clamping.above << " pixel(s) filtered to more than " << 65535.0 / depth_scale << " m (65535 / depth scale "
         << depth_scale << ") stored as 65535";
  if (clamping.above > 0 && clamping.below > 0)
    text << "; ";
  if (clamping.below > 0)
    text << clamping.below << " pixel(s) filtered to less than " << 0.5 / depth_scale << " m stored as 1";
  return text.str();
}

DepthImage
cloudToDepthImage(const pcl::PointCloud<pcl::PointXYZ>& cloud, double depth_scale, DepthClamping* clamping)
{
  const std::vector<double> depths = cloudToDepthValues(cloud, depth_scale);
  DepthImage image;
  image.width = static_cast<int>(cloud.width);
  image.height = static_cast<int>(cloud.height);
  image.values.assign(cloud.size(), 0);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (std::isnan(depths[i]))
      continue;
    const double value = std::round(depths[i]);
    if (clamping != nullptr && value > 65535.0) {
      image.values[i] = 65535;
      ++clamping->above;
      continue;
    }
    if (clamping != nullptr && value < 1.0) {
      image.values[i] = 1;
      ++clamping->below;
      continue;
    }
    if (!(value >= 1.0 && value <= 65535.0))
      throw std::invalid_argument(
          "depth " + numberText(cloud[i].z) + " m at pixel (" + std::to_string(i % cloud.width) + ", " +
          std::to_string(i / cloud.width) + ") does not fit a 16-bit depth image with depth_scale " +
          numberText(depth_scale) + " (representable: " + numberText(0.5 / depth_scale) + " to " +
          numberText(65535.0 / depth_scale) + " m); choose a smaller depth scale");
    image.values[i] = static_cast<std::uint16_t>(value);
  }
  return image;
}

DepthImage
cloudToDepthImage(const pcl::PointCloud<pcl::PointXYZ>& input, const pcl::PointCloud<pcl::PointXYZ>& filtered,
                  double depth_scale, DepthClamping* clamping)
{
  if (!(std::isfinite(depth_scale) && depth_scale > 0.0)) // before the re-projection's work
    throw std::invalid_argument("depth_scale must be a positive number, got " + numberText(depth_scale));
  return cloudToDepthImage(reprojectOntoRays(input, filtered), depth_scale, clamping);
}

pcl::PointCloud<pcl::PointXYZ>
loadDepthPng(const std::string& path, const DepthIntrinsics& intrinsics, const io::MemoryBudget& budget)
{
  const DepthImage image = readDepthPng(path, budget);
  try {
    return depthImageToCloud(image, intrinsics);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(quoted(path) + ": " + e.what());
  }
}

void
saveDepthPng(const std::string& path, const pcl::PointCloud<pcl::PointXYZ>& cloud, double depth_scale,
             DepthClamping* clamping)
{
  DepthImage image;
  try {
    image = cloudToDepthImage(cloud, depth_scale, clamping);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(quoted(path) + ": " + e.what());
  }
  writeDepthPng(path, image);
}

void
saveDepthPng(const std::string& path, const pcl::PointCloud<pcl::PointXYZ>& input,
             const pcl::PointCloud<pcl::PointXYZ>& filtered, double depth_scale, DepthClamping* clamping)
{
  DepthImage image;
  try {
    image = cloudToDepthImage(input, filtered, depth_scale, clamping);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(quoted(path) + ": " + e.what());
  }
  writeDepthPng(path, image);
}

} // namespace range_nlm
