#include "geometry/step_face.hpp"

#include "support/input_error.hpp"

#include <BRepTools.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <Geom2d_Curve.hxx>
#include <GeomConvert.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_Surface.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Wire.hxx>

#include <sstream>

namespace drom::geometry {

namespace {

// The file's faces, each once, in OpenCASCADE's exploration order.
TopTools_IndexedMapOfShape load_faces(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path.string() + ": no such STEP file");
  // OpenCASCADE reports its progress on stdout; drom's commands own stdout.
  Message::DefaultMessenger()->ChangePrinters().Clear();
  STEPControl_Reader reader;
  if (reader.ReadFile(path.string().c_str()) != IFSelect_RetDone) throw InputError(path.string() + ": not a readable STEP file");
  reader.TransferRoots();
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(reader.OneShape(), TopAbs_FACE, faces);
  if (faces.Extent() == 0) throw InputError(path.string() + ": the STEP file holds no face");
  return faces;
}

// The face's wires as polygons in its parameter space, edges sampled along their p-curves.
std::vector<std::vector<Eigen::Vector2d>> parameter_loops(const TopoDS_Face& face) {
  constexpr int kSamplesPerEdge = 64;
  std::vector<std::vector<Eigen::Vector2d>> loops;
  for (TopExp_Explorer w(face, TopAbs_WIRE); w.More(); w.Next()) {
    std::vector<Eigen::Vector2d> loop;
    for (BRepTools_WireExplorer e(TopoDS::Wire(w.Current()), face); e.More(); e.Next()) {
      const TopoDS_Edge& edge = e.Current();
      double first = 0, last = 0;
      const Handle(Geom2d_Curve) curve = BRep_Tool::CurveOnSurface(edge, face, first, last);
      if (curve.IsNull()) continue;
      const bool reversed = edge.Orientation() == TopAbs_REVERSED;
      for (int k = 0; k < kSamplesPerEdge; ++k) {
        const double s = static_cast<double>(k) / kSamplesPerEdge;
        const gp_Pnt2d p = curve->Value(reversed ? last + (first - last) * s : first + (last - first) * s);
        const Eigen::Vector2d q(p.X(), p.Y());
        if (loop.empty() || (q - loop.back()).norm() > 1e-12) loop.push_back(q);
      }
    }
    if (loop.size() >= 3) loops.push_back(std::move(loop));
  }
  return loops;
}

std::vector<double> knot_sequence(const Handle(Geom_BSplineSurface) & b, bool along_u) {
  TColStd_Array1OfReal knots(1, along_u ? b->NbUPoles() + b->UDegree() + 1 : b->NbVPoles() + b->VDegree() + 1);
  if (along_u) b->UKnotSequence(knots);
  else b->VKnotSequence(knots);
  return std::vector<double>(knots.begin(), knots.end());
}

}  // namespace

int count_step_faces(const std::filesystem::path& path) {
  try {
    return load_faces(path).Extent();
  } catch (const Standard_Failure& e) {
    throw InputError(path.string() + ": OpenCASCADE could not read it: " + e.GetMessageString());
  }
}

StepFace read_step_face(const std::filesystem::path& path, int index) {
  try {
    const TopTools_IndexedMapOfShape faces = load_faces(path);
    if (index < 1 || index > faces.Extent())
      throw InputError(path.string() + ": face " + std::to_string(index) + " asked for, but the file holds " + std::to_string(faces.Extent()) + " face" +
                       (faces.Extent() == 1 ? "" : "s") + " (1-based)");
    const TopoDS_Face face = TopoDS::Face(faces.FindKey(index));
    const Handle(Geom_Surface) surface = BRep_Tool::Surface(face);  // with the face's location applied
    double u0 = 0, u1 = 0, v0 = 0, v1 = 0;
    BRepTools::UVBounds(face, u0, u1, v0, v1);
    Handle(Geom_BSplineSurface) b = GeomConvert::SurfaceToBSplineSurface(new Geom_RectangularTrimmedSurface(surface, u0, u1, v0, v1));
    if (b->IsUPeriodic()) b->SetUNotPeriodic();
    if (b->IsVPeriodic()) b->SetVNotPeriodic();
    const int nu = b->NbUPoles(), nv = b->NbVPoles();
    std::vector<Eigen::Vector3d> points;
    std::vector<double> weights;
    points.reserve(static_cast<std::size_t>(nu * nv));
    for (int i = 1; i <= nu; ++i)
      for (int j = 1; j <= nv; ++j) {
        const gp_Pnt p = b->Pole(i, j);
        points.emplace_back(p.X(), p.Y(), p.Z());
        weights.push_back(b->Weight(i, j));
      }
    NurbsSurface nurbs(b->UDegree(), b->VDegree(), knot_sequence(b, true), knot_sequence(b, false), nu, nv, std::move(points),
                       b->IsURational() || b->IsVRational() ? std::move(weights) : std::vector<double>{});
    // Loops in the unit domain of the converted patch; dropped when the face is its whole rectangle.
    const double bu0 = nurbs.u_min(), bu1 = nurbs.u_max(), bv0 = nurbs.v_min(), bv1 = nurbs.v_max();
    auto loops = parameter_loops(face);
    for (auto& loop : loops)
      for (auto& q : loop) q = Eigen::Vector2d((q.x() - bu0) / (bu1 - bu0), (q.y() - bv0) / (bv1 - bv0));
    TrimLoops trim(std::move(loops));
    bool whole = true;
    for (int i = 0; i <= 20 && whole; ++i)
      for (int j = 0; j <= 20 && whole; ++j) whole = trim.contains(0.005 + 0.99 * i / 20.0, 0.005 + 0.99 * j / 20.0);
    StepFace result{nurbs.with_unit_domain(), whole ? TrimLoops{} : std::move(trim), surface->DynamicType()->Name(), face.Orientation() == TopAbs_REVERSED};
    return result;
  } catch (const Standard_Failure& e) {
    throw InputError(path.string() + ": OpenCASCADE could not convert face " + std::to_string(index) + ": " + e.GetMessageString());
  } catch (const std::invalid_argument& e) {
    throw InputError(path.string() + ": face " + std::to_string(index) + " is not a valid patch: " + e.what());
  }
}

}  // namespace drom::geometry
