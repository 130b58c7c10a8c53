#include "peers.h"

#include <pcl/search/kdtree.h>

#include <cmath>

namespace range_nlm
{
namespace tools
{
namespace bench
{

std::shared_ptr<pcl::FastBilateralFilterOMP<pcl::PointXYZ>>
makeFastBilateral(float sigma_s, float sigma_r, unsigned threads)
{
  auto filter = std::make_shared<pcl::FastBilateralFilterOMP<pcl::PointXYZ>>(threads);
  filter->setSigmaS(sigma_s);
  filter->setSigmaR(sigma_r);
  return filter;
}

std::shared_ptr<pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointXYZ>>
makeMovingLeastSquares(double radius, unsigned threads)
{
  auto mls = std::make_shared<pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointXYZ>>();
  mls->setPolynomialOrder(2);
  mls->setSearchRadius(radius);
  mls->setComputeNormals(false);
  mls->setNumberOfThreads(threads);
  return mls;
}

void
setMlsInput(pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointXYZ>& mls,
            const pcl::PointCloud<pcl::PointXYZ>::ConstPtr& cloud)
{
  auto finite = std::make_shared<pcl::Indices>();
  finite->reserve(cloud->size());
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const pcl::PointXYZ& q = (*cloud)[i];
    if (std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z))
      finite->push_back(static_cast<pcl::index_t>(i));
  }
  mls.setInputCloud(cloud);
  mls.setIndices(finite);
  mls.setSearchMethod(std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>());
}

} // namespace bench
} // namespace tools
} // namespace range_nlm
