// OpenVDB lives in this translation unit only (it is slow to compile and heavy to include).
#include "levelset/material_removal.hpp"

#include "levelset/element_lattice.hpp"
#include "support/vtk_xml.hpp"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetMeasure.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <vtkCellArray.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataWriter.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <map>
#include <unordered_map>
#include <cmath>
#include <mutex>
#include <stdexcept>

namespace drom::levelset {

namespace {

void initialize_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// Share of a sample cell of size `width` lying on the negative side of a distance `phi`.
double inside_fraction(double phi, double width) { return std::clamp(0.5 - phi / width, 0.0, 1.0); }

}  // namespace

struct Workpiece::SurfaceGrid {
  openvdb::FloatGrid::Ptr grid;
};

Workpiece Workpiece::from_shape(const geometry::PartShape& shape) {
  Workpiece w;
  w.shape_ = shape;
  Eigen::AlignedBox3d box;
  // Corners and mid-span points of the parametric box bound plates and (shallow) panels.
  for (double u : {0.0, 0.5, 1.0})
    for (double v : {0.0, 1.0})
      for (double t : {0.0, 1.0}) box.extend(shape.from_parametric({u * shape.length_u(), v * shape.length_v(), t * shape.thickness()}));
  w.bounds_ = box;
  return w;
}

Workpiece Workpiece::from_surface(const geometry::Plc& surface, double voxel_size) {
  initialize_openvdb();
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  Eigen::AlignedBox3d box;
  for (const auto& p : surface.points) {
    points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    box.extend(p);
  }
  for (const auto& f : surface.facets)
    for (std::size_t k = 1; k + 1 < f.size(); ++k)
      triangles.emplace_back(static_cast<unsigned>(f[0]), static_cast<unsigned>(f[k]), static_cast<unsigned>(f[k + 1]));
  const auto transform = openvdb::math::Transform::createLinearTransform(voxel_size);
  auto grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, points, triangles, 3.0f);
  Workpiece w;
  w.shape_ = geometry::PartShape::block(box.min(), box.max());
  w.surface_ = std::make_shared<SurfaceGrid>(SurfaceGrid{grid});
  w.bounds_ = box;
  return w;
}

double Workpiece::signed_distance(const Eigen::Vector3d& x) const {
  if (!surface_) return shape_.signed_distance(x);
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(*surface_->grid);
  return sampler.wsSample(openvdb::Vec3d(x.x(), x.y(), x.z()));
}

struct MaterialRemoval::Grid {
  openvdb::FloatGrid::Ptr grid;
};

// Every segment swept so far, binned in the plane, to evaluate the removed region exactly where the
// grid's trilinear interpolation would round it: at the sharp edges where the tool's floor meets its
// side, or the cut meets the stock's faces (about 0.3 v^2 of section lost along each edge).
struct MaterialRemoval::SweptSegments {
  struct Segment {
    Eigen::Vector3d a, b;
    Eigen::AlignedBox3d reach;     // where the tool's sweep along it can be, and a band beyond
    Eigen::AlignedBox3d tool_box;  // where the tool itself can be along it
  };
  // A lower bound of the signed distance to the tool's sweep along a segment: the sweep lies within
  // the vertical prism over the segment's plan view widened by R, between the segment's lowest tip
  // and its highest flute top, and the distance to a subset is never below the distance to the set.
  // It costs a few flops where the sweep's distance costs a golden-section search. It is lowered by
  // 1e-9 mm so that the rounding of either distance can never make it pass the other: a search it
  // skips could not have changed a single bit of the result.
  static double lower_bound(const Segment& s, double radius, const Eigen::Vector3d& x) {
    const Eigen::Vector2d a2 = s.a.head<2>(), ab2 = s.b.head<2>() - s.a.head<2>(), x2 = x.head<2>();
    const double len2 = ab2.squaredNorm();
    const double t = len2 > 0 ? std::clamp((x2 - a2).dot(ab2) / len2, 0.0, 1.0) : 0.0;
    const double across = (a2 + t * ab2 - x2).norm() - radius;
    return std::max({across, s.tool_box.min().z() - x.z(), x.z() - s.tool_box.max().z()}) - 1e-9;
  }
  double bin = 1;
  std::vector<Segment> segments;
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> bins;

  static std::int64_t key(std::int64_t i, std::int64_t j) { return (i << 32) ^ (j & 0xffffffff); }
  void add(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::AlignedBox3d& reach, const Eigen::AlignedBox3d& tool_box) {
    const auto index = static_cast<std::uint32_t>(segments.size());
    segments.push_back({a, b, reach, tool_box});
    const auto i0 = static_cast<std::int64_t>(std::floor(reach.min().x() / bin)), i1 = static_cast<std::int64_t>(std::floor(reach.max().x() / bin));
    const auto j0 = static_cast<std::int64_t>(std::floor(reach.min().y() / bin)), j1 = static_cast<std::int64_t>(std::floor(reach.max().y() / bin));
    for (auto i = i0; i <= i1; ++i)
      for (auto j = j0; j <= j1; ++j) bins[key(i, j)].push_back(index);
  }
  // The segments whose reach meets the box, each once.
  void reaching(const Eigen::AlignedBox3d& box, std::vector<std::uint32_t>& found) const {
    found.clear();
    const auto i0 = static_cast<std::int64_t>(std::floor(box.min().x() / bin)), i1 = static_cast<std::int64_t>(std::floor(box.max().x() / bin));
    const auto j0 = static_cast<std::int64_t>(std::floor(box.min().y() / bin)), j1 = static_cast<std::int64_t>(std::floor(box.max().y() / bin));
    for (auto i = i0; i <= i1; ++i)
      for (auto j = j0; j <= j1; ++j)
        if (const auto it = bins.find(key(i, j)); it != bins.end())
          for (std::uint32_t k : it->second)
            if (segments[k].reach.intersects(box)) found.push_back(k);
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
  }
};

MaterialRemoval::MaterialRemoval(Workpiece workpiece, paths::ToolAssembly tool, double voxel_size, double half_width)
    : grid_(std::make_unique<Grid>()),
      workpiece_(std::move(workpiece)),
      tool_(tool),
      voxel_(voxel_size),
      band_(half_width * voxel_size),
      swept_(std::make_unique<SweptSegments>()),
      lattices_(std::make_unique<ElementLattices>()) {
  swept_->bin = std::max(tool_.cutter.radius + band_, 4 * voxel_size);
  if (!(voxel_size > 0)) throw std::invalid_argument("voxel size must be positive");
  initialize_openvdb();
  grid_->grid = openvdb::FloatGrid::create(static_cast<float>(band_));
  grid_->grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel_size));
  grid_->grid->setGridClass(openvdb::GRID_LEVEL_SET);
  grid_->grid->setName("removed");
}

MaterialRemoval::~MaterialRemoval() = default;
MaterialRemoval::MaterialRemoval(MaterialRemoval&&) noexcept = default;

double MaterialRemoval::sweep(const std::vector<std::vector<Eigen::Vector3d>>& polylines) {
  auto acc = grid_->grid->getAccessor();
  const Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  const double cell = voxel_ * voxel_ * voxel_;
  const float band = static_cast<float>(band_);
  const Eigen::AlignedBox3d stock(workpiece_.bounds().min().array() - band_, workpiece_.bounds().max().array() + band_);
  double added = 0;
  last_bounds_.setEmpty();
  first_of_last_sweep_ = swept_->segments.size();
  for (const auto& line : polylines)
    for (std::size_t s = 0; s + 1 < line.size(); ++s) {
      const Eigen::Vector3d& a = line[s];
      const Eigen::Vector3d& b = line[s + 1];
      Eigen::AlignedBox3d box(a.cwiseMin(b), a.cwiseMax(b));
      box.min() -= Eigen::Vector3d(tool_.cutter.radius + band_, tool_.cutter.radius + band_, band_);
      box.max() += Eigen::Vector3d(tool_.cutter.radius + band_, tool_.cutter.radius + band_, tool_.flute_length + band_);
      const Eigen::AlignedBox3d reach = box;
      box = box.intersection(stock);
      if (box.isEmpty()) continue;
      last_bounds_.extend(box);
      Eigen::AlignedBox3d tool_box(a.cwiseMin(b), a.cwiseMax(b));
      tool_box.min() -= Eigen::Vector3d(tool_.cutter.radius, tool_.cutter.radius, 0);
      tool_box.max() += Eigen::Vector3d(tool_.cutter.radius, tool_.cutter.radius, tool_.flute_length);
      swept_->add(a, b, reach, tool_box);
      const Eigen::Vector3i lo = (box.min() / voxel_).array().ceil().cast<int>();
      const Eigen::Vector3i hi = (box.max() / voxel_).array().floor().cast<int>();
      // Columns farther across than the tool's reach are skipped before any distance is computed.
      const Eigen::Vector2d a2 = a.head<2>(), ab2 = b.head<2>() - a.head<2>();
      const double ab2_len2 = ab2.squaredNorm(), reach2 = (tool_.cutter.radius + band_) * (tool_.cutter.radius + band_);
      for (int i = lo.x(); i <= hi.x(); ++i)
        for (int j = lo.y(); j <= hi.y(); ++j) {
          const Eigen::Vector2d c(i * voxel_, j * voxel_);
          const double t = ab2_len2 > 0 ? std::clamp((c - a2).dot(ab2) / ab2_len2, 0.0, 1.0) : 0.0;
          if ((a2 + t * ab2 - c).squaredNorm() > reach2) continue;
          for (int k = lo.z(); k <= hi.z(); ++k) {
            const Eigen::Vector3d x(i * voxel_, j * voxel_, k * voxel_);
            const openvdb::Coord ijk(i, j, k);
            const float old = acc.getValue(ijk);
            // Removal only lowers a voxel's value (old <= band): a sweep that cannot come nearer than
            // the value already stored changes nothing, and its search is skipped.
            if (SweptSegments::lower_bound(swept_->segments.back(), tool_.cutter.radius, x) >= old) continue;
            const double swept = swept_signed_distance(tool_, axis, a, b, x, 0.01 * voxel_);
            if (swept >= band_) continue;
            const double phi = std::max(swept, workpiece_.signed_distance(x));
            if (phi >= band_) continue;
            const float now = std::max(static_cast<float>(phi), -band);
            if (now >= old) continue;
            added += (inside_fraction(now, voxel_) - inside_fraction(old, voxel_)) * cell;
            if (now <= -band) acc.setValueOff(ijk, -band);
            else acc.setValueOn(ijk, now);
          }
        }
    }
  openvdb::tools::pruneLevelSet(grid_->grid->tree());
  accumulated_ += added;
  return added;
}

double MaterialRemoval::measured_volume() const {
  if (grid_->grid->tree().activeVoxelCount() == 0) return 0;
  return openvdb::tools::levelSetVolume(*grid_->grid);
}

double MaterialRemoval::signed_distance(const Eigen::Vector3d& x) const {
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(*grid_->grid);
  return sampler.wsSample(openvdb::Vec3d(x.x(), x.y(), x.z()));
}

bool MaterialRemoval::entered(const Eigen::AlignedBox3d& box, bool last_sweep_only) const {
  // Touching a face (as the tool's floor touches the layer under the pocket) is not entering.
  const double touch = 1e-9 * std::max(1.0, box.diagonal().norm());
  auto enters = [&](const SweptSegments::Segment& segment) {
    const Eigen::AlignedBox3d overlap = segment.tool_box.intersection(box);
    return (overlap.max() - overlap.min()).minCoeff() > touch;
  };
  if (last_sweep_only) {
    for (std::size_t k = first_of_last_sweep_; k < swept_->segments.size(); ++k)
      if (enters(swept_->segments[k])) return true;
    return false;
  }
  std::vector<std::uint32_t> near;
  swept_->reaching(box, near);
  return std::any_of(near.begin(), near.end(), [&](std::uint32_t k) { return enters(swept_->segments[k]); });
}

void MaterialRemoval::update_remaining(const geometry::ElementGeometry& elements, geometry::RemovalCriterion criterion, std::vector<double>& remaining,
                                       bool only_last_sweep) const {
  remaining.resize(elements.size(), 1.0);
  if (only_last_sweep && last_bounds_.isEmpty()) return;
  const openvdb::FloatGrid::ConstAccessor acc = grid_->grid->getConstAccessor();
  openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler> sampler(acc, grid_->grid->transform());
  auto phi = [&](const Eigen::Vector3d& x) { return sampler.wsSample(openvdb::Vec3d(x.x(), x.y(), x.z())); };
  // Near the surface, the removed region exactly: the union of the tool's sweeps (the segments that
  // reach the element at hand) within the stock. The grid rounds its sharp edges by about 0.3 voxel
  // (where the tool's floor meets its side, or the cut meets the stock's faces), so it is trusted
  // only beyond 0.6 voxel.
  std::vector<std::uint32_t> reaching;
  ElementLattices::Field field;
  field.estimate = phi;
  field.exact = [&](const Eigen::Vector3d& x) {
    // Anything at or past the band reads as the band, so the search starts there, and a segment
    // whose lower bound is no nearer than the nearest sweep so far cannot change the minimum.
    double swept = band_;
    for (std::uint32_t k : reaching) {
      const auto& segment = swept_->segments[k];
      if (!segment.reach.contains(x) || SweptSegments::lower_bound(segment, tool_.cutter.radius, x) >= swept) continue;
      swept = std::min(swept, swept_signed_distance(tool_, Eigen::Vector3d::UnitZ(), segment.a, segment.b, x, 1e-7));
    }
    return std::min(std::max(swept, workpiece_.signed_distance(x)), band_);
  };
  field.trust = 0.6 * voxel_;
  // Whether any leaf of the narrow band lies within two voxels of the box (one for the interpolation
  // stencil, one for a curved element bulging past its nodes' box). Without one, the level set is
  // +band or -band all over the box: the region's surface does not cross it.
  auto band_near = [&](const Eigen::AlignedBox3d& box) {
    const Eigen::Vector3i lo = (box.min() / voxel_).array().floor().cast<int>() - 2;
    const Eigen::Vector3i hi = (box.max() / voxel_).array().ceil().cast<int>() + 2;
    constexpr int leaf = static_cast<int>(openvdb::FloatTree::LeafNodeType::DIM);
    for (int i = lo.x() & ~(leaf - 1); i <= hi.x(); i += leaf)
      for (int j = lo.y() & ~(leaf - 1); j <= hi.y(); j += leaf)
        for (int k = lo.z() & ~(leaf - 1); k <= hi.z(); k += leaf)
          if (acc.probeConstLeaf(openvdb::Coord(i, j, k))) return true;
    return false;
  };
  for (std::size_t e = 0; e < elements.size(); ++e) {
    // Removal only takes material away: an element already gone stays gone, and one whose inside the
    // tool never entered (it may touch a face, as the floor's layer does) is unchanged, or intact.
    if (only_last_sweep && (remaining[e] <= 0 || !entered(elements.bounds(e), true))) continue;
    if (!only_last_sweep && !entered(elements.bounds(e), false)) {
      remaining[e] = 1;
      continue;
    }
    if (!band_near(elements.bounds(e))) {
      remaining[e] = phi(elements.centroid(e)) < 0 ? 0.0 : 1.0;
      continue;
    }
    swept_->reaching(elements.bounds(e), reaching);
    if (criterion == geometry::RemovalCriterion::Centroid) {
      const Eigen::Vector3d& c = elements.centroid(e);
      remaining[e] = (std::abs(phi(c)) > field.trust ? phi(c) : field.exact(c)) < 0 ? 0.0 : 1.0;
      continue;
    }
    remaining[e] = std::clamp(1.0 - lattices_->negative_share(elements, e, voxel_, field), 0.0, 1.0);
  }
}

std::size_t MaterialRemoval::active_voxels() const { return grid_->grid->tree().activeVoxelCount(); }
std::size_t MaterialRemoval::memory_bytes() const { return grid_->grid->tree().memUsage(); }

void MaterialRemoval::write_surface(const std::filesystem::path& path) const {
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  if (grid_->grid->tree().activeVoxelCount() > 0) openvdb::tools::volumeToMesh(*grid_->grid, points, triangles, quads, 0.0, 0.3);  // adaptive: flat faces get few polygons
  vtkNew<vtkPoints> vtk_points;
  for (const auto& p : points) vtk_points->InsertNextPoint(p.x(), p.y(), p.z());
  vtkNew<vtkCellArray> polys;
  for (const auto& q : quads) {
    const vtkIdType ids[4] = {q[0], q[1], q[2], q[3]};
    polys->InsertNextCell(4, ids);
  }
  for (const auto& t : triangles) {
    const vtkIdType ids[3] = {t[0], t[1], t[2]};
    polys->InsertNextCell(3, ids);
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(vtk_points);
  poly->SetPolys(polys);
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetInputData(poly);
  write_vtk_xml(*writer, path);
}

double default_voxel_size(const paths::ToolAssembly& tool, double depth_of_cut, double smallest_element) {
  return std::min({tool.cutter.radius / 8, tool.cutter.corner_radius > 0 ? tool.cutter.corner_radius / 4 : tool.cutter.radius, depth_of_cut / 4, smallest_element / 4});
}

}  // namespace drom::levelset
