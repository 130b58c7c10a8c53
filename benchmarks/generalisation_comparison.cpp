#include "generalisation_comparison.h"
#include "bench_support.h"
#include "peer_grids.h"

#include <range_nlm/eval/synthetic_scene.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <map>
#include <stdexcept>

namespace range_nlm
{
namespace tools
{
namespace generalisation
{

using peer_grids::Cloud;
using peer_grids::fixed;
using peer_grids::mm;
using peer_grids::ScoredRow;
using peer_grids::Smoother;

namespace
{

/// Seed of the first scene's frames; the next scenes take the next seeds. Used by nothing else,
/// so the table is measured on noise no setting was chosen on.
constexpr std::uint64_t kFirstSeed = 9001;

std::vector<Smoother>
rangeNlmSmoothers(const Options& options)
{
  std::vector<Setting> settings{Setting{"default", FilterParameters::recommended()}};
  settings.insert(settings.end(), options.extra_settings.begin(), options.extra_settings.end());
  std::vector<Smoother> s;
  for (Setting setting : settings) {
    setting.parameters.threads = options.threads;
    s.push_back(peer_grids::rangeNlm(setting.name, setting.parameters));
  }
  return s;
}

/// The scene of one cell: the stereo model at `scale` with correlation length `length`.
SceneOptions
cellScene(const Options& options, std::size_t scene_index, double scale, double length)
{
  SceneOptions scene;
  scene.width = options.width;
  scene.height = options.height;
  scene.fx = scene.fy = 525.0 * options.width / 640.0;
  scene.scene = sceneTypeFromString(options.scenes[scene_index]);
  scene.noise = NoiseModel::stereo;
  scene.noise_scale = scale;
  scene.stereo_correlation_length = length;
  // The seed follows the scene, not its place in the run's list.
  const std::vector<std::string> all = Options().scenes;
  const auto place = std::find(all.begin(), all.end(), options.scenes[scene_index]);
  scene.seed = kFirstSeed + static_cast<std::uint64_t>(place != all.end() ? place - all.begin() : scene_index);
  return scene;
}

/// One cell of the table: the noisy frame's and every smoother's RMSEs.
struct Cell
{
  std::string scene;
  double scale = 0.0, length = 0.0;
  FrameMetrics noisy;
  std::vector<ScoredRow> rows;
  /// Seconds spent in each family's smoothers (without the scoring).
  std::map<std::string, double> seconds;
};

Cell
measureCell(const SceneOptions& scene, const std::vector<const std::vector<Smoother>*>& families, int threads)
{
  const SyntheticFrame frame = renderFrame(scene);
  EvaluationOptions eval;
  eval.threads = threads;
  Cell cell{toString(scene.scene), *scene.noise_scale, scene.stereo_correlation_length,
            evaluateFrame(frame.truth, frame.noisy, nullptr, eval), {}, {}};
  for (const auto* family : families)
    for (const Smoother& s : *family) {
      const auto start = std::chrono::steady_clock::now();
      const Cloud result = s.apply(frame.noisy);
      cell.seconds[s.family] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      cell.rows.push_back(ScoredRow{s.family, s.setting, evaluateFrame(frame.truth, result, &frame.noisy, eval), {}});
    }
  return cell;
}

std::string
rmsePair(const FrameMetrics& m)
{
  return mm(m.flat_rmse) + " / " + mm(m.feature_rmse);
}

nlohmann::json
jsonPair(const FrameMetrics& m)
{
  return {m.flat_rmse * 1e3, m.feature_rmse * 1e3};
}

void
printHeader(const std::vector<Smoother>& ours, std::ostream& report)
{
  report << "| scene | noise scale | correlation length (px) | noisy flat / feature | ";
  for (const Smoother& s : ours)
    report << "range_nlm " << s.setting << " | ";
  report << "FastBilateral best-balanced | MLS best-balanced |\n|---|---|---|---|";
  for (std::size_t k = 0; k < ours.size() + 2; ++k)
    report << "---|";
  report << "\n";
}

/// Prints the cell's row, adds its range_nlm results to `tally` and returns its JSON.
nlohmann::json
reportCell(const Cell& cell, peer_grids::WinTally& tally, std::ostream& report, std::ostream& log)
{
  const ScoredRow* fb = peer_grids::bestBalanced(cell.rows, "FastBilateral");
  const ScoredRow* mls = peer_grids::bestBalanced(cell.rows, "MLS");
  nlohmann::json j = {{"scene", cell.scene},
                      {"noise_scale", cell.scale},
                      {"correlation_length", cell.length},
                      {"noisy", jsonPair(cell.noisy)}};
  report << "| " << cell.scene << " | " << fixed(cell.scale, 1) << " | " << fixed(cell.length, 0) << " | "
         << rmsePair(cell.noisy) << " | ";
  log << cell.scene << " x" << fixed(cell.scale, 1) << " L " << fixed(cell.length, 0) << ": noisy "
      << rmsePair(cell.noisy);
  for (const ScoredRow& r : cell.rows)
    if (r.family == "range_nlm") {
      const bool win = tally.add(r.setting, r.m, fb->m, mls ? &mls->m : nullptr);
      report << rmsePair(r.m) << (win ? " (wins)" : "") << " | ";
      log << "; " << r.setting << " " << rmsePair(r.m);
      j["range_nlm"][r.setting] = {{"rmse", jsonPair(r.m)}, {"wins", win}};
    }
  report << rmsePair(fb->m) << " (" << fb->setting << ") | ";
  log << "; FastBilateral " << rmsePair(fb->m);
  j["FastBilateral"] = {{"rmse", jsonPair(fb->m)}, {"setting", fb->setting}};
  if (mls) {
    report << rmsePair(mls->m) << " (" << mls->setting << ") |\n";
    log << "; MLS " << rmsePair(mls->m);
    j["MLS"] = {{"rmse", jsonPair(mls->m)}, {"setting", mls->setting}};
  } else {
    report << "- |\n";
  }
  log << " (seconds:";
  for (const auto& [family, seconds] : cell.seconds)
    log << " " << family << " " << fixed(seconds, 1);
  log << ")" << std::endl;
  return j;
}

/// "1.0" or "0.5, 1.0": the noise scales of a list.
std::string
scaleList(const std::vector<double>& scales)
{
  std::string text;
  for (double s : scales)
    text += (text.empty() ? "" : ", ") + fixed(s, 1);
  return text;
}

/// Where MovingLeastSquares runs, for the table's preamble.
std::string
mlsScope(const std::vector<double>& scales)
{
  return scales.empty() ? "left out"
                        : "in the cells at noise scale " + scaleList(scales) +
                              " only (its radius grid costs about three times the rest of a cell)";
}

} // namespace

Setting
settingFromText(const std::string& spec)
{
  Setting setting{spec, FilterParameters::recommended()};
  std::size_t begin = 0;
  while (begin <= spec.size()) {
    const std::size_t end = std::min(spec.find(',', begin), spec.size());
    const std::string item = spec.substr(begin, end - begin);
    try {
      if (item.rfind("preset=", 0) == 0) // a preset's parameters, then the fields after it
        setting.parameters = FilterParameters::preset(item.substr(7));
      else
        bench::setRegistryField(item, setting.parameters);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("'" + item + "' of setting '" + spec + "': " + e.what());
    }
    begin = end + 1;
  }
  try {
    setting.parameters.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("setting '" + spec + "': " + e.what());
  }
  return setting;
}

void
makeQuick(Options& options)
{
  options.noise_scales = {1.0};
  options.correlation_lengths = {0, 2, 4, 8};
  options.mls_noise_scales.clear();
}

void
run(const Options& options, std::ostream& log, std::ostream& report, std::ostream* json)
{
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Smoother> ours = rangeNlmSmoothers(options);
  const std::vector<Smoother> fb = peer_grids::fastBilateralGrid();
  const std::vector<Smoother> mls = peer_grids::mlsGrid(options.threads);
  const std::vector<Smoother> none;
  const auto& mls_scales = options.mls_noise_scales;
  report << "## Stereo noise by correlation length and strength (point-to-plane RMSE against ground truth, mm)\n\n"
         << "Scenes " << options.width << "x" << options.height
         << ", stereo sensor model (correlated share 0.8), seed " << kFirstSeed
         << " for the first scene and one more for each next. FastBilateral and MLS: the setting of each grid with "
            "the smallest flat + feature RMSE in that cell (best-balanced)"
         << "; MLS " << mlsScope(mls_scales) << ". \"(wins)\": flat and feature RMSE both at most the best-balanced of each peer that ran.\n\n";
  printHeader(ours, report);
  peer_grids::WinTally tally;
  nlohmann::json cells = nlohmann::json::array();
  for (std::size_t k = 0; k < options.scenes.size(); ++k)
    for (double scale : options.noise_scales)
      for (double length : options.correlation_lengths) {
        const bool with_mls = std::find(mls_scales.begin(), mls_scales.end(), scale) != mls_scales.end();
        const Cell cell =
            measureCell(cellScene(options, k, scale, length), {&ours, &fb, with_mls ? &mls : &none}, options.threads);
        cells.push_back(reportCell(cell, tally, report, log));
      }
  std::vector<std::string> settings;
  for (const Smoother& s : ours)
    settings.push_back(s.setting);
  report << "\n";
  tally.print(report, settings, "cells",
              mls_scales.empty() ? "FastBilateral" : "FastBilateral, and MLS at noise scale " + scaleList(mls_scales));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report << "\n" << cells.size() << " cells in " << fixed(seconds / 60.0, 1) << " min.\n";
  if (json) {
    nlohmann::json summary = nlohmann::json::array();
    for (const auto& s : tally.summaries(settings))
      summary.push_back({{"setting", s.setting},
                         {"won", s.won},
                         {"cells", s.scenes},
                         {"flat_ratio_to_fast_bilateral", s.flat_ratio},
                         {"feature_ratio_to_fast_bilateral", s.feature_ratio}});
    *json << nlohmann::json{{"cells", cells}, {"summary", summary}, {"seconds", seconds}}.dump() << "\n";
  }
}

} // namespace generalisation
} // namespace tools
} // namespace range_nlm
