// drom_fuzz_seeds <corpus folder> <base folder>: the seed corpus of every harness, made from the shipped
// cases (cases/*.toml) and machines (cases/machines/*.toml): the case and machine files themselves, their
// quick overrides, their toolpaths as G-code, a 5-axis CL program (APT, CSV) and its post-processed G-code,
// their stress profiles as tables, their stock as STL, the chapter 2 blank as a measured surface,
// and the flat plate's coarse snapshot database and light model (the base files of the *_fields
// harnesses). Deterministic: the same tree gives the same seeds.
#include "case_file/case.hpp"
#include "fem/residual_stress.hpp"
#include "geometry/cloud_writer.hpp"
#include "levelset/gcode.hpp"
#include "machine/cl_data.hpp"
#include "machine/machine_definition.hpp"
#include "machine/post_processor.hpp"
#include "machine/rs274_reader.hpp"
#include "offline/offline_job.hpp"
#include "offline/part_setup.hpp"
#include "paths/copy/copy_settings.hpp"
#include "reduce/database_reduction.hpp"
#include "reduce/deviation_family.hpp"
#include "support/atomic_file.hpp"

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <Geom_BezierSurface.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <STEPControl_Writer.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Pln.hxx>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace drom;

namespace {

const fs::path kCases = DROM_SOURCE_DIR "/cases";
const fs::path kMachines = DROM_SOURCE_DIR "/cases/machines";

// A 5-axis CL program: rapid, a tilted plunge, a swept tool axis, with continuations and comments.
const char* kAptSeed = R"(PARTNO/SEED
UNITS/MM
MULTAX/ON
$$ a comment
RAPID
GOTO/0.000,0.000,20.000,0.0,0.0,1.0
FEDRAT/1200.0,MMPM
GOTO/10.000,0.000,5.000,$
0.0,0.2588190,0.9659258
GOTO/20.000,5.000,4.000,0.1736482,0.0,0.9848078
TLAXIS/0.0,0.0,1.0
GOTO/30.000,5.000,4.000
FINI
)";

void put(const fs::path& file, const std::string& bytes) { write_file_atomically(file, bytes); }

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

std::string stress_table(const fem::StressProfile& p, double thickness) {
  std::ostringstream csv;
  csv << "depth,sigma11,sigma22\n";
  for (int i = 0; i <= 10; ++i) {
    const double depth = thickness * i / 10.0;
    const Eigen::Vector2d s = p.evaluate(1 - 2 * depth / thickness);
    csv << depth << "," << s.x() << "," << s.y() << "\n";
  }
  return csv.str();
}

// The 12 triangles of an axis-aligned box, outward.
std::vector<std::array<Eigen::Vector3d, 3>> box_triangles(double lx, double ly, double lz) {
  const auto corner = [&](int i) { return Eigen::Vector3d((i & 1) ? lx : 0, (i & 2) ? ly : 0, (i & 4) ? lz : 0); };
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  std::vector<std::array<Eigen::Vector3d, 3>> t;
  for (const auto& q : quads) {
    t.push_back({corner(q[0]), corner(q[1]), corner(q[2])});
    t.push_back({corner(q[0]), corner(q[2]), corner(q[3])});
  }
  return t;
}

std::string ascii_stl(const std::vector<std::array<Eigen::Vector3d, 3>>& tris) {
  std::ostringstream s;
  s << "solid stock\n";
  for (const auto& t : tris) {
    const Eigen::Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
    s << " facet normal " << n.x() << " " << n.y() << " " << n.z() << "\n  outer loop\n";
    for (const auto& v : t) s << "   vertex " << v.x() << " " << v.y() << " " << v.z() << "\n";
    s << "  endloop\n endfacet\n";
  }
  s << "endsolid stock\n";
  return s.str();
}

std::string binary_stl(const std::vector<std::array<Eigen::Vector3d, 3>>& tris) {
  std::string s(80, ' ');
  const auto count = static_cast<std::uint32_t>(tris.size());
  s.append(reinterpret_cast<const char*>(&count), 4);
  for (const auto& t : tris) {
    const Eigen::Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
    float f[12];
    for (int k = 0; k < 3; ++k) f[k] = static_cast<float>(n[k]);
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k) f[3 + 3 * v + k] = static_cast<float>(t[static_cast<std::size_t>(v)][k]);
    s.append(reinterpret_cast<const char*>(f), sizeof f);
    s.append(2, '\0');
  }
  return s;
}

// A shape as STEP bytes (OpenCASCADE's writer, through a file: it writes to paths only).
std::string step_bytes(const TopoDS_Shape& shape, const fs::path& scratch) {
  Message::DefaultMessenger()->ChangePrinters().Clear();
  STEPControl_Writer writer;
  if (writer.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone || writer.Write(scratch.string().c_str()) != IFSelect_RetDone)
    throw std::runtime_error("OpenCASCADE could not write the STEP seed " + scratch.string());
  std::ifstream in(scratch, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  fs::remove(scratch);
  return s.str();
}

// A sphere cap of radius 38.25 mm (the seed's 76.5 mm sphere) sampled on a 6 x 6 grid, with outward normals.
geometry::PointCloud sphere_cap() {
  geometry::PointCloud cloud;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      const Eigen::Vector3d n = Eigen::Vector3d(0.12 * (i - 2.5), 0.12 * (j - 2.5), 1).normalized();
      cloud.points.push_back(38.25 * n);
      cloud.normals.push_back(n);
    }
  return cloud;
}

std::string file_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: drom_fuzz_seeds <corpus folder> <base folder>\n");
    return 2;
  }
  const fs::path corpus = argv[1], base = argv[2];
  try {
    for (const char* name : {"flat_plate", "curved_panel"}) {
      const fs::path file = kCases / (std::string(name) + ".toml");
      put(corpus / "case_file" / (std::string(name) + ".toml"), file_text(file));
      const case_file::Case written = case_file::load_case(file, {});
      put(corpus / "case_overrides" / (std::string(name) + "_quick"), joined(written.run_quick));
      const case_file::Case c = case_file::load_case(file, written.run_quick);
      const offline::PartModel part = offline::build_part(c);
      // The program's first 40 lines (its header, a plunge, arcs where it has them): a whole program is
      // tens of kB, and a small seed fuzzes faster.
      std::istringstream program(levelset::write_gcode(offline::build_toolpath(c, part), c.name));
      std::string head;
      int lines = 0;
      for (std::string line; lines < 40 && std::getline(program, line); ++lines) head += line + "\n";
      put(corpus / "gcode" / (std::string(name) + ".nc"), head + "M30\n");
      put(corpus / "stress_table" / (std::string(name) + ".csv"), stress_table(part.profile, part.shape.thickness()));
      put(corpus / "stress_table" / (std::string(name) + "_truth.csv"), stress_table(part.truth_profile, part.shape.thickness()));
      const auto box = box_triangles(c.length_x, c.length_y, c.thickness);
      put(corpus / "stl" / (std::string(name) + "_ascii.stl"), ascii_stl(box));
      put(corpus / "stl" / (std::string(name) + "_binary.stl"), binary_stl(box));
      put(corpus / "stl_mesh" / (std::string(name) + "_ascii.stl"), ascii_stl(box));
      put(corpus / "stl_mesh" / (std::string(name) + "_binary.stl"), binary_stl(box));
    }
    put(corpus / "case_overrides" / "docs", "sensor.noise=0\nrun.scale=seed\nmesh.nx=20\nmesh.ny=20\nclamps.0.box=[0,100,0,100]\ncontrol.correct=false\n");
    put(corpus / "gcode" / "arcs_inch.nc", "G20 G90 G17\nG0 X0 Y0 Z0.2\nG1 Z-0.05 F20\nG2 X1 Y1 I1 J0\nG3 X0 Y2 R1\nG91 G1 X-0.5\nG90 G43 H2 G0 Z1\nG49 M30\n");
    put(corpus / "deviation_case" / "deviation.toml", file_text(kCases / "deviation.toml"));
    put(corpus / "gcode" / "helix_planes.nc", "G21 G90 G17 G64 P0.02\nG0 X10 Y0 Z5\nG1 Z0 F600\nG3 X0 Y-10 I-10 J0 P2 Z-1\nG18 G2 X10 Z-1 I5 K0 F400\n"
                                               "G19 G3 Y-10 Z9 J0 K5\nG61.1 G4 P0.5\nM30\n");
    put(corpus / "gcode_rs274" / "parameters.ngc", "G21 G90\n#1 = 5\nG0 X0 Y0 Z[#1 * 2]\no100 repeat [3]\n  G91 G1 X#1 F300\no100 endrepeat\nG90 G2 X0 Y0 I-5 J0\nM2\n");
    put(corpus / "gcode_rs274" / "arcs_inch.nc", file_text(corpus / "gcode" / "arcs_inch.nc"));
    // rs274's own output on those programs and on one it refuses (an arc without its centre), for the
    // in-process harness of drom's side (rs274_calls); skipped where LinuxCNC is not installed.
    if (machine::rs274_available()) {
      fs::create_directories(base);
      put(base / "refused.ngc", "G21 G90\nG0 X0 Y0\nG2 X10 Y10 F100\nM2\n");
      for (const fs::path& program : {corpus / "gcode_rs274" / "parameters.ngc", corpus / "gcode_rs274" / "arcs_inch.nc", corpus / "gcode" / "helix_planes.nc", base / "refused.ngc"}) {
        const machine::Rs274Run run = machine::run_rs274(program);
        const char status = static_cast<char>(run.status == 0 ? 0 : run.status > 128 ? 255 : std::min(199 + run.status, 254));
        put(corpus / "rs274_calls" / program.filename(), std::string(1, status) + run.calls);
      }
      fs::remove(base / "refused.ngc");
    }
    for (const auto& machine_file : fs::directory_iterator(kMachines))
      if (machine_file.path().extension() == ".toml") put(corpus / "machine_file" / machine_file.path().filename(), file_text(machine_file.path()));
    const machine::ClProgram cl = machine::parse_apt_cl(kAptSeed, "seed.apt");
    put(corpus / "cl_file" / "five_axis.apt", kAptSeed);
    put(corpus / "cl_file" / "five_axis.csv", machine::cl_csv(cl));
    const machine::Kinematics five_axis(machine::load_machine("ucp710_like"));
    put(corpus / "gcode" / "five_axis_post.nc", machine::post_process(cl, five_axis));
    std::ostringstream surface;
    surface << "x,y,z\n";
    for (int i = 0; i <= 5; ++i)
      for (int j = 0; j <= 5; ++j) surface << 20.0 * i << "," << 20.0 * j << "," << reduce::seed_true_surface(20.0 * i, 20.0 * j) << "\n";
    put(corpus / "measured_surface" / "seed_blank.csv", surface.str());

    // The toolpath side (issues 22-24): clouds, STEP faces, finishing/copy/orientation cases.
    const geometry::PointCloud cap = sphere_cap();
    geometry::PointCloud bare = cap;
    bare.normals.clear();
    put(corpus / "cloud" / "cap_binary.ply", geometry::ply_bytes(cap, {}, true));
    put(corpus / "cloud" / "cap_ascii.ply", geometry::ply_bytes(bare, {}, false));
    std::ostringstream xyz, csv;
    csv << "x,y,z,nx,ny,nz\n";
    for (std::size_t i = 0; i < cap.size(); ++i) {
      xyz << cap.points[i].x() << " " << cap.points[i].y() << " " << cap.points[i].z() << "\n";
      csv << cap.points[i].x() << "," << cap.points[i].y() << "," << cap.points[i].z() << "," << cap.normals[i].x() << "," << cap.normals[i].y() << "," << cap.normals[i].z() << "\n";
    }
    put(corpus / "cloud" / "cap.xyz", xyz.str());
    put(corpus / "cloud" / "cap_normals.csv", csv.str());
    // PCD (issue 45): ascii with normals, binary float32 without, and a binary_compressed of two
    // points whose LZF stream holds a literal run and a back-reference.
    {
      const std::string fields = "FIELDS x y z normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4\nTYPE F F F F F F\nCOUNT 1 1 1 1 1 1\n";
      std::ostringstream ascii, binary;
      ascii << "# .PCD v0.7\nVERSION 0.7\n" << fields << "WIDTH " << cap.size() << "\nHEIGHT 1\nPOINTS " << cap.size() << "\nDATA ascii\n";
      binary << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH " << cap.size() << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << cap.size() << "\nDATA binary\n";
      for (std::size_t i = 0; i < cap.size(); ++i) {
        ascii << cap.points[i].x() << " " << cap.points[i].y() << " " << cap.points[i].z() << " " << cap.normals[i].x() << " " << cap.normals[i].y() << " " << cap.normals[i].z() << "\n";
        for (int k = 0; k < 3; ++k) {
          const auto v = static_cast<float>(cap.points[i][k]);
          binary.write(reinterpret_cast<const char*>(&v), sizeof v);
        }
      }
      put(corpus / "cloud" / "cap_ascii.pcd", ascii.str());
      put(corpus / "cloud" / "cap_binary.pcd", binary.str());
      const float one = 1.0f, two = 2.0f;
      std::string z(1, '\x07');  // 8 literal bytes: x of both points
      for (int k = 0; k < 2; ++k) z.append(reinterpret_cast<const char*>(&one), 4);
      z.append("\xc0\x07", 2);  // 8 bytes from 8 back: y = x
      z.push_back('\x07');
      for (int k = 0; k < 2; ++k) z.append(reinterpret_cast<const char*>(&two), 4);
      const std::uint32_t sizes[2] = {static_cast<std::uint32_t>(z.size()), 24u};
      put(corpus / "cloud" / "two_compressed.pcd",
          "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 2\nDATA binary_compressed\n" + std::string(reinterpret_cast<const char*>(sizes), 8) + z);
    }
    TColgp_Array2OfPnt poles(1, 3, 1, 3);
    for (int i = 1; i <= 3; ++i)
      for (int j = 1; j <= 3; ++j) poles.SetValue(i, j, gp_Pnt(40.0 * (i - 1), 22.5 * (j - 1), (i == 2 && j == 2) ? 30.0 : 5.0 * i));
    const fs::path step_scratch = base / "seed.step";
    fs::create_directories(base);
    put(corpus / "step_face" / "bezier.step", step_bytes(BRepBuilderAPI_MakeFace(new Geom_BezierSurface(poles), 1e-7).Face(), step_scratch));
    BRepBuilderAPI_MakePolygon triangle(gp_Pnt(0, 0, 2), gp_Pnt(10, 0, 2), gp_Pnt(0, 10, 2), Standard_True);
    put(corpus / "step_face" / "trimmed_plane.step", step_bytes(BRepBuilderAPI_MakeFace(gp_Pln(gp_Pnt(0, 0, 2), gp_Dir(0, 0, 1)), triangle.Wire()).Face(), step_scratch));
    put(corpus / "step_face" / "vertex_only.step", step_bytes(BRepBuilderAPI_MakeVertex(gp_Pnt(1, 2, 3)).Vertex(), step_scratch));
    for (const char* name : {"rubio", "choi", "inclined_plane"}) put(corpus / "path_cases" / (std::string("finish_") + name), std::string(1, char(0)) + file_text(kCases / (std::string(name) + ".toml")));
    put(corpus / "path_cases" / "copy_default", std::string(1, char(1)) + paths::default_copy_settings());
    for (const char* name : {"orient_bump", "orient_corner", "orient_impeller", "orient_panel"})
      put(corpus / "path_cases" / name, std::string(1, char(2)) + file_text(kCases / (std::string(name) + ".toml")));

    // The flat plate's coarsest database and model (3 x 3 x 5 Hex20, a station every 400 mm: 0.23 MB and
    // 39 kB, a third of the 5 x 5 x 5 plate's, so a harness writes and seals less per input).
    const case_file::Case coarse = case_file::load_case(kCases / "flat_plate.toml",
                                                {"mesh.nx=3", "mesh.ny=3", "path.station_spacing=400", "removal.voxel_size=2.0", "clamps.0.box=[0,200,0,200]",
                                                 "clamps.1.box=[800,1000,0,200]", "clamps.2.box=[0,200,800,1000]", "clamps.3.box=[800,1000,800,1000]"});
    offline::JobOptions options;
    options.out = base / "offline";
    options.quiet = true;
    if (!fs::exists(base / "database.h5")) {
      fs::remove_all(options.out);
      if (!offline::run_job(coarse, offline::JobKind::Offline, options).finished) throw std::runtime_error("the coarse offline job did not finish");
      fs::copy_file(options.out / "database.h5", base / "database.h5", fs::copy_options::overwrite_existing);
      const auto reduced = reduce::reduce_database(base / "database.h5", {});
      reduce::write_reduction(base / "model" / "model.h5", reduced);
      fs::copy_file(base / "model" / "model.h5", base / "model.h5", fs::copy_options::overwrite_existing);
      fs::remove_all(options.out);
      fs::remove_all(base / "model");
    }
    put(corpus / "database_bytes" / "flat_plate_coarse.h5", file_text(base / "database.h5"));
    put(corpus / "model_bytes" / "flat_plate_coarse.h5", file_text(base / "model.h5"));
    // The edit scripts: none (the base as it is), and a few bytes for the mutator to grow.
    for (const char* harness : {"database_fields", "model_fields"}) {
      put(corpus / harness / "unchanged", "");
      put(corpus / harness / "one_edit", std::string("\x02\x05\x01\x00", 4));
    }
    // Findings 16-23 (docs/robustness.md), as the edit scripts that found them on this base: every
    // smoke run replays them first. 16: a point dataset given a fourth column (a heap overflow in the
    // model reader); 17: snapshots made huge (the POD's std::invalid_argument); 18: a case coefficient
    // of -1.8e308 MPa (an infinite error bound accepted); 19: a path far out (a cut-time grid past an int).
    put(corpus / "model_fields" / "finding_16", std::string("\x01\x05\x10\x01", 4));
    put(corpus / "database_fields" / "finding_17", std::string("\x00\x02", 2));
    put(corpus / "database_fields" / "finding_18", std::string("\x03\x02", 2));
    put(corpus / "model_fields" / "finding_19", std::string("\xf4\x02", 2));
    // 20: a prior covariance that is no covariance (the predictor's std::invalid_argument); 21: the
    // stock top's snapshots made huge (an overflow to an empty POD block: UBSan).
    put(corpus / "model_fields" / "finding_20", std::string("\xb1\x12", 2));
    put(corpus / "database_fields" / "finding_21", std::string("\xfe\xff", 2));
    // 22: a model surface node far off (a bucket index past an int: UBSan); 23: surface faces of one
    // node (the mesh's std::invalid_argument).
    put(corpus / "model_fields" / "finding_22", std::string("\xff\x04\xfe\xff", 4));
    put(corpus / "database_fields" / "finding_23", std::string("\xfc\xff\x7e\xf9", 4));
    // 26: the prior mean scaled to 5.5e306 and a mode's space factors by 1e9 (an infinite bound on
    // the commanded offset).
    put(corpus / "model_fields" / "finding_26", std::string("\xfe\x7f\xff\xff\x83\x01\xff", 7));
    // 28: top_parametric reshaped to one column (read past its end while the stock's top was kept).
    put(corpus / "database_fields" / "finding_28", std::string("\x7b\x40\x01\xd1\x85\xc1\xfe\x61\x80\x98\x2e\x7b\x40\xb3", 14));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "drom_fuzz_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
