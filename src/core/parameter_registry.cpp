#include <range_nlm/parameter_registry.h>

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <type_traits>

namespace range_nlm
{
namespace
{

/// Builds one entry, a named property at a time, so that each entry of the table below reads as
/// a list of what the parameter is.
class Entry
{
public:
  template <typename T>
  Entry(const char* name, T FilterParameters::*field)
  {
    entry_.name = name;
    entry_.field = field;
  }
  Entry& unit(const char* text)
  {
    entry_.unit = text;
    return *this;
  }
  /// Valid values, and why the bounds are where they are.
  Entry& range(ParameterRange r, const char* why)
  {
    entry_.range = r;
    entry_.range.why = why;
    return *this;
  }
  Entry& choices(std::vector<std::pair<const char*, int>> list)
  {
    entry_.choices = std::move(list);
    return *this;
  }
  Entry& zeroMeans(const char* text)
  {
    entry_.zero_means = text;
    return *this;
  }
  Entry& help(const char* text)
  {
    entry_.help = text;
    return *this;
  }
  Entry& docs(const char* link)
  {
    entry_.docs_section = link;
    return *this;
  }
  /// Command-line option; `always`: it always has a value, the recommended one.
  Entry& cli(const char* option, bool always = false)
  {
    entry_.cli_option = option;
    entry_.cli_always = always;
    return *this;
  }
  Entry& cliSwitch(const char* flag, int on, const char* text)
  {
    entry_.cli_switches.push_back({flag, on, -1, text});
    return *this;
  }
  Entry& ros(const char* name)
  {
    entry_.ros_name = name;
    return *this;
  }
  Entry& rosSwitch(const char* name, int on, int off)
  {
    entry_.ros_switch = {name, on, off, ""};
    return *this;
  }
  Entry& pass(const char* key)
  {
    entry_.pass_key = key;
    return *this;
  }
  Entry& explicitPositive()
  {
    entry_.explicit_positive = true;
    return *this;
  }
  operator ParameterEntry() const { return entry_; }

private:
  ParameterEntry entry_;
};

ParameterRange
atLeast(double min, const char* requirement)
{
  ParameterRange r;
  r.min = min;
  r.requirement = requirement;
  return r;
}

ParameterRange
between(double min, double max, const char* requirement)
{
  ParameterRange r = atLeast(min, requirement);
  r.max = max;
  return r;
}

ParameterRange
oddBetween(double min, double max, const char* requirement)
{
  ParameterRange r = between(min, max, requirement);
  r.odd = true;
  return r;
}

ParameterRange
zeroOr(ParameterRange r)
{
  r.zero_allowed = true;
  return r;
}

template <typename E>
std::pair<const char*, int>
choice(const char* name, E value)
{
  return {name, static_cast<int>(value)};
}

using P = FilterParameters;

const char* const kSigmas = "noise sigmas";
const char* const kCloudUnits = "cloud units";

// Reasons shared by several entries.
const char* const kWindowCost =
    "each point's work grows with the square of the window; the largest is already over a hundred times the "
    "default's work, and candidates that far away weigh nothing under the automatic distance bandwidth";
const char* const kBandwidthSquare =
    "the weights divide by the bandwidth's square, which must stay a normal, finite float (1.2e-38 ... 3.4e38)";
const char* const kScaleFactor =
    "a factor on the automatic bandwidth: below 1/1000 no candidate but the point itself weighs anything (nothing "
    "moves), above 1000 every candidate weighs the same (a box blur across depth edges)";
const char* const kSigmaThreshold =
    "a threshold in noise sigmas: beyond 1000 sigmas nothing a sensor's noise produces is left out, so larger "
    "values only hide a unit mistake";

/// The entries of the windows, the passes and the bandwidths, in the order of their fields.
std::vector<ParameterEntry>
windowAndBandwidthEntries()
{
  // clang-format off
  return {
    Entry("search_window", &P::search_window).unit("pixels")
      .range(oddBetween(1, 101, "must be a positive odd number of pixels, at most 101"), kWindowCost)
      .help("S, odd side of the search window in pixels")
      .cli("search-window").ros("search_window").pass("search"),
    Entry("patch_size", &P::patch_size).unit("pixels")
      .range(oddBetween(1, 51, "must be a positive odd number of pixels, at most 51"),
             "each candidate compares P^2 pixels; a 51-pixel patch already costs 289 times the default's and spans "
             "more than any detail the filter keeps")
      .help("P, odd side of the similarity patch in pixels")
      .cli("patch").ros("patch").pass("patch"),
    Entry("temporal_search_window", &P::temporal_search_window).unit("pixels").zeroMeans("search_window")
      .range(zeroOr(oddBetween(1, 101, "must be 0 (the search window) or a positive odd number of pixels, at most "
                                       "101")),
             kWindowCost)
      .docs("[the live preset](#the-live-preset)")
      .help("odd side of the search window in the other frames of a temporal window (a stream's history or "
            "neighbours); 0 (or the search window and wider) = the search window")
      .cli("temporal-search-window").ros("temporal_search_window").pass("temporal_search"),
    Entry("dilation", &P::dilation).unit("pixels").zeroMeans("automatic")
      .range(between(0, 64, "must be 0 (automatic) ... 64"),
             "a frame is filtered as k^2 phases 1/k of its size, each of which must hold the windows: 64 leaves a "
             "4096-pixel-wide frame phases 64 pixels wide, and no sensor's noise is correlated farther")
      .docs("[dilated passes](#spatially-correlated-noise-dilated-passes)")
      .help("spacing k of the search window's and patches' pixels: 0 = automatic (2 or more where the noise is "
            "spatially correlated or strong, 1 otherwise), 1 = contiguous windows")
      .cli("dilation").ros("dilation").pass("dilation"),
    Entry("scales", &P::scales)
      .range(between(1, 6, "must be 1 (one scale) ... 6"),
             "each scale halves the frame: the sixth is 1/32 of its width, narrower than the windows of any frame "
             "a sensor delivers")
      .docs("[multiscale filtering](#multiscale-filtering)")
      .help("scales of the multiscale run: the frame halved scales - 1 times, filtered from the coarsest up, each "
            "finer scale after the coarser one's corrections are carried up; 1 = one scale")
      .cli("scales").ros("scales").pass("scales"),
    Entry("iterations", &P::iterations)
      .range(between(1, 100, "must be 1 ... 100"),
             "each pass costs one filtering of the frame; past a few passes the output no longer changes, and 100 "
             "bounds the run time at 50 times the default's")
      .help("filter passes; normals and automatic bandwidths are re-estimated before each")
      .cli("iterations").ros("iterations").pass("iterations"),
    Entry("threads", &P::threads).zeroMeans("all")
      .range(between(0, P::max_threads, "must be 0 (all available) ... 1024"),
             "OpenMP starts every thread asked for, and tens of thousands of them exhaust the stacks and crash")
      .help("OpenMP threads, 0 = all cores, at most 1024 (output does not depend on it)")
      .cli("threads", true).ros("threads"),
    Entry("distance_bandwidth", &P::distance_bandwidth).unit(kCloudUnits).zeroMeans("automatic")
      .range(zeroOr(between(1e-18, 1e18, "must be finite and >= 0 (0 = automatic), from 1e-18 to 1e18")),
             kBandwidthSquare)
      .help("d, bandwidth of the distance weight exp(-|p_i - p_j|^2 / d^2), in cloud units")
      .cli("distance-bandwidth").ros("distance_bandwidth").pass("distance_bandwidth").explicitPositive(),
    Entry("similarity_bandwidth", &P::similarity_bandwidth).unit(kCloudUnits).zeroMeans("automatic")
      .range(zeroOr(between(1e-18, 1e18, "must be finite and >= 0 (0 = automatic), from 1e-18 to 1e18")),
             kBandwidthSquare)
      .help("s, bandwidth of the similarity weight exp(-Sim / s^2), in cloud units")
      .cli("similarity-bandwidth").ros("similarity_bandwidth").pass("similarity_bandwidth").explicitPositive(),
    Entry("distance_scale", &P::distance_scale)
      .range(between(1e-3, 1e3, "must be finite and > 0, from 0.001 to 1000"), kScaleFactor)
      .help("factor on mu_d (or the window extent) for the automatic d")
      .cli("distance-scale").ros("distance_scale").pass("distance_scale"),
    Entry("similarity_scale", &P::similarity_scale)
      .range(between(1e-3, 1e3, "must be finite and > 0, from 0.001 to 1000"), kScaleFactor)
      .help("factor on sigma_s (or the local noise sigma) for the automatic s")
      .cli("similarity-scale").ros("similarity_scale").pass("similarity_scale"),
    Entry("similarity_spread", &P::similarity_spread).zeroMeans("off")
      .range(between(0, 1e3, "must be finite and >= 0 (0 = off), at most 1000"), kScaleFactor)
      .help("range-adaptive automatic s: s^2 = this times the frame's patch spread at the point's range (the "
            "median over sampled points of a low quantile of Sim to their candidates), at most (similarity_scale "
            "sigma)^2; 0 = off")
      .cli("similarity-spread").ros("similarity_spread").pass("similarity_spread"),
    Entry("seed", &P::seed)
      .range(between(0, 18446744073709551615.0, "must be an integer from 0 to 2^64 - 1"),
             "every 64-bit value seeds the sample; the bounds are the field's type (a negative value is refused "
             "where text is read, never taken modulo 2^64)")
      .help("seed of the bandwidth sample")
      .cli("seed", true).ros("seed"),
  };
  // clang-format on
}

/// The entries of the normals, the gates, the moves and the evaluation, in the order of their
/// fields.
std::vector<ParameterEntry>
normalAndMoveEntries()
{
  // clang-format off
  return {
    Entry("bandwidth_samples", &P::bandwidth_samples)
      .range(between(1, P::max_bandwidth_samples, "must be at least 1, at most 100000"),
             "the samples are drawn with replacement and binned by range into at most 8 bins of the noise profile: "
             "100000 samples (100 times the default) put 12500 windows in each, where a median's sampling error "
             "(about 1.25 / sqrt(n) of the spread) is 1 %, whatever the frame's size; more only cost time (a plane "
             "fit over the search window each, every iteration) and memory (about 30 bytes each, counted in the "
             "tools' memory estimate)")
      .help("random valid points sampled for the automatic bandwidths")
      .cli("bandwidth-samples").ros("bandwidth_samples").pass("bandwidth_samples"),
    Entry("normal_window", &P::normal_window).unit("pixels")
      .range(oddBetween(3, 51, "must be an odd number of pixels >= 3, at most 51"),
             "a plane fit over N^2 points: a 51-pixel fit already spans whole objects, and its normal is no longer "
             "the surface's at the point")
      .help("odd side of the normal-estimation neighbourhood (the plane fit)")
      .cli("normal-window").ros("normal_window").pass("normal"),
    Entry("normal_presmooth_window", &P::normal_presmooth_window).unit("pixels").zeroMeans("off")
      .range(zeroOr(oddBetween(1, 51, "must be 0 (off) or odd, at most 51")),
             "a smoothing of N^2 points a pixel: wider than 51 pixels it costs more than the filter and smooths "
             "over whole objects")
      .help("side of the edge-preserving depth pre-smoothing of the copy the normals are estimated from; "
            "0 or 1 = normals from the raw points")
      .cli("normal-presmooth-window").ros("normal_presmooth_window").pass("normal_presmooth_window"),
    Entry("normal_presmooth_range", &P::normal_presmooth_range).unit(kSigmas)
      .range(between(0.01, 1000, "must be finite and > 0, from 0.01 to 1000"),
             "in noise sigmas: below 1/100 sigma no neighbour weighs anything (window 0 turns the smoothing off), "
             "above 1000 sigmas it smooths across every depth edge")
      .help("range bandwidth of that pre-smoothing")
      .cli("normal-presmooth-range").ros("normal_presmooth_range").pass("normal_presmooth_range"),
    Entry("normal_edge_gate", &P::normal_edge_gate).unit(kSigmas).zeroMeans("off")
      .range(between(0, 1000, "must be finite and >= 0 (0 = off), at most 1000"), kSigmaThreshold)
      .help("gated normals: neighbours farther than this from a first plane fit through the point are left out "
            "of a second fit")
      .cli("normal-edge-gate").ros("normal_edge_gate").pass("normal_edge_gate"),
    Entry("patch_edge_gate", &P::patch_edge_gate).unit(kSigmas).zeroMeans("off")
      .range(between(0, 1000, "must be finite and >= 0 (0 = off), at most 1000"), kSigmaThreshold)
      .docs("[gated patches](#depth-edges-in-the-patches-gated-patches)")
      .help("pixels of a point's patch farther than this many noise sigmas from its tangent plane (the other "
            "side of a depth edge) are left out of the patch comparison")
      .cli("patch-gate").ros("patch_gate").pass("patch_edge_gate"),
    Entry("line_of_sight_min_cos", &P::line_of_sight_min_cos)
      .range(between(0, 1, "must be in [0, 1]"), "a cosine")
      .help("smallest |cos(normal, ray)| of the ray step h / cos of a move along the line of sight")
      .cli("line-of-sight-min-cos").ros("line_of_sight_min_cos").pass("line_of_sight_min_cos"),
    Entry("bandwidth_model", &P::bandwidth_model)
      .choices({choice("range_adaptive", BandwidthModel::range_adaptive), choice("global", BandwidthModel::global)})
      .docs("[Automatic bandwidths](#automatic-bandwidths)")
      .help("automatic bandwidths: 'range_adaptive' (per point, from the frame's noise profile by range) or "
            "'global' (one d and s for the frame, the paper)")
      .cli("bandwidth-model").ros("bandwidth_model").pass("bandwidth_model"),
    Entry("max_displacement", &P::max_displacement).unit(kSigmas).zeroMeans("unlimited")
      .range(between(0, 1000, "must be finite and >= 0 (0 = unlimited), at most 1000"), kSigmaThreshold)
      .help("largest move of a point, in noise sigmas (range_adaptive) or in s (global)")
      .cli("max-displacement").ros("max_displacement").pass("max_displacement"),
    Entry("outlier_sigmas", &P::outlier_sigmas).unit(kSigmas).zeroMeans("off")
      .range(between(0, 1000, "must be finite and >= 0 (0 = off), at most 1000"), kSigmaThreshold)
      .docs("[Isolated outliers](#isolated-outliers)")
      .help("isolated outliers (structured-light mismatches, time-of-flight flying pixels) farther than this "
            "many noise sigmas from all their neighbours are moved along their ray onto the neighbours' surface "
            "before filtering")
      .cli("outlier-sigmas").ros("outlier_sigmas").pass("outlier_sigmas"),
    Entry("displacement", &P::displacement)
      .choices({choice("automatic", Displacement::automatic), choice("normal", Displacement::normal),
                choice("line_of_sight", Displacement::line_of_sight)})
      .docs("[along the line of sight](#the-temporal-filter-along-the-line-of-sight)")
      .help("direction of the move: along the camera ray where other frames take part and along the normal for "
            "a frame filtered alone, along the normal (the paper), or along the camera ray")
      .cliSwitch("line-of-sight", int(Displacement::line_of_sight),
                 "move points along their camera ray instead of the normal, also when filtered alone "
                 "(default: along the ray in temporal runs, along the normal otherwise)")
      .cliSwitch("along-normal", int(Displacement::normal),
                 "move points along their normal, also in temporal runs (the paper)")
      .rosSwitch("line_of_sight", int(Displacement::line_of_sight), int(Displacement::normal))
      .pass("displacement"),
    Entry("cross_frame_bandwidth", &P::cross_frame_bandwidth)
      .choices({choice("guarded", CrossFrameBandwidth::guarded), choice("temporal", CrossFrameBandwidth::temporal),
                choice("spatial", CrossFrameBandwidth::spatial)})
      .docs("[Cross-frame bandwidths](#cross-frame-bandwidths)")
      .help("temporal runs: s and d of the other frames: 'guarded' (raised to their frame-to-frame noise unless "
            "the frame moved), 'temporal' (always raised: a static camera), 'spatial' (their own spatial noise, "
            "the paper)")
      .cli("cross-frame").ros("cross_frame").pass("cross_frame_bandwidth"),
    Entry("patch_guide", &P::patch_guide)
      .docs("[The patch guide](#the-patch-guide)")
      .help("guarded temporal runs: the other frames' patches are compared with the mean of the frames that "
            "did not move instead of the current frame's own noisy patch")
      .cli("patch-guide").ros("patch_guide").pass("patch_guide"),
    Entry("evaluation", &P::evaluation)
      .choices({choice("fast", Evaluation::fast), choice("direct", Evaluation::direct)})
      .help("evaluation of the patch similarity: windowed or the literal formula (the reference); the same "
            "result to float precision")
      .cliSwitch("direct", int(Evaluation::direct), "use the direct (reference) evaluation instead of the fast "
                                                    "(windowed) one")
      .rosSwitch("direct", int(Evaluation::direct), -1)
      .pass("evaluation"),
    Entry("uncertainty", &P::uncertainty)
      .docs("[Per-point uncertainty](#per-point-uncertainty)")
      .help("also estimate each output point's standard deviation along its direction of movement, metres, from "
            "the filter's weights (an 'uncertainty' field in PCD output)")
      .cli("uncertainty").ros("uncertainty").pass("uncertainty"),
    Entry("fill_holes", &P::fill_holes).unit("pixels").zeroMeans("off")
      .range(between(0, 64, "must be 0 (off) ... 64 pixels"),
             "a wider gap is a region the sensor did not see, not a dropout; the search for a hole's candidates "
             "grows with its width")
      .docs("[hole filling](#hole-filling)")
      .help("fill holes (invalid regions not touching the frame border) at most this many pixels wide from "
            "candidates whose patches match the hole's border, never across a depth edge; filled points are "
            "marked; 0 = off")
      .cli("fill-holes").ros("fill_holes").pass("fill_holes"),
    Entry("reuse_estimates", &P::reuse_estimates)
      .docs("[Estimates carried in a stream](#estimates-carried-in-a-stream)")
      .help("carry the noise profile and the automatic dilation from frame to frame of a stream, estimated "
            "afresh when a sparse check says the sensor's noise or the frame's ranges changed")
      .cli("reuse-estimates").ros("reuse_estimates").pass("reuse_estimates"),
  };
  // clang-format on
}

std::vector<ParameterEntry>
makeRegistry()
{
  std::vector<ParameterEntry> entries = windowAndBandwidthEntries();
  for (ParameterEntry& entry : normalAndMoveEntries())
    entries.push_back(std::move(entry));
  return entries;
}

template <typename T>
[[noreturn]] void
fail(const char* name, T value, const char* requirement)
{
  std::ostringstream msg;
  msg << "range_nlm: parameter " << name << " = " << value << " is invalid: " << requirement;
  throw std::invalid_argument(msg.str());
}

template <typename T>
bool
inRange(const ParameterRange& r, T value)
{
  const double x = static_cast<double>(value);
  if (std::is_floating_point_v<T> && !std::isfinite(x))
    return false;
  if (r.zero_allowed && x == 0.0)
    return true;
  // A bound is compared as the field holds it: a float field's 0.01 is the float nearest 0.01.
  const auto held = [](double bound) {
    return std::is_floating_point_v<T> ? static_cast<double>(static_cast<T>(bound)) : bound;
  };
  const double min = held(r.min), max = held(r.max);
  if (!(r.min_exclusive ? x > min : x >= min) || !(x <= max))
    return false;
  if constexpr (std::is_integral_v<T>)
    return !r.odd || value % 2 != 0;
  return true;
}

template <typename T>
T
parseWhole(const std::string& text, T (*parse)(const std::string&, std::size_t*), const char* expected)
{
  try {
    std::size_t used = 0;
    const T value = parse(text, &used);
    if (used == text.size())
      return value;
  } catch (const std::exception&) {
  }
  throw std::invalid_argument(expected);
}

int
toInt(const std::string& text, std::size_t* used)
{
  return std::stoi(text, used);
}

float
toFloat(const std::string& text, std::size_t* used)
{
  return std::stof(text, used);
}

std::uint64_t
toUnsigned(const std::string& text, std::size_t* used)
{
  if (text.find('-') != std::string::npos)
    throw std::invalid_argument(text);
  return std::stoull(text, used);
}

/// A value for the table: 0 with what it stands for, enumerators in code font.
std::string
tableValue(const ParameterEntry& entry, const FilterParameters& p)
{
  const std::string text = parameterText(entry, p);
  if (!entry.choices.empty())
    return "`" + text + "`";
  if (entry.zero_means && text == "0")
    return "0 (" + std::string(entry.zero_means) + ")";
  return text;
}

std::string
tableValidValues(const ParameterEntry& entry)
{
  if (!entry.choices.empty()) {
    std::string list;
    for (const auto& c : entry.choices)
      list += (list.empty() ? "`" : ", `") + std::string(c.first) + "`";
    return list;
  }
  if (std::holds_alternative<bool FilterParameters::*>(entry.field))
    return "true, false";
  if (!entry.range.requirement)
    return "any";
  const std::string requirement = entry.range.requirement;
  const std::string prefix = "must be ";
  return requirement.compare(0, prefix.size(), prefix) == 0 ? requirement.substr(prefix.size()) : requirement;
}

/// Markdown table cell text: a '|' would end the cell.
std::string
cell(const std::string& text)
{
  std::string out;
  for (const char c : text)
    out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

} // namespace

const std::vector<ParameterEntry>&
parameterRegistry()
{
  static const std::vector<ParameterEntry> registry = makeRegistry();
  return registry;
}

const ParameterEntry*
findParameter(const std::string& name)
{
  for (const ParameterEntry& entry : parameterRegistry())
    if (name == entry.name)
      return &entry;
  return nullptr;
}

void
checkParameter(const ParameterEntry& entry, const FilterParameters& p)
{
  if (!entry.range.requirement)
    return;
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
          if (!inRange(entry.range, p.*member))
            fail(entry.name, p.*member, entry.range.requirement);
        }
      },
      entry.field);
}

bool
isPositive(const ParameterEntry& entry, const FilterParameters& p)
{
  return std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>)
          return p.*member > T(0);
        else
          return false;
      },
      entry.field);
}

std::string
parameterText(const ParameterEntry& entry, const FilterParameters& p)
{
  return std::visit(
      [&](auto member) -> std::string {
        using T = std::decay_t<decltype(p.*member)>;
        const T value = p.*member;
        if constexpr (std::is_enum_v<T>) {
          for (const auto& c : entry.choices)
            if (c.second == static_cast<int>(value))
              return c.first;
          return std::to_string(static_cast<int>(value));
        } else if constexpr (std::is_same_v<T, bool>) {
          return value ? "true" : "false";
        } else {
          std::ostringstream text;
          text << value;
          return text.str();
        }
      },
      entry.field);
}

void
setParameterFromText(const ParameterEntry& entry, FilterParameters& p, const std::string& text)
{
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_enum_v<T>) {
          const int value = choiceValue(entry, text);
          if (value < 0)
            throw std::invalid_argument(choiceList(entry));
          p.*member = static_cast<T>(value);
        } else if constexpr (std::is_same_v<T, bool>) {
          if (text != "true" && text != "false")
            throw std::invalid_argument("true or false");
          p.*member = text == "true";
        } else if constexpr (std::is_same_v<T, int>) {
          p.*member = parseWhole(text, toInt, "an integer");
        } else if constexpr (std::is_same_v<T, float>) {
          p.*member = parseWhole(text, toFloat, "a number");
        } else {
          p.*member = parseWhole(text, toUnsigned, "an integer >= 0");
        }
      },
      entry.field);
}

std::string
choiceList(const ParameterEntry& entry)
{
  std::string list;
  for (std::size_t i = 0; i < entry.choices.size(); ++i) {
    if (i > 0)
      list += i + 1 == entry.choices.size() ? " or " : ", ";
    list += "'" + std::string(entry.choices[i].first) + "'";
  }
  return list;
}

int
choiceValue(const ParameterEntry& entry, const std::string& text)
{
  for (const auto& c : entry.choices)
    if (text == c.first)
      return c.second;
  return -1;
}

void
setChoice(const ParameterEntry& entry, FilterParameters& p, int value)
{
  std::visit(
      [&](auto member) {
        using T = std::decay_t<decltype(p.*member)>;
        if constexpr (std::is_enum_v<T>)
          p.*member = static_cast<T>(value);
        else
          throw std::logic_error(std::string("range_nlm: parameter ") + entry.name + " is not enumerated");
      },
      entry.field);
}

std::string
parameterTable()
{
  const FilterParameters recommended = FilterParameters::recommended(), live = FilterParameters::live(),
                         paper = FilterParameters::paper();
  std::string table = "| field | default | live | paper | unit | valid values | meaning |\n"
                      "|---|---|---|---|---|---|---|\n";
  for (const ParameterEntry& entry : parameterRegistry())
    table += "| `" + std::string(entry.name) + "` | " + tableValue(entry, recommended) + " | " +
             tableValue(entry, live) + " | " + tableValue(entry, paper) + " | " + (*entry.unit ? entry.unit : "-") +
             " | " +
             cell(tableValidValues(entry)) + " | " + cell(entry.help) +
             (entry.docs_section ? std::string("; see ") + entry.docs_section : std::string()) + " |\n";
  return table;
}

} // namespace range_nlm
