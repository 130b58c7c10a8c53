#include <range_nlm/parameters.h>

#include <range_nlm/parameter_registry.h>

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace range_nlm
{
void
FilterParameters::validate() const
{
  for (const ParameterEntry& entry : parameterRegistry())
    checkParameter(entry, *this);
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
  // A dilation k filters the frame's k^2 phases, each about width / k x height / k: the windows
  // must fit those, and the message must name the dilation, not a window that fits the frame.
  const int k = dilation;
  const int window = std::max({search_window, patch_size, normal_window});
  if (k > 1 && (window > width / k || window > height / k)) {
    std::ostringstream msg;
    msg << "range_nlm: parameter dilation = " << k << " splits the cloud (" << width << " x " << height
        << ") into phases of " << width / k << " x " << height / k << " pixels, smaller than the " << window
        << "-pixel windows; lower the dilation (0 = automatic)";
    throw std::invalid_argument(msg.str());
  }
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
  p.similarity_spread = 0.0f;
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
  p.scales = 1;
  return p;
}

FilterParameters
FilterParameters::live()
{
  // One pass with the default's 7x7 gated normals on a 7x7 pre-smoothed copy (5x5 windows lose
  // most of the lead over FastBilateralFilter at strong noise; docs/method.md, "The live preset"),
  // the sensor's estimates carried from frame to frame in a stream, and a 3x3 search in a
  // stream's history (its weight scaled to stand for the whole window).
  FilterParameters p;
  p.iterations = 1;
  p.reuse_estimates = true;
  p.temporal_search_window = 3;
  // s from the frame's patch spread sharpens the default's two passes; one pass needs the wider
  // s (measured, --real-noise: kinect x1 flat RMSE 1.88 with it against 1.75 mm without).
  p.similarity_spread = 0.0f;
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
  if (name == "live")
    return live();
  throw std::invalid_argument("range_nlm: unknown preset '" + name + "' (expected 'default', 'live' or 'paper')");
}

} // namespace range_nlm
