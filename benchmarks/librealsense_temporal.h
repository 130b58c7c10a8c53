// librealsense's temporal filter (rs2::temporal_filter), reimplemented as a baseline for the
// temporal comparison of range_nlm_bench: what users of Intel RealSense depth cameras run to
// steady their depth frames.
//
// Follows IntelRealSense/librealsense src/proc/temporal-filter.h and src/proc/temporal-filter.cpp
// as of commit cacc8e701a963a44b49fe51911443797e8b3a517 (master, July 2025; both files last
// changed in a6ed5ce0fbf3f274fe896a92546f394886f21db6, September 2024), Apache-2.0. The kernel
// (TemporalFilter::process) is the Z16 path of temporal_filter::temp_jw_smooth<uint16_t> and
// recalc_persistence_map, statement for statement:
//
// For each pixel, with cur the new depth, prev the pixel's last value (`_last_frame`, 0 before
// the pixel was ever valid) and history the pixel's validity over the last 8 frames (one bit per
// frame, bit `_cur_frame_index` for this frame):
//  - cur != 0, prev == 0: output cur; last = cur; history = this frame's bit only.
//  - cur != 0, |cur - prev| < delta: output and last = uint16(float(alpha * cur + (1 - alpha) *
//    prev)) (float arithmetic, truncated toward zero, as the source's static_cast); history |=
//    this frame's bit.
//  - cur != 0, |cur - prev| >= delta (an edge or a jump): output cur, no smoothing; last = cur;
//    history = this frame's bit only (the older bits are forgotten).
//  - cur == 0 (no measurement), prev != 0: the hole is filled with prev if the persistence map
//    says the history of the previous 8 frames (this frame's bit still holds the frame 8 frames
//    ago) is credible; last is kept; this frame's bit is cleared.
//  - cur == 0, prev == 0: stays 0.
// Then the frame index advances modulo 8. `last` is never reset to 0 by a hole: a pixel once
// valid can be filled as long as its history qualifies.
//
// Persistency modes (RS2_OPTION_HOLES_FILL, "Persistency mode", 0..8, default 3). Over the 8
// frames before this one (t-1 .. t-8), a hole is filled if the pixel was valid in
//   0 "Disabled": never;                  1 "Valid in 8/8": all of t-1 .. t-8;
//   2 "Valid in 2/last 3": 2 of t-1 .. t-3; 3 "Valid in 2/last 4": 2 of t-1 .. t-4;
//   4 "Valid in 2/8": 2 of t-1 .. t-8;    5 "Valid in 1/last 2": 1 of t-1 .. t-2;
//   6 "Valid in 1/last 5": 1 of t-1 .. t-5; 7 "Valid in 1/8": 1 of t-1 .. t-8;
//   8 "Always on": always (once the pixel has had a value).
//
// State is reset (last values and histories to 0; the frame index, as in the source, is not)
// when the frame size changes (the source: a new stream profile, which a restarted stream of the
// same size also is) and by reset() (the source: setting alpha or the persistency mode; setting
// alpha also restarts the frame index, which changes no output once the histories are zero).
//
// Deviations, none of which changes an output value of the Z16 path:
//  - Only depth (Z16) frames, as a program gets that calls the filter on its depth frames. The
//    source also filters disparity frames (float, no truncation): the path of the D400's
//    recommended processing chain (src/ds/ds-device-common.cpp: depth-to-disparity, spatial,
//    temporal, hole filling, back to depth), where delta is in disparity units.
//  - Parameters are fixed per filter object. The source resets the state when alpha or the
//    persistency mode is set; setting delta through its option does not (its callback locks a
//    weak_ptr never assigned, so on_set_delta is not called, though the value is stored).
//  - Point clouds: the cloud adaptor (TemporalFilter::filter) turns z into depth units
//    (round(z / depth_unit); a point whose z rounds to 0 is a hole, as the camera would report
//    it) and the filtered image back into points along each pixel's ray; the source only sees
//    depth images.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <array>
#include <cstdint>
#include <vector>

namespace range_nlm
{
namespace tools
{
namespace librealsense
{

/// The filter's options, with librealsense's names, defaults and ranges.
struct TemporalFilterParameters
{
  /// RS2_OPTION_FILTER_SMOOTH_ALPHA, "Alpha factor of Exp. moving average, 1=no filter,
  /// 0=infinite filter": weight of the new frame in the exponential moving average. [0, 1],
  /// default 0.4.
  float alpha = 0.4f;
  /// RS2_OPTION_FILTER_SMOOTH_DELTA, "Edge-preserving (gradient) threshold": depth units; a new
  /// value differing from the pixel's last one by this much or more is taken as it is (an
  /// edge), not averaged. Integer in [1, 100] (uint8 in the source), default 20.
  int delta = 20;
  /// RS2_OPTION_HOLES_FILL, "Persistency mode": when a hole (depth 0) is filled with the
  /// pixel's last value; see the file comment. [0, 8], default 3 ("Valid in 2/last 4").
  int persistence = 3;
  /// RS2_OPTION_DEPTH_UNITS of the sensor: metres per depth unit, for the cloud adaptor (z in
  /// metres -> depth units). > 0, default 0.001 (the D400 series' millimetres).
  double depth_unit = 0.001;

  /// Throws std::invalid_argument naming the parameter and its value if one is out of range.
  void validate() const;
};

/// One filter per stream: it carries the last value and the 8-frame validity history of every
/// pixel from frame to frame.
class TemporalFilter
{
public:
  /// Throws std::invalid_argument (TemporalFilterParameters::validate).
  explicit TemporalFilter(const TemporalFilterParameters& parameters = {});

  /// Filters a width x height depth image (row-major, depth units, 0 = no measurement) in
  /// place, the next frame of the stream. A size other than the previous frame's resets the
  /// state first. Throws std::invalid_argument for a non-positive size.
  void process(std::uint16_t* depth, int width, int height);

  /// The same on an organized cloud of points in metres (x right, y down, z forward, camera at
  /// the origin; NaN = no measurement): depth = round(z / depth_unit). Each output point is the
  /// filtered depth * depth_unit along the pixel's ray (x and y scaled with z), so a depth not
  /// on the unit grid comes out quantized, as in the camera's Z16 image; a point already at its
  /// depth (unchanged, on the grid) is kept bit for bit; a filled hole lies on the ray the pixel
  /// had when last valid. Holes left are NaN in x, y and z; is_dense is recomputed. Throws std::invalid_argument (naming
  /// the pixel and value, the state left as it was) for an unorganized cloud, a point with a
  /// finite z but a non-finite x or y, or a depth that is negative or above 65535 units (choose
  /// a larger depth_unit).
  pcl::PointCloud<pcl::PointXYZ> filter(const pcl::PointCloud<pcl::PointXYZ>& frame);

  /// Forgets every pixel's last value and history.
  void reset();

  const TemporalFilterParameters& parameters() const { return parameters_; }

  /// recalc_persistence_map: bit p of entry h is set if history byte h, read while this frame's
  /// index is p (so bit p - 1 is the previous frame, bit p the frame 8 frames ago), is credible
  /// under persistency mode `persistence`.
  static std::array<std::uint8_t, 256> persistenceMap(int persistence);

private:
  TemporalFilterParameters parameters_;
  std::array<std::uint8_t, 256> persistence_map_;
  std::vector<std::uint16_t> last_frame_;
  std::vector<std::uint8_t> history_;
  /// Pixel rays (x / z, y / z) of the cloud adaptor, from the frame a pixel was last valid in.
  std::vector<float> ray_x_, ray_y_;
  int width_ = 0, height_ = 0;
  unsigned cur_frame_index_ = 0;
};

} // namespace librealsense
} // namespace tools
} // namespace range_nlm
