/// \file message_frames.h
/// \brief ROS messages <-> the organized frames the filter works on: sensor_msgs/PointCloud2 of
/// any field layout, and depth images (16UC1 millimetres, 32FC1 metres) with their CameraInfo.
///
/// Every check of a message lives here: a message that cannot be a frame throws InvalidMessage
/// saying what is wrong with it (the caller adds the stamp and drops it).
#pragma once

#include <range_nlm/parameters.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace range_nlm_ros
{

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

/// A message that is not an organized frame (the text says why).
struct InvalidMessage : std::invalid_argument
{
  using std::invalid_argument::invalid_argument;
};

/// x, y, z of an organized PointCloud2 (FLOAT32 or FLOAT64 fields, any other fields alongside)
/// as a width x height cloud; a point with a NaN coordinate becomes NaN in all three.
/// Throws InvalidMessage if the cloud is unorganized (height 1) or empty, lacks a float x, y or
/// z field, a field does not fit point_step, row_step is not width * point_step, data is not
/// row_step * height bytes, its byte order is not the host's, or a coordinate is infinite; if a
/// field name appears twice or has COUNT 0 (as the PCD reader: io::fieldLayoutProblem); and,
/// before a point is decoded, if the cloud is smaller than the smallest window of any parameters
/// (3 x 3) or, given `parameters`, than their windows (FilterParameters::validateFor). Decoded
/// by the threads of `parameters` (FilterParameters::threads), else by OpenMP's default.
Cloud::Ptr
cloudFromPointCloud2(const sensor_msgs::PointCloud2& message, const range_nlm::FilterParameters* parameters = nullptr);

/// A copy of `message` whose x, y, z are those of `xyz` (same size): every other byte, the
/// header and the layout unchanged; is_dense recomputed. Written by `threads` threads (0: OpenMP's
/// default).
sensor_msgs::PointCloud2::Ptr
pointCloud2WithXyz(const sensor_msgs::PointCloud2& message, const Cloud& xyz, int threads = 0);

/// Back-projects a depth image through the pinhole of `info` (K: fx, fy, cx, cy), as
/// range_nlm::depthImageToCloud does: x = (u - cx) z / fx, y = (v - cy) z / fy. 16UC1 values
/// are millimetres, 32FC1 values metres; 0 and NaN mark pixels without depth.
/// Throws InvalidMessage for another encoding, an empty or unorganized image, step != width *
/// bytes per pixel, data of the wrong size, another byte order than the host's, a CameraInfo of
/// another size, or non-positive or non-finite fx, fy.
Cloud::Ptr
cloudFromDepthImage(const sensor_msgs::Image& image, const sensor_msgs::CameraInfo& info);

/// A copy of `image` whose depths are the z of `xyz` (same size), in its encoding: 16UC1
/// round(z * 1000) (as range_nlm::cloudToDepthImage), 32FC1 z. A pixel without a point is 0
/// (16UC1), or keeps the input's invalid value 0 / NaN (32FC1). Throws InvalidMessage if a
/// depth does not fit 16 bits.
sensor_msgs::Image::Ptr
depthImageWithZ(const sensor_msgs::Image& image, const Cloud& xyz);

/// The per-point uncertainty of a filtered frame (range_nlm::FilterParameters::uncertainty;
/// `sigma`, width x height values, row-major) as a 32FC1 image with `header`: metres, NaN where
/// the point is invalid. Throws InvalidMessage if the sizes do not match.
sensor_msgs::Image::Ptr
uncertaintyImage(const std_msgs::Header& header, std::uint32_t width, std::uint32_t height,
                 const std::vector<float>& sigma);
/// The filtered frame of the depth image `image` (with its `info`) as an image like it: each
/// point of `filtered` put on its pixel's ray where the ray meets the plane the filter moved it
/// onto (range_nlm::reprojectOntoRays against the image's own back-projection, the encoding of
/// range_nlm::cloudToDepthImage(input, filtered, ...) and of range_nlm_denoise's PNG output),
/// then encoded as depthImageWithZ does. Throws InvalidMessage as cloudFromDepthImage and
/// depthImageWithZ do.
sensor_msgs::Image::Ptr
filteredDepthImage(const sensor_msgs::Image& image, const sensor_msgs::CameraInfo& info, const Cloud& filtered);

/// True if some point of `cloud` is finite.
bool
hasValidPoint(const Cloud& cloud);

/// "stamp 12.000000345, frame 'camera_depth_optical_frame', seq 7": names a message in logs.
std::string
describe(const std_msgs::Header& header);

} // namespace range_nlm_ros
