// range_nlm_denoise: filters one organized PCD frame, or every frame of a directory (optionally
// with the temporal filter, in one or several passes), keeping every field of the input.
#include "tool_common.h"

#include <range_nlm/render.h>
#include <range_nlm/temporal_stream.h>

#include <deque>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

namespace po = boost::program_options;
using namespace range_nlm;
using namespace range_nlm::tools;

namespace
{

const char* const kUsage =
    "Usage:\n"
    "  range_nlm_denoise INPUT.pcd OUTPUT.pcd [options]\n"
    "  range_nlm_denoise --input-dir DIR --output-dir DIR [--temporal-radius R [--causal]] [options]\n"
    "  range_nlm_denoise --input-dir DIR --output-dir DIR --pass search=19,patch=11,radius=1 --pass "
    "search=11,patch=5,radius=0\n"
    "Filters organized range frames with the feature-preserving non-local filter. Every field of\n"
    "the input is kept; only x, y, z move. Outputs are binary PCD.\n"
    "16-bit depth PNGs (INPUT.png, or a directory of *.png) are read with the intrinsics options;\n"
    "--output-format png writes 16-bit depth PNGs with the same depth scale, --colorize curvature\n"
    "writes PointXYZRGB clouds coloured by mean curvature.";

/// One filter pass of a schedule: parameters and temporal radius.
struct Pass
{
  FilterParameters parameters;
  int radius = 0;
  bool causal = false;
};

Pass
parsePass(const std::string& spec, const Pass& base)
{
  Pass pass = base;
  std::stringstream ss(spec);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos)
      throw UsageError("--pass '" + spec + "': expected key=value items, got '" + item + "'");
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    int v = 0;
    try {
      std::size_t used = 0;
      v = std::stoi(value, &used);
      if (used != value.size())
        throw std::invalid_argument(value);
    } catch (const std::exception&) {
      throw UsageError("--pass '" + spec + "': '" + key + "' needs an integer, got '" + value + "'");
    }
    if (key == "search")
      pass.parameters.search_window = v;
    else if (key == "patch")
      pass.parameters.patch_size = v;
    else if (key == "radius")
      pass.radius = v;
    else if (key == "iterations")
      pass.parameters.iterations = v;
    else if (key == "normal")
      pass.parameters.normal_window = v;
    else
      throw UsageError("--pass '" + spec + "': unknown key '" + key +
                       "' (expected search, patch, radius, iterations, normal)");
  }
  try {
    pass.parameters.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError("--pass '" + spec + "': " + e.what());
  }
  if (pass.radius < 0)
    throw UsageError("--pass '" + spec + "': radius must be >= 0");
  return pass;
}

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

/// A frame in flight: the loaded file (all fields) and where its result goes.
struct PendingFrame
{
  LoadedCloud loaded;
  std::string input_path;
  std::string output_path;
};

struct FrameReport
{
  std::string name;
  double milliseconds = 0.0;
  Bandwidths bandwidths;
};

/// The chain of passes, each a TemporalStream, feeding the next.
class PassChain
{
public:
  explicit PassChain(const std::vector<Pass>& passes)
  {
    for (const Pass& p : passes)
      streams_.push_back(std::make_unique<TemporalStream<pcl::PointXYZ>>(p.radius, p.causal, p.parameters));
  }
  /// Pushes a frame through every pass; returns the finished frames.
  std::vector<Cloud::Ptr> push(const Cloud::ConstPtr& frame) { return feed(0, {frame}, false); }
  std::vector<Cloud::Ptr> flush() { return feed(0, {}, true); }
  const Bandwidths& firstPassBandwidths() const { return streams_.front()->lastBandwidths(); }

private:
  std::vector<Cloud::Ptr> feed(std::size_t level, const std::vector<Cloud::ConstPtr>& in, bool flush)
  {
    std::vector<Cloud::Ptr> out;
    for (const auto& f : in)
      for (auto& r : streams_[level]->push(f))
        out.push_back(r);
    if (flush)
      for (auto& r : streams_[level]->flush())
        out.push_back(r);
    if (level + 1 == streams_.size())
      return out;
    std::vector<Cloud::ConstPtr> next(out.begin(), out.end());
    return feed(level + 1, next, flush);
  }
  std::vector<std::unique_ptr<TemporalStream<pcl::PointXYZ>>> streams_;
};

/// How results are written: the input's fields (PCD), curvature colour (PCD) or 16-bit depth (PNG).
struct OutputOptions
{
  bool png = false;
  bool colorize = false;
  RenderParameters colour;
  double depth_scale = DepthIntrinsics().depth_scale;
};

OutputOptions
outputOptionsFrom(const po::variables_map& vm, bool single, const std::string& first_input,
                  const std::string& single_output, const DepthIntrinsics& intrinsics)
{
  OutputOptions out;
  const std::string format = vm["output-format"].as<std::string>();
  if (format == "png" || format == "pcd")
    out.png = format == "png";
  else if (format == "auto")
    out.png = isDepthImagePath(single ? single_output : first_input);
  else
    throw UsageError("--output-format must be 'pcd', 'png' or 'auto', got '" + format + "'");
  if (single && out.png != isDepthImagePath(single_output))
    throw UsageError("output '" + single_output + "' does not match --output-format " + format +
                     " (a PNG output must end in .png, a PCD output must not)");
  if (vm.count("colorize")) {
    const std::string what = vm["colorize"].as<std::string>();
    if (what != "curvature")
      throw UsageError("--colorize supports only 'curvature', got '" + what + "'");
    if (out.png)
      throw UsageError("--colorize writes PCD clouds; it cannot be combined with PNG output");
    out.colorize = true;
    out.colour.curvature_limit = vm["curvature-limit"].as<float>();
    try {
      out.colour.validate();
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--curvature-limit: ") + e.what());
    }
  }
  out.depth_scale = intrinsics.depth_scale;
  return out;
}

void
writeResult(PendingFrame& frame, const Cloud& result, const OutputOptions& out)
{
  if (out.png) {
    saveDepthPng(frame.output_path, result, out.depth_scale);
    return;
  }
  if (out.colorize) {
    RenderParameters colour = out.colour;
    colour.viewpoint = {frame.loaded.origin[0], frame.loaded.origin[1], frame.loaded.origin[2]};
    pcl::PointCloud<pcl::PointXYZRGB> coloured = colorizeByCurvature(result, colour);
    coloured.sensor_origin_ = frame.loaded.origin;
    coloured.sensor_orientation_ = frame.loaded.orientation;
    saveCloudAtomic(frame.output_path, coloured);
    return;
  }
  writeXyzToBlob(result, frame.loaded.blob);
  saveCloudAtomic(frame.output_path, frame.loaded.blob, frame.loaded.origin, frame.loaded.orientation);
}

void
printReport(const FrameReport& r, bool quiet, bool json)
{
  if (quiet || json)
    return;
  std::cout << r.name << ": " << std::fixed << std::setprecision(1) << r.milliseconds << " ms, d = "
            << std::setprecision(6) << r.bandwidths.distance << ", s = " << r.bandwidths.similarity
            << std::endl;
}

int
run(int argc, char** argv)
{
  po::options_description options("Options");
  // clang-format off
  options.add_options()
    ("help,h", "print this help")
    ("input", po::value<std::string>(), "input PCD file or 16-bit depth PNG (single-frame mode)")
    ("output", po::value<std::string>(), "output PCD file, or .png with PNG output (single-frame mode)")
    ("input-dir", po::value<std::string>(), "directory of *.pcd frames (if it has none: *.png depth images), filtered in name order")
    ("output-dir", po::value<std::string>(), "directory for the filtered frames (same file names)")
    ("temporal-radius", po::value<int>()->default_value(0), "R: frames on each side used by the temporal filter (0 = static)")
    ("causal", "temporal window uses only past frames (no output delay)")
    ("pass", po::value<std::vector<std::string>>(), "a pass of a schedule, repeatable: search=S,patch=P,radius=R[,iterations=N][,normal=W]")
    ("overwrite", "allow the output directory to be the input directory")
    ("quiet,q", "print nothing but errors")
    ("json", "print a JSON summary instead of per-frame lines")
    ("colorize", po::value<std::string>(),
     "'curvature': write PointXYZRGB coloured by mean curvature instead of the input's fields [default: keep the fields]")
    ("curvature-limit", po::value<float>()->default_value(0.0f),
     "half-range of the --colorize colour scale, 1 / cloud unit (0 = 95th percentile of |H| of each frame)")
    ("output-format", po::value<std::string>()->default_value("auto"),
     "pcd or png (16-bit depth = round(z * --depth-scale); x, y are not stored, so use --line-of-sight); "
     "auto = png for an OUTPUT.png, else the format of the input");
  // clang-format on
  addFilterOptions(options);
  addDepthImageOptions(options);
  po::positional_options_description positional;
  positional.add("input", 1).add("output", 1);
  po::variables_map vm;
  if (!parseCommandLine(argc, argv, options, positional, vm, kUsage))
    return 0;

  const bool quiet = vm.count("quiet") > 0;
  const bool json = vm.count("json") > 0;
  Pass base;
  base.parameters = filterParametersFrom(vm);
  base.radius = vm["temporal-radius"].as<int>();
  base.causal = vm.count("causal") > 0;
  if (base.radius < 0)
    throw UsageError("--temporal-radius must be >= 0, got " + std::to_string(base.radius));
  std::vector<Pass> passes;
  if (vm.count("pass"))
    for (const std::string& spec : vm["pass"].as<std::vector<std::string>>())
      passes.push_back(parsePass(spec, base));
  else
    passes.push_back(base);

  const bool single = vm.count("input") || vm.count("output");
  const bool directory = vm.count("input-dir") || vm.count("output-dir");
  if (single == directory)
    throw UsageError("give either INPUT.pcd OUTPUT.pcd or --input-dir DIR --output-dir DIR");
  std::vector<std::string> inputs;
  std::vector<std::string> outputs;
  if (single) {
    if (!vm.count("input") || !vm.count("output"))
      throw UsageError("single-frame mode needs INPUT.pcd and OUTPUT.pcd");
    inputs.push_back(vm["input"].as<std::string>());
    outputs.push_back(vm["output"].as<std::string>());
  } else {
    if (!vm.count("input-dir") || !vm.count("output-dir"))
      throw UsageError("directory mode needs both --input-dir and --output-dir");
    const std::string in_dir = vm["input-dir"].as<std::string>();
    const std::string out_dir = vm["output-dir"].as<std::string>();
    inputs = listInputFrames(in_dir);
    prepareOutputDirectory(in_dir, out_dir, vm.count("overwrite") > 0);
    for (const std::string& in : inputs)
      outputs.push_back(joinPath(out_dir, fileName(in)));
  }
  const DepthIntrinsics intrinsics = depthIntrinsicsFrom(vm);
  const OutputOptions output_options =
      outputOptionsFrom(vm, single, inputs.front(), single ? outputs.front() : std::string(), intrinsics);
  if (!single)
    for (std::string& output : outputs)
      output = replaceExtension(output, output_options.png ? ".png" : ".pcd");

  PassChain chain(passes);
  std::deque<PendingFrame> pending;
  std::vector<FrameReport> reports;
  Progress progress(inputs.size(), quiet || json);
  const auto run_start = std::chrono::steady_clock::now();
  unsigned width = 0, height = 0;
  auto finish = [&](const std::vector<Cloud::Ptr>& results, double ms) {
    for (const Cloud::Ptr& result : results) {
      PendingFrame frame = std::move(pending.front());
      pending.pop_front();
      writeResult(frame, *result, output_options);
      FrameReport report{fileName(frame.output_path), ms, chain.firstPassBandwidths()};
      printReport(report, quiet, json);
      reports.push_back(report);
      progress.update(reports.size());
    }
  };
  for (std::size_t f = 0; f < inputs.size(); ++f) {
    PendingFrame frame{loadFrame(inputs[f], intrinsics), inputs[f], outputs[f]};
    if (f == 0) {
      width = frame.loaded.blob.width;
      height = frame.loaded.blob.height;
    } else if (frame.loaded.blob.width != width || frame.loaded.blob.height != height) {
      throw InputError("'" + inputs[f] + "': frame is " + std::to_string(frame.loaded.blob.width) + " x " +
                       std::to_string(frame.loaded.blob.height) + " but the sequence is " +
                       std::to_string(width) + " x " + std::to_string(height));
    }
    Cloud::Ptr xyz(new Cloud(xyzFromBlob(frame.loaded, inputs[f])));
    pending.push_back(std::move(frame));
    const auto start = std::chrono::steady_clock::now();
    std::vector<Cloud::Ptr> results;
    try {
      results = chain.push(xyz);
    } catch (const std::invalid_argument& e) {
      throw InputError("'" + inputs[f] + "': " + e.what());
    }
    finish(results, millisecondsSince(start));
  }
  const auto start = std::chrono::steady_clock::now();
  finish(chain.flush(), millisecondsSince(start));
  progress.finish();

  if (json) {
    double total = 0.0;
    for (const auto& r : reports)
      total += r.milliseconds;
    std::cout << "{\"frames\": " << reports.size() << ", \"width\": " << width << ", \"height\": " << height
              << ", \"filter_ms_total\": " << total
              << ", \"wall_ms\": " << millisecondsSince(run_start) << ", \"outputs\": [";
    for (std::size_t i = 0; i < reports.size(); ++i)
      std::cout << (i ? ", " : "") << "{\"file\": \"" << reports[i].name << "\", \"ms\": " << reports[i].milliseconds
                << ", \"distance_bandwidth\": " << reports[i].bandwidths.distance
                << ", \"similarity_bandwidth\": " << reports[i].bandwidths.similarity << "}";
    std::cout << "]}" << std::endl;
  }
  return 0;
}

} // namespace

int
main(int argc, char** argv)
{
  return runTool("range_nlm_denoise", [&] { return run(argc, argv); });
}
