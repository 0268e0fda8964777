#include "geometry/step_face.hpp"

#include "support/byte_stream.hpp"
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

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <mutex>
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

int count_faces_here(const std::filesystem::path& path) {
  try {
    return load_faces(path).Extent();
  } catch (const Standard_Failure& e) {
    throw InputError(path.string() + ": OpenCASCADE could not read it: " + e.GetMessageString());
  }
}

StepFace read_face_here(const std::filesystem::path& path, int index) {
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

// ---- OpenCASCADE in a child process ----
// OpenCASCADE's STEP translator is not hardened against malformed files: the fuzzer found a file on
// which it dereferences a null entity (StepGeom_CartesianPoint::NbCoordinates, 7.6.3). A crash there
// must not take drom (and a night's closed loop) down with it, so the file is read in a forked child
// that sends back drom's own types as bytes; a child that dies or hangs becomes an InputError naming
// the file. The parent checks what it receives as it would any outside data.

// Bounds on what one face may hold: far above any CAD face, low enough that a damaged answer
// cannot ask for gigabytes.
constexpr std::int64_t kMostPoles = 1 << 22, kMostKnots = 1 << 16, kMostLoops = 1 << 16, kMostLoopPoints = 1 << 22;

std::string encode(const StepFace& face) {
  ByteWriter b;
  const NurbsSurface& s = face.surface;
  b.put<std::int64_t>(s.degree_u()), b.put<std::int64_t>(s.degree_v());
  b.put<std::int64_t>(s.count_u()), b.put<std::int64_t>(s.count_v());
  b.put(s.knots_u()), b.put(s.knots_v());
  std::vector<double> xyz;
  for (const auto& p : s.points()) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
  b.put(xyz);
  b.put(s.is_rational() ? s.weights() : std::vector<double>{});
  b.put<std::int64_t>(static_cast<std::int64_t>(face.trim.loops().size()));
  for (const auto& loop : face.trim.loops()) {
    std::vector<double> uv;
    for (const auto& q : loop) uv.insert(uv.end(), {q.x(), q.y()});
    b.put(uv);
  }
  b.put(std::string_view(face.source_type));
  b.put<std::int64_t>(face.reversed ? 1 : 0);
  return b.take();
}

StepFace decode(std::string_view bytes, const std::string& origin, int index) {
  ByteReader r(bytes, origin + ": OpenCASCADE's reader's answer");
  const auto count = [&](std::int64_t most) {
    const auto n = r.get<std::int64_t>();
    if (n < 0 || n > most) throw InputError(origin + ": OpenCASCADE's face holds a count of " + std::to_string(n) + ", expected 0 to " + std::to_string(most));
    return n;
  };
  const auto numbers = [&](std::int64_t most) {
    auto v = r.vector<double>();
    if (static_cast<std::int64_t>(v.size()) > most)
      throw InputError(origin + ": OpenCASCADE's face holds " + std::to_string(v.size()) + " numbers where " + std::to_string(most) + " at most are expected");
    for (const double x : v)
      if (!std::isfinite(x)) throw InputError(origin + ": OpenCASCADE's face holds a number that is not finite");
    return v;
  };
  const auto degree_u = static_cast<int>(count(64)), degree_v = static_cast<int>(count(64));
  const auto count_u = static_cast<int>(count(kMostPoles)), count_v = static_cast<int>(count(kMostPoles));
  auto knots_u = numbers(kMostKnots), knots_v = numbers(kMostKnots);
  const auto xyz = numbers(3 * kMostPoles);
  auto weights = numbers(kMostPoles);
  if (xyz.size() != 3 * static_cast<std::size_t>(count_u) * static_cast<std::size_t>(count_v))
    throw InputError(origin + ": face " + std::to_string(index) + ": " + std::to_string(xyz.size() / 3) + " control points for a " + std::to_string(count_u) + " x " +
                     std::to_string(count_v) + " net");
  std::vector<Eigen::Vector3d> points;
  for (std::size_t k = 0; k < xyz.size(); k += 3) points.emplace_back(xyz[k], xyz[k + 1], xyz[k + 2]);
  std::vector<std::vector<Eigen::Vector2d>> loops(static_cast<std::size_t>(count(kMostLoops)));
  for (auto& loop : loops) {
    const auto uv = numbers(2 * kMostLoopPoints);
    for (std::size_t k = 0; k + 1 < uv.size(); k += 2) loop.emplace_back(uv[k], uv[k + 1]);
  }
  StepFace face;
  face.source_type = r.text();
  face.reversed = count(1) == 1;
  if (!r.done()) throw InputError(origin + ": OpenCASCADE's reader sent more than one face");
  try {
    face.surface = NurbsSurface(degree_u, degree_v, std::move(knots_u), std::move(knots_v), count_u, count_v, std::move(points), std::move(weights));
  } catch (const std::invalid_argument& e) {
    throw InputError(origin + ": face " + std::to_string(index) + " is not a valid patch: " + e.what());
  }
  face.trim = TrimLoops(std::move(loops));
  return face;
}

void write_all(int fd, const std::string& bytes) {
  for (std::size_t done = 0; done < bytes.size();) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    done += static_cast<std::size_t>(n);
  }
}

// The STEP translator's static tables (the AP203/AP214 schema's entity types, its parameters) are
// built once, in drom's own process, so that every child inherits them and starts reading at once
// instead of building them again: with them built here a small file is read in a fraction of the time.
// Building them reads no file; only the translation of a file runs in the child.
void prepare_translator() {
  static std::once_flag once;
  std::call_once(once, [] {
    Message::DefaultMessenger()->ChangePrinters().Clear();
    STEPControl_Reader warm;
  });
}

// `work` run in a child process: its answer's bytes, or its InputError rethrown here. A child that
// crashes, stops without an answer or outlives `limit` is an InputError naming the file.
std::string in_child_process(const std::filesystem::path& path, const std::function<std::string()>& work, std::chrono::seconds limit) {
  const std::string origin = path.string();
  prepare_translator();
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) throw InputError(origin + ": cannot start OpenCASCADE's reader: " + std::strerror(errno));
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(pipe_fds[0]), ::close(pipe_fds[1]);
    throw InputError(origin + ": cannot start OpenCASCADE's reader: " + std::strerror(errno));
  }
  if (pid == 0) {
    // The child dies of its own crash: no handler inherited from the parent (a fuzzer's, a
    // sanitizer's) may report it as the parent's.
    for (const int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) ::signal(sig, SIG_DFL);
    ::close(pipe_fds[0]);
    char kind = 'F';
    std::string answer;
    try {
      answer = work();
    } catch (const InputError& e) {
      kind = 'E', answer = e.what();
    } catch (const Standard_Failure& e) {
      kind = 'E', answer = origin + ": OpenCASCADE could not read it: " + e.GetMessageString();
    } catch (const std::exception& e) {
      kind = 'E', answer = origin + ": OpenCASCADE's reader failed: " + e.what();
    } catch (...) {
      kind = 'E', answer = origin + ": OpenCASCADE's reader failed";
    }
    write_all(pipe_fds[1], std::string(1, kind) + answer);
    ::_exit(0);
  }
  ::close(pipe_fds[1]);
  std::string bytes;
  const auto deadline = std::chrono::steady_clock::now() + limit;
  bool timed_out = false;
  for (char buffer[65536];;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) {
      timed_out = true;
      break;
    }
    pollfd p{pipe_fds[0], POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(std::min<long long>(left, 1000)));
    if (ready < 0 && errno != EINTR) break;
    if (ready <= 0) continue;
    const ssize_t n = ::read(pipe_fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    bytes.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(pipe_fds[0]);
  if (timed_out) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out) throw InputError(origin + ": OpenCASCADE did not finish reading it within " + std::to_string(limit.count()) + " s");
  if (WIFSIGNALED(status))
    throw InputError(origin + ": OpenCASCADE crashed reading it (" + strsignal(WTERMSIG(status)) +
                     "): the file is malformed, or holds an entity OpenCASCADE 7.6 cannot translate");
  if (bytes.empty() || (bytes[0] != 'F' && bytes[0] != 'E'))
    throw InputError(origin + ": OpenCASCADE's reader stopped without an answer (exit status " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
  if (bytes[0] == 'E') throw InputError(bytes.substr(1));
  return bytes.substr(1);
}

// A large assembly takes OpenCASCADE a minute or two; ten is a reader stuck.
constexpr std::chrono::seconds kReadLimit{600};

}  // namespace

int count_step_faces(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path.string() + ": no such STEP file");
  const std::string answer = in_child_process(path, [&] { return std::to_string(count_faces_here(path)); }, kReadLimit);
  int faces = 0;
  std::istringstream in(answer);
  if (!(in >> faces) || faces < 1) throw InputError(path.string() + ": OpenCASCADE's reader sent no face count");
  return faces;
}

StepFace read_step_face(const std::filesystem::path& path, int index) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path.string() + ": no such STEP file");
  return decode(in_child_process(path, [&] { return encode(read_face_here(path, index)); }, kReadLimit), path.string(), index);
}

}  // namespace drom::geometry
