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
#include <IFSelect_WorkLibrary.hxx>
#include <Interface_Check.hxx>
#include <Interface_CheckIterator.hxx>
#include <Interface_EntityIterator.hxx>
#include <Interface_Graph.hxx>
#include <Interface_InterfaceModel.hxx>
#include <Interface_Protocol.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Wire.hxx>
#include <XSControl_WorkSession.hxx>

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>
#include <vector>

namespace drom::geometry {

namespace {

std::string file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// A file whose entities OpenCASCADE could not read (a syntax error, a reference to an entity that is
// not there or of the wrong type) is refused before anything is translated, with OpenCASCADE's
// words and the file's line: translating the rest is how OpenCASCADE 7.6 reached a null point and
// crashed (finding 14), and a shape with a hole where an entity failed is no face to machine.
void refuse_failed_checks(STEPControl_Reader& reader, const std::filesystem::path& path) {
  Interface_CheckIterator checks = reader.WS()->ModelCheckList();
  std::string first;
  int failed = 0;
  for (checks.Start(); checks.More(); checks.Next()) {
    const Handle(Interface_Check)& check = checks.Value();
    if (!check->HasFailed()) continue;
    failed += check->NbFails();
    if (first.empty()) {
      first = check->CFail(1);
      if (checks.Number() > 0) first = "entity #" + std::to_string(checks.Number()) + ": " + first;
    }
  }
  if (failed > 0)
    throw InputError(path.string() + ": a malformed STEP file: " + first + (failed > 1 ? " (and " + std::to_string(failed - 1) + " more)" : ""));
}

// OpenCASCADE 7.6 follows a shape entity's references recursively (an oriented edge's edge, a trimmed
// curve's basis curve, an offset surface's basis surface) with no guard, in its translation and
// already in the checks its ReadFile runs: an entity that refers back to itself, directly or through
// others, recursed until the stack ran out (a crash the step_face fuzzer found, docs/robustness.md).
// A shape's geometry and topology form a hierarchy in any real file, so a cycle among them is
// refused, naming it, before OpenCASCADE checks or translates anything. The search is iterative: a
// file's own depth cannot exhaust drom's stack either.
void refuse_reference_cycles(const Handle(Interface_InterfaceModel)& model, const Handle(Interface_Protocol)& protocol, const std::filesystem::path& path) {
  const Interface_Graph graph(model, protocol, Standard_False);
  const int n = model->NbEntities();
  const auto is_shape_entity = [](const Handle(Standard_Transient)& e) {
    if (e.IsNull()) return false;
    const char* type = e->DynamicType()->Name();
    return std::strncmp(type, "StepGeom_", 9) == 0 || std::strncmp(type, "StepShape_", 10) == 0;
  };
  const auto named = [&](int number) {
    const Handle(Standard_Transient)& e = model->Value(number);
    const Handle(TCollection_HAsciiString) label = model->StringLabel(e);
    return std::string(label.IsNull() ? "#?" : label->ToCString()) + " (" + e->DynamicType()->Name() + ")";
  };
  const auto shared_shapes = [&](int number) {
    std::vector<int> out;
    for (Interface_EntityIterator it = graph.Shareds(model->Value(number)); it.More(); it.Next())
      if (is_shape_entity(it.Value())) out.push_back(model->Number(it.Value()));
    return out;
  };
  enum : char { kUnseen, kOnPath, kDone };
  std::vector<char> state(static_cast<std::size_t>(n) + 1, kUnseen);
  struct Visit {
    int number;
    std::vector<int> next;
    std::size_t at = 0;
  };
  std::vector<Visit> path_to;
  for (int root = 1; root <= n; ++root) {
    if (state[static_cast<std::size_t>(root)] != kUnseen || !is_shape_entity(model->Value(root))) continue;
    path_to.push_back({root, shared_shapes(root)});
    state[static_cast<std::size_t>(root)] = kOnPath;
    while (!path_to.empty()) {
      Visit& v = path_to.back();
      if (v.at == v.next.size()) {
        state[static_cast<std::size_t>(v.number)] = kDone;
        path_to.pop_back();
        continue;
      }
      const int next = v.next[v.at++];
      if (next <= 0 || next > n || state[static_cast<std::size_t>(next)] == kDone) continue;
      if (state[static_cast<std::size_t>(next)] == kOnPath) {
        std::size_t first = path_to.size() - 1;
        while (path_to[first].number != next) --first;
        std::string through;
        for (std::size_t k = first + 1; k < path_to.size(); ++k) through += (through.empty() ? " through " : ", ") + named(path_to[k].number);
        throw InputError(path.string() + ": a malformed STEP file: " + named(next) + " refers back to itself" + through +
                         " (a shape's entities cannot refer to themselves)");
      }
      state[static_cast<std::size_t>(next)] = kOnPath;
      path_to.push_back({next, shared_shapes(next)});
    }
  }
}

// The file's faces, each once, in OpenCASCADE's exploration order. The worker keeps the last file's
// faces: a case that takes several faces of one part (check surfaces, a face count then a face) has
// the file translated once, not once a face (a large assembly takes a minute or two). The cache is
// keyed by the path and the file's whole content, read before and after the translation.
const TopTools_IndexedMapOfShape& load_faces(const std::filesystem::path& path) {
  static std::string cached_path, cached_bytes;
  static TopTools_IndexedMapOfShape cached_faces;
  if (!std::filesystem::is_regular_file(path)) throw InputError(path.string() + ": no such STEP file");
  std::string bytes = file_bytes(path);
  if (path.string() == cached_path && bytes == cached_bytes) return cached_faces;
  cached_path.clear(), cached_bytes.clear(), cached_faces.Clear();
  // OpenCASCADE reports its progress on stdout; drom's commands own stdout.
  Message::DefaultMessenger()->ChangePrinters().Clear();
  STEPControl_Reader reader;
  // What STEPControl_Reader::ReadFile does (parse, hand the model to the work session, which checks
  // it), with the cycle check between the parse and OpenCASCADE's checks.
  const Handle(XSControl_WorkSession)& session = reader.WS();
  Handle(Interface_InterfaceModel) model;
  int parsed = 1;
  try {
    parsed = session->WorkLibrary()->ReadFile(path.string().c_str(), model, session->Protocol());
  } catch (const Standard_Failure&) {
    parsed = 1;
  }
  if (parsed != 0 || model.IsNull()) throw InputError(path.string() + ": not a readable STEP file");
  // A file with a header and no entity: nothing to check (OpenCASCADE's check says "DATA NOT
  // AVAILABLE FOR CHECK"), and no face.
  if (model->NbEntities() == 0) throw InputError(path.string() + ": the STEP file holds no face");
  refuse_reference_cycles(model, session->Protocol(), path);
  session->SetModel(model);
  session->SetLoadedFile(path.string().c_str());
  session->InitTransferReader(4);
  refuse_failed_checks(reader, path);
  reader.TransferRoots();
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(reader.OneShape(), TopAbs_FACE, faces);
  if (faces.Extent() == 0) throw InputError(path.string() + ": the STEP file holds no face");
  cached_faces = faces;
  if (file_bytes(path) == bytes) cached_path = path.string(), cached_bytes = std::move(bytes);
  return cached_faces;
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
    const TopTools_IndexedMapOfShape& faces = load_faces(path);
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

// ---- OpenCASCADE in a worker process ----
// OpenCASCADE's STEP translator is not hardened against malformed files: the fuzzer found a file on
// which it dereferences a null entity (StepGeom_CartesianPoint::NbCoordinates, 7.6.3). A crash there
// must not take drom (and a night's closed loop) down with it, so the file is read in a worker
// process that sends back drom's own types as bytes; a worker that dies or hangs becomes an
// InputError naming the file. drom checks what it receives as it would any outside data.

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

// ---- The translator process ----
// OpenCASCADE runs in one worker process, forked at the first read and kept: each read is a request
// on a socket (kind, face index, path) and an answer ('F' and drom's bytes, or 'E' and a message). A
// fork per read cost most of a read (the parent's page tables copied, every page the translator
// touches copied again, its symbols bound anew: 15 reads a second under the sanitizers); a kept
// worker pays that once. A worker that crashes or hangs is ended, the read is an InputError naming
// the file, and the next read starts a new worker. The worker is also renewed every kRenewAfter
// reads, so that what OpenCASCADE keeps allocated between reads stays bounded.

constexpr int kRenewAfter = 1000;

bool send_all(int fd, std::string_view bytes) {
  for (std::size_t done = 0; done < bytes.size();) {
    const ssize_t n = ::send(fd, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

// Reads exactly `size` bytes, waiting until `deadline` (none: forever). Returns false at the end of
// the stream or an error; sets `timed_out` when the deadline passed.
bool receive_exactly(int fd, char* out, std::size_t size, std::optional<std::chrono::steady_clock::time_point> deadline, bool& timed_out) {
  timed_out = false;
  for (std::size_t done = 0; done < size;) {
    int wait_ms = -1;
    if (deadline) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(*deadline - std::chrono::steady_clock::now()).count();
      if (left <= 0) {
        timed_out = true;
        return false;
      }
      wait_ms = static_cast<int>(std::min<long long>(left, 1000));
    }
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, wait_ms);
    if (ready < 0 && errno != EINTR) return false;
    if (ready <= 0) continue;
    const ssize_t n = ::recv(fd, out + done, size - done, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

std::string frame(char kind, std::string_view payload) {
  std::string out(1, kind);
  const std::uint64_t n = payload.size();
  out.append(reinterpret_cast<const char*>(&n), sizeof n);
  out.append(payload);
  return out;
}

// The worker's loop: a request is 'C' (count) or 'R' (read), a 32-bit face index, then the path framed.
[[noreturn]] void serve(int fd) {
  for (;;) {
    bool timed_out = false;
    char head[1 + sizeof(std::int32_t) + sizeof(std::uint64_t)];
    if (!receive_exactly(fd, head, sizeof head, std::nullopt, timed_out)) ::_exit(0);  // drom closed its end
    std::int32_t index = 0;
    std::uint64_t length = 0;
    std::memcpy(&index, head + 1, sizeof index);
    std::memcpy(&length, head + 1 + sizeof index, sizeof length);
    if (length > 1 << 20) ::_exit(1);
    std::string path_text(length, '\0');
    if (!receive_exactly(fd, path_text.data(), length, std::nullopt, timed_out)) ::_exit(0);
    const std::filesystem::path path(path_text);
    const std::string origin = path.string();
    char kind = 'F';
    std::string answer;
    try {
      answer = head[0] == 'C' ? std::to_string(count_faces_here(path)) : encode(read_face_here(path, index));
    } catch (const InputError& e) {
      kind = 'E', answer = e.what();
    } catch (const Standard_Failure& e) {
      kind = 'E', answer = origin + ": OpenCASCADE could not read it: " + e.GetMessageString();
    } catch (const std::exception& e) {
      kind = 'E', answer = origin + ": OpenCASCADE's reader failed: " + e.what();
    } catch (...) {
      kind = 'E', answer = origin + ": OpenCASCADE's reader failed";
    }
    if (!send_all(fd, frame(kind, answer))) ::_exit(0);
  }
}

class TranslatorProcess {
 public:
  // The answer's payload, or its InputError rethrown here; a worker that crashes, stops without an
  // answer or outlives `limit` is an InputError naming the file.
  std::string ask(char kind, const std::filesystem::path& path, int index, std::chrono::seconds limit) {
    const std::lock_guard lock(mutex_);
    const std::string origin = path.string();
    if (pid_ > 0 && owner_ != ::getpid()) pid_ = -1, ::close(fd_);  // a forked copy of drom: the worker is its parent's
    if (pid_ > 0 && served_ >= kRenewAfter) stop();
    if (pid_ <= 0) start(origin);
    ++served_;
    std::string request(1, kind);
    const auto index32 = static_cast<std::int32_t>(index);
    request.append(reinterpret_cast<const char*>(&index32), sizeof index32);
    request += frame('P', path.string()).substr(1);
    bool timed_out = false;
    char head[1 + sizeof(std::uint64_t)];
    const auto deadline = std::chrono::steady_clock::now() + limit;
    std::string payload;
    bool answered = send_all(fd_, request) && receive_exactly(fd_, head, sizeof head, deadline, timed_out);
    if (answered) {
      std::uint64_t length = 0;
      std::memcpy(&length, head + 1, sizeof length);
      answered = (head[0] == 'F' || head[0] == 'E') && length <= (std::uint64_t{1} << 30);  // a face is a few MB; past 1 GB the worker is broken
      if (answered) {
        payload.resize(length);
        answered = receive_exactly(fd_, payload.data(), length, deadline, timed_out);
      }
    }
    if (answered) {
      if (head[0] == 'E') throw InputError(payload);
      return payload;
    }
    // No answer: the worker hung, crashed, or sent something no worker sends. It is ended either way.
    const int status = stop();
    if (timed_out) throw InputError(origin + ": OpenCASCADE did not finish reading it within " + std::to_string(limit.count()) + " s");
    if (WIFSIGNALED(status) && WTERMSIG(status) != SIGKILL)
      throw InputError(origin + ": OpenCASCADE crashed reading it (" + strsignal(WTERMSIG(status)) +
                       "): the file is malformed, or holds an entity OpenCASCADE 7.6 cannot translate");
    throw InputError(origin + ": OpenCASCADE's reader stopped without an answer (exit status " + std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
  }

  ~TranslatorProcess() {
    if (pid_ > 0 && owner_ == ::getpid()) stop();
  }

 private:
  void start(const std::string& origin) {
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) throw InputError(origin + ": cannot start OpenCASCADE's reader: " + std::strerror(errno));
    std::fflush(nullptr);
    const pid_t pid = ::fork();
    if (pid < 0) {
      ::close(fds[0]), ::close(fds[1]);
      throw InputError(origin + ": cannot start OpenCASCADE's reader: " + std::strerror(errno));
    }
    if (pid == 0) {
      // The worker dies of its own crash: no handler inherited from drom (a fuzzer's, a sanitizer's)
      // may report it as drom's.
      for (const int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) ::signal(sig, SIG_DFL);
      ::close(fds[0]);
      Message::DefaultMessenger()->ChangePrinters().Clear();
      serve(fds[1]);
    }
    ::close(fds[1]);
    pid_ = pid, fd_ = fds[0], served_ = 0, owner_ = ::getpid();
  }

  // Ends the worker and returns its status. Killed, not asked: it holds nothing of value between
  // reads, and a copy of drom's socket in another forked process would keep it waiting.
  int stop() {
    ::kill(pid_, SIGKILL);
    ::close(fd_);
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = -1, fd_ = -1;
    return status;
  }

  std::mutex mutex_;
  pid_t pid_ = -1, owner_ = -1;
  int fd_ = -1;
  int served_ = 0;
};

TranslatorProcess& translator() {
  static TranslatorProcess process;
  return process;
}

// A large assembly takes OpenCASCADE a minute or two; ten is a reader stuck.
constexpr std::chrono::seconds kReadLimit{600};

}  // namespace

int count_step_faces(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path.string() + ": no such STEP file");
  const std::string answer = translator().ask('C', path, 0, kReadLimit);
  int faces = 0;
  std::istringstream in(answer);
  if (!(in >> faces) || faces < 1) throw InputError(path.string() + ": OpenCASCADE's reader sent no face count");
  return faces;
}

StepFace read_step_face(const std::filesystem::path& path, int index) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path.string() + ": no such STEP file");
  return decode(translator().ask('R', path, index, kReadLimit), path.string(), index);
}

}  // namespace drom::geometry
