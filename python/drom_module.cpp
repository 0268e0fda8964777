// The `drom` Python module (pybind11): cases, the offline job, the reduction, the light model, the
// predictor, and the closed loop's simulated machine, with numpy arrays in and out (docs/python.md).
// Errors are drom.InputError (a ValueError) carrying the C++ message: file, line, key. Long calls
// release the GIL; the offline job's progress callback takes it back to run.
#include "case_file/case.hpp"
#include "loop/closed_loop_run.hpp"
#include "loop/closed_loop_study.hpp"
#include "loop/closed_loop_setup.hpp"
#include "offline/offline_job.hpp"
#include "online/loop_simulation.hpp"
#include "online/predictor.hpp"
#include "reduce/database_reduction.hpp"
#include "reduce/light_model.hpp"
#include "support/input_error.hpp"
#include "support/version.hpp"

#include "repr.hpp"

#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <stop_token>
#include <thread>
#include <type_traits>

namespace py = pybind11;
using namespace drom;
using drom::python::fields;

namespace {

// nlohmann::json -> the Python objects json.loads would make.
py::object to_python(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

// A laser profile as the predictor reads it: a C-contiguous float64 (N, 3) array is read in place
// (MeasuredPoint is three doubles); other arrays are converted once.
static_assert(sizeof(online::MeasuredPoint) == 3 * sizeof(double) && std::is_standard_layout_v<online::MeasuredPoint>);
using PointArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
std::span<const online::MeasuredPoint> as_points(const PointArray& points) {
  if (points.ndim() != 2 || points.shape(1) != 3) {
    std::string shape;
    for (py::ssize_t d = 0; d < points.ndim(); ++d) shape += (d ? ", " : "") + std::to_string(points.shape(d));
    throw InputError("points: an (N, 3) array of x, y, z expected, got shape (" + shape + ")");
  }
  return {reinterpret_cast<const online::MeasuredPoint*>(points.data()), static_cast<std::size_t>(points.shape(0))};
}

py::dict report_dict(const online::ProfileReport& r) {
  py::dict d;
  d["used"] = r.used, d["used_top"] = r.used_top, d["outside"] = r.outside, d["not_yet_cut"] = r.not_yet_cut;
  d["invalid"] = r.invalid, d["out_of_range"] = r.out_of_range, d["predictive_rms"] = r.predictive_rms;
  d["rejected"] = r.rejected ? py::object(py::str(r.rejected)) : py::object(py::none());
  return d;
}

py::dict job_dict(const offline::JobResult& r) {
  py::dict d;
  d["finished"] = r.finished, d["stations"] = r.stations, d["stations_saved"] = r.stations_saved;
  d["summary"] = r.finished ? to_python(r.summary) : py::none();
  return d;
}

// Runs `job` on a thread of its own while this thread, Python's, waits with the GIL released and
// looks at its signals every 20 ms: Ctrl-C (KeyboardInterrupt, or any exception a signal handler
// raises) asks the job to stop through its stop token, the job ends after the work in progress and
// leaves its checkpoints resumable, and the exception is raised here. A job run in this thread would
// see Python's signals only when it returned: Python runs its handlers between bytecodes.
template <class Result>
Result run_interruptible(const std::function<Result(std::stop_token)>& job) {
  std::stop_source stop;
  std::mutex mutex;
  std::condition_variable ended;
  bool done = false;
  Result result{};
  std::exception_ptr failure;
  PyObject *raised_type = nullptr, *raised_value = nullptr, *raised_trace = nullptr;
  {
    py::gil_scoped_release free;
    std::thread worker([&] {
      try {
        result = job(stop.get_token());
      } catch (...) {
        failure = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mutex);
      done = true;
      ended.notify_all();
    });
    std::unique_lock<std::mutex> lock(mutex);
    while (!ended.wait_for(lock, std::chrono::milliseconds(20), [&] { return done; })) {
      if (stop.stop_requested()) continue;
      lock.unlock();
      {
        py::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() != 0) {
          PyErr_Fetch(&raised_type, &raised_value, &raised_trace);
          stop.request_stop();
        }
      }
      lock.lock();
    }
    lock.unlock();
    worker.join();
  }
  if (raised_type) {  // the signal's exception wins over the job's StopRequested
    PyErr_Restore(raised_type, raised_value, raised_trace);
    throw py::error_already_set();
  }
  if (failure) std::rethrow_exception(failure);
  return result;
}

offline::JobResult run_job(const case_file::Case& c, offline::JobKind kind, const std::filesystem::path& out, bool resume, int stop_after, int threads,
                           int frames, bool quiet, const std::function<bool(std::size_t, std::size_t)>& progress) {
  offline::JobOptions o;
  o.out = out, o.resume = resume, o.stop_after = stop_after, o.threads = threads, o.frames = frames, o.quiet = quiet;
  if (progress)
    o.progress = [&progress](std::size_t saved, std::size_t total) {
      py::gil_scoped_acquire gil;
      return progress(saved, total);
    };
  return run_interruptible<offline::JobResult>([&](std::stop_token stop) {
    offline::JobOptions with_stop = o;
    with_stop.stop = stop;
    return offline::run_job(c, kind, with_stop);
  });
}

loop::RunOptions run_options(const std::filesystem::path& out, bool quiet, int threads, std::stop_token stop) {
  loop::RunOptions o;
  o.out = out, o.quiet = quiet, o.threads = threads, o.stop = stop;
  return o;
}

// The closed loop's simulated machine, with the truth it plays (loop/closed_loop_setup.hpp).
struct Machine {
  loop::TruthPlay truth;
  std::unique_ptr<online::LoopMachine> machine;
};

}  // namespace

void bind_machine(py::module_& m);  // machine_bindings.cpp

PYBIND11_MODULE(drom, m) {
  m.doc() = "drom: distortion-aware machining of thin parts (docs/python.md)";
  m.attr("__version__") = kVersion;
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);
  bind_machine(m);

  // ---- cases -------------------------------------------------------------------------------
  py::class_<case_file::Case>(m, "Case", "A case file read and validated (case_file/case.hpp); every key as in docs/case-files.md")
      .def_readonly("name", &case_file::Case::name)
      .def_readonly("description", &case_file::Case::description)
      .def_readonly("origin", &case_file::Case::origin)
      .def_readonly("resolved_toml", &case_file::Case::resolved_toml, "the case after its overrides, as TOML")
      .def_readonly("solver", &case_file::Case::solver)
      .def_readonly("shape", &case_file::Case::shape)
      .def_readonly("element", &case_file::Case::element)
      .def_readonly("nx", &case_file::Case::nx)
      .def_readonly("ny", &case_file::Case::ny)
      .def_readonly("nz", &case_file::Case::nz)
      .def_readonly("pocket_depth", &case_file::Case::pocket_depth)
      .def_readonly("sigma11", &case_file::Case::sigma11)
      .def_readonly("sigma22", &case_file::Case::sigma22)
      .def_readonly("sensor_noise", &case_file::Case::sensor_noise)
      .def_readonly("path_tolerance", &case_file::Case::path_tolerance)
      .def_readonly("shape_tolerance", &case_file::Case::shape_tolerance)
      .def_readonly("shape_pass", &case_file::Case::shape_pass)
      .def_readonly("run_scale", &case_file::Case::run_scale)
      .def("__repr__", fields<case_file::Case>({"name", "origin", "shape", "element", "solver", "nx", "ny", "nz", "run_scale"}));
  m.def("load_case", &case_file::load_case, py::arg("path") = std::nullopt, py::arg("overrides") = std::vector<std::string>{},
        "A case file (or, without one, the embedded flat plate) with 'key=value' overrides as --set gives them; raises InputError");
  m.def("case_from_text", &case_file::case_from_text, py::arg("text"), py::arg("origin") = "<text>", py::arg("overrides") = std::vector<std::string>{});
  m.def("load_run_case", &loop::load_run_case, py::arg("path") = std::nullopt, py::arg("overrides") = std::vector<std::string>{},
        "The case as drom run runs it: [run] quick's overrides first when its scale is 'quick'");

  // ---- the offline job ----------------------------------------------------------------------
  const char* job_doc =
      "Runs (or resumes) the job; returns {'finished', 'stations', 'stations_saved', 'summary'}. progress(saved, total) is called after each "
      "station; returning False stops the job (resume later). The GIL is released while it runs; Ctrl-C stops it after the stations in "
      "progress (KeyboardInterrupt), its checkpoints resumable with resume=True.";
  m.def(
      "run_offline",
      [](const case_file::Case& c, const std::filesystem::path& out, bool resume, int stop_after, int threads, int frames, bool quiet,
         const std::function<bool(std::size_t, std::size_t)>& progress) {
        return job_dict(run_job(c, offline::JobKind::Offline, out, resume, stop_after, threads, frames, quiet, progress));
      },
      py::arg("case"), py::arg("out"), py::arg("resume") = false, py::arg("stop_after") = -1, py::arg("threads") = 0, py::arg("frames") = -1,
      py::arg("quiet") = true, py::arg("progress") = nullptr, job_doc);
  m.def(
      "run_truth",
      [](const case_file::Case& c, const std::filesystem::path& out, bool resume, int stop_after, int threads, int frames, bool quiet,
         const std::function<bool(std::size_t, std::size_t)>& progress) {
        return job_dict(run_job(c, offline::JobKind::Truth, out, resume, stop_after, threads, frames, quiet, progress));
      },
      py::arg("case"), py::arg("out"), py::arg("resume") = false, py::arg("stop_after") = -1, py::arg("threads") = 0, py::arg("frames") = -1,
      py::arg("quiet") = true, py::arg("progress") = nullptr, job_doc);

  // ---- the light model and the reduction ----------------------------------------------------
  py::class_<reduce::LightModel, std::shared_ptr<reduce::LightModel>>(m, "LightModel", "The light model file (reduce/light_model.hpp)")
      .def_static("read", [](const std::filesystem::path& p) { return std::make_shared<reduce::LightModel>(reduce::LightModel::read(p)); }, py::arg("path"),
                  "reads a model file; raises InputError naming the file and dataset")
      .def("write", &reduce::LightModel::write, py::arg("path"), "writes the model file (atomically)")
      .def_property_readonly("rank", &reduce::LightModel::rank)
      .def_property_readonly("error_bound", &reduce::LightModel::error_bound, "mm: the bound on the model's max error for any database column")
      .def_readonly("tolerance", &reduce::LightModel::tolerance)
      .def_readonly("singular_values", &reduce::LightModel::singular_values)
      .def_readonly("prior_sd", &reduce::LightModel::prior_sd)
      .def_readonly("prior_mean", &reduce::LightModel::prior_mean)
      .def_readonly("path", &reduce::LightModel::path, "waypoints x 4: tool tip x, y, z and program time")
      .def_readonly("final_basis", &reduce::LightModel::final_basis)
      .def_readonly("shape_nodes", &reduce::LightModel::shape_nodes)
      .def_readonly("tool_radius", &reduce::LightModel::tool_radius)
      .def_readonly("case_toml", &reduce::LightModel::case_toml)
      .def_property_readonly("target_nodes", [](const reduce::LightModel& lm) { return Eigen::Matrix3Xd(lm.target.nodes()); })
      .def_property_readonly("has_top", &reduce::LightModel::has_top)
      .def("__repr__", fields<reduce::LightModel>({"rank", "error_bound", "tolerance", "tool_radius", "has_top", "path", "shape_nodes"}));
  m.def(
      "reduce_database",
      [](const std::filesystem::path& database, double tolerance, double history_tolerance, double profile_scale, int max_rank, const std::string& prior_mean,
         double top_margin, std::optional<std::filesystem::path> out) {
        if (prior_mean != "case" && prior_mean != "zero") throw InputError("prior_mean: expected 'case' or 'zero', got '" + prior_mean + "'");
        reduce::DatabaseReductionSettings s;
        s.tolerance = tolerance, s.history_tolerance = history_tolerance, s.profile_scale = profile_scale, s.max_rank = max_rank;
        s.prior_mean_from_case = prior_mean == "case", s.top_margin = top_margin;
        py::gil_scoped_release free;
        const auto start = std::chrono::steady_clock::now();
        auto reduced = reduce::reduce_database(database, s);
        if (out) reduce::write_reduction(*out, reduced, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        return std::make_shared<reduce::LightModel>(std::move(reduced.model));
      },
      py::arg("database"), py::arg("tolerance") = 1e-3, py::arg("history_tolerance") = -1.0, py::arg("profile_scale") = -1.0, py::arg("max_rank") = -1,
      py::arg("prior_mean") = "case", py::arg("top_margin") = -1.0, py::arg("out") = std::nullopt,
      "An offline database reduced to the light model (drom reduce); with out=MODEL.h5, the model and its pictures and summary are written too");

  // ---- the predictor ------------------------------------------------------------------------
  py::class_<online::PredictorSettings>(m, "PredictorSettings", "The predictor's settings (online/predictor.hpp); drom.predictor_settings(case, model) gives drom run's")
      .def(py::init<>())
      .def_readwrite("noise_sd", &online::PredictorSettings::noise_sd)
      .def_readwrite("prior_scale", &online::PredictorSettings::prior_scale)
      .def_readwrite("reading_range", &online::PredictorSettings::reading_range)
      .def_readwrite("learning_tolerance", &online::PredictorSettings::learning_tolerance)
      .def_readwrite("learning_window", &online::PredictorSettings::learning_window)
      .def_readwrite("max_offset_rate", &online::PredictorSettings::max_offset_rate)
      .def_readwrite("path_sample", &online::PredictorSettings::path_sample)
      .def_readwrite("use_stock_top", &online::PredictorSettings::use_stock_top)
      .def_readwrite("top_noise_sd", &online::PredictorSettings::top_noise_sd)
      .def_readwrite("max_offset", &online::PredictorSettings::max_offset)
      .def_readwrite("glitch_sigmas", &online::PredictorSettings::glitch_sigmas)
      .def_readwrite("glitch_run", &online::PredictorSettings::glitch_run)
      .def("__repr__", fields<online::PredictorSettings>({"noise_sd", "prior_scale", "reading_range", "learning_tolerance", "learning_window",
                                                          "max_offset_rate", "path_sample", "use_stock_top", "top_noise_sd", "max_offset",
                                                          "glitch_sigmas", "glitch_run"}));
  py::class_<online::ProfileReport>(m, "ProfileReport", "What add_profile did with a profile: points used and dropped, by reason")
      .def_readonly("used", &online::ProfileReport::used)
      .def_readonly("used_top", &online::ProfileReport::used_top)
      .def_readonly("outside", &online::ProfileReport::outside)
      .def_readonly("not_yet_cut", &online::ProfileReport::not_yet_cut)
      .def_readonly("invalid", &online::ProfileReport::invalid)
      .def_readonly("out_of_range", &online::ProfileReport::out_of_range)
      .def_readonly("predictive_rms", &online::ProfileReport::predictive_rms)
      .def_property_readonly("rejected", [](const online::ProfileReport& r) { return r.rejected ? py::object(py::str(r.rejected)) : py::object(py::none()); })
      .def("as_dict", &report_dict)
      .def("__repr__", fields<online::ProfileReport>({"rejected", "used", "used_top", "outside", "not_yet_cut", "invalid", "out_of_range", "predictive_rms"}));
  py::class_<online::Predictor>(m, "Predictor", "The online predictor (online/predictor.hpp): one thread feeds profiles, one asks for offsets")
      .def(py::init([](const std::shared_ptr<reduce::LightModel>& model, const online::PredictorSettings& s) { return std::make_unique<online::Predictor>(*model, s); }),
           py::arg("model"), py::arg_v("settings", online::PredictorSettings{}, "PredictorSettings()"))
      .def(
          "add_profile",
          [](online::Predictor& p, double t, const std::array<double, 3>& tip, double applied_offset, const PointArray& points) {
            const auto span = as_points(points);
            py::gil_scoped_release free;
            return p.add_profile(t, {Eigen::Vector3d(tip[0], tip[1], tip[2]), applied_offset}, span);
          },
          py::arg("t"), py::arg("tip"), py::arg("applied_offset"), py::arg("points"),
          "One laser profile read at program time t, the tool tip and offset then, points an (N, 3) float64 array (NaN z: no reading); returns the "
          "counts of points used and dropped")
      .def("record_offset", &online::Predictor::record_offset, py::arg("t"), py::arg("offset"))
      .def(
          "rejections",
          [](const online::Predictor& p) {
            const online::Rejections r = p.rejections();
            py::dict d;
            d["non_finite"] = r.non_finite, d["out_of_order"] = r.out_of_order, d["repeated"] = r.repeated, d["stuck"] = r.stuck, d["empty"] = r.empty;
            d["glitch"] = r.glitch, d["unlearned"] = r.unlearned, d["doubts_resolved"] = r.doubts_resolved, d["offsets_non_finite"] = r.offsets_non_finite, d["offsets_late"] = r.offsets_late;
            d["offsets_clamped"] = r.offsets_clamped;
            return d;
          },
          "what the stream held that was not a usable measurement, counted by reason (docs/robustness.md)")
      .def_property_readonly("max_offset", &online::Predictor::max_offset, "mm: the bound on the commanded offset")
      .def("tool_offset", &online::Predictor::tool_offset, py::arg("t"), "the rate-limited offset for program time t (the control thread's)")
      .def("predicted_offset", &online::Predictor::predicted_offset, py::arg("t"))
      .def("predicted_offset_sd", &online::Predictor::predicted_offset_sd, py::arg("t"))
      .def("target_altitude", &online::Predictor::target_altitude, py::arg("x"), py::arg("y"), py::arg("t"))
      .def("target_altitude_sd", &online::Predictor::target_altitude_sd, py::arg("x"), py::arg("y"), py::arg("t"))
      .def_property_readonly("learned", &online::Predictor::learned)
      .def("estimate",
           [](const online::Predictor& p) {
             const auto e = p.estimate();
             py::dict d;
             d["alpha"] = e.alpha, d["covariance"] = e.covariance, d["points"] = e.points, d["profiles"] = e.profiles, d["learned"] = e.learned;
             return d;
           })
      .def("final_shape",
           [](const online::Predictor& p) {
             const auto s = p.final_shape();
             py::dict d;
             d["nodes"] = s.nodes, d["displacement"] = s.displacement, d["sd"] = s.sd, d["faces"] = s.faces, d["face_nodes"] = s.face_nodes;
             return d;
           })
      .def(
          "verdict",
          [](const online::Predictor& p, double tolerance, double straightening_limit, double confidence) {
            return std::string(online::verdict_name(p.verdict({tolerance, straightening_limit, confidence})));
          },
          py::arg("tolerance") = 0.1, py::arg("straightening_limit") = 1.0, py::arg("confidence") = 1.96)
      .def("__repr__", fields<online::Predictor>({"learned", "max_offset"}));

  // ---- the closed loop ----------------------------------------------------------------------
  py::class_<loop::ClosedLoopInputs, std::shared_ptr<loop::ClosedLoopInputs>>(m, "ClosedLoopInputs",
                                                                              "drom run's model and truth (loop/closed_loop_setup.hpp)")
      .def_property_readonly("model", [](const loop::ClosedLoopInputs& in) { return std::make_shared<reduce::LightModel>(in.model); })
      .def_property_readonly("truth_final_displacement", [](const loop::ClosedLoopInputs& in) { return in.truth.final_displacement; })
      .def("__repr__", fields<loop::ClosedLoopInputs>({"model", "truth_final_displacement"}));
  m.def(
      "prepare_closed_loop",
      [](const case_file::Case& c, const std::filesystem::path& out, bool quiet, int threads) {
        return run_interruptible<std::shared_ptr<loop::ClosedLoopInputs>>([&](std::stop_token stop) {
          return std::make_shared<loop::ClosedLoopInputs>(loop::prepare_closed_loop(c, run_options(out, quiet, threads, stop)));
        });
      },
      py::arg("case"), py::arg("out"), py::arg("quiet") = true, py::arg("threads") = 0,
      "The offline, truth and model stages of drom run under out (computed, or reused while their case is unchanged); Ctrl-C stops them");
  m.def("predictor_settings", &loop::predictor_settings, py::arg("case"), py::arg("model"), "The predictor's settings as drom run takes them from the case");
  m.def(
      "run_closed_loop",
      [](const case_file::Case& c, const std::filesystem::path& out, bool quiet, int threads) {
        const nlohmann::json summary = run_interruptible<nlohmann::json>(
            [&](std::stop_token stop) { return loop::run_closed_loop(c, run_options(out, quiet, threads, stop)).summary; });
        return to_python(summary);
      },
      py::arg("case"), py::arg("out"), py::arg("quiet") = true, py::arg("threads") = 0,
      "drom run: returns its summary. Ctrl-C stops it within a second (KeyboardInterrupt); a rerun resumes its stages from their checkpoints");

  m.def(
      "run_study",
      [](const case_file::Case& base, const std::string& parameter, const std::vector<double>& values, const std::filesystem::path& out, bool quiet, int threads) {
        const nlohmann::json summary = run_interruptible<nlohmann::json>(
            [&](std::stop_token stop) { return loop::run_study(base, parameter, values, run_options(out, quiet, threads, stop)); });
        return to_python(summary);
      },
      py::arg("case"), py::arg("parameter"), py::arg("values"), py::arg("out"), py::arg("quiet") = true, py::arg("threads") = 0,
      "drom study: one loop parameter swept (noise, angle, refresh, calibration, desync, amplitude, seed); returns its summary");
  m.def("study_parameters", &loop::study_parameters);

  py::class_<online::LoopMachine::Step>(m, "LoopStep", "One step of LoopMachine.advance: its times, the tool tip, and whether a refresh or a scan is due")
      .def_readonly("index", &online::LoopMachine::Step::index)
      .def_readonly("clock", &online::LoopMachine::Step::clock)
      .def_readonly("true_time", &online::LoopMachine::Step::true_time)
      .def_readonly("believed_time", &online::LoopMachine::Step::believed_time)
      .def_readonly("tip", &online::LoopMachine::Step::tip)
      .def_readonly("believed_tip", &online::LoopMachine::Step::believed_tip)
      .def_readonly("pass_", &online::LoopMachine::Step::pass)
      .def_readonly("on_target", &online::LoopMachine::Step::on_target)
      .def_property_readonly("error", [](const online::LoopMachine::Step& s) { return s.sample.error; }, "applied offset - required, mm (on_target only)")
      .def_property_readonly("distortion", [](const online::LoopMachine::Step& s) { return s.sample.distortion; })
      .def_readonly("refresh", &online::LoopMachine::Step::refresh)
      .def_readonly("setpoint_time", &online::LoopMachine::Step::setpoint_time)
      .def_readonly("scan", &online::LoopMachine::Step::scan)
      .def("__repr__", fields<online::LoopMachine::Step>({"index", "clock", "true_time", "believed_time", "tip", "pass_", "on_target", "refresh",
                                                          "setpoint_time", "scan"}));
  py::class_<Machine>(m, "LoopMachine",
                      "drom run's simulated machine, part and laser sheet (online/loop_simulation.hpp), for a controller of one's own: step it, command "
                      "offsets when a refresh is due, read a profile when a scan is due")
      .def(py::init([](const std::shared_ptr<loop::ClosedLoopInputs>& in, const case_file::Case& c) {
             auto made = std::make_unique<Machine>();
             made->truth = in->play();
             made->machine = std::make_unique<online::LoopMachine>(in->model, made->truth.part, loop::loop_settings(c, in->model));
             return made;
           }),
           py::arg("inputs"), py::arg("case"), py::keep_alive<1, 2>())
      .def_property_readonly("steps", [](const Machine& mc) { return mc.machine->steps(); })
      .def("advance", [](Machine& mc, long k) { return mc.machine->advance(k); }, py::arg("k"))
      .def("command", [](Machine& mc, double offset) { mc.machine->command(offset); }, py::arg("offset"))
      .def_property_readonly("applied", [](const Machine& mc) { return mc.machine->applied(); })
      .def("__repr__", fields<Machine>({"steps", "applied"}))
      .def("scan", [](Machine& mc) {
        const auto points = mc.machine->scan();
        py::array_t<double> a({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
        auto v = a.mutable_unchecked<2>();
        for (std::size_t i = 0; i < points.size(); ++i) {
          const auto r = static_cast<py::ssize_t>(i);
          v(r, 0) = points[i].x, v(r, 1) = points[i].y, v(r, 2) = points[i].z;
        }
        return a;
      });

  // ---- a timing helper for bench/python_overhead.py: the same profiles fed from a C++ loop ---------
  m.def(
      "_add_profiles_in_cpp",
      [](online::Predictor& p, const std::vector<double>& times, const std::vector<std::array<double, 3>>& tips, const std::vector<double>& offsets,
         const std::vector<PointArray>& profiles) {
        std::vector<std::span<const online::MeasuredPoint>> spans;
        for (const auto& a : profiles) spans.push_back(as_points(a));
        py::gil_scoped_release free;
        const auto start = std::chrono::steady_clock::now();
        for (std::size_t i = 0; i < spans.size(); ++i) p.add_profile(times[i], {Eigen::Vector3d(tips[i][0], tips[i][1], tips[i][2]), offsets[i]}, spans[i]);
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      },
      py::arg("predictor"), py::arg("times"), py::arg("tips"), py::arg("offsets"), py::arg("profiles"),
      "Feeds the profiles from a C++ loop and returns the seconds it took (the reference of the Python-overhead benchmark)");
}
