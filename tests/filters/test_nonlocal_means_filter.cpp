#include "test_support.h"

#include <range_nlm/nonlocal_means_filter.h>
#include <range_nlm/point_types.h>

#include <pcl/common/transforms.h>
#include <pcl/point_types.h>

#include <boost/preprocessor/seq/enum.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>

using namespace range_nlm;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{
Cloud
filtered(const Cloud& in, const FilterParameters& p)
{
  NonLocalMeansFilter<pcl::PointXYZ> f;
  f.setParameters(p);
  f.setInputCloud(Cloud::ConstPtr(new Cloud(in)));
  Cloud out;
  f.filter(out);
  return out;
}

double
maxDistance(const Cloud& a, const Cloud& b)
{
  double m = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i].z) != std::isnan(b[i].z))
      return INFINITY;
    if (std::isnan(a[i].z))
      continue;
    m = std::max(m, double((a[i].getVector3fMap() - b[i].getVector3fMap()).norm()));
  }
  return m;
}

const Eigen::Vector3d kPlaneNormal(0.2, -0.1, 1.0);
constexpr double kPlaneOffset = 1.5;

Cloud
noisyPlane(double sigma, std::uint64_t seed = 1, int w = 48, int h = 40)
{
  return test::makeCloud(w, h, test::plane(kPlaneNormal, kPlaneOffset), sigma, seed);
}

} // namespace

TEST(NonLocalMeansFilter, MatchesNaiveReferenceOfTheFormula)
{
  Cloud in = test::makeCloud(21, 17, [](double a, double b, int u, int) { return 1.0 + 0.3 * a * a + (u > 12 ? 0.05 : 0.0) + 0.1 * b; },
                             0.003, 4);
  test::punchHoles(in, 0.08, 5);
  const Cloud expected = test::referenceFilter(in, 5, 3, 0.02, 0.003);
  for (Evaluation e : {Evaluation::direct, Evaluation::fast}) {
    FilterParameters p = FilterParameters::paper();
    p.search_window = 5;
    p.patch_size = 3;
    p.distance_bandwidth = 0.02f;
    p.similarity_bandwidth = 0.003f;
    p.evaluation = e;
    const Cloud out = filtered(in, p);
    EXPECT_LT(maxDistance(out, expected), 2e-5) << (e == Evaluation::fast ? "fast" : "direct");
    EXPECT_GT(maxDistance(out, in), 1e-4); // it did move points
  }
}

TEST(NonLocalMeansFilter, NoisyPlaneGetsMuchCloser)
{
  const Cloud in = noisyPlane(0.004);
  const double before = test::planeRmse(in, kPlaneNormal, kPlaneOffset);
  // 4 mm noise at 5 mm pixel spacing: depth-camera conditions.
  const double paper = test::planeRmse(filtered(in, FilterParameters::paper()), kPlaneNormal, kPlaneOffset);
  const double recommended = test::planeRmse(filtered(in, FilterParameters::recommended()), kPlaneNormal, kPlaneOffset);
  EXPECT_LT(paper, 0.75 * before) << before << " -> " << paper;
  EXPECT_LT(recommended, 0.5 * before) << before << " -> " << recommended;
  // Laser-grade noise (a quarter): the literal method works well.
  const Cloud fine = noisyPlane(0.001, 2);
  const double fine_before = test::planeRmse(fine, kPlaneNormal, kPlaneOffset);
  EXPECT_LT(test::planeRmse(filtered(fine, FilterParameters::paper()), kPlaneNormal, kPlaneOffset), 0.5 * fine_before);
}

TEST(NonLocalMeansFilter, ExactPlaneDoesNotMove)
{
  const Cloud in = noisyPlane(0.0);
  for (const FilterParameters& p : {FilterParameters::paper(), FilterParameters::recommended()}) {
    const Cloud out = filtered(in, p);
    EXPECT_LT(maxDistance(out, in), 1e-6);
    for (const auto& q : out)
      EXPECT_TRUE(std::isfinite(q.z));
  }
}

TEST(NonLocalMeansFilter, ZeroBandwidthsDoNotDivideByZero)
{
  const Cloud in = noisyPlane(0.0);
  FilterParameters p = FilterParameters::paper();
  p.similarity_bandwidth = 0.0f; // automatic: estimates ~0 on an exact plane
  NonLocalMeansFilter<pcl::PointXYZ> f;
  f.setParameters(p);
  f.setInputCloud(Cloud::ConstPtr(new Cloud(in)));
  Cloud out;
  f.filter(out);
  EXPECT_LT(f.getEstimatedSimilarityBandwidth(), 1e-6f);
  EXPECT_LT(maxDistance(out, in), 1e-6);
}

namespace
{
/// Mean displacement of the points within two columns of `edge_u`.
double
meanMoveNear(const Cloud& a, const Cloud& b, int edge_u)
{
  double sum = 0;
  int count = 0;
  for (unsigned v = 0; v < a.height; ++v)
    for (int u = edge_u - 2; u <= edge_u + 1; ++u) {
      sum += (a.at(u, v).getVector3fMap() - b.at(u, v).getVector3fMap()).norm();
      ++count;
    }
  return sum / count;
}

void
expectSharperThanBilateral(const Cloud& in, int edge_u)
{
  FilterParameters p = FilterParameters::paper();
  NonLocalMeansFilter<pcl::PointXYZ> f;
  f.setParameters(p);
  f.setInputCloud(Cloud::ConstPtr(new Cloud(in)));
  Cloud nlm;
  f.filter(nlm);
  // Plain bilateral weighting: the same d, similarity weights switched off (Phi_s = 1).
  p.distance_bandwidth = f.getEstimatedDistanceBandwidth();
  p.similarity_bandwidth = 1e6f;
  const Cloud bilateral = filtered(in, p);
  const double nlm_move = meanMoveNear(nlm, in, edge_u);
  const double bilateral_move = meanMoveNear(bilateral, in, edge_u);
  EXPECT_LT(nlm_move, 0.7 * bilateral_move) << nlm_move << " vs " << bilateral_move;
}
} // namespace

TEST(NonLocalMeansFilter, StepEdgeStaysSharp)
{
  expectSharperThanBilateral(test::makeCloud(40, 30, test::step(20, 1.0, 1.03), 0.002, 3), 20);
}

TEST(NonLocalMeansFilter, CreaseStaysSharp)
{
  // Two planes meeting at the centre column (19.5): a ridge.
  expectSharperThanBilateral(test::makeCloud(40, 30, test::crease(20, 1.0, 1.5), 0.002, 3), 20);
}

TEST(NonLocalMeansFilter, ScaleEquivariance)
{
  Cloud in = noisyPlane(0.004, 2);
  test::punchHoles(in, 0.05, 3);
  Cloud scaled = in;
  const float lambda = 1000.0f; // metres -> millimetres
  for (auto& q : scaled)
    q.getVector3fMap() *= lambda;
  // The paper's method is equivariant to float precision. The default adds thresholded
  // decisions (gated normal fits), which float rounding can flip for a borderline neighbour; the
  // result still agrees to a small fraction of the noise.
  for (const FilterParameters& p : {FilterParameters::paper(), FilterParameters::recommended()}) {
    Cloud a = filtered(in, p);
    const Cloud b = filtered(scaled, p);
    for (auto& q : a)
      q.getVector3fMap() *= lambda;
    const bool paper = p.normal_edge_gate == 0.0f;
    EXPECT_LT(maxDistance(a, b), (paper ? 1e-3 : 1e-2) * 0.004 * lambda);
  }
}

TEST(NonLocalMeansFilter, RigidMotionEquivariance)
{
  Cloud in = test::makeCloud(40, 30, test::step(20, 1.0, 1.05), 0.003, 6);
  test::punchHoles(in, 0.05, 7);
  Eigen::Affine3f motion = Eigen::Affine3f::Identity();
  motion.rotate(Eigen::AngleAxisf(0.4f, Eigen::Vector3f(1, 2, 3).normalized()));
  motion.translation() << 0.3f, -0.2f, 0.5f;
  Cloud moved;
  pcl::transformPointCloud(in, moved, motion);
  moved.sensor_origin_ = Eigen::Vector4f(0.3f, -0.2f, 0.5f, 0.0f); // the sensor moves with the data
  for (const FilterParameters& p : {FilterParameters::paper(), FilterParameters::recommended()}) {
    const Cloud a = filtered(in, p);
    Cloud a_moved;
    pcl::transformPointCloud(a, a_moved, motion);
    const Cloud b = filtered(moved, p);
    EXPECT_LT(maxDistance(a_moved, b), 1e-5);
  }
}

TEST(NonLocalMeansFilter, NaNsStayNaNAndNeverContribute)
{
  Cloud in = noisyPlane(0.004, 8);
  test::punchHoles(in, 0.2, 9);
  const Cloud out = filtered(in, FilterParameters::recommended());
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(std::isnan(in[i].x), std::isnan(out[i].x));
    EXPECT_EQ(std::isnan(in[i].y), std::isnan(out[i].y));
    EXPECT_EQ(std::isnan(in[i].z), std::isnan(out[i].z));
  }
  EXPECT_FALSE(out.is_dense);
  // Replacing NaN points by far-away garbage that is then NaN again changes nothing: a NaN point
  // has no influence on its neighbours.
  Cloud other = in;
  for (std::size_t i = 0; i < other.size(); ++i)
    if (std::isnan(in[i].z))
      other[i].x = std::nanf(""), other[i].y = 5.0f, other[i].z = 7.0f; // x NaN: still invalid
  EXPECT_EQ(maxDistance(filtered(other, FilterParameters::recommended()), out), 0.0);
}

TEST(NonLocalMeansFilter, IndicesLimitWhichPointsMove)
{
  const Cloud in = noisyPlane(0.004, 10);
  pcl::IndicesPtr indices(new pcl::Indices);
  for (int i = 0; i < static_cast<int>(in.size()); i += 3)
    indices->push_back(i);
  NonLocalMeansFilter<pcl::PointXYZ> f;
  f.setInputCloud(Cloud::ConstPtr(new Cloud(in)));
  f.setIndices(indices);
  Cloud out;
  // One pass: an indexed point gets exactly the value it gets when every point is filtered.
  f.setParameters(FilterParameters::paper());
  f.filter(out);
  ASSERT_EQ(out.size(), in.size());
  const Cloud all = filtered(in, FilterParameters::paper());
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (i % 3 == 0)
      EXPECT_EQ(out[i].getVector3fMap(), all[i].getVector3fMap());
    else
      EXPECT_EQ(out[i].getVector3fMap(), in[i].getVector3fMap());
  }
  // Several passes (the default): the others still never move.
  f.setParameters(FilterParameters::recommended());
  f.filter(out);
  int moved = 0;
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (i % 3 != 0)
      EXPECT_EQ(out[i].getVector3fMap(), in[i].getVector3fMap());
    else
      moved += out[i].getVector3fMap() != in[i].getVector3fMap();
  }
  EXPECT_GT(moved, static_cast<int>(in.size()) / 4);
  indices->push_back(static_cast<int>(in.size()) + 4);
  f.setIndices(indices);
  EXPECT_NE(test::errorOf([&] { f.filter(out); }).find("outside the cloud"), std::string::npos);
}

TEST(NonLocalMeansFilter, InPlaceEqualsOutOfPlace)
{
  const Cloud in = noisyPlane(0.004, 11);
  const Cloud expected = filtered(in, FilterParameters::recommended());
  Cloud::Ptr cloud(new Cloud(in));
  NonLocalMeansFilter<pcl::PointXYZ> f;
  f.setInputCloud(cloud);
  f.filter(*cloud);
  EXPECT_EQ(maxDistance(*cloud, expected), 0.0);
  EXPECT_EQ(cloud->width, in.width);
  EXPECT_EQ(cloud->height, in.height);
}

TEST(NonLocalMeansFilter, AFilterCalledAgainGivesWhatAFreshFilterGives)
{
  // One filter object and one output cloud for a sequence of clouds of changing sizes (the
  // filter keeps its buffers between calls, the output its points): every result must equal
  // that of a fresh filter into a fresh cloud, colours included.
  using ColourCloud = pcl::PointCloud<pcl::PointXYZRGB>;
  const auto colourCloud = [](int w, int h, std::uint64_t seed) {
    Cloud xyz = test::makeCloud(w, h, test::step(w / 2, 1.0, 1.05), 0.004, seed);
    test::punchHoles(xyz, 0.05, seed + 1);
    ColourCloud c;
    c.width = xyz.width;
    c.height = xyz.height;
    c.resize(xyz.size());
    for (std::size_t i = 0; i < xyz.size(); ++i) {
      c[i].x = xyz[i].x, c[i].y = xyz[i].y, c[i].z = xyz[i].z;
      c[i].r = static_cast<std::uint8_t>(i * 7 + seed), c[i].g = static_cast<std::uint8_t>(i * 3);
      c[i].b = static_cast<std::uint8_t>(seed);
    }
    c.is_dense = false;
    return ColourCloud::ConstPtr(new ColourCloud(c));
  };
  const auto same = [](const ColourCloud& a, const ColourCloud& b) {
    if (a.width != b.width || a.height != b.height || a.size() != b.size() || a.is_dense != b.is_dense)
      return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const bool nan = std::isnan(a[i].z);
      if (nan != std::isnan(b[i].z) || a[i].rgba != b[i].rgba)
        return false;
      if (!nan && (a[i].x != b[i].x || a[i].y != b[i].y || a[i].z != b[i].z))
        return false;
    }
    return true;
  };
  NonLocalMeansFilter<pcl::PointXYZRGB> reused;
  ColourCloud out;
  // 48 x 40, a smaller cloud, 40 x 48 (the first size again, transposed), the first again.
  const std::vector<ColourCloud::ConstPtr> clouds{colourCloud(48, 40, 21), colourCloud(30, 20, 22),
                                                  colourCloud(40, 48, 23), colourCloud(48, 40, 21)};
  for (std::size_t k = 0; k < clouds.size(); ++k) {
    reused.setInputCloud(clouds[k]);
    reused.filter(out);
    NonLocalMeansFilter<pcl::PointXYZRGB> fresh;
    fresh.setInputCloud(clouds[k]);
    ColourCloud expected;
    fresh.filter(expected);
    EXPECT_TRUE(same(out, expected)) << "call " << k;
    std::size_t moved = 0;
    for (std::size_t i = 0; i < out.size(); ++i)
      moved += out[i].z != (*clouds[k])[i].z ? 1 : 0; // NaN compares unequal: holes count too
    std::size_t holes = 0;
    for (const auto& p : *clouds[k])
      holes += std::isnan(p.z) ? 1 : 0;
    EXPECT_GT(moved, holes + out.size() / 2) << "call " << k;
  }
}

TEST(NonLocalMeansFilter, ThreadCountDoesNotChangeOutput)
{
  Cloud in = test::makeCloud(70, 50, test::step(33, 1.0, 1.04), 0.004, 12);
  test::punchHoles(in, 0.1, 13);
  for (std::size_t i : {std::size_t(10) * 70 + 10, std::size_t(30) * 70 + 50}) // isolated outliers too
    if (std::isfinite(in[i].z))
      in[i].getVector3fMap() *= 0.7f;
  for (Evaluation e : {Evaluation::fast, Evaluation::direct}) {
    FilterParameters p = FilterParameters::recommended();
    p.evaluation = e;
    p.threads = 1;
    const Cloud one = filtered(in, p);
    p.threads = 2;
    const Cloud two = filtered(in, p);
    p.threads = 3;
    const Cloud three = filtered(in, p);
    EXPECT_EQ(maxDistance(one, two), 0.0);
    EXPECT_EQ(maxDistance(one, three), 0.0);
  }
}

// The live preset runs the default's kernels with one pass: the windowed evaluation equals the
// direct one on an odd-sized frame with holes, a depth step and its borders, and the thread count
// does not change a bit.
TEST(NonLocalMeansFilter, TheLivePresetMatchesTheDirectEvaluationAndTheThreadCountDoesNotMatter)
{
  Cloud in = test::makeCloud(71, 53, test::step(37, 1.0, 1.06), 0.004, 31);
  test::punchHoles(in, 0.08, 32);
  FilterParameters p = FilterParameters::live();
  p.threads = 2;
  const Cloud fast = filtered(in, p);
  p.evaluation = Evaluation::direct;
  const Cloud direct = filtered(in, p);
  EXPECT_LT(maxDistance(fast, direct), 2e-5);
  EXPECT_GT(maxDistance(fast, in), 1e-3); // it filtered
  p.evaluation = Evaluation::fast;
  for (int threads : {1, 3}) {
    p.threads = threads;
    EXPECT_EQ(maxDistance(filtered(in, p), fast), 0.0) << threads << " threads";
  }
}

TEST(NonLocalMeansFilter, KeepsHeaderPoseAndSizes)
{
  Cloud in = noisyPlane(0.004, 14);
  in.header.frame_id = "camera_depth";
  in.header.stamp = 123456;
  in.sensor_origin_ = Eigen::Vector4f(0.01f, 0.02f, -0.03f, 0.0f);
  in.sensor_orientation_ = Eigen::Quaternionf(0.9f, 0.1f, 0.3f, 0.2f).normalized();
  NonLocalMeansFilter<pcl::PointXYZ> f;
  f.setInputCloud(Cloud::ConstPtr(new Cloud(in)));
  Cloud out;
  f.filter(out);
  EXPECT_EQ(out.header.frame_id, "camera_depth");
  EXPECT_EQ(out.header.stamp, 123456u);
  EXPECT_EQ(out.sensor_origin_, in.sensor_origin_);
  EXPECT_EQ(out.sensor_orientation_.coeffs(), in.sensor_orientation_.coeffs());
  EXPECT_EQ(out.width, in.width);
  EXPECT_EQ(out.height, in.height);
  EXPECT_TRUE(out.is_dense);
  EXPECT_GT(f.getEstimatedDistanceBandwidth(), 0.0f);
  EXPECT_GT(f.getEstimatedSimilarityBandwidth(), 0.0f);
}

TEST(NonLocalMeansFilter, PointsMoveOnlyAlongTheirNormal)
{
  // Each displacement is parallel to the point's estimated normal (no drift along the surface).
  Cloud in = test::makeCloud(40, 30, test::step(20, 1.0, 1.05), 0.004, 15);
  const FilterParameters p = FilterParameters::paper();
  const Cloud out = filtered(in, p);
  const Grid grid = Grid::fromInterleaved(&in[0].x, 40, 30, 4);
  const NormalField normals = estimateNormals(grid, p.normal_window, Viewpoint{0, 0, 0}, 1);
  int checked = 0;
  for (std::size_t i = 0; i < in.size(); ++i) {
    const Eigen::Vector3f d = out[i].getVector3fMap() - in[i].getVector3fMap();
    if (d.norm() < 1e-5f)
      continue;
    const Eigen::Vector3f n(normals.nx[i], normals.ny[i], normals.nz[i]);
    EXPECT_GT(std::fabs(d.normalized().dot(n)), 0.9999f);
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

TEST(NonLocalMeansFilter, BadInputGivesClearErrors)
{
  NonLocalMeansFilter<pcl::PointXYZ> f;
  Cloud out;
  Cloud::Ptr unorganized(new Cloud);
  unorganized->push_back(pcl::PointXYZ(0, 0, 1));
  unorganized->push_back(pcl::PointXYZ(0, 1, 1));
  f.setInputCloud(unorganized);
  EXPECT_NE(test::errorOf([&] { f.filter(out); }).find("not organized"), std::string::npos);

  Cloud::Ptr small(new Cloud(noisyPlane(0.001, 1, 8, 8)));
  f.setInputCloud(small);
  EXPECT_NE(test::errorOf([&] { f.filter(out); }).find("search_window = 9 is larger than the cloud (8 x 8)"),
            std::string::npos);

  Cloud::Ptr cloud(new Cloud(noisyPlane(0.001)));
  f.setInputCloud(cloud);
  f.setSearchWindowSize(4);
  EXPECT_NE(test::errorOf([&] { f.filter(out); }).find("search_window = 4"), std::string::npos);
  f.setSearchWindowSize(7);
  f.setPatchSize(-1);
  EXPECT_NE(test::errorOf([&] { f.filter(out); }).find("patch_size = -1"), std::string::npos);
  f.setPatchSize(5);

  Cloud::Ptr nan_cloud(new Cloud(*cloud));
  for (auto& q : *nan_cloud)
    q.x = q.y = q.z = std::nanf("");
  f.setInputCloud(nan_cloud);
  EXPECT_NE(test::errorOf([&] { f.filter(out); }).find("no valid point"), std::string::npos);

  Cloud::Ptr inf_cloud(new Cloud(*cloud));
  (*inf_cloud)[5].z = INFINITY;
  f.setInputCloud(inf_cloud);
  EXPECT_NE(test::errorOf([&] { f.filter(out); }).find("infinite coordinate at pixel (5, 0)"), std::string::npos);

  // Ranges are measured from the viewpoint: a non-finite one is refused, naming it and its value,
  // and the output is left as it was.
  for (const auto& [bad, text] :
       {std::pair<float, std::string>{INFINITY, "inf"}, {-INFINITY, "-inf"}, {std::nanf(""), "nan"}}) {
    Cloud::Ptr far(new Cloud(*cloud));
    far->sensor_origin_[1] = bad;
    f.setInputCloud(far);
    Cloud kept;
    kept.push_back(pcl::PointXYZ(1, 2, 3));
    const std::string error = test::errorOf([&] { f.filter(kept); });
    EXPECT_NE(error.find("the viewpoint (sensor origin) must be finite, got (0, " + text + ", 0)"), std::string::npos)
        << error;
    ASSERT_EQ(kept.size(), 1u);
    EXPECT_EQ(kept[0].z, 3.0f);
  }
}

// Every instantiated point type: same geometry as PointXYZ, every other field untouched.
template <typename PointT>
class PointTypes : public ::testing::Test
{};
using InstantiatedTypes = ::testing::Types<BOOST_PP_SEQ_ENUM(RANGE_NLM_POINT_TYPES)>;
TYPED_TEST_SUITE(PointTypes, InstantiatedTypes);

namespace
{
template <typename PointT>
void
decorate(PointT&, std::size_t)
{}
void
decorate(pcl::PointXYZI& p, std::size_t i)
{
  p.intensity = float(i % 97);
}
void
decorate(pcl::PointXYZRGB& p, std::size_t i)
{
  p.r = std::uint8_t(i), p.g = std::uint8_t(i * 3), p.b = std::uint8_t(i * 7);
}
void
decorate(pcl::PointXYZRGBA& p, std::size_t i)
{
  p.r = std::uint8_t(i), p.g = std::uint8_t(i * 3), p.b = std::uint8_t(i * 7), p.a = std::uint8_t(i * 11);
}
void
decorate(pcl::PointNormal& p, std::size_t i)
{
  p.normal_x = float(i), p.normal_y = 0.5f, p.normal_z = -1.0f, p.curvature = 0.25f;
}
void
decorate(pcl::PointXYZRGBNormal& p, std::size_t i)
{
  p.rgba = std::uint32_t(i * 2654435761u);
  p.normal_x = float(i), p.normal_y = 0.5f, p.normal_z = -1.0f, p.curvature = 0.25f;
}
} // namespace

TYPED_TEST(PointTypes, FiltersGeometryAndKeepsOtherFields)
{
  Cloud xyz = noisyPlane(0.004, 16, 30, 24);
  test::punchHoles(xyz, 0.1, 17);
  typename pcl::PointCloud<TypeParam>::Ptr in(new pcl::PointCloud<TypeParam>(xyz.width, xyz.height));
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    (*in)[i].x = xyz[i].x, (*in)[i].y = xyz[i].y, (*in)[i].z = xyz[i].z;
    decorate((*in)[i], i);
  }
  in->is_dense = false;
  NonLocalMeansFilter<TypeParam> f;
  f.setInputCloud(in);
  pcl::PointCloud<TypeParam> out;
  f.filter(out);
  const Cloud expected = filtered(xyz, FilterParameters::recommended());
  ASSERT_EQ(out.size(), in->size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    TypeParam ref = (*in)[i];
    ref.x = expected[i].x, ref.y = expected[i].y, ref.z = expected[i].z;
    EXPECT_EQ(std::memcmp(&ref, &out[i], sizeof(TypeParam)), 0) << "point " << i;
  }
  EXPECT_FALSE(out.is_dense);
}

// setNumberOfThreads with an absurd count: the filter refuses it before OpenMP sees it.
TEST(NonLocalMeansFilter, AbsurdThreadCountIsRefusedNotCrashed)
{
  NonLocalMeansFilter<pcl::PointXYZ> f;
  f.setInputCloud(Cloud::Ptr(new Cloud(noisyPlane(0.001))));
  f.setNumberOfThreads(100000);
  Cloud out;
  EXPECT_NE(test::errorOf([&] { f.filter(out); }).find("threads = 100000"), std::string::npos);
}

TEST(NonLocalMeansFilter, IsolatedOutliersAreMovedOntoTheSurfaceAndCounted)
{
  // A noisy plane with three points pushed along their rays 30 % toward the sensor (about
  // 0.45 m): the default moves them back onto the plane (along their rays, then the filter moves
  // them along their normals like every point) and says how many it moved; with
  // outlier_sigmas 0 they stay where they are (no patch resembles theirs).
  const Cloud plane = noisyPlane(0.002, 3);
  Cloud spiky = plane;
  const std::vector<std::size_t> spikes{std::size_t(5) * 48 + 7, std::size_t(20) * 48 + 24, std::size_t(33) * 48 + 40};
  for (std::size_t i : spikes)
    spiky[i].getVector3fMap() *= 0.7f;
  NonLocalMeansFilter<pcl::PointXYZ> f;
  f.setInputCloud(Cloud::ConstPtr(new Cloud(spiky)));
  Cloud out;
  f.filter(out);
  EXPECT_EQ(f.getOutliersMoved(), spikes.size());
  FilterParameters off = FilterParameters::recommended();
  off.outlier_sigmas = 0.0f;
  NonLocalMeansFilter<pcl::PointXYZ> g;
  g.setParameters(off);
  g.setInputCloud(Cloud::ConstPtr(new Cloud(spiky)));
  Cloud kept;
  g.filter(kept);
  EXPECT_EQ(g.getOutliersMoved(), 0u);
  for (std::size_t i : spikes) {
    // On the plane n . p = offset to within the noise, and on its own ray.
    const Eigen::Vector3d n = kPlaneNormal.normalized();
    const double offset = kPlaneOffset / kPlaneNormal.norm();
    EXPECT_LT(std::fabs(n.dot(out[i].getVector3fMap().cast<double>()) - offset), 0.01) << i;
    EXPECT_GT(std::fabs(n.dot(kept[i].getVector3fMap().cast<double>()) - offset), 0.3) << i;
  }
  // The count is the last call's: a frame without outliers gives 0.
  f.setInputCloud(Cloud::ConstPtr(new Cloud(plane)));
  f.filter(out);
  EXPECT_EQ(f.getOutliersMoved(), 0u);
}

TEST(NonLocalMeansFilter, PatchEdgeGateSetterReachesTheFilter)
{
  // A ragged depth step: the default's gated patches move the points beside it differently from
  // patches compared whole; the setter gives what the parameter gives, and an invalid value is
  // refused by name when filtering.
  const auto ragged = [](double, double, int u, int v) { return u < 22 + (v * 37) % 5 ? 1.0 : 1.4; };
  const Cloud in = test::makeCloud(48, 40, ragged, 0.003, 21);
  NonLocalMeansFilter<pcl::PointXYZ> f;
  EXPECT_EQ(f.getPatchEdgeGate(), 18.0f);
  f.setInputCloud(Cloud::ConstPtr(new Cloud(in)));
  Cloud gated, open;
  f.filter(gated);
  f.setPatchEdgeGate(0.0f);
  EXPECT_EQ(f.getPatchEdgeGate(), 0.0f);
  f.filter(open);
  FilterParameters off = FilterParameters::recommended();
  off.patch_edge_gate = 0.0f;
  const Cloud expected = filtered(in, off);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(open[i].z, expected[i].z) << i;
    differ += gated[i].z != open[i].z;
  }
  EXPECT_GT(differ, 40u);
  f.setPatchEdgeGate(-1.0f);
  try {
    f.filter(open);
    ADD_FAILURE() << "a negative patch gate must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("patch_edge_gate"), std::string::npos) << e.what();
  }
}
