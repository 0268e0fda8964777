#include "geometry/surface_input.hpp"

#include "geometry/local_geometry.hpp"
#include "geometry/step_face.hpp"
#include "support/input_error.hpp"

#include <sstream>
#include <stdexcept>

namespace drom::geometry {

namespace {

std::vector<Eigen::Vector3d> read_points(TomlReader& r, const std::string& key, std::size_t expected) {
  const auto rows = r.real_rows(key, 3, Range{});
  if (rows.size() != expected)
    r.fail(key, std::to_string(rows.size()) + " control points given; the net's counts need " + std::to_string(expected) + " (index (i, j) at row i * count_v + j)");
  std::vector<Eigen::Vector3d> points;
  for (const auto& p : rows) points.emplace_back(p[0], p[1], p[2]);
  return points;
}

}  // namespace

SurfaceInput read_surface(TomlReader& r, const std::string& table, const std::filesystem::path& base_dir) {
  const std::string t = table + ".";
  SurfaceInput in;
  in.kind = r.choice(t + "kind", {"bezier", "bspline", "nurbs", "step"});
  std::string net_key = t + "points";
  if (in.kind == "step") {
    const std::string file = r.text(t + "step");
    in.step_file = std::filesystem::path(file).is_absolute() ? std::filesystem::path(file) : base_dir / file;
    in.face = static_cast<int>(r.integer(t + "face", 1, 1000000, 1));
    StepFace face = [&] {
      try {
        return read_step_face(in.step_file, in.face);
      } catch (const InputError& e) {
        r.fail(std::string(e.what()).find(" face ") != std::string::npos && std::filesystem::exists(in.step_file) ? t + "face" : t + "step", e.what());
      }
    }();
    in.surface = std::move(face.surface);
    in.trim = std::move(face.trim);
    in.description = "face " + std::to_string(in.face) + " of " + in.step_file.filename().string() + " (" + face.source_type + (in.trim.empty() ? "" : ", trimmed") + ")";
    net_key = t + "step";
  } else {
    const auto counts = r.reals(t + "count", Range::closed(2, 10000));
    if (counts.size() != 2 || counts[0] != static_cast<int>(counts[0]) || counts[1] != static_cast<int>(counts[1]))
      r.fail(t + "count", "expected [count_u, count_v], two whole numbers >= 2");
    const int nu = static_cast<int>(counts[0]), nv = static_cast<int>(counts[1]);
    auto points = read_points(r, t + "points", static_cast<std::size_t>(nu * nv));
    std::vector<double> weights;
    if (in.kind == "nurbs") weights = r.reals(t + "weights", Range::positive());
    try {
      if (in.kind == "bezier") {
        in.surface = NurbsSurface::bezier(nu, nv, std::move(points));
        in.description = "Bézier " + std::to_string(nu) + " x " + std::to_string(nv);
      } else {
        const int pu = static_cast<int>(r.integer(t + "degree_u", 1, NurbsSurface::kMaxDegree));
        const int pv = static_cast<int>(r.integer(t + "degree_v", 1, NurbsSurface::kMaxDegree));
        if (pu >= nu) r.fail(t + "degree_u", "must be below count_u (" + std::to_string(nu) + ")");
        if (pv >= nv) r.fail(t + "degree_v", "must be below count_v (" + std::to_string(nv) + ")");
        auto ku = r.has(t + "knots_u") ? r.reals(t + "knots_u", Range{}) : NurbsSurface::clamped_uniform_knots(pu, nu);
        auto kv = r.has(t + "knots_v") ? r.reals(t + "knots_v", Range{}) : NurbsSurface::clamped_uniform_knots(pv, nv);
        if (weights.size() != static_cast<std::size_t>(nu * nv) && in.kind == "nurbs")
          r.fail(t + "weights", std::to_string(weights.size()) + " weights given for " + std::to_string(nu * nv) + " control points");
        in.surface = NurbsSurface(pu, pv, std::move(ku), std::move(kv), nu, nv, std::move(points), std::move(weights)).with_unit_domain();
        in.description = (in.kind == "nurbs" ? "NURBS " : "B-spline ") + std::to_string(nu) + " x " + std::to_string(nv) + ", degrees " + std::to_string(pu) + ", " +
                         std::to_string(pv);
      }
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      r.fail(what.find("knot") != std::string::npos ? (what.find(" v ") != std::string::npos || what.find("the v ") != std::string::npos ? t + "knots_v" : t + "knots_u")
                                                    : net_key,
             what);
    }
  }
  if (const auto bad = find_degenerate_point(in.surface, 64, 64)) {
    std::ostringstream msg;
    msg << "degenerate patch: the surface has no normal at (u, v) = (" << (*bad)(0) << ", " << (*bad)(1)
        << ") (S_u x S_v vanishes: collapsed or collinear control points)";
    r.fail(net_key, msg.str());
  }
  return in;
}

}  // namespace drom::geometry
