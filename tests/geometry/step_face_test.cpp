// STEP faces: the seed's Bézier test surfaces exported by OpenCASCADE and read back through drom's
// reader evaluate like their control points (issue 22, check 7); a trimmed face keeps its loops; a
// missing, faceless or unreadable file is a clear error.
#include "geometry/step_face.hpp"
#include "support/input_error.hpp"
#include "tests/geometry/test_surfaces.hpp"
#include "tests/scratch_folder.hpp"

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <Geom_BezierSurface.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <STEPControl_Writer.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Wire.hxx>
#include <TopoDS_Vertex.hxx>
#include <gp_Circ.hxx>
#include <gp_Pln.hxx>
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const fs::path dir = drom::tests::scratch_folder("drom_step_test_");
  fs::create_directories(dir);
  return dir / name;
}

void write_step(const TopoDS_Shape& shape, const fs::path& path) {
  Message::DefaultMessenger()->ChangePrinters().Clear();
  STEPControl_Writer writer;
  ASSERT_EQ(writer.Transfer(shape, STEPControl_AsIs), IFSelect_RetDone);
  ASSERT_EQ(writer.Write(path.string().c_str()), IFSelect_RetDone);
}

TopoDS_Face bezier_face(const drom::geometry::NurbsSurface& s) {
  TColgp_Array2OfPnt poles(1, s.count_u(), 1, s.count_v());
  for (int i = 0; i < s.count_u(); ++i)
    for (int j = 0; j < s.count_v(); ++j) {
      const auto& p = s.points()[static_cast<std::size_t>(i * s.count_v() + j)];
      poles.SetValue(i + 1, j + 1, gp_Pnt(p.x(), p.y(), p.z()));
    }
  return BRepBuilderAPI_MakeFace(new Geom_BezierSurface(poles), 1e-7).Face();
}

// The InputError reading face `index` of `file` gives; empty when it reads.
std::string error(const fs::path& file, int index) {
  try {
    drom::geometry::read_step_face(file, index);
  } catch (const drom::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(StepFace, BezierTestSurfacesRoundTripTo1e9) {
  for (const auto& [name, surface] : {std::pair{"rubio", drom::tests::rubio_surface()}, std::pair{"choi", drom::tests::choi_surface()}}) {
    const fs::path file = scratch(std::string(name) + ".step");
    write_step(bezier_face(surface), file);
    EXPECT_EQ(drom::geometry::count_step_faces(file), 1);
    const auto face = drom::geometry::read_step_face(file, 1);
    EXPECT_TRUE(face.trim.empty()) << name;
    double worst = 0;
    for (int a = 0; a <= 40; ++a)
      for (int b = 0; b <= 40; ++b) worst = std::max(worst, (face.surface.point(a / 40.0, b / 40.0) - surface.point(a / 40.0, b / 40.0)).norm());
    EXPECT_LT(worst, 1e-9) << name << ": " << face.source_type;
    RecordProperty(std::string(name) + "_worst_mm", testing::PrintToString(worst) + " (read back as " + face.source_type + ")");
  }
}

TEST(StepFace, TrimmedFaceKeepsItsLoops) {
  // A disk of radius 10 on the plane z = 2: the face's UV rectangle is the disk's bounding square.
  const gp_Circ circle(gp_Ax2(gp_Pnt(0, 0, 2), gp_Dir(0, 0, 1)), 10);
  const TopoDS_Wire wire = BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(circle).Edge()).Wire();
  const fs::path file = scratch("disk.step");
  write_step(BRepBuilderAPI_MakeFace(gp_Pln(gp_Pnt(0, 0, 2), gp_Dir(0, 0, 1)), wire).Face(), file);
  const auto face = drom::geometry::read_step_face(file, 1);
  ASSERT_FALSE(face.trim.empty());
  EXPECT_TRUE(face.trim.contains(0.5, 0.5));
  EXPECT_TRUE(face.trim.contains(0.5, 0.04));
  EXPECT_FALSE(face.trim.contains(0.02, 0.02));
  EXPECT_FALSE(face.trim.contains(0.95, 0.95));
  const Eigen::Vector3d centre = face.surface.point(0.5, 0.5);
  EXPECT_LT((centre - Eigen::Vector3d(0, 0, 2)).norm(), 1e-9);
  EXPECT_NEAR((face.surface.point(1, 0.5) - centre).norm(), 10, 1e-9);
}

TEST(StepFace, ErrorsNameTheFile) {
  const fs::path missing = scratch("missing.step");
  EXPECT_EQ(error(missing, 1), missing.string() + ": no such STEP file");
  const fs::path vertex = scratch("vertex.step");
  write_step(BRepBuilderAPI_MakeVertex(gp_Pnt(1, 2, 3)).Vertex(), vertex);
  EXPECT_EQ(error(vertex, 1), vertex.string() + ": the STEP file holds no face");
  const fs::path garbage = scratch("garbage.step");
  std::ofstream(garbage) << "this is not ISO 10303-21\n";
  EXPECT_EQ(error(garbage, 1), garbage.string() + ": not a readable STEP file");
  const fs::path one = scratch("one.step");
  write_step(bezier_face(drom::tests::rubio_surface()), one);
  EXPECT_EQ(error(one, 2), one.string() + ": face 2 asked for, but the file holds 1 face (1-based)");
}

std::string text_of(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The first ORIENTED_EDGE of a STEP text: its own id ("#20") and the span of its edge reference (the
// "#21" of `#20 = ORIENTED_EDGE('',*,*,#21,.T.)`); edge_at is npos where there is none.
struct OrientedEdge {
  std::string self;
  std::size_t edge_at = std::string::npos, edge_length = 0;
};
OrientedEdge first_oriented_edge(const std::string& step) {
  const std::string head = " = ORIENTED_EDGE('',*,*,";
  const auto at = step.find(head + "#");
  if (at == std::string::npos) return {};
  const auto id_start = step.rfind('#', at);
  const auto edge_at = at + head.size();
  return {step.substr(id_start, at - id_start), edge_at, step.find(',', edge_at) - edge_at};
}

// Fuzz finding 14 (docs/robustness.md): a vertex whose point entity has a damaged type name made
// OpenCASCADE 7.6.3 dereference a null point (StepGeom_CartesianPoint::NbCoordinates, SIGSEGV) while
// translating. A file whose entities OpenCASCADE could not read is now refused before any translation,
// naming the line.
TEST(StepFace, AFileWithEntitiesOpenCascadeCouldNotReadIsRefusedNamingTheLine) {
  const fs::path file = scratch("damaged_vertex.step");
  write_step(bezier_face(drom::tests::rubio_surface()), file);
  std::string step = text_of(file);
  const std::string vertex = "VERTEX_POINT('',";
  const auto at = step.find(vertex);
  ASSERT_NE(at, std::string::npos);
  const std::string point = step.substr(at + vertex.size(), step.find(')', at) - at - vertex.size()) + " = CARTESIAN_POINT";
  const auto where = step.find(point);
  ASSERT_NE(where, std::string::npos) << point;
  step.replace(where, point.size(), point.substr(0, point.size() - 15) + "CARTESI[N_POINT");
  const auto line = 1 + std::count(step.begin(), step.begin() + static_cast<std::ptrdiff_t>(where), '\n');
  std::ofstream(file) << step;
  const std::string e = error(file, 1), head = file.string() + ": a malformed STEP file: Undefined Parsing: Line ";
  ASSERT_EQ(e.rfind(head, 0), 0u) << e;
  // OpenCASCADE's lexer names the line where it met the unexpected token: the damaged one or the next.
  const long named = std::stol(e.substr(head.size()));
  EXPECT_TRUE(named == line || named == line + 1) << e << " (damaged line " << line << ")";
  EXPECT_NE(e.find("Incorrect syntax"), std::string::npos) << e;
}

// Found by the fuzzer past that check: an oriented edge that is its own edge sent OpenCASCADE 7.6.3
// into an endless recursion (SIGSEGV; the worker process contained it). A cycle among a shape's
// entities is now refused before translation, naming it; so is one through several entities.
TEST(StepFace, AShapeEntityThatRefersBackToItselfIsRefusedNamingTheCycle) {
  const fs::path file = scratch("own_edge.step");
  write_step(bezier_face(drom::tests::rubio_surface()), file);
  const std::string sound = text_of(file);
  const OrientedEdge edge = first_oriented_edge(sound);
  ASSERT_NE(edge.edge_at, std::string::npos);
  const std::string& self = edge.self;
  std::string step = sound;
  step.replace(edge.edge_at, edge.edge_length, self);
  std::ofstream(file) << step;
  EXPECT_EQ(error(file, 1), file.string() + ": a malformed STEP file: " + self + " (StepShape_OrientedEdge) refers back to itself (a shape's entities cannot refer to themselves)");
  // Through two entities: the oriented edge's edge is a second oriented edge, whose edge is the first.
  step = sound;
  const std::string second = "#999999";
  step.replace(edge.edge_at, edge.edge_length, second);
  const auto data_end = step.rfind("ENDSEC;");
  step.insert(data_end, second + " = ORIENTED_EDGE('',*,*," + self + ",.T.);\n");
  std::ofstream(file) << step;
  EXPECT_EQ(error(file, 1), file.string() + ": a malformed STEP file: " + self + " (StepShape_OrientedEdge) refers back to itself through " + second +
                                " (StepShape_OrientedEdge) (a shape's entities cannot refer to themselves)");
  // The process still reads a sound file afterwards.
  std::ofstream(file) << sound;
  EXPECT_EQ(drom::geometry::count_step_faces(file), 1);
}

// A crash of OpenCASCADE that drom does not foresee is contained by the worker process: oriented
// edges nested 400 000 deep (legal STEP, no cycle) recurse past the stack in OpenCASCADE 7.6.3's
// StepShape_OrientedEdge::EdgeStart. drom reports it and lives on.
TEST(StepFace, AFileThatCrashesOpenCascadeIsAClearErrorAndDromLivesOn) {
  // 400 000 frames of some 48 bytes overrun a stack of up to ~19 MB (Debian's default is 8 MB).
  rlimit stack{};
  ASSERT_EQ(::getrlimit(RLIMIT_STACK, &stack), 0);
  if (stack.rlim_cur == RLIM_INFINITY || stack.rlim_cur > (16u << 20))
    GTEST_SKIP() << "the stack limit (ulimit -s) is above 16 MB: the nested edges would not overrun it";
  const fs::path file = scratch("deep_edges.step");
  write_step(bezier_face(drom::tests::rubio_surface()), file);
  std::string step = text_of(file);
  const OrientedEdge edge = first_oriented_edge(step);
  ASSERT_NE(edge.edge_at, std::string::npos);
  const std::string edge_curve = step.substr(edge.edge_at, edge.edge_length);
  constexpr int kDepth = 400000, kFirst = 1000000;
  step.replace(edge.edge_at, edge.edge_length, "#" + std::to_string(kFirst));
  std::ostringstream chain;
  for (int k = 0; k < kDepth; ++k) {
    chain << '#' << kFirst + k << " = ORIENTED_EDGE('',*,*,";
    if (k + 1 < kDepth) chain << '#' << kFirst + k + 1;
    else chain << edge_curve;
    chain << ",.T.);\n";
  }
  step.insert(step.rfind("ENDSEC;"), chain.str());
  std::ofstream(file) << step;
  EXPECT_EQ(error(file, 1).rfind(file.string() + ": OpenCASCADE crashed reading it (Segmentation fault)", 0), 0u) << error(file, 1);
  // The process still reads a sound file afterwards.
  const fs::path sound = scratch("sound.step");
  write_step(bezier_face(drom::tests::rubio_surface()), sound);
  EXPECT_EQ(drom::geometry::count_step_faces(sound), 1);
}

// OpenCASCADE runs in one kept worker process (geometry/step_face.cpp): reads in a row, crashes
// between them, and a forked copy of drom each get their own answers.
TEST(StepFace, TheKeptTranslatorServesReadsInARowAcrossCrashesAndForks) {
  const fs::path sound = scratch("row.step");
  write_step(bezier_face(drom::tests::rubio_surface()), sound);
  const fs::path garbage = scratch("row_garbage.step");
  std::ofstream(garbage) << "ISO-10303-21;\nnothing here\n";
  for (int round = 0; round < 3; ++round) {
    for (int k = 0; k < 20; ++k) {
      EXPECT_EQ(drom::geometry::count_step_faces(sound), 1);
      EXPECT_EQ(error(garbage, 1), garbage.string() + ": not a readable STEP file");
    }
    const auto face = drom::geometry::read_step_face(sound, 1);
    EXPECT_LT((face.surface.point(0.5, 0.5) - drom::tests::rubio_surface().point(0.5, 0.5)).norm(), 1e-9);
    // A forked copy of this process reads with a worker of its own, and leaves this one's alone.
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) ::_exit(drom::geometry::count_step_faces(sound) == 1 ? 0 : 1);
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  }
  // The worker keeps the last file's faces: the same path written anew is translated anew.
  write_step(bezier_face(drom::tests::choi_surface()), sound);
  const auto choi = drom::geometry::read_step_face(sound, 1);
  EXPECT_LT((choi.surface.point(0.3, 0.7) - drom::tests::choi_surface().point(0.3, 0.7)).norm(), 1e-9);
}

}  // namespace
