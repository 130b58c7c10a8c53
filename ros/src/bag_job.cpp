// range_nlm_denoise --input-bag (tools/cli/bag_job.h): the command line of bag mode, the run of
// filterBag with the tool's progress display, and its report. Built only with ROS 1.
#include "cli/bag_job.h"

#include "cli/cli.h"

#include <range_nlm/ros/bag_filter.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>
#include <string>

namespace po = boost::program_options;

namespace range_nlm
{
namespace tools
{
namespace
{

/// The options of a bag run, checked: bag mode takes one topic, one pass and the bag's layout.
range_nlm_ros::BagFilterOptions
bagOptionsFrom(const po::variables_map& vm)
{
  for (const char* other : {"input", "output", "input-dir", "output-dir"})
    if (vm.count(other))
      throw UsageError(std::string("--input-bag cannot be combined with ") +
                       (std::string(other).find("dir") == std::string::npos ? "INPUT/OUTPUT files" : "--input-dir/--output-dir"));
  for (const char* needed : {"input-bag", "output-bag", "topic"})
    if (!vm.count(needed))
      throw UsageError("bag mode needs --input-bag, --output-bag and --topic (missing --" + std::string(needed) + ")");
  for (const char* unsupported : {"pass", "resume", "colorize"})
    if (vm.count(unsupported))
      throw UsageError(std::string("--") + unsupported + " is not supported with --input-bag");
  if (vm["output-format"].as<std::string>() != "auto")
    throw UsageError("--output-format is not supported with --input-bag (the bag keeps the messages' layout)");
  range_nlm_ros::BagFilterOptions options;
  options.input_bag = vm["input-bag"].as<std::string>();
  options.output_bag = vm["output-bag"].as<std::string>();
  options.topic = vm["topic"].as<std::string>();
  options.keep_going = vm.count("keep-going") > 0;
  options.settings.parameters = filterParametersFrom(vm);
  options.settings.temporal_radius = vm["temporal-radius"].as<int>();
  if (options.settings.temporal_radius < 0)
    throw UsageError("--temporal-radius must be >= 0, got " + std::to_string(options.settings.temporal_radius));
  options.settings.window = vm.count("recursive") ? TemporalWindow::recursive
                            : vm.count("causal")  ? TemporalWindow::causal
                                                  : TemporalWindow::centred;
  return options;
}

/// Runs filterBag with the progress display (shown unless `quiet`); a BagError becomes an
/// InputError.
range_nlm_ros::BagFilterReport
filterBagWithProgress(const range_nlm_ros::BagFilterOptions& options, bool quiet)
{
  std::unique_ptr<Progress> progress;
  range_nlm_ros::BagFilterReport report;
  try {
    report = range_nlm_ros::filterBag(options, [&](std::size_t done, std::size_t total) {
      if (!progress)
        progress = std::make_unique<Progress>("range_nlm_denoise", total, options.settings.parameters.iterations,
                                              !quiet);
      progress->update(done);
    });
  } catch (const range_nlm_ros::BagError& e) {
    if (progress)
      progress->finish();
    throw InputError(e.what());
  }
  if (progress)
    progress->finish();
  return report;
}

/// Totals of the filtered topic for the summary.
struct BagTotals
{
  std::size_t unfiltered = 0;
  double filter_ms = 0.0;
};

BagTotals
totalsOf(const range_nlm_ros::BagFilterReport& report)
{
  BagTotals totals;
  for (const auto& frame : report.frames) {
    totals.unfiltered += !frame.unfiltered.empty();
    totals.filter_ms += frame.milliseconds;
  }
  return totals;
}

void
printBagJson(const range_nlm_ros::BagFilterReport& report, const BagTotals& totals, double wall_ms)
{
  nlohmann::json out;
  nlohmann::json invalid = nlohmann::json::array();
  for (const auto& i : report.invalid)
    invalid.push_back({{"message", i.first}, {"error", i.second}});
  out["frames"] = report.frames.size();
  out["unfiltered"] = totals.unfiltered;
  out["invalid"] = invalid;
  out["copied"] = report.copied;
  out["restarts"] = report.restarts;
  out["filter_ms_total"] = totals.filter_ms;
  out["wall_ms"] = wall_ms;
  std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << std::endl;
}

/// A line per message of the topic and one for the bag.
void
printBagLines(const range_nlm_ros::BagFilterOptions& options, const range_nlm_ros::BagFilterReport& report,
              const BagTotals& totals)
{
  for (const auto& frame : report.frames)
    if (frame.unfiltered.empty())
      std::cout << frame.message << ": " << std::fixed << std::setprecision(1) << frame.milliseconds << " ms"
                << std::endl;
    else
      std::cout << frame.message << ": not filtered, written unchanged (" << frame.unfiltered << ")" << std::endl;
  std::cout << options.output_bag << ": " << report.frames.size() << " message(s) of " << options.topic
            << " filtered (" << totals.unfiltered << " unchanged), " << report.copied << " other message(s) copied"
            << std::endl;
}

} // namespace

int
runBagJob(const po::variables_map& vm)
{
  const range_nlm_ros::BagFilterOptions options = bagOptionsFrom(vm);
  const bool quiet = vm.count("quiet") > 0, json = vm.count("json") > 0;
  const auto start = std::chrono::steady_clock::now();
  const range_nlm_ros::BagFilterReport report = filterBagWithProgress(options, quiet || json);
  const BagTotals totals = totalsOf(report);
  if (json)
    printBagJson(report, totals, millisecondsSince(start));
  else if (!quiet)
    printBagLines(options, report, totals);
  if (!report.invalid.empty()) {
    std::cerr << "range_nlm_denoise: " << report.invalid.size() << " message(s) of " << options.topic
              << " are not organized clouds and were copied unchanged:\n";
    for (const auto& i : report.invalid)
      std::cerr << "  " << i.first << ": " << i.second << "\n";
    std::cerr << std::flush;
    return 3;
  }
  return 0;
}

} // namespace tools
} // namespace range_nlm
