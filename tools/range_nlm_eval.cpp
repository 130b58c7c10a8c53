// range_nlm_eval: accuracy of filtered range frames against ground truth (range_nlm_synth output):
// point-to-plane RMSE and normal error in flat and feature regions, lost points, and for
// sequences the temporal standard deviation and the error at moving edges.
#include "cli/cli.h"

#include <nlohmann/json.hpp>

#include <range_nlm/eval/metrics.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <vector>

namespace fs = std::filesystem;
namespace po = boost::program_options;
using namespace range_nlm;
using namespace range_nlm::tools;

namespace
{

const char* const kUsage =
    "Usage:\n"
    "  range_nlm_eval GT RESULT [--input NOISY] [--json]\n"
    "GT, RESULT and NOISY are all PCD files or all directories of *.pcd frames with the same\n"
    "names. GT holds exact points and normals (PointNormal, as written by range_nlm_synth).\n"
    "Prints point-to-plane RMSE (mm) and normal error (degrees, normals of the result from a\n"
    "5x5 least-squares fit) in flat regions and within 3 px of depth discontinuities and\n"
    "creases, points lost (valid in NOISY, NaN in RESULT), and for sequences the mean per-pixel\n"
    "temporal standard deviation of static pixels and the RMSE near moving edges. With --input\n"
    "the noisy frames are scored too, as the baseline.\n"
    "\n"
    "Real frames, without ground truth:\n"
    "  range_nlm_eval --raw RAW [RESULT ...] [--min-region N] [--border-band K] [--json]\n"
    "Finds large planar regions in the raw frame RAW and prints for RAW (the baseline) and each\n"
    "RESULT (a filtered copy of RAW) the RMS residual (mm) to each region's plane fitted on RAW, in\n"
    "the regions' interior and in a band of K px along their borders (bleeding), and the region\n"
    "points lost (valid in RAW, NaN in RESULT).\n"
    "  range_nlm_eval --jitter SEQ [SEQ ...] [--json]\n"
    "For each directory SEQ of frames of a static scene: mean and median over the pixels valid in\n"
    "every frame of the per-pixel standard deviation (mm) of the range over the frames.\n"
    "Frames are PCD files or 16-bit depth PNGs (see the depth PNG options).";

/// A JSON string literal (bytes that are not UTF-8 replaced).
std::string
jsonQuote(const std::string& text)
{
  return nlohmann::json(text).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

/// The frames named by a path: the file itself, or the sorted *.pcd files of a directory.
std::vector<std::string>
framesOf(const std::string& path, bool directory)
{
  if (directory)
    return listFrames(path);
  return {path};
}

const pcl::PCLPointField*
findField(const pcl::PCLPointCloud2& blob, const char* name)
{
  for (const auto& f : blob.fields)
    if (f.name == name)
      return &f;
  return nullptr;
}

/// Bytes scoring a width x height frame of `point_step`-byte points needs, for the largest of the
/// modes: ground truth, result and noisy input each loaded and as x, y, z (point_step + 16 bytes a
/// pixel each), the truth with normals (48) and the evaluator's normals, masks and sums (120).
/// Peak resident memory (/usr/bin/time -v) grows from 1280 x 960 to 2560 x 1920 frames by 213
/// bytes a pixel for a result scored with its noisy input (truth of 24-byte points, frames of 12;
/// estimated 252 to 288), 49 for --raw.
std::uint64_t
evalMemory(std::uint64_t width, std::uint64_t height, std::uint64_t point_step)
{
  const std::uint64_t per_pixel = 3 * (point_step + 16) + 48 + 120;
  const std::uint64_t pixels = width * height;
  return pixels > UINT64_MAX / per_pixel ? UINT64_MAX : pixels * per_pixel;
}

/// loadFrame, with running out of memory named by the file.
LoadedCloud
loadChecked(const std::string& path, const DepthIntrinsics* intrinsics, const io::MemoryBudget& budget)
{
  try {
    return intrinsics ? loadFrame(path, *intrinsics, budget) : loadCloud(path, true, budget);
  } catch (const std::bad_alloc&) {
    throw InputError("'" + path + "': out of memory while reading the frame (lower --memory-limit to refuse such "
                     "frames up front, or free memory)");
  }
}

/// Ground truth: x, y, z and normal_x, normal_y, normal_z (float or double) of a PCD file.
pcl::PointCloud<pcl::PointNormal>
loadTruth(const std::string& path, const io::MemoryBudget& budget)
{
  const LoadedCloud loaded = loadChecked(path, nullptr, budget);
  const pcl::PointCloud<pcl::PointXYZ> xyz = xyzFromBlob(loaded, path);
  const pcl::PCLPointField* fields[3];
  const char* names[3] = {"normal_x", "normal_y", "normal_z"};
  for (int a = 0; a < 3; ++a) {
    fields[a] = findField(loaded.blob, names[a]);
    if (!fields[a] || fields[a]->count != 1 ||
        (fields[a]->datatype != pcl::PCLPointField::FLOAT32 && fields[a]->datatype != pcl::PCLPointField::FLOAT64))
      throw InputError("'" + path + "': ground truth needs float fields normal_x, normal_y, normal_z (field '" +
                       names[a] + "' is missing or not a single float)");
  }
  pcl::PointCloud<pcl::PointNormal> truth(xyz.width, xyz.height);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    pcl::PointNormal& q = truth[i];
    q.x = xyz[i].x, q.y = xyz[i].y, q.z = xyz[i].z;
    const std::uint8_t* p = &loaded.blob.data[i * loaded.blob.point_step];
    float* normal[3] = {&q.normal_x, &q.normal_y, &q.normal_z};
    for (int a = 0; a < 3; ++a) {
      if (fields[a]->datatype == pcl::PCLPointField::FLOAT64) {
        double v;
        std::memcpy(&v, p + fields[a]->offset, sizeof v);
        *normal[a] = float(v);
      } else {
        std::memcpy(normal[a], p + fields[a]->offset, sizeof(float));
      }
    }
    q.curvature = 0.0f;
  }
  truth.is_dense = false;
  return truth;
}

pcl::PointCloud<pcl::PointXYZ>
loadXyz(const std::string& path, const pcl::PointCloud<pcl::PointNormal>& truth, const std::string& truth_path,
        const io::MemoryBudget& budget)
{
  const LoadedCloud loaded = loadChecked(path, nullptr, budget);
  if (loaded.blob.width != truth.width || loaded.blob.height != truth.height)
    throw InputError("'" + path + "': cloud is " + std::to_string(loaded.blob.width) + " x " +
                     std::to_string(loaded.blob.height) + " but the ground truth '" + truth_path + "' is " +
                     std::to_string(truth.width) + " x " + std::to_string(truth.height));
  return xyzFromBlob(loaded, path);
}

void
checkSameFrames(const std::vector<std::string>& truth, const std::vector<std::string>& other,
                const std::string& truth_path, const std::string& other_path)
{
  if (other.size() != truth.size())
    throw InputError("'" + other_path + "' holds " + std::to_string(other.size()) + " frames but the ground truth '" +
                     truth_path + "' holds " + std::to_string(truth.size()));
  for (std::size_t k = 0; k < truth.size(); ++k)
    if (fileName(other[k]) != fileName(truth[k]))
      throw InputError("'" + other[k] + "' does not match the ground-truth frame '" + truth[k] +
                       "' (frames are paired by sorted file name)");
}

std::string
secondaryLine(const char* what, double value, std::size_t pixels, const char* pixel_kind,
              const SequenceMetrics* input, double input_value)
{
  std::ostringstream s;
  s << what << ": ";
  if (std::isfinite(value))
    s << std::fixed << std::setprecision(3) << value * 1000.0 << " mm";
  else
    s << "-";
  s << " over " << pixels << " " << pixel_kind;
  if (input) {
    s << " (input: ";
    if (std::isfinite(input_value))
      s << std::fixed << std::setprecision(3) << input_value * 1000.0 << " mm)";
    else
      s << "-)";
  }
  return s.str();
}

/// One real frame (PCD or depth PNG) as x, y, z.
pcl::PointCloud<pcl::PointXYZ>
loadRealFrame(const std::string& path, const DepthIntrinsics& intrinsics, const io::MemoryBudget& budget,
              DefaultIntrinsicsWarning& warning)
{
  const LoadedCloud loaded = loadChecked(path, &intrinsics, budget);
  warning.frameRead(path);
  return xyzFromBlob(loaded, path);
}

std::string
millimetres(double metres)
{
  std::ostringstream s;
  if (std::isfinite(metres))
    s << std::fixed << std::setprecision(3) << metres * 1000.0;
  else
    s << "-";
  return s.str();
}

/// --raw: residuals to the planes of the raw frame, for the raw frame and each result.
int
runPlanar(const po::variables_map& vm, const std::vector<std::string>& results, bool json)
{
  PlanarRegionOptions options;
  options.min_region_pixels = vm["min-region"].as<int>();
  options.border_band = vm["border-band"].as<int>();
  options.block_size = vm["block-size"].as<int>();
  options.plane_distance = vm["plane-distance"].as<double>();
  try {
    options.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  const DepthIntrinsics intrinsics = depthIntrinsicsFrom(vm);
  DefaultIntrinsicsWarning warning("range_nlm_eval", vm);
  const io::MemoryBudget budget = memoryBudgetFrom(vm, evalMemory);
  const std::string raw_path = vm["raw"].as<std::string>();
  const pcl::PointCloud<pcl::PointXYZ> raw = loadRealFrame(raw_path, intrinsics, budget, warning);
  PlanarRegions regions;
  try {
    regions = findPlanarRegions(raw, options);
  } catch (const std::invalid_argument& e) {
    throw InputError("'" + raw_path + "': " + e.what());
  }
  std::vector<std::string> names{raw_path};
  std::vector<PlanarResidual> residuals{planarResidual(regions, raw)};
  for (const std::string& path : results) {
    const pcl::PointCloud<pcl::PointXYZ> frame = loadRealFrame(path, intrinsics, budget, warning);
    try {
      residuals.push_back(planarResidual(regions, frame));
    } catch (const std::invalid_argument& e) {
      throw InputError("'" + path + "': " + e.what());
    }
    names.push_back(path);
  }
  if (json) {
    std::ostringstream s;
    s << "{\"raw\": " << jsonQuote(raw_path) << ", \"width\": " << raw.width << ", \"height\": " << raw.height
      << ", \"border_band\": " << options.border_band << ", \"min_region_pixels\": " << options.min_region_pixels
      << ", \"frames\": [";
    for (std::size_t k = 0; k < residuals.size(); ++k)
      s << (k ? ", " : "") << "{\"name\": " << jsonQuote(names[k]) << ", " << toJson(residuals[k]).substr(1);
    std::cout << s.str() << "]}" << std::endl;
    return 0;
  }
  std::cout << regions.planes.size() << " planar region" << (regions.planes.size() == 1 ? "" : "s") << " in '"
            << printable(raw_path) << "' (at least " << options.min_region_pixels << " px; border band "
            << options.border_band << " px)\n";
  std::cout << std::left << std::setw(40) << "frame" << std::right << std::setw(13) << "interior mm" << std::setw(11)
            << "border mm" << std::setw(13) << "interior px" << std::setw(11) << "border px" << std::setw(8) << "lost"
            << "\n";
  for (std::size_t k = 0; k < residuals.size(); ++k) {
    const PlanarResidual& r = residuals[k];
    std::cout << std::left << std::setw(40) << printable(k == 0 ? "raw: " + fileName(names[k]) : fileName(names[k]))
              << std::right << std::setw(13) << millimetres(r.interior_rms) << std::setw(11)
              << millimetres(r.border_rms) << std::setw(13) << r.interior_pixels << std::setw(11) << r.border_pixels
              << std::setw(8) << r.points_lost << "\n";
  }
  std::cout << std::flush;
  return 0;
}

/// --jitter: per-pixel range standard deviation over the frames of each static sequence.
int
runJitter(const po::variables_map& vm, const std::vector<std::string>& sequences, bool json)
{
  if (sequences.empty())
    throw UsageError("--jitter expects at least one directory of frames");
  const DepthIntrinsics intrinsics = depthIntrinsicsFrom(vm);
  DefaultIntrinsicsWarning warning("range_nlm_eval", vm);
  const io::MemoryBudget budget = memoryBudgetFrom(vm, evalMemory);
  std::vector<TemporalJitter> jitters;
  for (const std::string& directory : sequences) {
    JitterEvaluator evaluator;
    for (const std::string& path : listInputFrames(directory)) {
      const pcl::PointCloud<pcl::PointXYZ> frame = loadRealFrame(path, intrinsics, budget, warning);
      try {
        evaluator.add(frame);
      } catch (const std::invalid_argument& e) {
        throw InputError("'" + path + "': " + e.what());
      }
    }
    jitters.push_back(evaluator.jitter());
  }
  if (json) {
    std::ostringstream s;
    s << "{\"sequences\": [";
    for (std::size_t k = 0; k < jitters.size(); ++k)
      s << (k ? ", " : "") << "{\"name\": " << jsonQuote(sequences[k]) << ", " << toJson(jitters[k]).substr(1);
    std::cout << s.str() << "]}" << std::endl;
    return 0;
  }
  std::cout << std::left << std::setw(40) << "sequence" << std::right << std::setw(8) << "frames" << std::setw(10)
            << "pixels" << std::setw(10) << "mean mm" << std::setw(12) << "median mm" << "\n";
  for (std::size_t k = 0; k < jitters.size(); ++k)
    std::cout << std::left << std::setw(40) << printable(sequences[k]) << std::right << std::setw(8) << jitters[k].frames
              << std::setw(10) << jitters[k].pixels << std::setw(10) << millimetres(jitters[k].mean) << std::setw(12)
              << millimetres(jitters[k].median) << "\n";
  std::cout << std::flush;
  return 0;
}

/// The options of every mode; `planar` gives the defaults of --raw.
void
addOptions(po::options_description& options, const PlanarRegionOptions& planar)
{
  // clang-format off
  options.add_options()
    ("help,h", "print this help")
    ("gt", po::value<std::string>(), "ground truth: PCD file or directory of *.pcd frames")
    ("result", po::value<std::string>(), "result to score: PCD file or directory (same frame names)")
    ("input", po::value<std::string>(), "noisy input the result was computed from (for lost points and the baseline)")
    ("json", "print one JSON object instead of the table")
    ("raw", po::value<std::string>(), "real frame without ground truth: find planar regions in it and score the "
     "frames given as arguments (filtered copies of it) against their planes")
    ("min-region", po::value<int>()->default_value(planar.min_region_pixels), "--raw: smallest planar region, pixels")
    ("border-band", po::value<int>()->default_value(planar.border_band),
     "--raw: width of the band along a region's border reported apart, pixels")
    ("block-size", po::value<int>()->default_value(planar.block_size), "--raw: side of the plane-fit seed blocks, pixels")
    ("plane-distance", po::value<double>()->default_value(planar.plane_distance),
     "--raw: largest distance of a point from its region's plane at 1 m depth, m (scaled by z^2)")
    ("jitter", "static sequences without ground truth: per-pixel range standard deviation over the frames of each "
     "directory given as an argument");
  // clang-format on
  addDepthImageOptions(options);
  addMemoryLimitOption(options);
}

/// The frames of a ground-truth run: GT, RESULT and (optionally) NOISY, frame k of each the same.
struct GroundTruthJob
{
  std::vector<std::string> gt_frames, result_frames, input_frames;
  bool has_input = false;
  bool json = false;
  io::MemoryBudget budget;
};

/// GT and RESULT as the two positional arguments or as options, --input; all files or all
/// directories with the same frame names.
GroundTruthJob
groundTruthJobFrom(const po::variables_map& vm, const std::vector<std::string>& paths)
{
  std::size_t next = 0;
  std::string gt_path, result_path;
  if (vm.count("gt"))
    gt_path = vm["gt"].as<std::string>();
  else if (next < paths.size())
    gt_path = paths[next++];
  if (vm.count("result"))
    result_path = vm["result"].as<std::string>();
  else if (next < paths.size())
    result_path = paths[next++];
  if (next < paths.size())
    throw UsageError("unexpected argument '" + paths[next] + "' (expected GT and RESULT)");
  if (gt_path.empty() || result_path.empty())
    throw UsageError("expected GT and RESULT");
  const std::string input_path = vm.count("input") ? vm["input"].as<std::string>() : std::string();
  GroundTruthJob job;
  job.has_input = !input_path.empty();
  job.json = vm.count("json") > 0;
  job.budget = memoryBudgetFrom(vm, evalMemory);

  std::error_code ec;
  auto checkExists = [&](const std::string& path) {
    if (!fs::exists(path, ec))
      throw InputError("'" + path + "': no such file or directory");
  };
  checkExists(gt_path);
  checkExists(result_path);
  if (job.has_input)
    checkExists(input_path);
  const bool directory = fs::is_directory(gt_path, ec);
  auto checkKind = [&](const std::string& path) {
    if (fs::is_directory(path, ec) != directory)
      throw InputError("'" + path + "' is a " + (directory ? "file" : "directory") + " but the ground truth '" +
                       gt_path + "' is a " + (directory ? "directory" : "file"));
  };
  checkKind(result_path);
  if (job.has_input)
    checkKind(input_path);

  job.gt_frames = framesOf(gt_path, directory);
  job.result_frames = framesOf(result_path, directory);
  if (directory)
    checkSameFrames(job.gt_frames, job.result_frames, gt_path, result_path);
  if (job.has_input) {
    job.input_frames = framesOf(input_path, directory);
    if (directory)
      checkSameFrames(job.gt_frames, job.input_frames, gt_path, input_path);
  }
  return job;
}

/// The scores of a ground-truth run: of the result, and of the noisy input if given.
struct GroundTruthScores
{
  SequenceMetrics metrics;
  std::unique_ptr<SequenceMetrics> input_metrics;
  std::vector<std::string> names;
  unsigned width = 0, height = 0;
};

GroundTruthScores
score(const GroundTruthJob& job)
{
  SequenceEvaluator result_evaluator;
  std::unique_ptr<SequenceEvaluator> input_evaluator;
  if (job.has_input)
    input_evaluator = std::make_unique<SequenceEvaluator>();
  GroundTruthScores scores;
  unsigned& width = scores.width;
  unsigned& height = scores.height;
  for (std::size_t k = 0; k < job.gt_frames.size(); ++k) {
    const pcl::PointCloud<pcl::PointNormal> truth = loadTruth(job.gt_frames[k], job.budget);
    if (k == 0) {
      width = truth.width;
      height = truth.height;
    } else if (truth.width != width || truth.height != height) {
      throw InputError("'" + job.gt_frames[k] + "': frame is " + std::to_string(truth.width) + " x " +
                       std::to_string(truth.height) + " but the sequence is " + std::to_string(width) + " x " +
                       std::to_string(height));
    }
    const pcl::PointCloud<pcl::PointXYZ> result = loadXyz(job.result_frames[k], truth, job.gt_frames[k], job.budget);
    pcl::PointCloud<pcl::PointXYZ> input;
    if (job.has_input)
      input = loadXyz(job.input_frames[k], truth, job.gt_frames[k], job.budget);
    try {
      result_evaluator.add(truth, result, job.has_input ? &input : nullptr);
      if (job.has_input)
        input_evaluator->add(truth, input, nullptr);
    } catch (const std::invalid_argument& e) {
      throw InputError("'" + job.result_frames[k] + "': " + e.what());
    }
    scores.names.push_back(fileName(job.gt_frames[k]));
  }
  scores.metrics = result_evaluator.metrics();
  if (job.has_input)
    scores.input_metrics = std::make_unique<SequenceMetrics>(input_evaluator->metrics());
  return scores;
}

void
printScoresJson(const GroundTruthScores& scores)
{
  std::string text = toJson(scores.metrics, scores.names);
  text.pop_back(); // closing brace
  text += ", \"width\": " + std::to_string(scores.width) + ", \"height\": " + std::to_string(scores.height);
  if (scores.input_metrics)
    text += ", \"input\": " + toJson(*scores.input_metrics);
  std::cout << text << "}" << std::endl;
}

/// The table: a row per frame, the sequence's total, the input's, then the temporal figures.
void
printScoresTable(const GroundTruthScores& scores)
{
  const SequenceMetrics& metrics = scores.metrics;
  const std::unique_ptr<SequenceMetrics>& input_metrics = scores.input_metrics;
  std::cout << metricsTableHeader() << "\n";
  const bool sequence = metrics.frames.size() > 1;
  for (std::size_t k = 0; k < metrics.frames.size(); ++k)
    std::cout << metricsTableRow(printable(scores.names[k]), metrics.frames[k]) << "\n";
  if (sequence)
    std::cout << metricsTableRow("all " + std::to_string(metrics.frames.size()) + " frames", metrics.total) << "\n";
  if (input_metrics)
    std::cout << metricsTableRow(sequence ? "input, all frames" : "input", input_metrics->total) << "\n";
  if (sequence) {
    std::cout << secondaryLine("temporal std", metrics.temporal_std, metrics.temporal_pixels, "static pixels",
                               input_metrics.get(), input_metrics ? input_metrics->temporal_std : 0.0)
              << "\n";
    std::cout << secondaryLine("moving-edge RMSE", metrics.moving_edge_rmse, metrics.moving_edge_pixels,
                               "pixel-frames", input_metrics.get(),
                               input_metrics ? input_metrics->moving_edge_rmse : 0.0)
              << "\n";
  }
  std::cout << std::flush;
}

int
run(int argc, char** argv)
{
  const PlanarRegionOptions planar;
  po::options_description options("Options");
  addOptions(options, planar);
  po::options_description hidden;
  hidden.add_options()("paths", po::value<std::vector<std::string>>(), "positional arguments");
  po::options_description all;
  all.add(options).add(hidden);
  po::positional_options_description positional;
  positional.add("paths", -1);
  po::variables_map vm;
  po::store(po::command_line_parser(argc, argv).options(all).positional(positional).run(), vm);
  if (vm.count("help")) {
    std::cout << kUsage << "\n\n" << options << "\n";
    return 0;
  }
  po::notify(vm);
  std::vector<std::string> paths;
  if (vm.count("paths"))
    paths = vm["paths"].as<std::vector<std::string>>();
  if (vm.count("raw") && vm.count("jitter"))
    throw UsageError("--raw and --jitter are separate modes; give one of them");
  if (vm.count("raw") || vm.count("jitter")) {
    if (vm.count("gt") || vm.count("result") || vm.count("input"))
      throw UsageError("--gt, --result and --input belong to the ground-truth mode, not to --raw or --jitter");
    return vm.count("raw") ? runPlanar(vm, paths, vm.count("json") > 0) : runJitter(vm, paths, vm.count("json") > 0);
  }
  const GroundTruthJob job = groundTruthJobFrom(vm, paths);
  const GroundTruthScores scores = score(job);
  if (job.json)
    printScoresJson(scores);
  else
    printScoresTable(scores);
  return 0;
}

} // namespace

int
main(int argc, char** argv)
{
  return runTool("range_nlm_eval", [&] { return run(argc, argv); });
}
