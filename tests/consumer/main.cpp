#include <range_nlm/nonlocal_means_filter.h>

#include <cmath>

int
main()
{
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>(16, 16));
  for (int v = 0; v < 16; ++v)
    for (int u = 0; u < 16; ++u)
      cloud->at(u, v) = pcl::PointXYZ(0.01f * u, 0.01f * v, 1.0f + 0.001f * ((u * 7 + v * 3) % 5));
  range_nlm::NonLocalMeansFilter<pcl::PointXYZ> filter;
  filter.setParameters(range_nlm::FilterParameters::paper());
  filter.setInputCloud(cloud);
  pcl::PointCloud<pcl::PointXYZ> out;
  filter.filter(out);
  return out.size() == cloud->size() && std::isfinite(out.at(8, 8).z) ? 0 : 1;
}
