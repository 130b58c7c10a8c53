// range_nlm_synth: renders synthetic organized range frames with exact ground truth, for measuring
// filters with range_nlm_eval.
#include "cli/cli.h"

#include <range_nlm/eval/synthetic_scene.h>

#include <algorithm>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace po = boost::program_options;
using namespace range_nlm;
using namespace range_nlm::tools;

namespace
{

const char* const kUsage =
    "Usage:\n"
    "  range_nlm_synth --output-dir DIR [--frames N] [--noise MODEL] [options]\n"
    "MODEL: kinect, laser, stripes, none, or a sensor model: stereo, kinect1, tof\n"
    "Ray-casts an analytic scene seen by a pinhole camera at the origin (looking down +z, y down)\n"
    "and writes DIR/noisy/frame_0000.pcd ... (PointXYZ, NaN where invalid) and\n"
    "DIR/truth/frame_0000.pcd ... (PointNormal: exact points and normals). Lengths in metres.\n"
    "Same options and seed, same files.";

/// The options, with the defaults of `d`.
void
addOptions(po::options_description& options, const SceneOptions& d)
{
  // clang-format off
  options.add_options()
    ("help,h", "print this help")
    ("output-dir", po::value<std::string>(), "output directory (required); noisy/ and truth/ are created in it")
    ("frames", po::value<int>()->default_value(d.frames), "number of frames")
    ("scene", po::value<std::string>()->default_value(toString(d.scene)),
     "boxes (floor, wall, boxes, sphere, cylinder, ridged panel at 0.8-3 m), plane (one plane at --plane-depth), steps (floor, wall, a staircase, a tilted and a folded panel at 0.8-3 m) or ridges (one plate at 1.1 m with terraces, thin ridges and grooves of 2-5 mm)")
    ("plane-depth", po::value<double>()->default_value(d.plane_depth), "depth of the plane scene, m")
    ("width", po::value<int>()->default_value(d.width), "image width, pixels")
    ("height", po::value<int>()->default_value(d.height), "image height, pixels")
    ("fx", po::value<double>()->default_value(d.fx), "focal length along x, pixels")
    ("fy", po::value<double>()->default_value(d.fy), "focal length along y, pixels")
    ("cx", po::value<double>(), "principal point x, pixels [default: (width - 1) / 2]")
    ("cy", po::value<double>(), "principal point y, pixels [default: (height - 1) / 2]")
    ("noise", po::value<std::string>()->default_value(toString(d.noise)),
     "kinect: depth error N(0, s(z)), s(z) = scale * (1.2 mm + 1.9 mm * (z - 0.4 m)^2); laser: kinect with "
     "scale 0.25; stripes: sinusoid along the columns with a per-frame phase plus N(0, s(z)); stereo: active "
     "stereo (RealSense D4xx-like), disparity noise partly correlated in blobs, quantized, error ~ z^2; kinect1: "
     "structured light after Handa et al. ICRA 2014 (simkinect): pixel shifts, 9x9 block matching (NaN at depth "
     "edges), disparity noise, 1/8 px disparity and 1 mm depth quantization; tof: time of flight, mixed pixels at "
     "depth edges, range noise growing with range; none")
    ("noise-scale", po::value<double>(), "factor on s(z) [default: 1 for kinect, 0.25 for laser and stripes]; for "
     "stereo, kinect1 and tof a factor (default 1) on the disparity or range noise sigma")
    ("stripe-amplitude", po::value<double>()->default_value(d.stripe_amplitude), "amplitude of the stripe artefact, m")
    ("stripe-period", po::value<double>()->default_value(d.stripe_period), "period of the stripe artefact, pixels")
    ("stereo-baseline", po::value<double>()->default_value(d.stereo_baseline), "stereo: baseline B, m")
    ("stereo-disparity-sigma", po::value<double>()->default_value(d.stereo_disparity_sigma),
     "stereo: disparity error standard deviation, pixels")
    ("stereo-correlated-share", po::value<double>()->default_value(d.stereo_correlated_share),
     "stereo: share of the disparity error variance that is spatially correlated, [0, 1]")
    ("stereo-correlation-length", po::value<double>()->default_value(d.stereo_correlation_length),
     "stereo: correlation length L of the correlated part (autocorrelation exp(-(lag/L)^2)), pixels, [0, 64]")
    ("stereo-subpixel", po::value<double>()->default_value(d.stereo_subpixel),
     "stereo: disparity quantization step, pixels (0 = none)")
    ("kinect1-baseline", po::value<double>()->default_value(d.kinect1_baseline), "kinect1: projector-camera baseline, m")
    ("kinect1-shift-sigma", po::value<double>()->default_value(d.kinect1_shift_sigma),
     "kinect1: standard deviation of the pixel shifts, pixels")
    ("kinect1-disparity-sigma", po::value<double>()->default_value(d.kinect1_disparity_sigma),
     "kinect1: disparity noise standard deviation, pixels")
    ("kinect1-subpixel", po::value<double>()->default_value(d.kinect1_subpixel),
     "kinect1: disparity quantization step, pixels (0 = none)")
    ("kinect1-block", po::value<int>()->default_value(d.kinect1_block), "kinect1: side of the matching block, pixels, odd")
    ("kinect1-block-threshold", po::value<double>()->default_value(d.kinect1_block_threshold),
     "kinect1: inlier threshold of the block consistency test (distance-weighted disparity difference), pixels")
    ("kinect1-depth-unit", po::value<double>()->default_value(d.kinect1_depth_unit),
     "kinect1: depth unit the depth is rounded to, m (0 = none)")
    ("tof-sigma", po::value<double>()->default_value(d.tof_sigma), "tof: range noise sigma at range 0, m")
    ("tof-sigma-slope", po::value<double>()->default_value(d.tof_sigma_slope),
     "tof: growth of the range noise sigma with range, m per m")
    ("tof-edge-band", po::value<int>()->default_value(d.tof_edge_band),
     "tof: width of the band at depth discontinuities where mixed pixels occur, pixels (0 = none)")
    ("tof-mixed-probability", po::value<double>()->default_value(d.tof_mixed_probability),
     "tof: probability that a pixel in the band is a mixed pixel, [0, 1]")
    ("tof-edge-jump", po::value<double>()->default_value(d.tof_edge_jump),
     "tof: range difference between neighbours that makes a depth discontinuity, fraction of the range")
    ("dropout", po::value<double>()->default_value(d.dropout), "probability that a pixel is dropped (NaN), [0, 1]")
    ("grazing-dropout", po::value<double>()->default_value(d.grazing_dropout),
     "drop pixels whose ray meets the surface at more than this angle from the normal, degrees (90 = off)")
    ("motion", po::value<std::string>()->default_value(toString(d.motion)),
     "static, or moving: the near box translates along +x by --motion-step per frame")
    ("motion-step", po::value<double>()->default_value(d.motion_step), "translation of the moving box per frame, m")
    ("seed", unsigned64Value(d.seed), "seed of the noise, dropouts and stripe phases")
    ("quiet,q", "print nothing but errors");
  // clang-format on
}

/// The scene, camera and noise of the options, validated (UsageError naming the problem).
SceneOptions
sceneOptionsFrom(const po::variables_map& vm)
{
  SceneOptions o;
  try {
    o.scene = sceneTypeFromString(vm["scene"].as<std::string>());
    o.noise = noiseModelFromString(vm["noise"].as<std::string>());
    o.motion = motionFromString(vm["motion"].as<std::string>());
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  o.frames = vm["frames"].as<int>();
  o.plane_depth = vm["plane-depth"].as<double>();
  o.width = vm["width"].as<int>();
  o.height = vm["height"].as<int>();
  o.fx = vm["fx"].as<double>();
  o.fy = vm["fy"].as<double>();
  if (vm.count("cx"))
    o.cx = vm["cx"].as<double>();
  if (vm.count("cy"))
    o.cy = vm["cy"].as<double>();
  if (vm.count("noise-scale"))
    o.noise_scale = vm["noise-scale"].as<double>();
  o.stripe_amplitude = vm["stripe-amplitude"].as<double>();
  o.stripe_period = vm["stripe-period"].as<double>();
  o.stereo_baseline = vm["stereo-baseline"].as<double>();
  o.stereo_disparity_sigma = vm["stereo-disparity-sigma"].as<double>();
  o.stereo_correlated_share = vm["stereo-correlated-share"].as<double>();
  o.stereo_correlation_length = vm["stereo-correlation-length"].as<double>();
  o.stereo_subpixel = vm["stereo-subpixel"].as<double>();
  o.kinect1_baseline = vm["kinect1-baseline"].as<double>();
  o.kinect1_shift_sigma = vm["kinect1-shift-sigma"].as<double>();
  o.kinect1_disparity_sigma = vm["kinect1-disparity-sigma"].as<double>();
  o.kinect1_subpixel = vm["kinect1-subpixel"].as<double>();
  o.kinect1_block = vm["kinect1-block"].as<int>();
  o.kinect1_block_threshold = vm["kinect1-block-threshold"].as<double>();
  o.kinect1_depth_unit = vm["kinect1-depth-unit"].as<double>();
  o.tof_sigma = vm["tof-sigma"].as<double>();
  o.tof_sigma_slope = vm["tof-sigma-slope"].as<double>();
  o.tof_edge_band = vm["tof-edge-band"].as<int>();
  o.tof_mixed_probability = vm["tof-mixed-probability"].as<double>();
  o.tof_edge_jump = vm["tof-edge-jump"].as<double>();
  o.dropout = vm["dropout"].as<double>();
  o.grazing_dropout = vm["grazing-dropout"].as<double>();
  o.motion_step = vm["motion-step"].as<double>();
  o.seed = vm["seed"].as<Unsigned64>().value;
  try {
    o.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  return o;
}

/// Renders the frames of `o` into OUT_DIR/noisy and OUT_DIR/truth, with progress and (unless
/// `quiet`) a closing line.
void
writeFrames(const SceneOptions& o, const std::string& out_dir, bool quiet)
{
  const std::string noisy_dir = joinPath(out_dir, "noisy"), truth_dir = joinPath(out_dir, "truth");
  prepareOutputDirectory("", noisy_dir, false);
  prepareOutputDirectory("", truth_dir, false);

  Progress progress("range_nlm_synth", std::size_t(o.frames), 1, !quiet);
  const auto start = std::chrono::steady_clock::now();
  // Zero-padded to at least 4 digits and to the largest index, so name order is frame order.
  const int digits = std::max(4, int(std::to_string(o.frames - 1).size()));
  for (int k = 0; k < o.frames; ++k) {
    // Frames are rendered one at a time so long sequences need no memory beyond one frame.
    const SyntheticFrame frame = renderFrame(o, k);
    std::ostringstream name;
    name << "frame_" << std::setw(digits) << std::setfill('0') << k << ".pcd";
    saveCloudAtomic(joinPath(noisy_dir, name.str()), frame.noisy);
    saveCloudAtomic(joinPath(truth_dir, name.str()), frame.truth);
    progress.update(std::size_t(k + 1));
  }
  progress.finish();
  if (!quiet)
    std::cout << "wrote " << o.frames << " frame" << (o.frames == 1 ? "" : "s") << " of " << o.width << " x "
              << o.height << " (scene " << toString(o.scene) << ", noise " << toString(o.noise) << " x "
              << o.effectiveNoiseScale() << ", " << toString(o.motion) << ") to " << noisy_dir << " and "
              << truth_dir << " in " << static_cast<long>(millisecondsSince(start)) << " ms" << std::endl;
}

int
run(int argc, char** argv)
{
  po::options_description options("Options");
  addOptions(options, SceneOptions());
  po::positional_options_description positional;
  po::variables_map vm;
  if (!parseCommandLine(argc, argv, options, positional, vm, kUsage))
    return 0;
  if (!vm.count("output-dir"))
    throw UsageError("--output-dir is required");
  const SceneOptions o = sceneOptionsFrom(vm);
  writeFrames(o, vm["output-dir"].as<std::string>(), vm.count("quiet") > 0);
  return 0;
}

} // namespace

int
main(int argc, char** argv)
{
  return runTool("range_nlm_synth", [&] { return run(argc, argv); });
}
