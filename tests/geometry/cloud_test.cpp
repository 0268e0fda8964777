// Point clouds: the XYZ/CSV and PLY readers (round trips, every format, and malformed input refused
// with the file, the line or byte and what was expected), the drop frame, and the spatial indexes
// against brute force.
#include "geometry/cloud_bins.hpp"
#include "geometry/cloud_kdtree.hpp"
#include "geometry/cloud_outliers.hpp"
#include "geometry/cloud_reader.hpp"
#include "geometry/cloud_voxel_map.hpp"
#include "geometry/cloud_writer.hpp"
#include "geometry/point_cloud.hpp"
#include "support/input_error.hpp"

#include <Eigen/LU>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>

namespace {

using namespace drom::geometry;

PointCloud random_cloud(int n, unsigned seed, bool normals) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-50, 50);
  PointCloud c;
  c.origin = "random";
  for (int i = 0; i < n; ++i) {
    c.points.emplace_back(u(rng), u(rng), 0.2 * u(rng));
    if (normals) c.normals.push_back(Eigen::Vector3d(u(rng), u(rng), u(rng) + 60).normalized());
  }
  return c;
}

// The message of the InputError `f` throws (fails the test if it does not throw one).
template <class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const drom::InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not an InputError: " << e.what();
    return {};
  }
  ADD_FAILURE() << "no error";
  return {};
}

#define EXPECT_ERROR(call, fragment)                                     \
  do {                                                                   \
    const std::string message = error_of([&] { (void)(call); });         \
    EXPECT_NE(message.find(fragment), std::string::npos) << message;     \
  } while (0)

TEST(CloudReader, PlyRoundTripsInBinaryAndAscii) {
  const PointCloud c = random_cloud(500, 1, true);
  for (const bool binary : {true, false}) {
    const std::string bytes = ply_bytes(c, {{"packet", std::vector<double>(500, 3), true}}, binary);
    const PointCloud back = parse_ply(bytes, "round.ply");
    ASSERT_EQ(back.size(), c.size());
    ASSERT_TRUE(back.has_normals());
    for (std::size_t i = 0; i < c.size(); ++i) {
      EXPECT_EQ(back.points[i], c.points[i]);  // %.17g and binary doubles are exact
      EXPECT_NEAR((back.normals[i] - c.normals[i]).norm(), 0, 1e-15);
    }
  }
}

TEST(CloudReader, ReadsBigEndianFloatPlyWithFacesBeforeTheVertices) {
  // A face list element first (it must be skipped record by record), float vertices, big-endian.
  std::string bytes = "ply\nformat binary_big_endian 1.0\ncomment made by hand\nelement face 2\nproperty list uchar int vertex_indices\n"
                      "element vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nend_header\n";
  const auto put_be = [&](const void* data, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < n; ++k) bytes.push_back(static_cast<char>(b[n - 1 - k]));
  };
  for (int face = 0; face < 2; ++face) {
    bytes.push_back(3);
    for (int k = 0; k < 3; ++k) {
      const std::int32_t v = k;
      put_be(&v, 4);
    }
  }
  const float vertices[2][3] = {{1.5f, -2.0f, 3.25f}, {0.0f, 0.5f, -1.0f}};
  for (const auto& v : vertices) {
    for (const float x : v) put_be(&x, 4);
    bytes.push_back(static_cast<char>(200));
  }
  const PointCloud c = parse_ply(bytes, "big.ply");
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.points[0], Eigen::Vector3d(1.5, -2.0, 3.25));
  EXPECT_EQ(c.points[1], Eigen::Vector3d(0.0, 0.5, -1.0));
  EXPECT_FALSE(c.has_normals());
}

TEST(CloudReader, ReadsXyzAndCsvWithHeadersCommentsAndNormals) {
  const PointCloud a = parse_xyz("# scan\n1 2 3\n4\t5\t6\n\n7 8 9\n", "a.xyz");
  ASSERT_EQ(a.size(), 3u);
  EXPECT_EQ(a.points[1], Eigen::Vector3d(4, 5, 6));
  const PointCloud b = parse_xyz("x,y,z,intensity\r\n1.5,-2,3e1,17\r\n+4,5,6,0\r\n", "b.csv");
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b.points[0], Eigen::Vector3d(1.5, -2, 30));
  const PointCloud c = parse_xyz("0 0 0 0 0 1\n1 0 0 0 0.6 0.8\n", "c.xyz");
  ASSERT_TRUE(c.has_normals());
  EXPECT_NEAR(c.normals[1].y(), 0.6, 1e-15);
  const PointCloud d = parse_xyz("nz;x;ny;y;nx;z\n1;10;0;20;0;30\n", "d.txt");
  EXPECT_EQ(d.points[0], Eigen::Vector3d(10, 20, 30));
  EXPECT_EQ(d.normals[0], Eigen::Vector3d(0, 0, 1));
  // A file on disk, scaled (the seed's 7/20).
  const auto path = std::filesystem::temp_directory_path() / "drom_cloud_test.xyz";
  std::ofstream(path) << "20 40 0\n";
  EXPECT_NEAR(read_cloud(path, 7.0 / 20).points[0].x(), 7, 1e-12);
  std::filesystem::remove(path);
}

TEST(CloudReader, RefusesMalformedInputNamingWhereAndWhat) {
  EXPECT_ERROR(parse_xyz("", "empty.xyz"), "empty.xyz: the cloud has no point");
  EXPECT_ERROR(parse_xyz("# only a comment\n", "c.xyz"), "no point");
  const CloudReadOptions strict{.not_finite_is_error = true};
  EXPECT_ERROR(parse_xyz("1 2 3\n4 nan 6\n", "n.xyz", strict), "n.xyz: line 2: column 2: 'nan' is not a finite number");
  EXPECT_ERROR(parse_xyz("1 2 3\n4 5 inf\n", "i.xyz", strict), "line 2: column 3");
  EXPECT_ERROR(parse_xyz("1 2 3\n4 5\n", "short.xyz"), "short.xyz: line 2: expected 3 columns");
  EXPECT_ERROR(parse_xyz("1 2\n", "two.xyz"), "expected at least 3 columns");
  EXPECT_ERROR(parse_xyz("1 2 3\n4 5 abc\n", "word.xyz"), "line 2: column 3: expected a number, found 'abc'");
  EXPECT_ERROR(parse_xyz("1 2 0x3\n", "hex.xyz"), "expected a number");
  EXPECT_ERROR(parse_xyz("a,b,c\n1,2,3\n", "names.csv"), "names.csv: line 1: a header line must name the columns x, y and z");
  EXPECT_ERROR(parse_xyz("x y z nx ny\n", "half.xyz"), "nx, ny and nz are named together");
  EXPECT_ERROR(parse_xyz("1 2 3 255 0 0\n", "rgb.xyz"), "columns 4-6 are not a unit normal");
  EXPECT_ERROR(parse_xyz("x y z nx ny nz\n0 0 0 0 0 0\n", "zero.xyz"), "line 2: the normal (0.000000, 0.000000, 0.000000) has no direction");
  EXPECT_ERROR(parse_xyz(std::string("1 2 3\n4 5 \0 6\n", 13), "nul.xyz"), "line 2: a NUL byte");
  EXPECT_ERROR(read_cloud("/nonexistent/cloud.ply"), "/nonexistent/cloud.ply: cannot open");
  EXPECT_ERROR(read_cloud("/dev/null"), "/dev/null: the cloud file is empty");

  const std::string head = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n";
  EXPECT_ERROR(parse_ply(head + "end_header\n1 2\n3 4\n", "noz.ply"), "noz.ply: line 3: the vertex element has no property 'z'");
  EXPECT_ERROR(parse_ply(head + "property float z\n", "noend.ply"), "noend.ply: the PLY header has no 'end_header' line");
  EXPECT_ERROR(parse_ply(head + "property float z\nend_header\n1 2 3\n", "trunc.ply"), "trunc.ply: line 9: the data ends after 1 of the 2 'vertex' elements");
  EXPECT_ERROR(parse_ply(head + "property float z\nend_header\n1 2 3\n1 nan 3\n", "nan.ply", strict), "nan.ply: line 9: vertex 1 has a coordinate that is not a finite number");
  EXPECT_ERROR(parse_ply(head + "property float z\nend_header\n1 2 3 4\n1 2 3\n", "extra.ply"), "extra.ply: line 8: 'vertex' 0: 1 values more");
  EXPECT_ERROR(parse_ply(head + "property quaternion z\nend_header\n", "type.ply"), "type.ply: line 6: unknown property type 'quaternion'");
  EXPECT_ERROR(parse_ply("ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty double x\nproperty double y\nproperty double z\nend_header\n" +
                             std::string(48, '\0'),
                         "huge.ply"),
               "huge.ply: byte 127: 1000000000 vertices of at least 24 bytes declared, but only 48 bytes follow the header");
  EXPECT_ERROR(parse_ply("ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\nend_header\n" +
                             std::string(30, '\0'),
                         "cut.ply"),
               "cut.ply: byte 118: 2 vertices of at least 24 bytes declared, but only 30 bytes follow the header");
  EXPECT_ERROR(parse_ply("ply\nformat ascii 1.0\nelement vertex 99999999999999999999\n", "count.ply"), "count.ply: line 3: element count");
  EXPECT_ERROR(parse_ply("ply\nformat ascii 1.0\nend_header\n", "novertex.ply"), "declares no 'vertex' element");
  EXPECT_ERROR(parse_ply("ply\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n", "nofmt.ply"), "no 'format' line");
  EXPECT_ERROR(parse_ply("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n", "zero.ply"), "zero.ply: the cloud has no point");
  EXPECT_ERROR(parse_cloud("plywood 1 2\n", "notply.xyz"), "notply.xyz: line 1: column 1: expected a number, found 'plywood'");
}

namespace {

// How many of the file's proper prefixes parse_cloud refuses with an InputError (all should).
int refused_prefixes(const std::string& full, const std::string& origin) {
  int errors = 0;
  for (std::size_t n = 0; n < full.size(); ++n) {
    try {
      parse_cloud(std::string_view(full).substr(0, n), origin);
    } catch (const drom::InputError&) {
      ++errors;
    }
  }
  return errors;
}

}  // namespace

TEST(CloudReader, TruncationsOfAValidFileNeverCrash) {
  // Every prefix of a valid binary PLY with a list element: an error (or, at the full length, the cloud).
  PointCloud c = random_cloud(20, 2, true);
  const std::string full = ply_bytes(c, {{"id", std::vector<double>(20, 1), true}}, true);
  EXPECT_EQ(refused_prefixes(full, "prefix.ply"), static_cast<int>(full.size()));
  EXPECT_EQ(parse_cloud(full, "full.ply").size(), 20u);
}

// Issue 44: a PLY whose header counts the vertices wrong, either way, is refused naming where; the
// scanner's "no return" points (NaN, Inf) are dropped and counted unless asked to be errors.
TEST(CloudReader, VertexCountsThatDoNotMatchTheDataAreErrorsBothWays) {
  const PointCloud c = random_cloud(20, 3, false);
  for (const bool binary : {false, true}) {
    const std::string bytes = ply_bytes(c, {}, binary);
    const auto count_at = bytes.find("element vertex 20");
    ASSERT_NE(count_at, std::string::npos);
    std::string fewer = bytes, more = bytes;
    fewer.replace(count_at, 17, "element vertex 19");  // declares 19 of the 20 points the file holds
    more.replace(count_at, 17, "element vertex 21");   // declares one point the file does not hold
    const std::string short_count = error_of([&] { parse_ply(fewer, "fewer.ply"); });
    EXPECT_NE(short_count.find("fewer.ply: "), std::string::npos) << short_count;
    EXPECT_NE(short_count.find("after the 19 vertices the header declares (line 4)"), std::string::npos) << short_count;
    if (!binary) { EXPECT_NE(short_count.find("line " + std::to_string(std::count(bytes.begin(), bytes.end(), '\n'))), std::string::npos) << short_count; }
    const std::string long_count = error_of([&] { parse_ply(more, "more.ply"); });
    EXPECT_NE(long_count.find("more.ply: "), std::string::npos) << long_count;
    EXPECT_NE(long_count.find(binary ? "21 vertices of at least 24 bytes declared, but only 480 bytes follow the header" : "the data ends after 20 of the 21 'vertex' elements"),
              std::string::npos)
        << long_count;
    EXPECT_EQ(parse_ply(bytes, "right.ply").size(), 20u);
  }
}

TEST(CloudReader, PointsThatAreNotFiniteAreDroppedAndCounted) {
  const PointCloud xyz = parse_xyz("1 2 3\n4 nan 6\n7 8 9\ninf 0 0\n", "scan.xyz");
  ASSERT_EQ(xyz.size(), 2u);
  EXPECT_EQ(xyz.points[1], Eigen::Vector3d(7, 8, 9));
  EXPECT_EQ(xyz.dropped.not_finite, 2u);
  EXPECT_NE(xyz.dropped.first_not_finite.find("scan.xyz: line 2: column 2: 'nan' is not a finite number"), std::string::npos) << xyz.dropped.first_not_finite;
  PointCloud c = random_cloud(30, 4, true);
  c.points[7].y() = std::numeric_limits<double>::quiet_NaN();
  c.normals[12].z() = std::numeric_limits<double>::infinity();
  for (const bool binary : {false, true}) {
    const PointCloud back = parse_ply(ply_bytes(c, {}, binary), "scan.ply");
    ASSERT_EQ(back.size(), 28u);
    EXPECT_EQ(back.dropped.not_finite, 2u);
    EXPECT_EQ(back.points[7], c.points[8]);
    EXPECT_NE(back.dropped.first_not_finite.find("vertex 7 has a coordinate that is not a finite number"), std::string::npos) << back.dropped.first_not_finite;
    const std::string strict = error_of([&] { parse_ply(ply_bytes(c, {}, binary), "scan.ply", {.not_finite_is_error = true}); });
    EXPECT_NE(strict.find("vertex 7 has a coordinate that is not a finite number"), std::string::npos) << strict;
  }
}

// The far-outlier rule (geometry/cloud_outliers.hpp) on clouds it was not tuned to: a regular grid
// (its MAD is 0: the floor of ten spacings must keep its edges and corners), noisy random samples of a
// sphere and of a bumpy sheet at several densities; then the same clouds with stray points added
// metres away and two part widths aside.
TEST(CloudOutliers, StrayPointsFarFromTheScanAreFoundAndNothingElse) {
  std::mt19937 rng(44);
  std::normal_distribution<double> noise(0, 0.02);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<PointCloud> clouds;
  PointCloud grid;
  for (int i = 0; i < 60; ++i)
    for (int j = 0; j < 40; ++j) grid.points.emplace_back(0.5 * i, 0.5 * j, 0);
  clouds.push_back(grid);
  for (const int n : {2000, 20000}) {
    PointCloud sphere, sheet;
    for (int k = 0; k < n; ++k) {
      const double z = 2 * u(rng) - 1, phi = 2 * std::acos(-1.0) * u(rng), r = std::sqrt(1 - z * z);
      sphere.points.push_back((40 + noise(rng)) * Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z));
      const double x = 200 * u(rng), y = 120 * u(rng);
      sheet.points.emplace_back(x, y, 5 * std::sin(x / 15) * std::cos(y / 20) + noise(rng));
    }
    clouds.push_back(sphere);
    clouds.push_back(sheet);
  }
  for (PointCloud& cloud : clouds) {
    EXPECT_TRUE(find_far_outliers(cloud).indices.empty()) << cloud.size() << " points";
    const std::size_t n = cloud.size();
    const Box3 box = bounding_box(cloud.points);
    cloud.points.push_back(box.hi + Eigen::Vector3d(0, 0, 5000));                    // 5 m above the part
    cloud.points.push_back(box.centre() + Eigen::Vector3d(3 * box.size().x(), 0, 0));  // two part widths aside
    const FarOutliers found = find_far_outliers(cloud);
    EXPECT_EQ(found.indices, (std::vector<std::size_t>{n, n + 1})) << n << " points: threshold " << found.threshold_mm << " mm, spacing " << found.median_mm;
    remove_points(cloud, found.indices);
    EXPECT_EQ(cloud.size(), n);
  }
  // No spacing to measure against: a handful of points, or a grid written ten times over (median d8 = 0).
  PointCloud few;
  for (int k = 0; k < 6; ++k) few.points.emplace_back(k, 0, k == 5 ? 5000 : 0);
  EXPECT_TRUE(find_far_outliers(few).indices.empty());
  PointCloud stacked;
  for (int copy = 0; copy < 10; ++copy) stacked.points.insert(stacked.points.end(), grid.points.begin(), grid.points.end());
  stacked.points.emplace_back(0, 0, 5000);
  EXPECT_TRUE(find_far_outliers(stacked).indices.empty());
}

TEST(PointCloud, FrameAlongTurnsTheAxisOntoZ) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  for (int k = 0; k < 200; ++k) {
    Eigen::Vector3d axis(g(rng), g(rng), g(rng));
    if (k == 0) axis = Eigen::Vector3d::UnitX();
    if (k == 1) axis = -Eigen::Vector3d::UnitZ();
    const Eigen::Matrix3d q = frame_along(axis);
    EXPECT_NEAR((q * axis.normalized() - Eigen::Vector3d::UnitZ()).norm(), 0, 1e-14);
    EXPECT_NEAR((q * q.transpose() - Eigen::Matrix3d::Identity()).norm(), 0, 1e-14);
    EXPECT_NEAR(q.determinant(), 1, 1e-14);
  }
}

TEST(CloudBins, QueriesAgreeWithBruteForce) {
  const PointCloud c = random_cloud(20000, 4, false);
  for (const double cell : {0.3, 1.7, 25.0}) {
    const CloudBins bins(c.points, cell);
    const CloudKdTree tree(c.points, 2);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-60, 60), r(0.1, 30);
    std::vector<int> a, b;
    for (int q = 0; q < 300; ++q) {
      const double x = u(rng), y = u(rng), radius = r(rng), z = 0.2 * u(rng);
      double top = -std::numeric_limits<double>::infinity();
      bool above = false;
      std::vector<int> brute;
      for (std::size_t i = 0; i < c.size(); ++i) {
        const double dx = c.points[i].x() - x, dy = c.points[i].y() - y, d2 = dx * dx + dy * dy;
        if (d2 <= radius * radius) {
          top = std::max(top, c.points[i].z());
          brute.push_back(static_cast<int>(i));
        }
        if (d2 < radius * radius && c.points[i].z() > z) above = true;
      }
      EXPECT_EQ(bins.max_z_within(x, y, radius), top);
      // With a floor: the larger of it and the highest point, whichever blocks it let the query skip.
      EXPECT_EQ(bins.max_z_within(x, y, radius, z), std::max(top, z));
      EXPECT_EQ(bins.any_above(x, y, radius, z), above);
      bins.within(x, y, radius, a);
      std::sort(a.begin(), a.end());
      EXPECT_EQ(a, brute);
      tree.within(Eigen::Vector3d(x, y, 0), radius, b);
      std::sort(b.begin(), b.end());
      EXPECT_EQ(b, brute);
    }
  }
}

TEST(CloudKdTree, NearestNeighboursAgreeWithBruteForce) {
  const PointCloud c = random_cloud(5000, 6, false);
  const CloudKdTree tree(c.points, 3);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-60, 60);
  std::vector<int> found;
  std::vector<double> d2;
  for (int q = 0; q < 100; ++q) {
    const Eigen::Vector3d p(u(rng), u(rng), 0.2 * u(rng));
    std::vector<std::pair<double, int>> all;
    for (std::size_t i = 0; i < c.size(); ++i) all.emplace_back((c.points[i] - p).squaredNorm(), static_cast<int>(i));
    std::sort(all.begin(), all.end());
    tree.nearest(p, 8, found, d2);
    ASSERT_EQ(found.size(), 8u);
    for (int k = 0; k < 8; ++k) EXPECT_NEAR(d2[static_cast<std::size_t>(k)], all[static_cast<std::size_t>(k)].first, 1e-9);
    EXPECT_EQ(tree.nearest(p), all[0].second);
  }
}

TEST(CloudVoxelMap, BarycentresAndPlaneNormalsOfItsVoxels) {
  // A tilted plane sampled densely: every full voxel's barycentre lies on it, and its least-squares
  // normal is the plane's (up to sign).
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.2, 1).normalized();
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 200; ++i)
    for (int j = 0; j < 200; ++j) {
      const double x = 0.05 * i + 0.013, y = 0.05 * j + 0.007;
      points.emplace_back(x, y, (5 - n.x() * x - n.y() * y) / n.z());
    }
  const CloudVoxelMap map(points, 1.0);
  const auto voxels = map.voxels();
  ASSERT_GT(voxels.size(), 100u);
  int counted = 0;
  for (const auto& v : voxels) {
    counted += v.count;
    EXPECT_NEAR(n.dot(v.barycentre), 5, 1e-9);
    if (v.count >= 20) {
      EXPECT_NEAR(std::abs(v.normal.dot(n)), 1, 1e-9);
    }
    EXPECT_TRUE(map.full(v.barycentre));
  }
  EXPECT_EQ(counted, 40000);
  EXPECT_EQ(map.full_voxels(), voxels.size());
  EXPECT_FALSE(map.full(Eigen::Vector3d(100, 100, 100)));
}

}  // namespace

// ---- PCD (issue 45): an encoder of the test's own, apart from the reader ---------------------

namespace {

// liblzf's format, greedy, brute-force matches within a 1 KiB window: a compressor the reader's
// decompressor shares nothing with.
std::string lzf_compress(const std::string& in) {
  std::string out, literal;
  auto flush = [&] {
    for (std::size_t k = 0; k < literal.size(); k += 32) {
      const std::string run = literal.substr(k, 32);
      out.push_back(static_cast<char>(run.size() - 1));
      out += run;
    }
    literal.clear();
  };
  for (std::size_t i = 0; i < in.size();) {
    std::size_t best = 0, best_back = 0;
    for (std::size_t back = 1; back <= std::min<std::size_t>(i, 1024); ++back) {
      std::size_t n = 0;
      while (i + n < in.size() && n < 264 && in[i + n] == in[i + n - back]) ++n;
      if (n > best) best = n, best_back = back;
    }
    if (best < 3) {
      literal.push_back(in[i++]);
      continue;
    }
    flush();
    const std::size_t len = best - 2, off = best_back - 1;
    if (len < 7) {
      out.push_back(static_cast<char>((len << 5) | (off >> 8)));
    } else {
      out.push_back(static_cast<char>((7u << 5) | (off >> 8)));
      out.push_back(static_cast<char>(len - 7));
    }
    out.push_back(static_cast<char>(off & 0xff));
    i += best;
  }
  flush();
  return out;
}

enum class Pcd { ascii, binary, compressed };

// The cloud as PCD with an rgb field (U4) and a 3-value padding field between x, y, z and the
// normals, as PCL's PointXYZRGBNormal lays them out; float64 coordinates so the points read back exact.
std::string pcd_bytes(const PointCloud& c, Pcd mode, std::size_t width = 0) {
  const bool n = c.has_normals();
  std::string h = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n";
  h += n ? "FIELDS x y z rgb _ normal_x normal_y normal_z\nSIZE 8 8 8 4 4 8 8 8\nTYPE F F F U F F F F\nCOUNT 1 1 1 1 3 1 1 1\n"
         : "FIELDS x y z rgb\nSIZE 8 8 8 4\nTYPE F F F U\nCOUNT 1 1 1 1\n";
  const std::size_t w = width ? width : c.size();
  h += "WIDTH " + std::to_string(w) + "\nHEIGHT " + std::to_string(c.size() / w) + "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(c.size()) + "\n";
  h += std::string("DATA ") + (mode == Pcd::ascii ? "ascii" : mode == Pcd::binary ? "binary" : "binary_compressed") + "\n";
  // Each field's bytes per point, in order.
  auto fields_of = [&](std::size_t i) {
    std::vector<std::string> f;
    auto put = [&](auto v) { f.emplace_back(reinterpret_cast<const char*>(&v), sizeof v); };
    put(c.points[i].x()), put(c.points[i].y()), put(c.points[i].z()), put(static_cast<std::uint32_t>(0x00ff8000u + i));
    if (n) {
      f.emplace_back(12, '\0');
      put(c.normals[i].x()), put(c.normals[i].y()), put(c.normals[i].z());
    }
    return f;
  };
  if (mode == Pcd::ascii) {
    char buf[128];
    for (std::size_t i = 0; i < c.size(); ++i) {
      std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g %u", c.points[i].x(), c.points[i].y(), c.points[i].z(), 0x00ff8000u + static_cast<unsigned>(i));
      h += buf;
      if (n) std::snprintf(buf, sizeof buf, " 0 0 0 %.17g %.17g %.17g", c.normals[i].x(), c.normals[i].y(), c.normals[i].z()), h += buf;
      h += "\n";
    }
    return h;
  }
  if (mode == Pcd::binary) {
    for (std::size_t i = 0; i < c.size(); ++i)
      for (const auto& f : fields_of(i)) h += f;
    return h;
  }
  std::string by_field;
  const std::size_t nf = fields_of(0).size();
  for (std::size_t k = 0; k < nf; ++k)
    for (std::size_t i = 0; i < c.size(); ++i) by_field += fields_of(i)[k];
  const std::string z = lzf_compress(by_field);
  const auto sizes = std::array<std::uint32_t, 2>{static_cast<std::uint32_t>(z.size()), static_cast<std::uint32_t>(by_field.size())};
  h.append(reinterpret_cast<const char*>(sizes.data()), 8);
  return h + z;
}

}  // namespace

TEST(CloudReader, PcdReadsTheSamePointsAsThePlyOfTheSameCloud) {
  for (const bool normals : {true, false}) {
    PointCloud c = random_cloud(240, 11, normals);
    for (std::size_t i = 0; i < 60; ++i) c.points[i + 60] = c.points[i];  // repeats: the compressor's back-references
    const PointCloud ply = parse_ply(ply_bytes(c, {}, true), "same.ply");
    for (const Pcd mode : {Pcd::ascii, Pcd::binary, Pcd::compressed}) {
      const std::string bytes = pcd_bytes(c, mode, 24);  // organised: 24 x 10
      const PointCloud pcd = parse_cloud(bytes, "same.pcd");
      ASSERT_EQ(pcd.size(), ply.size()) << static_cast<int>(mode);
      ASSERT_EQ(pcd.has_normals(), normals);
      for (std::size_t i = 0; i < ply.size(); ++i) {
        EXPECT_EQ(pcd.points[i], ply.points[i]) << i;
        if (normals) { EXPECT_NEAR((pcd.normals[i] - ply.normals[i]).norm(), 0, 1e-15); }
      }
    }
  }
  // The compressor used back-references on the repeated points (so the reader's were exercised).
  PointCloud c = random_cloud(240, 11, false);
  for (std::size_t i = 0; i < 60; ++i) c.points[i + 60] = c.points[i];
  EXPECT_LT(pcd_bytes(c, Pcd::compressed).size() + 1000, pcd_bytes(c, Pcd::binary).size());
}

TEST(CloudReader, PcdNoReturnPointsAreDroppedAndCountedAndCountsMustMatch) {
  PointCloud c = random_cloud(30, 12, true);
  c.points[4].z() = std::numeric_limits<double>::quiet_NaN();  // an organised cloud's "no return"
  c.points[9] = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  for (const Pcd mode : {Pcd::ascii, Pcd::binary, Pcd::compressed}) {
    const PointCloud back = parse_pcd(pcd_bytes(c, mode, 10), "organised.pcd");
    ASSERT_EQ(back.size(), 28u);
    EXPECT_EQ(back.dropped.not_finite, 2u);
    EXPECT_EQ(back.points[4], c.points[5]);
    EXPECT_NE(back.dropped.first_not_finite.find("point 4 has a coordinate that is not a finite number"), std::string::npos) << back.dropped.first_not_finite;
    EXPECT_ERROR(parse_pcd(pcd_bytes(c, mode, 10), "organised.pcd", {.not_finite_is_error = true}), "point 4 has a coordinate");
  }
  const PointCloud clean = random_cloud(30, 13, false);
  for (const Pcd mode : {Pcd::ascii, Pcd::binary, Pcd::compressed}) {
    const std::string bytes = pcd_bytes(clean, mode);
    std::string fewer = bytes, more = bytes;
    for (std::string* s : {&fewer, &more})
      for (const char* key : {"WIDTH 30", "POINTS 30"}) s->replace(s->find(key), std::strlen(key), std::string(key).replace(std::strlen(key) - 2, 2, s == &fewer ? "29" : "31"));
    const std::string short_count = error_of([&] { parse_pcd(fewer, "fewer.pcd"); });
    const std::string long_count = error_of([&] { parse_pcd(more, "more.pcd"); });
    EXPECT_NE(short_count.find("fewer.pcd: "), std::string::npos) << short_count;
    EXPECT_NE(long_count.find("more.pcd: "), std::string::npos) << long_count;
    if (mode == Pcd::ascii) {
      EXPECT_NE(short_count.find("a point beyond the 29 the header declares (line 10)"), std::string::npos) << short_count;
      EXPECT_NE(long_count.find("the file holds 30 points, the header (line 10) 31"), std::string::npos) << long_count;
    } else if (mode == Pcd::binary) {
      EXPECT_NE(short_count.find("bytes after the 29 points the header declares"), std::string::npos) << short_count;
      EXPECT_NE(long_count.find("the data ends before the 31 points"), std::string::npos) << long_count;
    } else {
      EXPECT_NE(short_count.find("is not the 29 points of 28 bytes"), std::string::npos) << short_count;
      EXPECT_NE(long_count.find("is not the 31 points of 28 bytes"), std::string::npos) << long_count;
    }
  }
}

TEST(CloudReader, PcdMalformedHeadersAndDataAreRefusedNamingWhere) {
  const std::string head = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n";
  EXPECT_EQ(parse_cloud(head + "1 2 3\n4 5 6\n", "ok.pcd").size(), 2u);
  auto edited = [&](const std::string& from, const std::string& to) {
    std::string s = head;
    s.replace(s.find(from), from.size(), to);
    return s + "1 2 3\n4 5 6\n";
  };
  EXPECT_ERROR(parse_pcd(edited("FIELDS x y z", "FIELDS x y w"), "f.pcd"), "f.pcd: line 2: FIELDS must name x, y and z");
  EXPECT_ERROR(parse_pcd(edited("SIZE 4 4 4", "SIZE 4 4"), "f.pcd"), "line 2: FIELDS names 3 fields, SIZE 2, TYPE 3");
  EXPECT_ERROR(parse_pcd(edited("TYPE F F F", "TYPE F F Q"), "f.pcd"), "field z: TYPE must be I, U or F");
  EXPECT_ERROR(parse_pcd(edited("SIZE 4 4 4", "SIZE 4 4 2"), "f.pcd"), "field z: a float (F) has SIZE 4 or 8");
  EXPECT_ERROR(parse_pcd(edited("WIDTH 2", "WIDTH 3"), "f.pcd"), "line 9: POINTS 2 is not WIDTH x HEIGHT = 3");
  EXPECT_ERROR(parse_pcd(edited("DATA ascii", "DATA zipped"), "f.pcd"), "line 9: DATA: expected ascii, binary or binary_compressed");
  EXPECT_ERROR(parse_pcd(edited("HEIGHT 1", "COLOUR 1"), "f.pcd"), "line 7: expected a PCD header line");
  EXPECT_ERROR(parse_pcd(head.substr(0, head.find("DATA")), "f.pcd"), "the header ends before its DATA line");
  EXPECT_ERROR(parse_pcd(head + "1 2 3\n4 five 6\n", "f.pcd"), "f.pcd: line 11: 'five' is not a number");
  EXPECT_ERROR(parse_pcd(head + "1 2 3\n4 5\n", "f.pcd"), "line 11: expected 3 values");
  // Compressed data that lies: a back-reference before the start, a literal run past the end.
  const std::string chead = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA binary_compressed\n";
  auto compressed = [&](const std::string& z) {
    const std::array<std::uint32_t, 2> sizes{static_cast<std::uint32_t>(z.size()), 12u};
    return chead + std::string(reinterpret_cast<const char*>(sizes.data()), 8) + z;
  };
  EXPECT_ERROR(parse_pcd(compressed(std::string("\x01\x00\x00\x40\x05", 5)), "z.pcd"), "z.pcd: byte ");
  EXPECT_ERROR(parse_pcd(compressed(std::string("\x01\x00\x00\x40\x05", 5)), "z.pcd"), "a back-reference before the start of the data");
  EXPECT_ERROR(parse_pcd(compressed(std::string("\x1f\x00\x00", 3)), "z.pcd"), "the compressed data ends inside a literal run");
  EXPECT_ERROR(parse_pcd(compressed(std::string("\x03\x00\x00\x80\x3f", 5)), "z.pcd"), "the compressed data gives 4 bytes, the header 12");
  // A million points claimed from five compressed bytes: refused before 12 MB are taken for them.
  const std::array<std::uint32_t, 2> lie{5u, 12000000u};
  EXPECT_ERROR(parse_pcd("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1000000\nDATA binary_compressed\n" + std::string(reinterpret_cast<const char*>(lie.data()), 8) +
                             std::string("\x01\x00\x00\x40\x05", 5),
                         "z.pcd"),
               "the uncompressed size 12000000 cannot come from 5 compressed bytes");
  // "ABCD" then a back-reference of 4 bytes 4 back, then 4 more literal: x = y, z its own.
  const float one = 1.0f, two = 2.0f;
  std::string z(1, '\x03');
  z.append(reinterpret_cast<const char*>(&one), 4).append("\x40\x03", 2).push_back('\x03');
  z.append(reinterpret_cast<const char*>(&two), 4);
  const PointCloud p = parse_pcd(compressed(z), "z.pcd");
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p.points[0], Eigen::Vector3d(1, 1, 2));
}

TEST(CloudReader, PcdTruncationsNeverCrash) {
  for (const Pcd mode : {Pcd::binary, Pcd::compressed}) {
    const std::string full = pcd_bytes(random_cloud(20, 14, true), mode);
    EXPECT_EQ(refused_prefixes(full, "prefix.pcd"), static_cast<int>(full.size()));
  }
}
