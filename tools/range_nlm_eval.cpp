// range_nlm_eval: accuracy of filtered range frames against ground truth (range_nlm_synth output):
// point-to-plane RMSE and normal error in flat and feature regions, lost points, and for
// sequences the temporal standard deviation and the error at moving edges.
#include "cli/cli.h"

#include <range_nlm/eval/metrics.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

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
    "the noisy frames are scored too, as the baseline.";

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

/// Ground truth: x, y, z and normal_x, normal_y, normal_z (float or double) of a PCD file.
pcl::PointCloud<pcl::PointNormal>
loadTruth(const std::string& path)
{
  const LoadedCloud loaded = loadCloud(path);
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
loadXyz(const std::string& path, const pcl::PointCloud<pcl::PointNormal>& truth, const std::string& truth_path)
{
  const LoadedCloud loaded = loadCloud(path);
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

int
run(int argc, char** argv)
{
  po::options_description options("Options");
  // clang-format off
  options.add_options()
    ("help,h", "print this help")
    ("gt", po::value<std::string>(), "ground truth: PCD file or directory of *.pcd frames")
    ("result", po::value<std::string>(), "result to score: PCD file or directory (same frame names)")
    ("input", po::value<std::string>(), "noisy input the result was computed from (for lost points and the baseline)")
    ("json", "print one JSON object instead of the table");
  // clang-format on
  po::positional_options_description positional;
  positional.add("gt", 1).add("result", 1);
  po::variables_map vm;
  if (!parseCommandLine(argc, argv, options, positional, vm, kUsage))
    return 0;
  if (!vm.count("gt") || !vm.count("result"))
    throw UsageError("expected GT and RESULT");

  const std::string gt_path = vm["gt"].as<std::string>();
  const std::string result_path = vm["result"].as<std::string>();
  const std::string input_path = vm.count("input") ? vm["input"].as<std::string>() : std::string();
  const bool has_input = !input_path.empty();
  const bool json = vm.count("json") > 0;

  std::error_code ec;
  auto checkExists = [&](const std::string& path) {
    if (!fs::exists(path, ec))
      throw InputError("'" + path + "': no such file or directory");
  };
  checkExists(gt_path);
  checkExists(result_path);
  if (has_input)
    checkExists(input_path);
  const bool directory = fs::is_directory(gt_path, ec);
  auto checkKind = [&](const std::string& path) {
    if (fs::is_directory(path, ec) != directory)
      throw InputError("'" + path + "' is a " + (directory ? "file" : "directory") + " but the ground truth '" +
                       gt_path + "' is a " + (directory ? "directory" : "file"));
  };
  checkKind(result_path);
  if (has_input)
    checkKind(input_path);

  const std::vector<std::string> gt_frames = framesOf(gt_path, directory);
  const std::vector<std::string> result_frames = framesOf(result_path, directory);
  std::vector<std::string> input_frames;
  if (directory)
    checkSameFrames(gt_frames, result_frames, gt_path, result_path);
  if (has_input) {
    input_frames = framesOf(input_path, directory);
    if (directory)
      checkSameFrames(gt_frames, input_frames, gt_path, input_path);
  }

  SequenceEvaluator result_evaluator;
  std::unique_ptr<SequenceEvaluator> input_evaluator;
  if (has_input)
    input_evaluator = std::make_unique<SequenceEvaluator>();
  std::vector<std::string> names;
  unsigned width = 0, height = 0;
  for (std::size_t k = 0; k < gt_frames.size(); ++k) {
    const pcl::PointCloud<pcl::PointNormal> truth = loadTruth(gt_frames[k]);
    if (k == 0) {
      width = truth.width;
      height = truth.height;
    } else if (truth.width != width || truth.height != height) {
      throw InputError("'" + gt_frames[k] + "': frame is " + std::to_string(truth.width) + " x " +
                       std::to_string(truth.height) + " but the sequence is " + std::to_string(width) + " x " +
                       std::to_string(height));
    }
    const pcl::PointCloud<pcl::PointXYZ> result = loadXyz(result_frames[k], truth, gt_frames[k]);
    pcl::PointCloud<pcl::PointXYZ> input;
    if (has_input)
      input = loadXyz(input_frames[k], truth, gt_frames[k]);
    try {
      result_evaluator.add(truth, result, has_input ? &input : nullptr);
      if (has_input)
        input_evaluator->add(truth, input, nullptr);
    } catch (const std::invalid_argument& e) {
      throw InputError("'" + result_frames[k] + "': " + e.what());
    }
    names.push_back(fileName(gt_frames[k]));
  }
  const SequenceMetrics metrics = result_evaluator.metrics();
  std::unique_ptr<SequenceMetrics> input_metrics;
  if (has_input)
    input_metrics = std::make_unique<SequenceMetrics>(input_evaluator->metrics());

  if (json) {
    std::string text = toJson(metrics, names);
    text.pop_back(); // closing brace
    text += ", \"width\": " + std::to_string(width) + ", \"height\": " + std::to_string(height);
    if (input_metrics)
      text += ", \"input\": " + toJson(*input_metrics);
    std::cout << text << "}" << std::endl;
    return 0;
  }
  std::cout << metricsTableHeader() << "\n";
  const bool sequence = metrics.frames.size() > 1;
  for (std::size_t k = 0; k < metrics.frames.size(); ++k)
    std::cout << metricsTableRow(names[k], metrics.frames[k]) << "\n";
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
  return 0;
}

} // namespace

int
main(int argc, char** argv)
{
  return runTool("range_nlm_eval", [&] { return run(argc, argv); });
}
