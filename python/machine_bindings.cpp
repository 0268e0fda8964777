// drom.machine from Python: machine files, the kinematics, the feed a program or CL data really
// reaches on a machine, and the post-processor (machine/, docs/machine.md). numpy arrays in and out.
#include "machine/cl_data.hpp"
#include "machine/feed_prediction.hpp"
#include "machine/post_processor.hpp"
#include "machine/program_check.hpp"
#include "support/input_error.hpp"

#include "repr.hpp"

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

namespace py = pybind11;
using namespace drom;

namespace {

py::object to_python(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

// CL data as an (N, 7) array: x, y, z, i, j, k, feed (mm/min; 0: a rapid; the first row is where the tool starts).
machine::ClProgram cl_from_array(const py::array_t<double, py::array::c_style | py::array::forcecast>& rows) {
  if (rows.ndim() != 2 || rows.shape(1) != 7) throw InputError("cl: an (N, 7) array of x, y, z, i, j, k, feed expected");
  machine::ClProgram cl;
  cl.origin = "<numpy CL data>";
  const auto r = rows.unchecked<2>();
  for (py::ssize_t i = 0; i < rows.shape(0); ++i) {
    machine::ClPoint p;
    p.pose.tip = {r(i, 0), r(i, 1), r(i, 2)};
    const Eigen::Vector3d axis(r(i, 3), r(i, 4), r(i, 5));
    if (!p.pose.tip.allFinite() || !axis.allFinite() || !(axis.norm() > 1e-9) || !std::isfinite(r(i, 6)) || r(i, 6) < 0)
      throw InputError("cl: row " + std::to_string(i) + " is not finite, has a zero axis or a negative feed");
    p.pose.axis = axis.normalized();
    p.feed = r(i, 6);
    p.rapid = i == 0 || p.feed == 0;
    p.line = static_cast<int>(i) + 1;
    cl.points.push_back(p);
  }
  if (cl.points.size() < 2) throw InputError("cl: at least two rows (the start and one move)");
  return cl;
}

}  // namespace

void bind_machine(py::module_& top) {
  py::module_ m = top.def_submodule("machine", "machine tools: kinematics, the feed programs really reach, post-processing (docs/machine.md)");
  m.def("shipped", &machine::shipped_machine_names, "the names of the machines shipped with drom");
  py::class_<machine::Machine>(m, "Machine", "a machine file read and checked (machine/machine_definition.hpp)")
      .def_readonly("name", &machine::Machine::name)
      .def_readonly("description", &machine::Machine::description)
      .def_readonly("origin", &machine::Machine::origin)
      .def_property_readonly("kinematics", [](const machine::Machine& x) { return std::string(machine::chain_name(x.chain)); })
      .def_property_readonly("rotary_axes", &machine::Machine::rotary_letters)
      .def_readonly("interpolation_cycle", &machine::Machine::interpolation_cycle)
      .def_readonly("tool_length", &machine::Machine::tool_length)
      .def("__repr__", python::fields<machine::Machine>({"name", "kinematics", "rotary_axes", "tool_length", "interpolation_cycle", "origin"}));
  m.def("load", &machine::load_machine, py::arg("path_or_name"), py::arg("overrides") = std::vector<std::string>{},
        "a machine file, or a shipped machine's name, with 'key=value' overrides; raises InputError");

  m.def(
      "inverse",
      [](const machine::Machine& mc, const Eigen::MatrixXd& poses) {
        if (poses.cols() != 6) throw InputError("poses: an (N, 6) array of x, y, z, i, j, k expected");
        const machine::Kinematics kin(mc);
        std::vector<machine::ClPose> p(static_cast<std::size_t>(poses.rows()));
        for (Eigen::Index i = 0; i < poses.rows(); ++i) p[static_cast<std::size_t>(i)] = {poses.row(i).head<3>().transpose(), poses.row(i).tail<3>().transpose().normalized()};
        machine::JointPath path;
        {
          py::gil_scoped_release free;
          path = machine::inverse_path(kin, p);
        }
        Eigen::MatrixXd joints(poses.rows(), mc.joint_count());
        for (Eigen::Index i = 0; i < poses.rows(); ++i)
          for (int j = 0; j < mc.joint_count(); ++j) joints(i, j) = machine::joint_in_program_units(mc, j, path.joints[static_cast<std::size_t>(i)][j]);
        py::list violations;
        for (const auto& v : path.violations) violations.append(py::make_tuple(v.pose, v.what));
        py::dict d;
        d["joints"] = joints;  // mm and degrees, in the machine's joint order (X, Y, Z, then its rotary axes)
        d["branch"] = path.branch;
        d["singularity_distance_deg"] = Eigen::Map<const Eigen::VectorXd>(path.singularity_distance.data(), static_cast<Eigen::Index>(path.singularity_distance.size())) *
                                        (180 / 3.14159265358979323846);
        d["violations"] = violations;
        return d;
      },
      py::arg("machine"), py::arg("poses"), "joints for part-frame poses (N, 6): continuous branches, unwound rotary axes, stroke violations");

  m.def(
      "predict",
      [](const machine::Machine& mc, const py::array_t<double, py::array::c_style | py::array::forcecast>& cl) {
        const machine::ClProgram program = cl_from_array(cl);
        const machine::Kinematics kin(mc);
        machine::ClOnMachine on;
        machine::FeedPrediction p;
        {
          py::gil_scoped_release free;
          on = machine::cl_to_machine_program(program, kin);
          p = machine::predict_feed(on.program, kin);
        }
        const std::size_t n = p.blocks.size();
        Eigen::VectorXd t(static_cast<Eigen::Index>(n)), dt(t.size()), length(t.size()), programmed(t.size()), min_feed(t.size()), max_feed(t.size());
        std::vector<std::string> limit(n);
        for (std::size_t i = 0; i < n; ++i) {
          const auto& b = p.blocks[i];
          const auto k = static_cast<Eigen::Index>(i);
          t[k] = b.t_start, dt[k] = b.duration, length[k] = b.length, programmed[k] = b.programmed_duration;
          min_feed[k] = 60 * b.min_speed, max_feed[k] = 60 * b.max_speed;
          limit[i] = std::string(machine::feed_limit_name(b.limit)) + (b.limit_axis >= 0 ? std::string(":") + mc.axes[b.limit_axis].name : "");
        }
        py::dict d;
        d["cycle_time"] = p.cycle_time, d["programmed_time"] = p.programmed_time, d["cutting_length"] = p.cutting_length;
        d["length_at_programmed_feed"] = p.length_at_programmed_feed;
        d["block_start"] = t, d["block_duration"] = dt, d["block_length"] = length, d["block_programmed_duration"] = programmed;
        d["block_min_feed"] = min_feed, d["block_max_feed"] = max_feed, d["block_limit"] = limit;
        py::list violations;
        for (const auto& v : on.joints.violations) violations.append(py::make_tuple(v.pose, v.what));
        d["violations"] = violations;
        return d;
      },
      py::arg("machine"), py::arg("cl"), "the feed CL data (N, 7: x, y, z, i, j, k, feed mm/min) really reaches on the machine, block by block, and its cycle time");

  m.def(
      "post",
      [](const machine::Machine& mc, const py::array_t<double, py::array::c_style | py::array::forcecast>& cl, const std::string& title, int tool,
         double tool_diameter, double spindle_speed, double clearance) {
        return machine::post_process(cl_from_array(cl), machine::Kinematics(mc),
                                     {.title = title, .tool = tool, .tool_diameter = tool_diameter, .spindle_speed = spindle_speed, .clearance = clearance});
      },
      py::arg("machine"), py::arg("cl"), py::arg("title") = "drom", py::arg("tool") = 1, py::arg("tool_diameter") = 0.0, py::arg("spindle_speed") = 0.0,
      py::arg("clearance") = 10.0,
      "G-code for the machine (LinuxCNC's dialect) from CL data (N, 7), ready to run: header, spindle (spindle_speed in rev/min; 0: 300 m/min on "
      "tool_diameter), a retract to the machine's safe Z first, rotary moves at the safe height, rapids across at the clearance plane, M5 M30; "
      "raises InputError out of reach");

  m.def(
      "check_program",
      [](const std::filesystem::path& program, const std::string& mc, const std::filesystem::path& out, const std::vector<std::string>& overrides) {
        machine::ProgramCheckOptions o;
        o.program = program, o.machine = mc, o.out = out, o.machine_overrides = overrides;
        nlohmann::json s;
        {
          py::gil_scoped_release free;
          s = machine::check_program(o);
        }
        return to_python(s);
      },
      py::arg("program"), py::arg("machine") = "vmc_3axis", py::arg("out") = "out/machine", py::arg("overrides") = std::vector<std::string>{},
      "drom machine: writes feed.csv/png, axes.csv, blocks.csv, saturation.vtp, summary.json; returns the summary");
}
