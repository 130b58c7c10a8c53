// range_nlm_denoise: filters one organized PCD frame, or every frame of a directory (optionally
// with the temporal filter, in one or several passes), keeping every field of the input.
#include "cli/cli.h"

#include <range_nlm/eval/render.h>
#include <range_nlm/temporal_nonlocal_means_filter.h>
#include <range_nlm/temporal_stream.h>

#include <algorithm>
#include <deque>
#include <filesystem>
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

/// The frames a pass reads to filter the `needed` ones.
std::vector<bool>
framesRead(const Pass& pass, const std::vector<bool>& needed)
{
  std::vector<bool> read(needed.size(), false);
  const std::size_t r = static_cast<std::size_t>(pass.radius);
  for (std::size_t t = 0; t < needed.size(); ++t)
    if (needed[t])
      for (std::size_t k = t >= r ? t - r : 0; k <= (pass.causal ? t : std::min(t + r, needed.size() - 1)); ++k)
        read[k] = true;
  return read;
}

/// The chain of passes, each a TemporalStream, feeding the next.
class PassChain
{
public:
  /// `wanted[t]`: the result of frame t is to be written. From the last pass back, each pass
  /// filters only the frames that the next one reads.
  PassChain(const std::vector<Pass>& passes, const std::vector<bool>& wanted)
  {
    std::vector<std::vector<bool>> needed(passes.size());
    std::vector<bool> next = wanted;
    for (std::size_t level = passes.size(); level-- > 0;) {
      needed[level] = next;
      next = framesRead(passes[level], next);
    }
    inputs_read_ = next;
    for (std::size_t level = 0; level < passes.size(); ++level)
      levels_.push_back({std::make_unique<TemporalStream<pcl::PointXYZ>>(passes[level].radius, passes[level].causal,
                                                                          passes[level].parameters),
                         needed[level]});
  }
  /// False if no result depends on input frame t: it need not even be loaded.
  bool inputRead(std::size_t t) const { return inputs_read_[t]; }
  /// Pushes a frame through every pass; returns the finished frames (null: not wanted).
  std::vector<Cloud::ConstPtr> push(const Cloud::ConstPtr& frame) { return feed(0, {frame}, false); }
  std::vector<Cloud::ConstPtr> flush() { return feed(0, {}, true); }
  const Bandwidths& firstPassBandwidths() const { return levels_.front().stream->lastBandwidths(); }

private:
  /// One pass: its stream and which of its frames the next pass (or the output) reads.
  struct Level
  {
    std::unique_ptr<TemporalStream<pcl::PointXYZ>> stream;
    std::vector<bool> needed;
    std::size_t pushed = 0;
  };

  std::vector<Cloud::ConstPtr> feed(std::size_t level, const std::vector<Cloud::ConstPtr>& in, bool flush)
  {
    Level& l = levels_[level];
    std::vector<Cloud::ConstPtr> out;
    for (const auto& f : in)
      for (auto& r : l.stream->push(f, l.needed[l.pushed++]))
        out.push_back(r);
    if (flush)
      for (auto& r : l.stream->flush())
        out.push_back(r);
    if (level + 1 == levels_.size())
      return out;
    return feed(level + 1, out, flush);
  }
  std::vector<Level> levels_;
  std::vector<bool> inputs_read_;
};

/// For --resume: removes the temporary files an interrupted run left beside `outputs`
/// (".NAME.tmpPID", see saveCloudAtomic).
void
removeTemporaries(const std::vector<std::string>& outputs)
{
  namespace fs = std::filesystem;
  std::vector<std::string> prefixes;
  for (const std::string& output : outputs)
    prefixes.push_back("." + fileName(output) + ".tmp");
  std::error_code ec;
  const fs::path dir = fs::path(outputs.front()).parent_path();
  for (const auto& entry : fs::directory_iterator(dir.empty() ? fs::path(".") : dir, ec)) {
    const std::string name = entry.path().filename().string();
    for (const std::string& prefix : prefixes)
      if (name.compare(0, prefix.size(), prefix) == 0 &&
          name.find_first_not_of("0123456789", prefix.size()) == std::string::npos) {
        fs::remove(entry.path(), ec);
        break;
      }
  }
}

/// For --resume: `path` holds a complete output of a width x height frame.
bool
isFinishedOutput(const std::string& path, bool png, const DepthIntrinsics& intrinsics, unsigned width,
                 unsigned height)
{
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    return false;
  try {
    if (png) {
      const Cloud cloud = loadDepthPng(path, intrinsics);
      return cloud.width == width && cloud.height == height;
    }
    const LoadedCloud loaded = loadCloud(path);
    return loaded.blob.width == width && loaded.blob.height == height;
  } catch (const std::exception&) {
    return false;
  }
}

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
    ("resume", "skip frames whose output already exists and is a complete frame of the input's size "
               "(temporal runs still read them as neighbours); removes temporary files an interrupted run left")
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

  unsigned width = 0, height = 0;
  std::vector<bool> wanted(inputs.size(), true);
  if (vm.count("resume")) {
    std::error_code ec;
    if (single ? std::filesystem::equivalent(inputs.front(), outputs.front(), ec)
               : std::filesystem::equivalent(vm["input-dir"].as<std::string>(),
                                             vm["output-dir"].as<std::string>(), ec))
      throw UsageError("--resume cannot be used when the output is the input (every frame would count as finished)");
    removeTemporaries(outputs);
    const LoadedCloud first = loadFrame(inputs.front(), intrinsics);
    width = first.blob.width;
    height = first.blob.height;
    for (std::size_t f = 0; f < inputs.size(); ++f)
      wanted[f] = !isFinishedOutput(outputs[f], output_options.png, intrinsics, width, height);
  }

  PassChain chain(passes, wanted);
  std::deque<PendingFrame> pending;
  std::vector<FrameReport> reports;
  Progress progress(inputs.size(), quiet || json);
  const auto run_start = std::chrono::steady_clock::now();
  std::size_t skipped = 0;
  auto finish = [&](const std::vector<Cloud::ConstPtr>& results, double ms) {
    for (const Cloud::ConstPtr& result : results) {
      PendingFrame frame = std::move(pending.front());
      pending.pop_front();
      if (!result) { // --resume: finished before
        ++skipped;
        if (!quiet && !json)
          std::cout << fileName(frame.output_path) << ": skipped (complete output exists)" << std::endl;
        progress.update(reports.size() + skipped);
        continue;
      }
      writeResult(frame, *result, output_options);
      FrameReport report{fileName(frame.output_path), ms, chain.firstPassBandwidths()};
      printReport(report, quiet, json);
      reports.push_back(report);
      progress.update(reports.size() + skipped);
    }
  };
  for (std::size_t f = 0; f < inputs.size(); ++f) {
    if (!chain.inputRead(f)) { // finished, and no frame still to filter reads it
      pending.push_back(PendingFrame{LoadedCloud(), inputs[f], outputs[f]});
      finish(chain.push(nullptr), 0.0);
      continue;
    }
    PendingFrame frame{loadFrame(inputs[f], intrinsics), inputs[f], outputs[f]};
    if (width == 0) {
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
    std::vector<Cloud::ConstPtr> results;
    try {
      results = chain.push(xyz);
    } catch (const std::invalid_argument& e) {
      throw InputError("'" + inputs[f] + "': " + e.what());
    }
    finish(results, millisecondsSince(start));
  }
  const auto start = std::chrono::steady_clock::now();
  std::vector<Cloud::ConstPtr> results;
  try {
    results = chain.flush();
  } catch (const std::invalid_argument& e) {
    throw InputError("'" + (pending.empty() ? inputs.back() : pending.front().input_path) + "': " + e.what());
  }
  finish(results, millisecondsSince(start));
  progress.finish();

  if (json) {
    double total = 0.0;
    for (const auto& r : reports)
      total += r.milliseconds;
    std::cout << "{\"frames\": " << reports.size() << ", \"skipped\": " << skipped << ", \"width\": " << width
              << ", \"height\": " << height << ", \"filter_ms_total\": " << total
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
