// OpenVDB lives in this translation unit only (it is slow to compile and heavy to include).
#include "levelset/material_removal.hpp"

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

Workpiece Workpiece::from_shape(const PartShape& shape) {
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

Workpiece Workpiece::from_surface(const Plc& surface, double voxel_size) {
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
  w.shape_ = PartShape::block(box.min(), box.max());
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

MaterialRemoval::MaterialRemoval(Workpiece workpiece, Tool tool, double voxel_size, double half_width)
    : grid_(std::make_unique<Grid>()), workpiece_(std::move(workpiece)), tool_(tool), voxel_(voxel_size), band_(half_width * voxel_size) {
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
  for (const auto& line : polylines)
    for (std::size_t s = 0; s + 1 < line.size(); ++s) {
      const Eigen::Vector3d& a = line[s];
      const Eigen::Vector3d& b = line[s + 1];
      Eigen::AlignedBox3d box(a.cwiseMin(b), a.cwiseMax(b));
      box.min() -= Eigen::Vector3d(tool_.radius + band_, tool_.radius + band_, band_);
      box.max() += Eigen::Vector3d(tool_.radius + band_, tool_.radius + band_, tool_.flute_length + band_);
      box = box.intersection(stock);
      if (box.isEmpty()) continue;
      last_bounds_.extend(box);
      const Eigen::Vector3i lo = (box.min() / voxel_).array().ceil().cast<int>();
      const Eigen::Vector3i hi = (box.max() / voxel_).array().floor().cast<int>();
      // Columns farther across than the tool's reach are skipped before any distance is computed.
      const Eigen::Vector2d a2 = a.head<2>(), ab2 = b.head<2>() - a.head<2>();
      const double ab2_len2 = ab2.squaredNorm(), reach2 = (tool_.radius + band_) * (tool_.radius + band_);
      for (int i = lo.x(); i <= hi.x(); ++i)
        for (int j = lo.y(); j <= hi.y(); ++j) {
          const Eigen::Vector2d c(i * voxel_, j * voxel_);
          const double t = ab2_len2 > 0 ? std::clamp((c - a2).dot(ab2) / ab2_len2, 0.0, 1.0) : 0.0;
          if ((a2 + t * ab2 - c).squaredNorm() > reach2) continue;
          for (int k = lo.z(); k <= hi.z(); ++k) {
            const Eigen::Vector3d x(i * voxel_, j * voxel_, k * voxel_);
            const double swept = swept_signed_distance(tool_, axis, a, b, x, 0.01 * voxel_);
            if (swept >= band_) continue;
            const double phi = std::max(swept, workpiece_.signed_distance(x));
            if (phi >= band_) continue;
            const openvdb::Coord ijk(i, j, k);
            const float old = acc.getValue(ijk);
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

void MaterialRemoval::update_remaining(const ElementSamples& elements, RemovalCriterion criterion, std::vector<double>& remaining,
                                       bool only_last_sweep) const {
  remaining.resize(elements.size(), 1.0);
  if (only_last_sweep && last_bounds_.isEmpty()) return;
  const openvdb::FloatGrid::ConstAccessor acc = grid_->grid->getConstAccessor();
  openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler> sampler(acc, grid_->grid->transform());
  auto phi = [&](const Eigen::Vector3d& x) { return sampler.wsSample(openvdb::Vec3d(x.x(), x.y(), x.z())); };
  for (std::size_t e = 0; e < elements.size(); ++e) {
    if (only_last_sweep && !elements.bounds[e].intersects(last_bounds_)) continue;
    if (criterion == RemovalCriterion::Centroid) {
      remaining[e] = phi(elements.centroid[e]) < 0 ? 0.0 : 1.0;
      continue;
    }
    const auto& pts = elements.points[e];
    const auto& w = elements.weights[e];
    double volume = 0, gone = 0;
    for (double wi : w) volume += wi;
    const bool has_cell = e < elements.cell.size() && elements.cell[e].squaredNorm() > 0;
    // Without a cell shape, each sample stands for a cube of the element's volume / sample count.
    const double cube = std::cbrt(volume / static_cast<double>(pts.size()));
    for (std::size_t q = 0; q < pts.size(); ++q) {
      const double value = phi(pts[q]);
      if (!has_cell || std::abs(value) >= band_) {
        // Far from the cut (or no cell shape): beyond the band the level set only says inside or
        // outside, so the ramp may not be wider than the band.
        gone += w[q] * inside_fraction(value, std::clamp(cube, voxel_, 2 * band_));
        continue;
      }
      // Near the cut: integrate the cell at the level set's own resolution, a one-voxel ramp per
      // sub-sample (exact for a planar cut; thin removed layers inside one cell stay right too).
      const Eigen::Matrix3d& c = elements.cell[e];
      int m[3];
      for (int d = 0; d < 3; ++d) m[d] = std::clamp(static_cast<int>(std::ceil(c.col(d).norm() / voxel_)), 1, 12);
      double share = 0;
      for (int i = 0; i < m[0]; ++i)
        for (int j = 0; j < m[1]; ++j)
          for (int k = 0; k < m[2]; ++k) {
            const Eigen::Vector3d offset((i + 0.5) / m[0] - 0.5, (j + 0.5) / m[1] - 0.5, (k + 0.5) / m[2] - 0.5);
            share += inside_fraction(phi(pts[q] + c * offset), voxel_);
          }
      gone += w[q] * share / (m[0] * m[1] * m[2]);
    }
    remaining[e] = std::clamp(1.0 - gone / volume, 0.0, 1.0);
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

double default_voxel_size(const Tool& tool, double depth_of_cut, double smallest_element) {
  return std::min({tool.radius / 8, tool.corner_radius > 0 ? tool.corner_radius / 4 : tool.radius, depth_of_cut / 4, smallest_element / 4});
}

}  // namespace drom::levelset
