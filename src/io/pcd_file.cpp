#include <range_nlm/io/pcd_file.h>

#include "output_file.h"

#include <pcl/common/io.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;

namespace range_nlm
{
namespace io
{

namespace
{
const pcl::PCLPointField*
findField(const pcl::PCLPointCloud2& blob, const std::string& name)
{
  for (const auto& f : blob.fields)
    if (f.name == name)
      return &f;
  return nullptr;
}

double
readCoordinate(const std::uint8_t* p, const pcl::PCLPointField& f)
{
  if (f.datatype == pcl::PCLPointField::FLOAT64) {
    double v;
    std::memcpy(&v, p + f.offset, sizeof v);
    return v;
  }
  float v;
  std::memcpy(&v, p + f.offset, sizeof v);
  return v;
}

void
writeCoordinate(std::uint8_t* p, const pcl::PCLPointField& f, float value)
{
  if (f.datatype == pcl::PCLPointField::FLOAT64) {
    const double v = value;
    std::memcpy(p + f.offset, &v, sizeof v);
  } else {
    std::memcpy(p + f.offset, &value, sizeof value);
  }
}

/// A PCD file's layout as announced by its header, checked before PCL's reader sees the file:
/// PCDReader trusts the header (it allocates POINTS x point size up front, reads uninitialised
/// values from malformed numbers, skips or zero-fills malformed ascii values and writes past its
/// buffer when a binary_compressed body announces a wrong size), so every size is validated here.
struct PcdLayout
{
  enum class Data
  {
    ascii,
    binary,
    binary_compressed
  };
  std::vector<pcl::PCLPointField> fields; // offsets packed in FIELDS order
  std::vector<int> sizes;                 // bytes of one element of each field
  std::vector<char> types;                // 'F', 'I', 'U' or 'B'
  std::uint64_t point_step = 0;
  std::uint64_t width = 0, height = 0, points = 0;
  Data data = Data::ascii;
  std::uint64_t data_offset = 0; // first byte of the body
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
};

constexpr std::uint64_t kMaxPoints = std::uint64_t(1) << 28;
constexpr std::uint64_t kMaxPointStep = std::uint64_t(1) << 20;
constexpr std::size_t kMaxHeaderBytes = std::size_t(1) << 20;

/// A token of the file as it may appear inside a one-line message: printable ASCII, shortened.
std::string
quote(const std::string& token)
{
  std::string out;
  for (const char c : token.substr(0, 40))
    out += (c >= 0x20 && c < 0x7f) ? c : '?';
  if (token.size() > 40)
    out += "...";
  return "'" + out + "'";
}

[[noreturn]] void
fail(const std::string& path, const std::string& problem)
{
  throw InputError("'" + path + "': " + problem);
}

std::vector<std::string>
tokenize(const std::string& line)
{
  std::vector<std::string> tokens;
  std::size_t start = 0;
  while (true) {
    start = line.find_first_not_of(" \t\r", start);
    if (start == std::string::npos)
      return tokens;
    const std::size_t end = line.find_first_of(" \t\r", start);
    tokens.push_back(line.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos)
      return tokens;
    start = end;
  }
}

bool
parseUnsigned(const std::string& token, std::uint64_t& value)
{
  if (token.empty() || token.size() > 19 || token.find_first_not_of("0123456789") != std::string::npos)
    return false;
  value = std::stoull(token);
  return true;
}

/// A decimal number as PCL's reader converts it (no hex, no trailing characters), or nan/inf.
bool
isDecimalNumber(const std::string& token)
{
  std::size_t i = (!token.empty() && (token[0] == '+' || token[0] == '-')) ? 1 : 0;
  std::string rest = token.substr(i);
  std::transform(rest.begin(), rest.end(), rest.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (rest == "nan" || rest == "inf" || rest == "infinity")
    return true;
  std::size_t digits = 0;
  i = 0;
  while (i < rest.size() && std::isdigit(static_cast<unsigned char>(rest[i])))
    ++i, ++digits;
  if (i < rest.size() && rest[i] == '.') {
    ++i;
    while (i < rest.size() && std::isdigit(static_cast<unsigned char>(rest[i])))
      ++i, ++digits;
  }
  if (digits == 0)
    return false;
  if (i < rest.size() && rest[i] == 'e') {
    ++i;
    if (i < rest.size() && (rest[i] == '+' || rest[i] == '-'))
      ++i;
    const std::size_t exponent_start = i;
    while (i < rest.size() && std::isdigit(static_cast<unsigned char>(rest[i])))
      ++i;
    if (i == exponent_start)
      return false;
  }
  return i == rest.size();
}

/// An ascii value of a field of `size` bytes and `type` 'F', 'I', 'U' or 'B'.
bool
isValidValue(const std::string& token, int size, char type)
{
  if (type == 'F')
    return isDecimalNumber(token);
  if (type == 'B')
    return token == "0" || token == "1";
  const bool negative = !token.empty() && token[0] == '-';
  const std::string digits = token.substr((!token.empty() && (token[0] == '-' || token[0] == '+')) ? 1 : 0);
  if (digits.empty() || digits.size() > 20 || digits.find_first_not_of("0123456789") != std::string::npos)
    return false;
  if (type == 'U' && negative)
    return !digits.empty() && digits.find_first_not_of('0') == std::string::npos; // "-0"
  errno = 0;
  if (type == 'U') {
    const unsigned long long v = std::strtoull(digits.c_str(), nullptr, 10);
    return errno == 0 && (size == 8 || v < (1ull << (8 * size)));
  }
  const long long v = std::strtoll(token.c_str(), nullptr, 10);
  if (errno != 0)
    return false;
  if (size == 8)
    return true;
  const long long limit = 1ll << (8 * size - 1);
  return v >= -limit && v < limit;
}

/// The first bytes of a PCD file, as many as its header may take (kMaxHeaderBytes).
std::string
readHeaderBytes(const std::string& path, std::uint64_t file_size)
{
  std::ifstream in(path, std::ios::binary);
  if (!in)
    fail(path, std::string("cannot open file: ") + std::strerror(errno));
  std::string head(static_cast<std::size_t>(std::min<std::uint64_t>(file_size, kMaxHeaderBytes)), '\0');
  in.read(&head[0], static_cast<std::streamsize>(head.size()));
  if (in.gcount() != static_cast<std::streamsize>(head.size()))
    fail(path, "read error in the PCD header");
  return head;
}

const std::string kMalformed = "malformed PCD header: ";

/// Builds a PcdLayout from the header's lines, one keyword line at a time, then checks it as a
/// whole (finish): the field table and the cloud's size.
class PcdHeaderParser
{
public:
  explicit PcdHeaderParser(const std::string& path) : path_(path) {}

  /// One line of the header, `t` its tokens (t[0] the keyword, not a comment); `last`: the line
  /// has no newline, `next` is where the line after it starts. True at the DATA line, the last
  /// of the header.
  bool parseLine(const std::vector<std::string>& t, const std::string& line, bool last, std::size_t next)
  {
    const std::string& key = t[0];
    if (key == "VERSION")
      return false;
    if (key == "FIELDS" || key == "COLUMNS")
      parseFields(t);
    else if (key == "SIZE")
      parseSize(t);
    else if (key == "TYPE")
      parseType(t);
    else if (key == "COUNT")
      parseCount(t);
    else if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS")
      parseDimension(t);
    else if (key == "VIEWPOINT")
      parseViewpoint(t);
    else if (key == "DATA") {
      parseData(t, last, next);
      return true;
    } else {
      fail(path_, kMalformed + "unexpected line " + quote(line));
    }
    return false;
  }

  /// The layout, once the DATA line is read: every field typed and packed, the size checked.
  PcdLayout finish()
  {
    if (layout_.fields.empty())
      fail(path_, "malformed PCD header: no FIELDS line");
    if (!have_size_ || !have_type_)
      fail(path_, std::string("malformed PCD header: no ") + (have_size_ ? "TYPE" : "SIZE") + " line");
    packFields();
    checkSize();
    return layout_;
  }

private:
  void parseFields(const std::vector<std::string>& t)
  {
    const std::size_t n = t.size() - 1;
    if (!layout_.fields.empty())
      fail(path_, kMalformed + "second FIELDS line");
    if (n == 0)
      fail(path_, kMalformed + "FIELDS line names no field");
    const std::vector<std::string> names(t.begin() + 1, t.end());
    const std::string problem = fieldLayoutProblem(names, std::vector<std::uint64_t>(n, 1), kMaxPointStep);
    if (!problem.empty())
      fail(path_, kMalformed + problem);
    for (const std::string& name : names) {
      pcl::PCLPointField f;
      f.name = name;
      layout_.fields.push_back(f);
    }
    layout_.sizes.assign(n, 4);
    layout_.types.assign(n, 'F');
    counts_.assign(n, 1);
  }

  void parseSize(const std::vector<std::string>& t)
  {
    needFields(t);
    for (std::size_t i = 0; i + 1 < t.size(); ++i) {
      const std::uint64_t v = number(t[0], t[i + 1]);
      if (v != 1 && v != 2 && v != 4 && v != 8)
        fail(path_, kMalformed + "field " + quote(layout_.fields[i].name) + " has SIZE " + std::to_string(v) +
                        " (expected 1, 2, 4 or 8)");
      layout_.sizes[i] = int(v);
    }
    have_size_ = true;
  }

  void parseType(const std::vector<std::string>& t)
  {
    needFields(t);
    for (std::size_t i = 0; i + 1 < t.size(); ++i) {
      if (t[i + 1].size() != 1 || !std::strchr("FIUB", t[i + 1][0]))
        fail(path_, kMalformed + "field " + quote(layout_.fields[i].name) + " has TYPE " + quote(t[i + 1]) +
                        " (expected F, I, U or B)");
      layout_.types[i] = t[i + 1][0];
    }
    have_type_ = true;
  }

  void parseCount(const std::vector<std::string>& t)
  {
    needFields(t);
    std::vector<std::string> names;
    for (std::size_t i = 0; i + 1 < t.size(); ++i) {
      counts_[i] = number(t[0], t[i + 1]);
      names.push_back(layout_.fields[i].name);
    }
    const std::string problem = fieldLayoutProblem(names, counts_, kMaxPointStep);
    if (!problem.empty())
      fail(path_, kMalformed + problem);
  }

  /// WIDTH, HEIGHT or POINTS.
  void parseDimension(const std::vector<std::string>& t)
  {
    const std::string& key = t[0];
    const std::size_t n = t.size() - 1;
    if (n != 1)
      fail(path_, kMalformed + key + " needs one value, got " + std::to_string(n));
    bool& seen = key == "WIDTH" ? have_width_ : key == "HEIGHT" ? have_height_ : have_points_;
    if (seen)
      fail(path_, kMalformed + "second " + key + " line");
    seen = true;
    (key == "WIDTH" ? layout_.width : key == "HEIGHT" ? layout_.height : layout_.points) = number(key, t[1]);
  }

  void parseViewpoint(const std::vector<std::string>& t)
  {
    const std::size_t n = t.size() - 1;
    if (n != 7)
      fail(path_, kMalformed + "VIEWPOINT needs 7 values (tx ty tz qw qx qy qz), got " + std::to_string(n));
    float v[7];
    for (std::size_t i = 0; i < 7; ++i) {
      const std::string& token = t[i + 1];
      v[i] = std::strtof(token.c_str(), nullptr);
      if (!isDecimalNumber(token) || !std::isfinite(v[i]))
        fail(path_, kMalformed + "VIEWPOINT value " + quote(token) + " is not a finite number");
    }
    layout_.origin = Eigen::Vector4f(v[0], v[1], v[2], 0.0f);
    layout_.orientation = Eigen::Quaternionf(v[3], v[4], v[5], v[6]);
  }

  void parseData(const std::vector<std::string>& t, bool last, std::size_t next)
  {
    const std::size_t n = t.size() - 1;
    if (n != 1 || (t[1] != "ascii" && t[1] != "binary" && t[1] != "binary_compressed"))
      fail(path_, kMalformed + "DATA must be ascii, binary or binary_compressed, got " +
                      quote(n ? t[1] : std::string()));
    layout_.data = t[1] == "ascii"    ? PcdLayout::Data::ascii
                   : t[1] == "binary" ? PcdLayout::Data::binary
                                      : PcdLayout::Data::binary_compressed;
    if (last && layout_.data != PcdLayout::Data::ascii)
      fail(path_, "truncated PCD header (DATA line not terminated)");
    layout_.data_offset = next;
  }

  /// A line of values per field (SIZE, TYPE, COUNT): after FIELDS, one value for each field.
  void needFields(const std::vector<std::string>& t) const
  {
    const std::size_t n = t.size() - 1;
    if (layout_.fields.empty())
      fail(path_, kMalformed + t[0] + " line before the FIELDS line");
    if (n != layout_.fields.size())
      fail(path_, kMalformed + t[0] + " has " + std::to_string(n) + " values for " +
                      std::to_string(layout_.fields.size()) + " fields");
  }

  std::uint64_t number(const std::string& key, const std::string& token) const
  {
    std::uint64_t v = 0;
    if (!parseUnsigned(token, v))
      fail(path_, kMalformed + key + " value " + quote(token) + " is not a non-negative integer");
    return v;
  }

  /// The field table: each field's PCL datatype, count and offset, packed in FIELDS order.
  void packFields()
  {
    std::uint64_t offset = 0;
    for (std::size_t i = 0; i < layout_.fields.size(); ++i) {
      pcl::PCLPointField& f = layout_.fields[i];
      const int datatype = pcl::getFieldType(layout_.sizes[i], layout_.types[i]);
      if (datatype < 0)
        fail(path_, "malformed PCD header: field " + quote(f.name) + " has TYPE " + layout_.types[i] +
                        " with SIZE " + std::to_string(layout_.sizes[i]));
      f.datatype = static_cast<std::uint8_t>(datatype);
      f.count = static_cast<std::uint32_t>(counts_[i]);
      f.offset = static_cast<std::uint32_t>(offset);
      offset += counts_[i] * layout_.sizes[i];
      if (offset > kMaxPointStep)
        fail(path_, "malformed PCD header: a point would take more than " + std::to_string(kMaxPointStep) + " bytes");
    }
    layout_.point_step = offset;
  }

  /// WIDTH, HEIGHT and POINTS agree and stay within kMaxPoints.
  void checkSize()
  {
    if (!have_width_ && !have_height_) {
      layout_.width = layout_.points; // PCD v0.6: a list of POINTS points
      layout_.height = 1;
    } else if (!have_height_) {
      layout_.height = 1;
    } else if (!have_width_) {
      fail(path_, "malformed PCD header: HEIGHT without WIDTH");
    }
    if (layout_.width == 0 || layout_.height == 0)
      fail(path_, "cloud has zero width or height (" + std::to_string(layout_.width) + " x " +
                      std::to_string(layout_.height) + ")");
    if (layout_.width > kMaxPoints || layout_.height > kMaxPoints || layout_.width * layout_.height > kMaxPoints)
      fail(path_, "absurd size " + std::to_string(layout_.width) + " x " + std::to_string(layout_.height) +
                      " (more than " + std::to_string(kMaxPoints) + " points)");
    if (!have_points_)
      layout_.points = layout_.width * layout_.height;
    if (layout_.points != layout_.width * layout_.height)
      fail(path_, "malformed PCD header: POINTS " + std::to_string(layout_.points) + " but WIDTH x HEIGHT = " +
                      std::to_string(layout_.width * layout_.height));
  }

  const std::string& path_;
  PcdLayout layout_;
  std::vector<std::uint64_t> counts_; // COUNT of each field
  bool have_width_ = false, have_height_ = false, have_points_ = false, have_size_ = false, have_type_ = false;
};

PcdLayout
readPcdLayout(const std::string& path, std::uint64_t file_size)
{
  const std::string head = readHeaderBytes(path, file_size);
  PcdHeaderParser parser(path);
  std::size_t pos = 0;
  while (true) {
    if (pos >= head.size())
      fail(path, file_size > head.size() ? "malformed PCD header: no DATA line in the first MiB"
                                         : "truncated PCD header (no DATA line)");
    const std::size_t newline = head.find('\n', pos);
    const bool last = newline == std::string::npos;
    const std::string line = head.substr(pos, last ? std::string::npos : newline - pos);
    pos = last ? head.size() : newline + 1;
    if (last && file_size == head.size() && line.compare(0, 5, "DATA ") != 0)
      fail(path, "truncated PCD header (it ends inside the line " + quote(line) + ")");
    if (line.empty())
      continue;
    const std::vector<std::string> t = tokenize(line);
    if (t.empty())
      fail(path, "malformed PCD header: a line holds only blanks");
    if (t[0][0] == '#')
      continue;
    if (parser.parseLine(t, line, last, pos))
      return parser.finish();
  }
}

std::uint32_t
readLittleEndian32(const unsigned char* p)
{
  return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24;
}

/// Checks that a binary body of `body` bytes holds the points the header announces. (PCL's writer
/// may leave bytes after the data: they are ignored.)
void
checkBinarySize(const std::string& path, const PcdLayout& layout, std::uint64_t body)
{
  const std::uint64_t bytes = layout.points * layout.point_step;
  if (body < bytes)
    fail(path, "truncated PCD body (binary: " + std::to_string(body) + " of " + std::to_string(bytes) +
                   " bytes for " + std::to_string(layout.points) + " points)");
}

/// Checks that a binary_compressed body (`file` holds the whole file) decompresses to exactly the
/// points the header announces.
void
checkCompressedBody(const std::string& path, const PcdLayout& layout, const std::vector<unsigned char>& file)
{
  const std::uint64_t body = file.size() - layout.data_offset;
  const std::uint64_t bytes = layout.points * layout.point_step;
  if (body < 8)
    fail(path, "truncated PCD body (binary_compressed: no size record)");
  for (const pcl::PCLPointField& f : layout.fields)
    if (f.name == "_")
      fail(path, "malformed PCD header: padding field '_' in a binary_compressed file");
  const unsigned char* sizes = file.data() + layout.data_offset;
  const std::uint64_t compressed = readLittleEndian32(sizes), uncompressed = readLittleEndian32(sizes + 4);
  if (uncompressed != bytes)
    fail(path, "malformed PCD body (binary_compressed: announces " + std::to_string(uncompressed) +
                   " bytes, WIDTH x HEIGHT points need " + std::to_string(bytes) + ")");
  if (compressed == 0 || 8 + compressed > body)
    fail(path, "truncated PCD body (binary_compressed: " + std::to_string(body - 8) + " of " +
                   std::to_string(compressed) + " compressed bytes)");
  // LZF expands a 3-byte back reference to at most 264 bytes.
  if (uncompressed > 88 * compressed + 32)
    fail(path, "malformed PCD body (binary_compressed: " + std::to_string(compressed) +
                   " compressed bytes cannot hold " + std::to_string(uncompressed) + ")");
}

/// Checks that an ascii body holds exactly the points the header announces, each with one valid
/// value per element (PCL skips empty lines and counts every other line as a point).
void
checkAsciiBody(const std::string& path, const PcdLayout& layout)
{
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(layout.data_offset));
  std::uint64_t elements = 0;
  for (const pcl::PCLPointField& f : layout.fields)
    elements += f.count;
  std::uint64_t point = 0;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty())
      continue;
    const std::vector<std::string> t = tokenize(line);
    if (point == layout.points) {
      if (t.empty())
        continue;
      fail(path, "malformed PCD body (ascii: more than the " + std::to_string(layout.points) +
                     " points of the header)");
    }
    ++point;
    if (t.size() != elements && in.eof())
      fail(path, "truncated PCD body (ascii: point " + std::to_string(point) + " of " +
                     std::to_string(layout.points) + " is cut off)");
    if (t.size() != elements)
      fail(path, "malformed PCD body (ascii: point " + std::to_string(point) + " has " +
                     std::to_string(t.size()) + " values, expected " + std::to_string(elements) + ")");
    std::size_t k = 0;
    for (std::size_t i = 0; i < layout.fields.size(); ++i)
      for (std::uint32_t c = 0; c < layout.fields[i].count; ++c, ++k)
        if (layout.fields[i].name != "_" && !isValidValue(t[k], layout.sizes[i], layout.types[i]))
          fail(path, "malformed PCD body (ascii: point " + std::to_string(point) + ", field " +
                         quote(layout.fields[i].name) + ": " + quote(t[k]) + " is not a valid " +
                         (layout.types[i] == 'F' ? "number" : "integer of its TYPE and SIZE") + ")");
  }
  if (point < layout.points)
    fail(path, "truncated PCD body (ascii: " + std::to_string(point) + " of " + std::to_string(layout.points) +
                   " points)");
}

/// The blob with its fields back to back in the order of their offsets and no bytes between or
/// after them. PCL's header generator names such bytes `_` fields, which some of PCL's own
/// converters (pcl_pcd2ply) cannot read: they abort on a `_` field that is not the last one.
/// Returns false (and leaves `packed` alone) if the blob is packed already.
bool
packFields(const pcl::PCLPointCloud2& blob, pcl::PCLPointCloud2& packed)
{
  std::vector<pcl::PCLPointField> fields = blob.fields;
  std::stable_sort(fields.begin(), fields.end(),
                   [](const pcl::PCLPointField& a, const pcl::PCLPointField& b) { return a.offset < b.offset; });
  std::vector<std::uint32_t> sizes(fields.size());
  std::uint32_t step = 0;
  bool already = true;
  for (std::size_t k = 0; k < fields.size(); ++k) {
    sizes[k] = static_cast<std::uint32_t>(pcl::getFieldSize(fields[k].datatype)) * fields[k].count;
    already = already && fields[k].offset == step && blob.fields[k].offset == fields[k].offset;
    step += sizes[k];
  }
  if (already && step == blob.point_step)
    return false;
  for (std::size_t k = 0; k < fields.size(); ++k)
    if (sizes[k] == 0 || std::uint64_t(fields[k].offset) + sizes[k] > blob.point_step)
      return false; // not a layout to repack; the header generator refuses it
  const std::size_t points = std::size_t(blob.width) * blob.height;
  packed.header = blob.header;
  packed.width = blob.width;
  packed.height = blob.height;
  packed.is_bigendian = blob.is_bigendian;
  packed.is_dense = blob.is_dense;
  packed.point_step = step;
  packed.row_step = step * blob.width;
  packed.fields = fields;
  packed.data.assign(points * step, 0);
  std::uint32_t offset = 0;
  for (std::size_t k = 0; k < fields.size(); ++k) {
    for (std::size_t i = 0; i < points; ++i)
      std::memcpy(&packed.data[i * step + offset], &blob.data[i * blob.point_step + fields[k].offset], sizes[k]);
    packed.fields[k].offset = offset;
    offset += sizes[k];
  }
  return true;
}
} // namespace

std::string
fieldLayoutProblem(const std::vector<std::string>& names, const std::vector<std::uint64_t>& counts,
                   std::uint64_t max_count)
{
  for (std::size_t i = 0; i < names.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j)
      if (names[i] == names[j] && names[i] != "_")
        return "field " + quote(names[i]) + " appears twice";
    if (i < counts.size() && (counts[i] < 1 || counts[i] > max_count))
      return "field " + quote(names[i]) + " has COUNT " + std::to_string(counts[i]);
  }
  return "";
}

LoadedCloud
loadCloud(const std::string& path, bool organized, const MemoryBudget& budget)
{
  std::error_code ec;
  if (!fs::exists(path, ec)) // ec: it cannot be told (e.g. a loop of symbolic links)
    fail(path, ec ? "cannot open the file: " + ec.message() : std::string("file does not exist"));
  if (!fs::is_regular_file(path, ec))
    fail(path, "not a regular file");
  const std::uint64_t file_size = fs::file_size(path, ec);
  if (ec)
    fail(path, "cannot read the file size: " + ec.message());
  if (file_size == 0)
    fail(path, "file is empty");
  const PcdLayout layout = readPcdLayout(path, file_size);
  // Before the body is read (a binary_compressed body expands up to 88-fold).
  const std::string refusal = budget.refusal(layout.width, layout.height, layout.point_step);
  if (!refusal.empty())
    fail(path, refusal);
  for (const char* axis : {"x", "y", "z"}) {
    const auto f = std::find_if(layout.fields.begin(), layout.fields.end(),
                                [&](const pcl::PCLPointField& field) { return field.name == axis; });
    if (f == layout.fields.end())
      fail(path, std::string("PCD has no '") + axis + "' field");
    if ((f->datatype != pcl::PCLPointField::FLOAT32 && f->datatype != pcl::PCLPointField::FLOAT64) ||
        f->count != 1)
      fail(path, std::string("field '") + axis + "' is not a single float");
  }
  if (organized && layout.height < 2)
    fail(path, "cloud is not organized (height " + std::to_string(layout.height) +
                   "); range_nlm needs a grid such as a depth-camera frame");

  // The body is decoded by PCL from the validated layout; PCL never parses the header itself.
  LoadedCloud loaded;
  loaded.origin = layout.origin;
  loaded.orientation = layout.orientation;
  pcl::PCLPointCloud2& blob = loaded.blob;
  blob.fields = layout.fields;
  blob.width = static_cast<std::uint32_t>(layout.width);
  blob.height = static_cast<std::uint32_t>(layout.height);
  blob.point_step = static_cast<std::uint32_t>(layout.point_step);
  blob.row_step = static_cast<std::uint32_t>(layout.point_step * layout.width);
  blob.is_bigendian = false;
  pcl::PCDReader reader;
  if (layout.data == PcdLayout::Data::ascii) {
    checkAsciiBody(path, layout);
    blob.data.resize(layout.points * layout.point_step);
    std::ifstream in(path, std::ios::binary);
    in.seekg(static_cast<std::streamoff>(layout.data_offset));
    if (!in || reader.readBodyASCII(in, blob, pcl::PCDReader::PCD_V7) < 0)
      fail(path, "cannot read the ascii PCD body");
  } else if (layout.data == PcdLayout::Data::binary) {
    // The body is the points' bytes as they are: read straight into the blob (PCL's reader
    // copies them out of a copy of the file and then tests every element for NaN, which took
    // most of a tool's reading time at VGA size).
    const std::uint64_t bytes = layout.points * layout.point_step;
    checkBinarySize(path, layout, file_size - layout.data_offset);
    blob.data.resize(static_cast<std::size_t>(bytes));
    std::ifstream in(path, std::ios::binary);
    in.seekg(static_cast<std::streamoff>(layout.data_offset));
    if (!in || !in.read(reinterpret_cast<char*>(blob.data.data()), static_cast<std::streamsize>(bytes)))
      fail(path, "read error in the PCD body");
  } else {
    std::vector<unsigned char> file(static_cast<std::size_t>(file_size));
    std::ifstream in(path, std::ios::binary);
    if (!in.read(reinterpret_cast<char*>(file.data()), static_cast<std::streamsize>(file.size())))
      fail(path, "read error in the PCD body");
    checkCompressedBody(path, layout, file);
    blob.data.resize(layout.points * layout.point_step);
    if (reader.readBodyBinary(file.data(), blob, pcl::PCDReader::PCD_V7, true,
                              static_cast<unsigned int>(layout.data_offset)) < 0)
      fail(path, "corrupt binary_compressed PCD body (the LZF data does not decompress to WIDTH x HEIGHT points)");
  }
  if (blob.data.size() != layout.points * layout.point_step)
    fail(path, "PCD body does not hold width x height points");
  return loaded;
}

pcl::PointCloud<pcl::PointXYZ>
xyzFromBlob(const LoadedCloud& loaded, const std::string& path)
{
  const pcl::PCLPointCloud2& blob = loaded.blob;
  const pcl::PCLPointField* fx = findField(blob, "x");
  const pcl::PCLPointField* fy = findField(blob, "y");
  const pcl::PCLPointField* fz = findField(blob, "z");
  if (!fx || !fy || !fz)
    throw InputError("'" + path + "': PCD has no x, y, z fields");
  pcl::PointCloud<pcl::PointXYZ> cloud(blob.width, blob.height);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  bool dense = true;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const std::uint8_t* p = &blob.data[i * blob.point_step];
    const double x = readCoordinate(p, *fx), y = readCoordinate(p, *fy), z = readCoordinate(p, *fz);
    if (std::isinf(x) || std::isinf(y) || std::isinf(z))
      throw InputError("'" + path + "': infinite coordinate at pixel (" + std::to_string(i % blob.width) +
                       ", " + std::to_string(i / blob.width) + "); invalid points must be NaN");
    const double largest = std::numeric_limits<float>::max();
    if (std::fabs(x) > largest || std::fabs(y) > largest || std::fabs(z) > largest)
      throw InputError("'" + path + "': coordinate outside the float range at pixel (" +
                       std::to_string(i % blob.width) + ", " + std::to_string(i / blob.width) + ")");
    pcl::PointXYZ& q = cloud[i];
    if (std::isnan(x) || std::isnan(y) || std::isnan(z)) {
      q.x = q.y = q.z = nan;
      dense = false;
    } else {
      q.x = float(x), q.y = float(y), q.z = float(z);
    }
  }
  cloud.is_dense = dense;
  cloud.sensor_origin_ = loaded.origin;
  cloud.sensor_orientation_ = loaded.orientation;
  return cloud;
}

void
writeXyzToBlob(const pcl::PointCloud<pcl::PointXYZ>& xyz, pcl::PCLPointCloud2& blob)
{
  const pcl::PCLPointField* fx = findField(blob, "x");
  const pcl::PCLPointField* fy = findField(blob, "y");
  const pcl::PCLPointField* fz = findField(blob, "z");
  bool dense = true;
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    std::uint8_t* p = &blob.data[i * blob.point_step];
    writeCoordinate(p, *fx, xyz[i].x);
    writeCoordinate(p, *fy, xyz[i].y);
    writeCoordinate(p, *fz, xyz[i].z);
    dense = dense && std::isfinite(xyz[i].x) && std::isfinite(xyz[i].y) && std::isfinite(xyz[i].z);
  }
  blob.is_dense = dense;
}

void
saveCloudAtomic(const std::string& path, const pcl::PCLPointCloud2& unpacked, const Eigen::Vector4f& origin,
                const Eigen::Quaternionf& orientation)
{
  // PCL's PCDWriter::writeBinary fills a memory map of the file: on a full disk the kernel
  // answers with SIGBUS. The same bytes (PCL's header, then the points) go out with write(2)
  // here, every return checked.
  if (unpacked.data.empty() ||
      unpacked.data.size() < std::size_t(unpacked.point_step) * unpacked.width * unpacked.height)
    throw InputError("'" + path + "': cannot write output file: the cloud holds " +
                     std::to_string(unpacked.data.size()) + " bytes, not " + std::to_string(unpacked.width) + " x " +
                     std::to_string(unpacked.height) + " points of " + std::to_string(unpacked.point_step) + " bytes");
  // Written packed: no padding between or after the fields, so no `_` fields in the header.
  pcl::PCLPointCloud2 packed_blob;
  const pcl::PCLPointCloud2& blob = packFields(unpacked, packed_blob) ? packed_blob : unpacked;
  pcl::PCDWriter writer;
  std::string header = writer.generateHeaderBinary(blob, origin, orientation);
  if (header.empty())
    throw InputError("'" + path + "': cannot write output file: the fields do not fit the point step");
  header += "DATA binary\n";
  detail::OutputFile out(path);
  out.write(header.data(), header.size());
  out.write(blob.data.data(), blob.data.size());
  // PCL sizes its file to one page more than the points and maps the header and the points
  // into it, so its files end in zeros up to that size; the same zeros keep the output
  // byte-identical to PCL's (readers ignore bytes after the points).
  const std::size_t pcl_size = static_cast<std::size_t>(::getpagesize()) + blob.data.size();
  const std::size_t written = header.size() + blob.data.size();
  if (pcl_size > written) {
    const std::vector<char> zeros(pcl_size - written, 0);
    out.write(zeros.data(), zeros.size());
  }
  out.commit();
}

bool
isDepthImagePath(const std::string& path)
{
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".png";
}

LoadedCloud
loadFrame(const std::string& path, const DepthIntrinsics& intrinsics, const MemoryBudget& budget)
{
  if (!isDepthImagePath(path))
    return loadCloud(path, true, budget);
  pcl::PointCloud<pcl::PointXYZ> cloud;
  try {
    cloud = loadDepthPng(path, intrinsics, budget);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  if (cloud.height < 2)
    throw InputError("'" + path + "': depth image has a single row; range_nlm needs a grid");
  LoadedCloud loaded;
  pcl::toPCLPointCloud2(cloud, loaded.blob);
  return loaded;
}

} // namespace io
} // namespace range_nlm
