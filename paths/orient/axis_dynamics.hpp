#pragma once
// The tool axis as a rigid body pivoting about the fixed CL point (seed 000 ch. 2-3): roll θf about the
// feed direction f and pitch θt about t = f × n, two decoupled critically damped pendulums
//   J θ̈f + c (θ̇f − θ̇f,prog) + k (θf − θf,prog) = Mf,rep      (2.26)
//   J θ̈t + c (θ̇t − θ̇t,prog) + k (θt − θt,prog) = Mt,rep      (2.27)
// with ω0 = 2π v0 / d0, J = k / ω0², c = 2 ξ √(kJ), ξ = 1, and M_rep the repulsive moment at CL from
// the tool's nodes: the point G only (3.1), every node with its lever (3.18), or its direction only
// (3.19, scaled by the mean lever so the three compare). The axis is u = R_t(θt) R_f(θf) n.
//
// Beyond the seed, a third-order term bounds the jerk: the moment reaches the pendulum through a
// first-order lag, τ Ṁ* + M* = M_rep. The Khatib force is only C⁰ where a node enters r0, so θ⃛
// jumps there in the seed's model; with the lag θ⃛ = (Ṁ* − c θ̈ − k θ̇)/J stays bounded by |M_rep − M*|/τ.
//
// Integrated in time t = s / v0 along the pass by SUNDIALS ARKODE (explicit Dormand-Prince 4(5),
// adaptive with error control; the seed's ode45), the step capped so no tool node moves more than a
// fraction of its clearance; or by classical fixed-step RK4 (the seed's eq. 2.12-2.14).
#include "paths/orient/repulsive_field.hpp"

#include <Eigen/Core>

#include <functional>
#include <optional>
#include <vector>

namespace drom::paths {

// The recall, tuned from the obstacle mesh spacing (seed §3-2.2).
struct RecallParameters {
  double stiffness = 1000;     // k, N·mm/rad (the seed's 1 N·m/rad)
  double feed = 1000;          // v0, mm/min
  double spacing = 2;          // d0, mm: the obstacle spacing the recall low-pass filters
  double damping_ratio = 1;    // ξ
  double omega0() const;       // rad/s
  double inertia() const;      // J = k / ω0²
  double damping() const;      // c = 2 ξ √(kJ)
};

// Something that gives the repulsive force at a point of the part frame (direct sum, or a voxel field).
class ForceField {
 public:
  virtual ~ForceField() = default;
  virtual FieldSample sample(const Eigen::Vector3d& p) const = 0;
  // The force alone: what the integrator's right-hand sides need (a voxel field then skips its
  // nearest-distance grid).
  virtual Eigen::Vector3d force(const Eigen::Vector3d& p) const { return sample(p).force; }
};

class DirectField : public ForceField {
 public:
  DirectField(const ObstacleCloud& obstacles, KhatibParameters khatib, Aggregation aggregation)
      : obstacles_(obstacles), khatib_(khatib), aggregation_(aggregation) {}
  FieldSample sample(const Eigen::Vector3d& p) const override { return repulsive_force(obstacles_, p, khatib_, aggregation_); }

 private:
  const ObstacleCloud& obstacles_;
  KhatibParameters khatib_;
  Aggregation aggregation_;
};

enum class MomentModel { PointG, Lever, Direction };  // (3.1), (3.18), (3.19)
const char* moment_model_name(MomentModel m);

// A CL path with its local frame and the programmed strategy angles, at increasing arc length.
struct FramedPath {
  std::vector<double> s;                       // mm, from 0
  std::vector<Eigen::Vector3d> cl, feed, normal;  // CL (the pivot), unit f, unit n ⊥ f
  std::vector<double> roll_prog, pitch_prog;    // θf,prog, θt,prog (rad)
  // Builds s, and f from the CL polyline (central differences), n made normal to f.
  static FramedPath from_points(const std::vector<Eigen::Vector3d>& cl, const std::vector<Eigen::Vector3d>& normals, double roll, double pitch);
  double length() const { return s.empty() ? 0 : s.back(); }
  struct Frame {
    Eigen::Vector3d cl, f, n, t;
    double roll_prog = 0, pitch_prog = 0, roll_rate_prog = 0, pitch_rate_prog = 0;  // rates per mm
  };
  Frame at(double arc) const;  // linear between samples, f and n re-orthonormalized
};

// Where the tool's reference point sits for the axis u, from the path's CL at the frame: the CL itself
// for a ball, CL + offset · e(u) for a torus (DynamicsSettings::contact_offset).
Eigen::Vector3d reference_point(const FramedPath::Frame& frame, const Eigen::Vector3d& axis, double contact_offset);

// The tool axis for a frame and angles: u = R_t(θt) R_f(θf) n, and the rotation that takes the local
// tool frame (x = f, y = t, z = n at θ = 0) to the part frame.
Eigen::Matrix3d tool_rotation(const FramedPath::Frame& frame, double roll, double pitch);

struct DynamicsSettings {
  RecallParameters recall;
  MomentModel moment = MomentModel::Direction;
  double lever_g = 20;           // mm, |CL G| for the point-G model (3.1)
  double jerk_lag = 0;           // τ (s) of the moment's first-order lag; 0: the seed's second-order model
  bool roll_only = false;        // the seed's ch. 3 timing: moment about f only
  // R − r of a torus (0 for a ball). The seed pivots a ball about its centre, which keeps the contact;
  // a torus pivoted about the centre of its corner circle would dip (R − r) sin α into the surface. So
  // the path's CL is the tube's centre over the contact point, CC + r n, and the tool's reference point
  // (the corner circle's centre) follows the axis u: CL + (R − r) e(u), e(u) the unit of n − (n·u) u
  // (the rim that dips is on the side the axis leans to; the centre sits back from it).
  double contact_offset = 0;
  // Beyond the seed, the machine's singularity: where the axis comes within `singular_cone` (rad) of
  // the machine's singular direction (part frame; a table-table machine's C axis), its table must spin
  // about C at the tilt rate / sin(angle) to follow. A stiff angular spring, singular_stiffness × k
  // per rad of intrusion, pushes the axis back out of the cone; 0: off (the seed's model).
  std::optional<Eigen::Vector3d> singular_direction;
  double singular_cone = 0;
  double singular_stiffness = 10;
  // Integration.
  bool adaptive = true;          // ARKODE; else fixed-step RK4
  double rk4_step = 0.1;         // mm of path per RK4 step
  double relative_tolerance = 1e-5, absolute_tolerance = 1e-6;  // ARKODE, on θ (rad) and θ̇ (rad/s)
  double clearance_fraction = 0.25;  // no node moves more than this share of its clearance in one step
  double output_step = 0.1;      // mm between output samples
  bool settle_start = true;      // start from the equilibrium at s = 0 (else θ = θprog, the seed's Heaviside start)
};

struct AxisSample {
  double s = 0;
  double roll = 0, pitch = 0;                // θf, θt (rad)
  double roll_rate = 0, pitch_rate = 0;      // rad/s at the feed
  double roll_acc = 0, pitch_acc = 0;        // rad/s²
  double roll_jerk = 0, pitch_jerk = 0;      // rad/s³ (from the model where the lag is on; else differenced)
  // cl: the tool's reference point (ToolAssembly's pivot: a ball's centre, a torus's corner-circle centre)
  // for `axis`; programmed_cl for `programmed_axis` (they differ for a torus only).
  Eigen::Vector3d cl = Eigen::Vector3d::Zero(), programmed_cl = Eigen::Vector3d::Zero(), axis = Eigen::Vector3d::UnitZ(),
                  programmed_axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();  // M_rep at CL (N·mm)
  int active_nodes = 0;                      // tool nodes within r0 of an obstacle
  double nearest_node_distance = 1e300;      // mm, tool node to obstacle
};

struct AxisHistory {
  std::vector<AxisSample> samples;
  long rhs_evaluations = 0, steps = 0;
};

// Integrates one pass from the equilibrium at s = 0 (settle_start), or from θ = θ_prog, θ̇ = 0 (the seed's). `nodes`: the tool's nodes,
// local frame (ignored by the point-G model). `start`: the (θf, θt) the pendulum is released from at
// s = 0 instead of θprog (a collision-free start when the programmed one collides).
AxisHistory integrate_axis(const FramedPath& path, const std::vector<Eigen::Vector3d>& nodes, const ForceField& field,
                           const DynamicsSettings& settings, const std::optional<Eigen::Vector2d>& start = std::nullopt);

// Beyond the seed, a zero-phase filter of the result: the deviation θ − θprog of each angle smoothed
// along s by a Gaussian of standard deviation `sigma` (mm; the ends reflected oddly, so the start
// and end poses stay), then the axis, the reference point, and θ̇, θ̈, θ⃛ (central differences in
// time) recomputed. Symmetric, so it anticipates as much as it lags: the lag's trouble (the tool
// reacting late, nearer the wall) does not arise, but a smoothed peak is lower, so the result must be
// checked again (run_orient does). The moment, active nodes and nearest distance keep the model's.
void smooth_axis(AxisHistory& history, const FramedPath& path, double sigma, const DynamicsSettings& settings);

// Generic integrators, exposed for their validation (seed Annex A1): y' = f(t, y) from t0 to each of
// `times`, returning y there.
using OdeRhs = std::function<void(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dy)>;
std::vector<Eigen::VectorXd> integrate_rk4(const OdeRhs& f, double t0, Eigen::VectorXd y0, const std::vector<double>& times, double step);
std::vector<Eigen::VectorXd> integrate_arkode(const OdeRhs& f, double t0, Eigen::VectorXd y0, const std::vector<double>& times, double rtol,
                                              double atol, const std::function<double(double t, const Eigen::VectorXd& y)>& max_step = {},
                                              long* rhs_evaluations = nullptr, long* steps = nullptr);

// The free pendulum's closed form θ(t) for θ̈ + 2ξω0 θ̇ + ω0² θ = 0 in its three regimes (ξ = 1:
// (θ0 + (θ̇0 + ω0 θ0) t) e^{−ω0 t}, where the seed's formula is singular).
double free_response(double theta0, double rate0, double omega0, double xi, double t);

}  // namespace drom::paths
