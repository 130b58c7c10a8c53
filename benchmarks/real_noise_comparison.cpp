#include "real_noise_comparison.h"
#include "bench_support.h"
#include "peer_grids.h"
#include "quality_comparison.h"

#include <range_nlm/core/pipeline.h>
#include <range_nlm/eval/render.h>
#include <range_nlm/eval/synthetic_scene.h>
#include <range_nlm/io/depth_image.h>
#include <range_nlm/io/pcd_file.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <limits>
#include <sstream>

namespace range_nlm
{
namespace tools
{
namespace real_noise
{

using Cloud = pcl::PointCloud<pcl::PointXYZ>;
namespace fs = std::filesystem;

namespace
{
using peer_grids::fixed;
using peer_grids::mm;
using peer_grids::ScoredRow;
using peer_grids::Smoother;

std::vector<Smoother>
rangeNlmSmoothers(const Options& options)
{
  std::vector<Smoother> s;
  const int threads = options.threads;
  for (auto [name, p] : options.settings.empty() ? variants() : options.settings) {
    p.threads = threads;
    s.push_back(peer_grids::rangeNlm(name, p));
  }
  return s;
}

std::string
correlationText(const Cloud& c)
{
  const Grid g = Grid::fromInterleaved(reinterpret_cast<const float*>(c.points.data()), int(c.width), int(c.height),
                                       sizeof(pcl::PointXYZ) / sizeof(float));
  const NoiseCorrelation n = estimateNoiseCorrelation(g);
  std::ostringstream s;
  s << "second-difference scale by lag (mm):";
  for (float v : n.scale)
    s << " " << fixed(1000 * v, 2);
  s << "; in pixel footprints:";
  for (float v : n.scale_in_footprints)
    s << " " << fixed(v, 2);
  s << "; automatic dilation " << automaticDilation(g);
  return s.str();
}

/// `result` with every point made invalid whose pixel is invalid in `other`: scored against the
/// truth, the points both kept.
Cloud
keptByBoth(const Cloud& result, const Cloud& other)
{
  Cloud both = result;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < both.size() && i < other.size(); ++i)
    if (!std::isfinite(other[i].z))
      both[i].x = both[i].y = both[i].z = nan;
  return both;
}

/// "+0.4 %": how much larger `png` is than `pcd`.
std::string
excess(double png, double pcd)
{
  return pcd > 0.0 ? (png >= pcd ? "+" : "") + fixed(100.0 * (png / pcd - 1.0), 1) + " %" : "-";
}

/// The depth-image outputs of one filtered frame, read back: re-projected onto the rays (what
/// range_nlm_denoise --output-format png and the ROS depth topic write) and z only (the encoding
/// of a cloud already on its rays).
struct PngOutputs
{
  Cloud reprojected, z_only;
};

PngOutputs
pngOutputs(const Cloud& input, const Cloud& filtered, double depth_scale)
{
  return {bench::depthImageOutput(input, filtered, depth_scale),
          bench::depthImageOutput(input, filtered, depth_scale, true)};
}

const char* const kPngTableNote =
    "PNG: the filtered cloud through the depth-image output (each point re-projected onto its pixel's ray, "
    "16-bit at the frame's depth scale: its intrinsics.txt for a depth PNG, 5000 per metre, range_nlm_denoise's "
    "default, otherwise) and read back, scored as the PCD output; z only: the same image of the filtered z as it "
    "is (the encoding before the re-projection).";

} // namespace

std::vector<std::pair<std::string, FilterParameters>>
variants()
{
  std::vector<std::pair<std::string, FilterParameters>> v;
  v.emplace_back("default", FilterParameters::recommended());
  v.emplace_back("preset paper", FilterParameters::paper());
  FilterParameters p = FilterParameters::recommended();
  p.dilation = 1;
  v.emplace_back("default, contiguous windows", p);
  p = FilterParameters::recommended();
  p.iterations = 3;
  v.emplace_back("default, 3 passes", p);
  p = FilterParameters::recommended();
  p.scales = 2;
  v.emplace_back("default, 2 scales", p);
  return v;
}

std::vector<std::vector<std::string>>
staticRealSequences(const std::string& dir)
{
  std::vector<std::vector<std::string>> sequences;
  if (dir.empty())
    return sequences;
  for (const auto& [pose, first] : {std::pair<std::string, int>{"pose4", 3}, {"pose5", 6}}) {
    std::vector<std::string> seq;
    for (int k = first; k < first + 3; ++k) {
      const fs::path p =
          fs::path(dir) / "depth-images/realsense-d435-static" / pose / (std::to_string(k) + "_realsense_depth.png");
      if (fs::exists(p))
        seq.push_back(p.string());
    }
    if (seq.size() == 3)
      sequences.push_back(seq);
  }
  return sequences;
}

void
addShippedFrames(Options& options, const std::string& data_dir, const std::string& extra_dir)
{
  auto add = [&](const std::string& dir, const std::string& name) {
    const fs::path p = fs::path(dir) / name;
    if (!dir.empty() && fs::exists(p))
      options.real_frames.push_back(p.string());
  };
  for (const std::string& dir : {data_dir, extra_dir}) {
    add(dir, "milk_cartoon_all_small_clorox.pcd");
    add(dir, "table_scene_mug_stereo_textured.pcd");
    add(dir, "kinect-sequence/frame_20121214T142255.814212.pcd");
    add(dir, "depth-images/tum-fr2-desk-pair/1_depth.png");
    add(dir, "depth-images/realsense-d415-vcl3d/0_M11_depth_0.png");
    add(dir, "depth-images/azure-kinect-mug/depth_nfov_unbinned.png");
  }
  // The same file under both folders once.
  std::vector<std::string> unique;
  for (const std::string& f : options.real_frames) {
    const bool seen = std::any_of(unique.begin(), unique.end(), [&](const std::string& u) {
      return fs::path(u).filename() == fs::path(f).filename();
    });
    if (!seen)
      unique.push_back(f);
  }
  options.real_frames = unique;
  options.static_sequences = staticRealSequences(extra_dir);
}

void
run(const Options& options, std::ostream& log, std::ostream& report, std::ostream* json)
{
  nlohmann::json out = nlohmann::json::object();
  const std::vector<Smoother> ours = rangeNlmSmoothers(options);
  const std::vector<Smoother> fb = peer_grids::fastBilateralGrid();
  const std::vector<Smoother> mls = options.include_mls ? peer_grids::mlsGrid(options.threads) : std::vector<Smoother>{};

  // 1. Generated scenes with ground truth.
  peer_grids::WinTally tally;
  std::ostringstream like_for_like; // rows of the scenes on which MLS's best-balanced setting lost points
  std::ostringstream png_generated; // PCD against PNG output of every range_nlm setting
  const double generated_depth_scale = DepthIntrinsics().depth_scale;
  report << "## Generated scenes with sensor noise (point-to-plane RMSE against ground truth, mm)\n\n"
         << "FastBilateral and MLS: the setting of each grid with the smallest flat + feature RMSE on that scene "
            "(best-balanced).\n\n"
         << "| scene | noisy flat / feature | ";
  for (const Smoother& s : ours)
    report << s.setting << " | ";
  report << "FastBilateral best-balanced | MLS best-balanced |\n|---|---|";
  for (std::size_t k = 0; k < ours.size() + 2; ++k)
    report << "---|";
  report << "\n";
  for (const std::string& model : options.models)
    for (double scale : options.noise_scales)
      for (std::uint64_t seed : options.seeds) {
        SceneOptions scene;
        scene.width = options.width;
        scene.height = options.height;
        scene.noise = noiseModelFromString(model);
        scene.noise_scale = scale;
        scene.seed = seed;
        const SyntheticFrame frame = renderSequence(scene).front();
        EvaluationOptions eval;
        eval.threads = options.threads;
        const std::string name = model + " x" + fixed(scale, 1) + " seed " + std::to_string(seed);
        std::vector<ScoredRow> rows;
        log << name << ": " << correlationText(frame.noisy) << std::endl;
        const FrameMetrics noisy = evaluateFrame(frame.truth, frame.noisy, nullptr, eval);
        for (const auto* family : {&ours, &fb, &mls})
          for (const Smoother& s : *family) {
            Cloud result = s.apply(frame.noisy);
            const FrameMetrics m = evaluateFrame(frame.truth, result, &frame.noisy, eval);
            rows.push_back(ScoredRow{s.family, s.setting, m, std::move(result)});
          }
        const ScoredRow* fb_best = peer_grids::bestBalanced(rows, "FastBilateral");
        const ScoredRow* mls_best = peer_grids::bestBalanced(rows, "MLS");
        if (mls_best && mls_best->m.points_lost > 0) {
          // The RMSEs skip lost points: the default scored again on the points MLS kept.
          const ScoredRow& ours_default = rows.front();
          const FrameMetrics m =
              evaluateFrame(frame.truth, keptByBoth(ours_default.result, mls_best->result), &frame.noisy, eval);
          like_for_like << "| " << name << " | " << mls_best->m.points_lost << " | " << mm(ours_default.m.flat_rmse)
                        << " / " << mm(ours_default.m.feature_rmse) << " | " << mm(m.flat_rmse) << " / "
                        << mm(m.feature_rmse) << " | " << mm(mls_best->m.flat_rmse) << " / "
                        << mm(mls_best->m.feature_rmse) << " (" << mls_best->setting << ") |\n";
          out["generated"][name]["default on the points MLS kept"] = {m.flat_rmse * 1e3, m.feature_rmse * 1e3};
        }
        report << "| " << name << " | " << mm(noisy.flat_rmse) << " / " << mm(noisy.feature_rmse) << " | ";
        nlohmann::json& j = out["generated"][name];
        j["noisy"] = {noisy.flat_rmse * 1e3, noisy.feature_rmse * 1e3};
        for (const ScoredRow& r : rows)
          if (r.family == "range_nlm") {
            const PngOutputs png = pngOutputs(frame.noisy, r.result, generated_depth_scale);
            const FrameMetrics p = evaluateFrame(frame.truth, png.reprojected, &frame.noisy, eval);
            const FrameMetrics z = evaluateFrame(frame.truth, png.z_only, &frame.noisy, eval);
            png_generated << "| " << name << " | " << r.setting << " | " << mm(r.m.flat_rmse) << " / "
                          << mm(r.m.feature_rmse) << " | " << mm(p.flat_rmse) << " / " << mm(p.feature_rmse) << " | "
                          << excess(p.flat_rmse, r.m.flat_rmse) << " | " << mm(z.flat_rmse) << " / "
                          << mm(z.feature_rmse) << " |\n";
            j["png"][r.setting] = {p.flat_rmse * 1e3, p.feature_rmse * 1e3};
            j["png z only"][r.setting] = {z.flat_rmse * 1e3, z.feature_rmse * 1e3};
            const bool win = tally.add(r.setting, r.m, fb_best->m, mls_best ? &mls_best->m : nullptr);
            report << mm(r.m.flat_rmse) << " / " << mm(r.m.feature_rmse) << (win ? " (wins)" : "") << " | ";
            j[r.setting] = {r.m.flat_rmse * 1e3, r.m.feature_rmse * 1e3};
          }
        report << mm(fb_best->m.flat_rmse) << " / " << mm(fb_best->m.feature_rmse) << " (" << fb_best->setting << ") | ";
        j["FastBilateral"] = {fb_best->m.flat_rmse * 1e3, fb_best->m.feature_rmse * 1e3, fb_best->setting};
        if (mls_best) {
          report << mm(mls_best->m.flat_rmse) << " / " << mm(mls_best->m.feature_rmse) << " (" << mls_best->setting
                 << ") |\n";
          j["MLS"] = {mls_best->m.flat_rmse * 1e3, mls_best->m.feature_rmse * 1e3, mls_best->setting};
        } else {
          report << "- |\n";
        }
        log << name << ": FastBilateral " << mm(fb_best->m.flat_rmse) << " / " << mm(fb_best->m.feature_rmse);
        for (const ScoredRow& r : rows)
          if (r.family == "range_nlm")
            log << "; " << r.setting << " " << mm(r.m.flat_rmse) << " / " << mm(r.m.feature_rmse);
        log << std::endl;
      }
  report << "\n";
  std::vector<std::string> settings;
  for (const Smoother& s : ours)
    settings.push_back(s.setting);
  tally.print(report, settings, "scenes", "FastBilateral and MLS");

  if (!like_for_like.str().empty())
    report << "\n### Where MovingLeastSquares drops points\n\nThe RMSEs skip lost points (range_nlm and "
              "FastBilateral lose none). The default scored again on the points MLS's best-balanced setting kept "
              "(flat / feature RMSE, mm):\n\n| scene | points MLS lost | default | default on the points MLS kept | "
              "MLS best-balanced |\n|---|---|---|---|---|\n"
           << like_for_like.str();

  report << "\n### PNG output against PCD output\n\n" << kPngTableNote
         << " Flat / feature RMSE against ground truth (mm).\n\n| scene | setting | PCD | PNG | PNG flat against "
            "PCD | z only |\n|---|---|---|---|---|---|\n"
         << png_generated.str();

  // 2. Real frames: residual of the raw frame's planar regions.
  std::ostringstream png_real; // PCD against PNG output of every range_nlm setting
  const std::vector<Smoother> fb_real{peer_grids::fastBilateral(5.0f, 0.03f), peer_grids::fastBilateral(10.0f, 0.05f),
                                      peer_grids::fastBilateral(15.0f, 0.05f)};
  if (!options.real_frames.empty()) {
    report << "\n## Real frames: residual to the planes of the raw frame's planar regions (RMS, mm; interior / border "
              "band of 3 px; points lost)\n\n| frame | regions | raw | ";
    for (const Smoother& s : ours)
      report << s.setting << " | ";
    for (const Smoother& s : fb_real)
      report << "FastBilateral " << s.setting << " | ";
    report << "\n|---|---|---|";
    for (std::size_t k = 0; k < ours.size() + fb_real.size(); ++k)
      report << "---|";
    report << "\n";
  }
  for (const std::string& path : options.real_frames) {
    const Cloud raw = bench::loadXyzFrame(path);
    log << path << ": " << correlationText(raw) << std::endl;
    const PlanarRegions regions = findPlanarRegions(raw);
    const PlanarResidual before = planarResidual(regions, raw);
    const std::string name = fs::path(path).filename().string();
    report << "| " << name << " | " << regions.planes.size() << " | " << mm(before.interior_rms) << " / "
           << mm(before.border_rms) << " | ";
    nlohmann::json& j = out["real"][name];
    j["raw"] = {before.interior_rms * 1e3, before.border_rms * 1e3};
    log << name << ": raw " << mm(before.interior_rms) << " / " << mm(before.border_rms);
    std::vector<Cloud> results;
    const double depth_scale = bench::frameDepthScale(path);
    for (const auto* family : {&ours, &fb_real})
      for (const Smoother& s : *family) {
        results.push_back(s.apply(raw));
        const PlanarResidual r = planarResidual(regions, results.back());
        if (family == &ours) {
          const PngOutputs png = pngOutputs(raw, results.back(), depth_scale);
          const PlanarResidual p = planarResidual(regions, png.reprojected);
          const PlanarResidual z = planarResidual(regions, png.z_only);
          png_real << "| " << name << " | " << s.setting << " | " << mm(before.interior_rms) << " / "
                   << mm(before.border_rms) << " | " << mm(r.interior_rms) << " / " << mm(r.border_rms) << " | "
                   << mm(p.interior_rms) << " / " << mm(p.border_rms) << " | " << excess(p.interior_rms, r.interior_rms)
                   << " | " << mm(z.interior_rms) << " / " << mm(z.border_rms) << " |\n";
          j["png " + s.setting] = {p.interior_rms * 1e3, p.border_rms * 1e3};
          j["png z only " + s.setting] = {z.interior_rms * 1e3, z.border_rms * 1e3};
        }
        report << mm(r.interior_rms) << " / " << mm(r.border_rms) << (r.points_lost ? " (" + std::to_string(r.points_lost) + " lost)" : "") << " | ";
        j[s.family + " " + s.setting] = {r.interior_rms * 1e3, r.border_rms * 1e3, r.points_lost};
        log << "; " << s.family << " " << s.setting << " " << mm(r.interior_rms) << " / " << mm(r.border_rms);
      }
    report << "\n";
    log << std::endl;
    if (!options.render_dir.empty()) {
      // raw | range_nlm default (the first variant) | FastBilateral 5 / 0.03 (the first peer).
      RenderParameters rp;
      rp.threads = options.threads;
      const Rgb white{255, 255, 255};
      const RgbImage image = sideBySide(
          sideBySide(renderShaded(gridFromCloud(raw), rp), renderShaded(gridFromCloud(results.front()), rp), rp.gap,
                     white),
          renderShaded(gridFromCloud(results[ours.size()]), rp), rp.gap, white);
      fs::create_directories(options.render_dir);
      saveRgbPng((fs::path(options.render_dir) / (fs::path(path).stem().string() + ".png")).string(), image);
    }
  }

  if (!png_real.str().empty())
    report << "\n### Real frames: PNG output against PCD output\n\n" << kPngTableNote
           << " Residual to the raw frame's planes, interior / border band (mm).\n\n| frame | setting | raw | PCD | "
              "PNG | PNG interior against PCD | z only |\n|---|---|---|---|---|---|---|\n"
           << png_real.str();

  // 3. Static real sequences: jitter of the frames filtered one by one.
  std::ostringstream png_jitter; // PCD against PNG output of every range_nlm setting
  if (!options.static_sequences.empty()) {
    report << "\n## Static real sequences: median per-pixel range jitter (sample std over the frames, mm), frames "
              "filtered one by one\n\n| sequence | raw | ";
    for (const Smoother& s : ours)
      report << s.setting << " | ";
    for (const Smoother& s : fb_real)
      report << "FastBilateral " << s.setting << " | ";
    report << "\n|---|---|";
    for (std::size_t k = 0; k < ours.size() + fb_real.size(); ++k)
      report << "---|";
    report << "\n";
  }
  for (const std::vector<std::string>& sequence : options.static_sequences) {
    std::vector<Cloud> raw;
    for (const std::string& f : sequence)
      raw.push_back(bench::loadXyzFrame(f));
    const std::string name = fs::path(sequence.front()).parent_path().filename().string();
    log << sequence.front() << ": " << correlationText(raw.front()) << std::endl;
    const TemporalJitter before = temporalJitter(raw);
    report << "| " << name << " | " << mm(before.median) << " | ";
    nlohmann::json& j = out["jitter"][name];
    j["raw"] = before.median * 1e3;
    log << name << ": raw " << mm(before.median);
    const double depth_scale = bench::frameDepthScale(sequence.front());
    for (const auto* family : {&ours, &fb_real})
      for (const Smoother& s : *family) {
        JitterEvaluator e, png, z_only;
        for (const Cloud& c : raw) {
          const Cloud result = s.apply(c);
          if (family == &ours) {
            const PngOutputs outputs = pngOutputs(c, result, depth_scale);
            png.add(outputs.reprojected);
            z_only.add(outputs.z_only);
          }
          e.add(result);
        }
        const TemporalJitter t = e.jitter();
        if (family == &ours) {
          const TemporalJitter p = png.jitter(), z = z_only.jitter();
          png_jitter << "| " << name << " | " << s.setting << " | " << mm(before.median) << " | " << mm(t.median)
                     << " | " << mm(p.median) << " | " << excess(p.median, t.median) << " | " << mm(z.median) << " |\n";
          j["png " + s.setting] = p.median * 1e3;
          j["png z only " + s.setting] = z.median * 1e3;
        }
        report << mm(t.median) << " | ";
        j[s.family + " " + s.setting] = t.median * 1e3;
        log << "; " << s.family << " " << s.setting << " " << mm(t.median);
      }
    report << "\n";
    log << std::endl;
  }
  if (!png_jitter.str().empty())
    report << "\n### Static real sequences: PNG output against PCD output\n\n" << kPngTableNote
           << " Median per-pixel range jitter, frames filtered one by one (mm).\n\n| sequence | setting | raw | PCD | "
              "PNG | PNG against PCD | z only |\n|---|---|---|---|---|---|---|\n"
           << png_jitter.str();
  if (json)
    *json << out.dump() << "\n";
}

} // namespace real_noise
} // namespace tools
} // namespace range_nlm
