#include <range_nlm/parameters.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace range_nlm
{
namespace
{
template <typename T>
[[noreturn]] void
fail(const char* name, T value, const char* requirement)
{
  std::ostringstream msg;
  msg << "range_nlm: parameter " << name << " = " << value << " is invalid: " << requirement;
  throw std::invalid_argument(msg.str());
}

void
checkOddWindow(const char* name, int value)
{
  if (value < 1 || value % 2 == 0)
    fail(name, value, "must be a positive odd number of pixels");
}
} // namespace

void
FilterParameters::validate() const
{
  checkOddWindow("search_window", search_window);
  checkOddWindow("patch_size", patch_size);
  if (dilation < 0)
    fail("dilation", dilation, "must be >= 0 (0 = automatic)");
  if (iterations < 1)
    fail("iterations", iterations, "must be at least 1");
  if (threads < 0 || threads > max_threads)
    fail("threads", threads, "must be 0 (all available) ... 1024");
  if (!(std::isfinite(distance_bandwidth) && distance_bandwidth >= 0.0f))
    fail("distance_bandwidth", distance_bandwidth, "must be finite and >= 0 (0 = automatic)");
  if (!(std::isfinite(similarity_bandwidth) && similarity_bandwidth >= 0.0f))
    fail("similarity_bandwidth", similarity_bandwidth, "must be finite and >= 0 (0 = automatic)");
  if (!(std::isfinite(distance_scale) && distance_scale > 0.0f))
    fail("distance_scale", distance_scale, "must be finite and > 0");
  if (!(std::isfinite(similarity_scale) && similarity_scale > 0.0f))
    fail("similarity_scale", similarity_scale, "must be finite and > 0");
  if (bandwidth_samples < 1)
    fail("bandwidth_samples", bandwidth_samples, "must be at least 1");
  if (normal_window < 3 || normal_window % 2 == 0)
    fail("normal_window", normal_window, "must be an odd number of pixels >= 3");
  if (normal_presmooth_window < 0 || (normal_presmooth_window > 1 && normal_presmooth_window % 2 == 0))
    fail("normal_presmooth_window", normal_presmooth_window, "must be 0 (off) or odd");
  if (!(std::isfinite(normal_edge_gate) && normal_edge_gate >= 0.0f))
    fail("normal_edge_gate", normal_edge_gate, "must be finite and >= 0 (0 = off)");
  if (!(std::isfinite(patch_edge_gate) && patch_edge_gate >= 0.0f))
    fail("patch_edge_gate", patch_edge_gate, "must be finite and >= 0 (0 = off)");
  if (!(line_of_sight_min_cos >= 0.0f && line_of_sight_min_cos <= 1.0f))
    fail("line_of_sight_min_cos", line_of_sight_min_cos, "must be in [0, 1]");
  if (!(std::isfinite(max_displacement) && max_displacement >= 0.0f))
    fail("max_displacement", max_displacement, "must be finite and >= 0 (0 = unlimited)");
  if (!(std::isfinite(outlier_sigmas) && outlier_sigmas >= 0.0f))
    fail("outlier_sigmas", outlier_sigmas, "must be finite and >= 0 (0 = off)");
  if (!(std::isfinite(normal_presmooth_range) && normal_presmooth_range > 0.0f))
    fail("normal_presmooth_range", normal_presmooth_range, "must be finite and > 0");
}

void
FilterParameters::validateFor(int width, int height) const
{
  validate();
  auto fits = [&](const char* name, int window) {
    if (window > width || window > height) {
      std::ostringstream msg;
      msg << "range_nlm: parameter " << name << " = " << window << " is larger than the cloud ("
          << width << " x " << height << ")";
      throw std::invalid_argument(msg.str());
    }
  };
  fits("search_window", search_window);
  fits("patch_size", patch_size);
  fits("normal_window", normal_window);
}

FilterParameters
FilterParameters::paper()
{
  FilterParameters p;
  p.search_window = 7;
  p.patch_size = 5;
  p.iterations = 1;
  p.distance_scale = 0.75f;
  p.similarity_scale = 1.0f;
  p.normal_window = 3;
  p.normal_presmooth_window = 0;
  p.normal_edge_gate = 0.0f;
  p.patch_edge_gate = 0.0f;
  p.bandwidth_model = BandwidthModel::global;
  p.max_displacement = 0.0f;
  p.outlier_sigmas = 0.0f;
  p.displacement = Displacement::normal;
  p.cross_frame_bandwidth = CrossFrameBandwidth::spatial;
  p.patch_guide = false;
  p.dilation = 1;
  return p;
}

FilterParameters
FilterParameters::recommended()
{
  return FilterParameters{};
}

FilterParameters
FilterParameters::preset(const std::string& name)
{
  if (name == "paper")
    return paper();
  if (name == "default")
    return recommended();
  throw std::invalid_argument("range_nlm: unknown preset '" + name + "' (expected 'paper' or 'default')");
}

} // namespace range_nlm
