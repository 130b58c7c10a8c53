#include "tool_common.h"

#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>
#include <unistd.h>

namespace fs = std::filesystem;
namespace po = boost::program_options;

namespace range_nlm
{
namespace tools
{

int
runTool(const std::string& tool, const std::function<int()>& body)
{
  // PCL's own console messages would add lines to our one-line errors.
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  try {
    return body();
  } catch (const UsageError& e) {
    std::cerr << tool << ": usage error: " << e.what() << " (see " << tool << " --help)\n";
    return 2;
  } catch (const po::error& e) {
    std::cerr << tool << ": usage error: " << e.what() << " (see " << tool << " --help)\n";
    return 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << tool << ": error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << tool << ": error: " << e.what() << "\n";
    return 1;
  }
}

bool
parseCommandLine(int argc, char** argv, const po::options_description& options,
                 const po::positional_options_description& positional, po::variables_map& vm,
                 const std::string& usage)
{
  po::store(po::command_line_parser(argc, argv).options(options).positional(positional).run(), vm);
  if (vm.count("help")) {
    std::cout << usage << "\n\n" << options << "\n";
    return false;
  }
  po::notify(vm);
  return true;
}

void
addFilterOptions(po::options_description& options)
{
  const FilterParameters d = FilterParameters::recommended();
  // clang-format off
  options.add_options()
    ("preset", po::value<std::string>()->default_value("default"),
     "parameter preset: 'default' (recommended) or 'paper' (the literal method); options below override it")
    ("search-window", po::value<int>(), ("S, odd side of the search window in pixels [preset: " + std::to_string(d.search_window) + "]").c_str())
    ("patch", po::value<int>(), ("P, odd side of the similarity patch in pixels [preset: " + std::to_string(d.patch_size) + "]").c_str())
    ("iterations", po::value<int>(), ("filter passes [preset: " + std::to_string(d.iterations) + "]").c_str())
    ("threads", po::value<int>()->default_value(0), "OpenMP threads, 0 = all cores (output does not depend on it)")
    ("distance-bandwidth", po::value<float>(), "d in cloud units [default: automatic]")
    ("similarity-bandwidth", po::value<float>(), "s in cloud units [default: automatic]")
    ("seed", po::value<std::uint64_t>()->default_value(42), "seed of the bandwidth sample")
    ("normal-window", po::value<int>(), ("odd side of the normal-estimation neighbourhood [preset: " + std::to_string(d.normal_window) + "]").c_str())
    ("direct", "use the direct (reference) evaluation instead of the box-filtered one")
    ("line-of-sight", "move points along their camera ray instead of the normal (depth sensors)");
  // clang-format on
}

FilterParameters
filterParametersFrom(const po::variables_map& vm)
{
  FilterParameters p;
  try {
    p = FilterParameters::preset(vm["preset"].as<std::string>());
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  if (vm.count("search-window"))
    p.search_window = vm["search-window"].as<int>();
  if (vm.count("patch"))
    p.patch_size = vm["patch"].as<int>();
  if (vm.count("iterations"))
    p.iterations = vm["iterations"].as<int>();
  p.threads = vm["threads"].as<int>();
  if (vm.count("distance-bandwidth"))
    p.distance_bandwidth = vm["distance-bandwidth"].as<float>();
  if (vm.count("similarity-bandwidth"))
    p.similarity_bandwidth = vm["similarity-bandwidth"].as<float>();
  p.seed = vm["seed"].as<std::uint64_t>();
  if (vm.count("normal-window"))
    p.normal_window = vm["normal-window"].as<int>();
  if (vm.count("direct"))
    p.evaluation = Evaluation::direct;
  if (vm.count("line-of-sight"))
    p.displacement = Displacement::line_of_sight;
  if ((vm.count("distance-bandwidth") && !(p.distance_bandwidth > 0.0f)) ||
      (vm.count("similarity-bandwidth") && !(p.similarity_bandwidth > 0.0f)))
    throw UsageError("a bandwidth given on the command line must be a positive number (omit it for automatic)");
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  return p;
}

std::vector<std::string>
listFrames(const std::string& directory, const std::string& extension)
{
  std::error_code ec;
  if (!fs::is_directory(directory, ec))
    throw InputError("input directory '" + directory + "' does not exist or is not a directory");
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(directory, ec)) {
    if (!entry.is_regular_file())
      continue;
    const std::string name = entry.path().filename().string();
    if (name.size() > extension.size() &&
        name.compare(name.size() - extension.size(), extension.size(), extension) == 0 &&
        name[0] != '.')
      files.push_back(entry.path().string());
  }
  if (ec)
    throw InputError("cannot read directory '" + directory + "': " + ec.message());
  if (files.empty())
    throw InputError("input directory '" + directory + "' holds no " + extension + " frame");
  std::sort(files.begin(), files.end());
  return files;
}

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
} // namespace

LoadedCloud
loadCloud(const std::string& path, bool organized)
{
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw InputError("'" + path + "': file does not exist");
  if (!fs::is_regular_file(path, ec))
    throw InputError("'" + path + "': not a regular file");
  if (fs::file_size(path, ec) == 0)
    throw InputError("'" + path + "': file is empty");
  pcl::PCDReader reader;
  pcl::PCLPointCloud2 header;
  int version = 0, type = 0;
  unsigned int data_idx = 0;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  if (reader.readHeader(path, header, origin, orientation, version, type, data_idx) < 0)
    throw InputError("'" + path + "': not a valid PCD file (malformed header)");
  for (const char* axis : {"x", "y", "z"}) {
    const pcl::PCLPointField* f = findField(header, axis);
    if (!f)
      throw InputError("'" + path + "': PCD has no '" + axis + "' field");
    if ((f->datatype != pcl::PCLPointField::FLOAT32 && f->datatype != pcl::PCLPointField::FLOAT64) ||
        f->count != 1)
      throw InputError("'" + path + "': field '" + axis + "' is not a single float");
  }
  if (header.width == 0 || header.height == 0)
    throw InputError("'" + path + "': cloud has zero width or height (" + std::to_string(header.width) +
                     " x " + std::to_string(header.height) + ")");
  const std::uint64_t points = std::uint64_t(header.width) * header.height;
  if (points > (std::uint64_t(1) << 28))
    throw InputError("'" + path + "': absurd size " + std::to_string(header.width) + " x " +
                     std::to_string(header.height));
  if (type == 1) { // binary: the body must hold every point
    const std::uint64_t need = std::uint64_t(data_idx) + points * header.point_step;
    if (fs::file_size(path, ec) < need)
      throw InputError("'" + path + "': truncated PCD body (" + std::to_string(fs::file_size(path, ec)) +
                       " bytes, header announces " + std::to_string(need) + ")");
  }
  LoadedCloud loaded;
  pcl::PCLPointCloud2& blob = loaded.blob;
  if (reader.read(path, blob, loaded.origin, loaded.orientation, version) < 0)
    throw InputError("'" + path + "': cannot read PCD body (truncated or malformed)");
  if (std::uint64_t(blob.width) * blob.height * blob.point_step != blob.data.size() ||
      std::uint64_t(blob.width) * blob.height != points)
    throw InputError("'" + path + "': PCD body does not hold width x height points");
  if (organized && blob.height < 2)
    throw InputError("'" + path + "': cloud is not organized (height " + std::to_string(blob.height) +
                     "); range_nlm needs a grid such as a depth-camera frame");
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
saveCloudAtomic(const std::string& path, const pcl::PCLPointCloud2& blob, const Eigen::Vector4f& origin,
                const Eigen::Quaternionf& orientation)
{
  const fs::path target(path);
  const fs::path tmp = target.parent_path() / ("." + target.filename().string() + ".tmp" +
                                               std::to_string(::getpid()));
  pcl::PCDWriter writer;
  int rc = -1;
  try {
    rc = writer.writeBinary(tmp.string(), blob, origin, orientation);
  } catch (const std::exception&) {
    rc = -1;
  }
  std::error_code ec;
  if (rc != 0) {
    fs::remove(tmp, ec);
    throw InputError("'" + path + "': cannot write output file");
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw InputError("'" + path + "': cannot move output into place: " + ec.message());
  }
}

void
prepareOutputDirectory(const std::string& input_dir, const std::string& output_dir, bool allow_same)
{
  std::error_code ec;
  if (fs::exists(output_dir, ec)) {
    if (!fs::is_directory(output_dir, ec))
      throw InputError("output '" + output_dir + "' exists and is not a directory");
    if (!input_dir.empty() && fs::equivalent(input_dir, output_dir, ec) && !allow_same)
      throw InputError("output directory '" + output_dir +
                       "' is the input directory; refusing to overwrite the input (use --overwrite)");
    return;
  }
  fs::create_directories(output_dir, ec);
  if (ec)
    throw InputError("cannot create output directory '" + output_dir + "': " + ec.message());
}

std::string
joinPath(const std::string& directory, const std::string& name)
{
  return (fs::path(directory) / name).string();
}

std::string
fileName(const std::string& path)
{
  return fs::path(path).filename().string();
}

Progress::Progress(std::size_t total, bool quiet)
    : total_(total), enabled_(!quiet && ::isatty(2)), start_(std::chrono::steady_clock::now())
{
}

void
Progress::update(std::size_t done)
{
  if (!enabled_ || total_ == 0)
    return;
  const double seconds = millisecondsSince(start_) / 1000.0;
  const double fps = seconds > 0 ? done / seconds : 0.0;
  const double left = fps > 0 ? (total_ - done) / fps : 0.0;
  const int width = 30;
  const int filled = static_cast<int>(width * done / total_);
  std::ostringstream line;
  line << "\r[" << std::string(filled, '#') << std::string(width - filled, '.') << "] " << done << "/"
       << total_ << "  " << std::fixed << std::setprecision(2) << fps << " frames/s  "
       << std::setprecision(0) << left << " s left ";
  std::cerr << line.str() << std::flush;
}

void
Progress::finish()
{
  if (enabled_)
    std::cerr << "\n";
}

double
millisecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void
addDepthImageOptions(po::options_description& options)
{
  const DepthIntrinsics d;
  // clang-format off
  options.add_options()
    ("fx", po::value<double>()->default_value(d.fx), "depth PNG input: focal length along x, pixels")
    ("fy", po::value<double>()->default_value(d.fy), "depth PNG input: focal length along y, pixels")
    ("cx", po::value<double>()->default_value(d.cx), "depth PNG input: principal point column, pixels")
    ("cy", po::value<double>()->default_value(d.cy), "depth PNG input: principal point row, pixels")
    ("depth-scale", po::value<double>()->default_value(d.depth_scale),
     "depth PNG values per metre: z = value / scale (TUM 5000, RealSense/Azure 1000)")
    ("intrinsics", po::value<std::string>(),
     "intrinsics.txt with fx, fy, cx, cy and the depth scale; options given explicitly override it [default: none]");
  // clang-format on
}

DepthIntrinsics
depthIntrinsicsFrom(const po::variables_map& vm)
{
  DepthIntrinsics intrinsics;
  if (vm.count("intrinsics")) {
    try {
      intrinsics = readIntrinsics(vm["intrinsics"].as<std::string>());
    } catch (const std::invalid_argument& e) {
      throw InputError(e.what());
    }
  }
  const std::pair<const char*, double*> fields[] = {{"fx", &intrinsics.fx},
                                                    {"fy", &intrinsics.fy},
                                                    {"cx", &intrinsics.cx},
                                                    {"cy", &intrinsics.cy},
                                                    {"depth-scale", &intrinsics.depth_scale}};
  for (const auto& field : fields) {
    if (!vm.count(field.first))
      continue;
    if (!vm[field.first].defaulted() || !vm.count("intrinsics"))
      *field.second = vm[field.first].as<double>();
  }
  try {
    intrinsics.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string(e.what()) + " (check --fx, --fy, --cx, --cy, --depth-scale and --intrinsics)");
  }
  return intrinsics;
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
loadFrame(const std::string& path, const DepthIntrinsics& intrinsics)
{
  if (!isDepthImagePath(path))
    return loadCloud(path);
  pcl::PointCloud<pcl::PointXYZ> cloud;
  try {
    cloud = loadDepthPng(path, intrinsics);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  if (cloud.height < 2)
    throw InputError("'" + path + "': depth image has a single row; range_nlm needs a grid");
  LoadedCloud loaded;
  pcl::toPCLPointCloud2(cloud, loaded.blob);
  return loaded;
}

std::vector<std::string>
listInputFrames(const std::string& directory)
{
  try {
    return listFrames(directory, ".pcd");
  } catch (const InputError&) {
    std::error_code ec;
    if (!fs::is_directory(directory, ec))
      throw;
  }
  try {
    return listFrames(directory, ".png");
  } catch (const InputError&) {
    throw InputError("input directory '" + directory + "' holds no .pcd frame and no .png depth image");
  }
}

std::string
replaceExtension(const std::string& path, const std::string& extension)
{
  return fs::path(path).replace_extension(extension).string();
}

} // namespace tools
} // namespace range_nlm
