// Every writer against every kind of output (tests/support/output_targets.h): PCD
// (range_nlm_denoise), depth PNG, uncertainty PFM, render PNG, range_nlm_bench --json-file and
// the Slurm scripts' write_output. Each follows the rules of io::detail::OutputFile: links
// followed, FIFOs and character devices written in place, directories, paths ending in '/' and
// sockets refused by name, a full device named with the system's reason and no file left. (The
// bag writer: tests/ros/test_bag_output.cpp.)
#include "output_targets.h"
#include "test_support.h"

#include "cli/frame_output.h"

#include <range_nlm/eval/render.h>
#include <range_nlm/io/depth_image.h>
#include <range_nlm/io/pcd_file.h>

#include <gtest/gtest.h>

#include <string>
#include <vector>

using namespace range_nlm;
using namespace range_nlm::test;

namespace
{

/// A writer called in this process: the message of what it throws.
WriteOutcome
called(const std::function<void()>& write)
{
  try {
    write();
  } catch (const std::exception& e) {
    return {false, e.what()};
  }
  return {true, ""};
}

WriteOutcome
ran(const CommandResult& r)
{
  return {r.status == 0, r.output};
}

class WriterMatrix : public OutputTargets, public ::testing::WithParamInterface<const char*>
{
protected:
  void SetUp() override
  {
    OutputTargets::SetUp();
    if (std::string(GetParam()) == "PcdFromDenoise")
      io::saveCloudAtomic(path("in.pcd"), makeCloud(64, 48, plane({0.1, 0.0, 1.0}, 1.0), 0.002, 4));
  }

  Writer writer() const
  {
    const std::string name = GetParam();
    const std::string input = path("in.pcd");
    if (name == "PcdFromDenoise")
      return {name, [input](const std::string& out) { return ran(runDenoise(input + " " + out + " -q --overwrite")); }};
    if (name == "DepthPng")
      return {name, [](const std::string& out) {
                return called([&] {
                  saveDepthPng(out, makeCloud(32, 24, plane({0.1, 0.0, 1.0}, 1.0), 0.002, 3), 1000.0);
                });
              }};
    if (name == "UncertaintyPfm")
      return {name, [](const std::string& out) {
                return called([&] {
                  const std::vector<float> values{0.5f, 1.0f, 1.5f, 2.0f, 2.5f, 3.0f};
                  tools::writeFloatImage(out, values, 3, 2);
                });
              }};
    if (name == "RenderPng")
      return {name, [](const std::string& out) { return called([&] { saveRgbPng(out, RgbImage(5, 4, {10, 20, 30})); }); }};
    if (name == "BenchJson")
      return {name, [](const std::string& out) {
                return ran(runTool("range_nlm_bench", "--uncertainty-calibration --quality-size 64x48 -q --json-file " +
                                                          out));
              }};
    // SlurmRecord: scripts/slurm/output_file.sh, as submit.sh writes its submission record.
    return {name, [](const std::string& out) {
              return ran(runCommand("printf 'in_dir=/data\\nshards=4\\n' | bash -c '. " +
                                    std::string(RANGE_NLM_SOURCE_DIR) +
                                    "/scripts/slurm/output_file.sh && write_output \"$0\"' " + out));
            }};
  }
};

INSTANTIATE_TEST_SUITE_P(Writers, WriterMatrix,
                         ::testing::Values("PcdFromDenoise", "DepthPng", "UncertaintyPfm", "RenderPng", "BenchJson",
                                           "SlurmRecord"),
                         [](const ::testing::TestParamInfo<const char*>& info) { return std::string(info.param); });

TEST_P(WriterMatrix, SymbolicLinksAreFollowedAndStayLinks)
{
  expectLinksFollowed(writer());
}

TEST_P(WriterMatrix, FifoIsWrittenInPlace)
{
  expectFifoWrittenInPlace(writer());
}

TEST_P(WriterMatrix, CharacterDeviceIsWrittenInPlace)
{
  expectDeviceWrittenInPlace(writer());
}

TEST_P(WriterMatrix, DirectorySocketAndTrailingSlashAreRefused)
{
  expectRefused(writer());
}

TEST_P(WriterMatrix, FullDeviceIsNamedAndLeftAsItWas)
{
  expectFullDeviceNamed(writer());
}

} // namespace
