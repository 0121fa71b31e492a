// Scenes from Python (docs/scenes.md, docs/studies.md): parse and validate a scene from JSON text, build
// its model once and run it many times with other loads or parameters, returning the summary metrics and
// the surface displacement at requested times. Parsing, building and running release the GIL, so threads
// (and Dask workers with several threads) run scenes in parallel.
//
//   r = SceneRunner()
//   out = r.run(json_text, base_dir, "study run 17", field_times=[500.0])
//   out["summary"]["contact_hold_mm"], out["fields"]  # (T, S, 3) float64 displacement, mm
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bind_common.hpp"
#include "bind_params.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/scene/batch.hpp"
#include "medspring/scene/build.hpp"
#include "medspring/scene/file_loader.hpp"
#include "medspring/scene/runner.hpp"
#include "medspring/scene/scene.hpp"
#include "medspring/scene/study_schema.hpp"
#include "medspring/scene/study_settings.hpp"
#include "medspring/scene/study_switches.hpp"
#ifdef MEDSPRING_PYTHON_WITH_FEM
#include "medspring/fem/volumetric.hpp"
#endif
#ifdef MEDSPRING_PYTHON_WITH_IO
#include "medspring/io/centerline_io.hpp"
#include "medspring/io/mesh_io.hpp"
#include "medspring/io/volume_io.hpp"
#endif
#ifdef MEDSPRING_PYTHON_WITH_MESHING
#include "medspring/meshing/balloon.hpp"
#include "medspring/meshing/isosurface.hpp"
#endif
#ifdef MEDSPRING_PYTHON_WITH_BUILDERS
#include "medspring/builders/scene_organ_tree.hpp"
#endif

namespace medspring::python {

void bind_scene(py::module_& m);

namespace {

// File access of scenes with file sources (scene/file_loader.hpp): the io layer's readers and, when
// built, the meshing layer's balloon surfaces and isosurfaces and the fem layer's TetGen. Meshes and
// balloons are cached for the life of the runner, so a worker builds the real kidney's 458-node balloon
// once for a whole study.

SceneFileAccess file_access() {
  SceneFileAccess a;
#ifdef MEDSPRING_PYTHON_WITH_IO
  a.read_mesh = [](const std::filesystem::path& file, LengthUnit unit) {
    return medspring::read_mesh(file, {.unit = unit});
  };
  a.read_centerlines = [](const std::filesystem::path& file, LengthUnit unit,
                          const std::string& radius_array) {
    return medspring::read_centerlines(file, unit, radius_array);
  };
  a.read_label_volume = [](const std::filesystem::path& file) { return medspring::read_label_volume(file); };
#endif
#ifdef MEDSPRING_PYTHON_WITH_MESHING
  a.isosurface = [](const MaskVolume& mask) { return medspring::isosurface(mask); };
  a.balloon = [](const SurfaceMesh& organ, Index nodes) {
    const BalloonResult r = build_balloon_surface(organ, {.target_nodes = nodes});
    return BalloonSurface{r.mesh, r.report.note_lines()};
  };
#endif
#ifdef MEDSPRING_PYTHON_WITH_FEM
  a.tetrahedralize = [](const SurfaceMesh& organ, Index nodes, MeshSizing sizing) {
    return fem::volumetric_mesh(organ, {.target_nodes = nodes, .sizing = sizing});
  };
#endif
#ifdef MEDSPRING_PYTHON_WITH_BUILDERS
  a.tree_surface = [](const CenterlineTree& tree, const SmrmTree& plain, double spacing,
                      std::vector<std::string>& notes) {  // "blend": true (CGAL union)
    TreeSurface r = blended_tree_surface(tree, plain, spacing);
    for (const auto& n : r.notes) notes.push_back(n);
    for (const auto& w : r.warnings) notes.push_back("warning: " + w);
    return std::move(r.mesh);
  };
  a.organ_tree = [](const OrganTreeRequest& r, std::vector<std::string>& notes) {
    return scene_organ_tree(r, notes);  // `medspring build vessel --mesh F | --segmentation F --branches all`
  };
#endif
  return a;
}

// The part of a scene that decides its model: equal keys build equal models.
std::string model_key(const Scene& scene) {
  Scene k;
  k.name = scene.name;
  k.file = scene.file;
  k.model = scene.model;
  return scene_to_json(k);
}

struct RunOutput {
  RunSummary summary;
  Index load_node = -1;
  Vec3 load_force = Vec3::Zero();
  std::vector<double> field_times;  // the frame times of the fields (>= the requested times)
  std::vector<MatX3> fields;        // surface displacement at those frames, mm
  double build_seconds = 0.0;       // this run's build (loads and settings; the model when first seen)
  double run_seconds = 0.0;
  bool model_built = false;  // the model was built by this run (not found in the cache)
  Index num_surface_nodes = 0;
  // The first tool (scene "tools", docs/tools.md), over every update: the peak and final magnitude of
  // its reaction force (N) and its peak penetration (mm); 0 without tools.
  double tool_peak_force = 0.0, tool_final_force = 0.0, tool_peak_penetration = 0.0;
};

// Builds and runs scenes, keeping every model it built (by model key) for later runs.
class SceneRunner {
 public:
  Scene parse(const std::string& text, const std::string& base_dir, const std::string& origin) const {
    return parse_scene(text, base_dir, origin);
  }

  const BuiltScene& model_of(const Scene& scene, bool* built) {
    const std::string key = model_key(scene);
    auto it = models_.find(key);
    if (it != models_.end()) {
      *built = false;
      return it->second;
    }
    *built = true;
    return models_.emplace(key, build_scene(scene, &loader_)).first->second;
  }

  BuiltScene build(const Scene& scene, bool* built) {
    const BuiltScene& prior = model_of(scene, built);
    return *built ? prior : build_scene_reusing(scene, prior);
  }

  RunOutput run(const Scene& parsed, const std::vector<double>& times) {
    RunOutput out;
    Scene scene = parsed;
    for (std::size_t i = 0; i < times.size(); ++i)
      if (!(std::isfinite(times[i]) && times[i] >= 0 && times[i] <= scene.duration))
        throw InvalidInput(cat("field_times[", i, "]: ", times[i], " ms is outside the scene's [0, ",
                               scene.duration, "] ms"));
    // Frames only where fields are asked for (the rest state and the last frame are always recorded).
    scene.record.frames = !times.empty();
    scene.record.every = std::numeric_limits<Index>::max() / 2;
    scene.record.key_times = times;
    const auto t0 = std::chrono::steady_clock::now();
    const BuiltScene built = build(scene, &out.model_built);
    const auto t1 = std::chrono::steady_clock::now();
    out.num_surface_nodes = built.body->num_surface_nodes();
    if (!built.loads.empty()) {
      out.load_node = built.loads.front().node;
      out.load_force = built.loads.front().force;
    }
    std::vector<double> frame_times;
    std::vector<MatX3> frames;
    const MatX3& rest = built.body->rest_surface();
    RunHooks hooks;
    if (!times.empty())
      hooks.on_frame = [&](const Simulation& sim, const RecordedFrame& f) {
        frame_times.push_back(f.time);
        frames.push_back(sim.surface() - rest);
      };
    const SceneResult r = run_scene(built, hooks);
    out.summary = r.summary;
    if (!r.trace.tools.empty()) {
      const SceneTrace::ToolTrace& tt = r.trace.tools.front();
      for (std::size_t k = 0; k < tt.fx.size(); ++k) {
        const double f = std::sqrt(tt.fx[k] * tt.fx[k] + tt.fy[k] * tt.fy[k] + tt.fz[k] * tt.fz[k]);
        out.tool_peak_force = std::max(out.tool_peak_force, f);
        out.tool_final_force = f;
        out.tool_peak_penetration = std::max(out.tool_peak_penetration, tt.penetration[k]);
      }
    }
    for (double t : times) {
      std::size_t j = 0;
      while (j + 1 < frame_times.size() && frame_times[j] < t - 1e-9) ++j;
      out.field_times.push_back(frame_times[j]);
      out.fields.push_back(frames[j]);
    }
    out.build_seconds = std::chrono::duration<double>(t1 - t0).count();
    out.run_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    return out;
  }

  // Runs in batches (scene/batch.hpp): every run built here (a run whose build fails gets its error in
  // `errors` and no output), then stepped in groups by `make`. Outputs in the runs' order.
  std::vector<RunOutput> run_batch(const std::vector<Scene>& parsed, const std::vector<double>& times,
                                   const BatchStepperFactory& make, std::vector<std::string>& errors) {
    const std::size_t R = parsed.size();
    std::vector<RunOutput> out(R);
    errors.assign(R, "");
    std::vector<BuiltScene> built;
    built.reserve(R);
    std::vector<std::size_t> which;  // run of built[k]
    for (std::size_t i = 0; i < R; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      try {
        built.push_back(build(parsed[i], &out[i].model_built));
        which.push_back(i);
      } catch (const InvalidInput& e) {  // as the study worker names a failed run: "Type: message"
        errors[i] = cat("InvalidInput: ", e.what());
      } catch (const IoError& e) {
        errors[i] = cat("IoError: ", e.what());
      } catch (const Error& e) {
        errors[i] = cat("Error: ", e.what());
      }
      out[i].build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    std::vector<const BuiltScene*> ptrs;
    for (const BuiltScene& b : built) ptrs.push_back(&b);
    std::vector<BatchRunResult> r = run_scene_batch(ptrs, make, times);
    for (std::size_t k = 0; k < built.size(); ++k) {
      RunOutput& o = out[which[k]];
      const BuiltScene& b = built[k];
      o.num_surface_nodes = b.body->num_surface_nodes();
      if (!b.loads.empty()) {
        o.load_node = b.loads.front().node;
        o.load_force = b.loads.front().force;
      }
      o.summary = r[k].summary;
      o.field_times = std::move(r[k].field_times);
      o.fields = std::move(r[k].fields);
      o.run_seconds = r[k].run_seconds / std::max(1, r[k].group_size);  // the run's share of its batch
    }
    return out;
  }

  std::size_t cached_models() const { return models_.size(); }

 private:
  CachingSceneLoader loader_{file_access()};
  std::map<std::string, BuiltScene> models_;
};

}  // namespace

std::unique_ptr<SceneLoader> make_file_loader() {
  return std::make_unique<CachingSceneLoader>(file_access());
}

namespace {

py::dict summary_dict(const RunSummary& s) {
  py::dict d;
  d["updates"] = s.updates;
  d["wall_seconds"] = s.wall_seconds;
  d["median_update_us"] = s.median_update_us;
  d["substeps"] = s.substeps;
  d["warnings"] = s.warnings;
  d["contact_peak_mm"] = s.contact_peak_mm;
  d["contact_hold_mm"] = s.contact_hold_mm;
  d["max_disp_peak_mm"] = s.max_disp_peak_mm;
  d["atom_hold_mm"] = s.atom_hold_mm;
  d["local_hold_mm"] = s.local_hold_mm;
  d["return_ms"] = s.return_ms;
  d["final_max_disp_mm"] = s.final_max_disp_mm;
  return d;
}

py::dict output_dict(RunOutput& o, bool fields) {
  py::dict d;
  py::dict summary = summary_dict(o.summary);
  summary["tool_peak_force_N"] = o.tool_peak_force;
  summary["tool_final_force_N"] = o.tool_final_force;
  summary["tool_peak_penetration_mm"] = o.tool_peak_penetration;
  d["summary"] = summary;
  d["load_node"] = o.load_node;
  d["load_force"] = copy_of(o.load_force);
  d["build_seconds"] = o.build_seconds;
  d["run_seconds"] = o.run_seconds;
  d["model_built"] = o.model_built;
  d["field_times"] = copy_of(o.field_times);
  if (fields) {
    const auto T = static_cast<py::ssize_t>(o.fields.size());
    const auto S = static_cast<py::ssize_t>(o.num_surface_nodes);
    py::array_t<double> a({T, S, static_cast<py::ssize_t>(3)});
    double* p = a.mutable_data();
    for (const MatX3& f : o.fields) {
      std::memcpy(p, f.data(), sizeof(double) * static_cast<std::size_t>(f.size()));
      p += f.size();
    }
    d["fields"] = a;
  }
  return d;
}

}  // namespace

BatchStepperFactory& gpu_batch_factory() {  // set by bind_gpu (bind_gpu.cpp) in a build with the backend
  static BatchStepperFactory f;
  return f;
}

void bind_scene(py::module_& m) {
  m.def(
      "scene_json",
      [](const std::string& text, const std::string& base_dir, const std::string& origin) {
        py::gil_scoped_release release;
        return scene_to_json(parse_scene(text, base_dir, origin));
      },
      py::arg("text"), py::arg("base_dir") = ".", py::arg("origin") = "scene",
      "Parses and validates scene JSON text (relative file names against base_dir; messages start with "
      "origin) and returns the scene with every default filled in and every path absolute, as JSON text. "
      "Raises InvalidInput naming the JSON path at fault.");
  m.def(
      "load_scene_json",
      [](const std::filesystem::path& file) {
        py::gil_scoped_release release;
        return scene_to_json(load_scene(file));
      },
      py::arg("file"),
      "Reads and validates a scene file; returns it with every default filled in and every path absolute "
      "(JSON text). Raises IoError or InvalidInput naming the file and JSON path.");
  m.def(
      "scene_data_dir", [] { return scene_data_dir(); },
      "The folder that ${MEDSPRING_DATA} in scene files stands for.");

  // ---- Study settings (docs/studies.md), declared in scene/study_settings.hpp ----
  py::enum_<SampleMethod> sample_method(m, "SampleMethod",
                                        "How a study draws its sampled quantities ('random' or "
                                        "'latin_hypercube' accepted wherever one is expected).");
  sample_method.value("Random", SampleMethod::Random).value("LatinHypercube", SampleMethod::LatinHypercube);
  enum_accepts_strings(
      sample_method,
      +[](const std::string& t) { return parse_enum(t, static_cast<SampleMethod*>(nullptr)); });
  py::class_<StudySamples> samples_cls(m, "StudySamples", "A study file's \"samples\" object.");
  def_params(samples_cls);
  settings_helpers(samples_cls);
  py::class_<StudySettings> study_cls(m, "StudySettings",
                                      "The declared keys of a study file: samples, seed, batch, max_runs "
                                      "(docs/parameters.md).");
  def_params(study_cls);
  settings_helpers(study_cls);
  m.def("study_settings_from_json", &study_settings_from_json, py::arg("text"), py::arg("origin") = "study",
        "The declared keys of a study file's JSON object (text), every one checked; other keys are left "
        "to the caller. Raises InvalidInput 'ORIGIN: samples.count: must be ...'.");
  m.def("study_settings_json", &study_settings_json, py::arg("settings"),
        "A StudySettings as the JSON object a study file holds (text).");
  m.def(
      "study_file_schema",
      [] {
        py::list keys, metrics;
        for (const StudyKey& k : study_file_keys())
          keys.append(py::dict(py::arg("path") = k.path, py::arg("type") = std::string(to_string(k.type)),
                               py::arg("unit") = k.unit, py::arg("default") = k.def, py::arg("doc") = k.doc,
                               py::arg("lo") = k.lo, py::arg("lo_open") = k.lo_open,
                               py::arg("range") = k.range(), py::arg("words") = k.words,
                               py::arg("required") = k.required, py::arg("one_of") = k.one_of,
                               py::arg("non_empty") = k.non_empty, py::arg("open") = k.open));
        for (const StudyMetric& x : study_metrics())
          metrics.append(py::dict(py::arg("name") = x.name, py::arg("unit") = x.unit, py::arg("doc") = x.doc,
                                  py::arg("by_default") = x.by_default));
        return py::dict(py::arg("keys") = keys, py::arg("metrics") = metrics);
      },
      "The lists and objects of a study file as declared once in C++ (scene/study_schema.hpp): keys, each "
      "a dict (path such as 'vary[].grid.num', type, unit, default, doc, lo, lo_open, range, words, "
      "required, one_of, non_empty, open), and metrics (name, unit, doc, by_default). medspring.study "
      "checks study files against it; docs/parameters.md is generated from it.");
  m.def(
      "study_runner_cli",
      [] {
        const StudyRunnerCli& d = study_runner_cli();
        py::list switches;
        for (const StudySwitch& w : d.switches)
          switches.append(py::dict(py::arg("name") = w.name, py::arg("type") = std::string(to_string(w.type)),
                                   py::arg("value") = w.value, py::arg("unit") = w.unit,
                                   py::arg("default") = w.def, py::arg("help") = w.help,
                                   py::arg("group") = w.group, py::arg("min") = w.min,
                                   py::arg("required") = w.required, py::arg("hidden") = w.hidden));
        return py::dict(py::arg("summary") = d.summary, py::arg("about") = d.about,
                        py::arg("positional") = d.positional, py::arg("positional_help") = d.positional_help,
                        py::arg("switches") = switches);
      },
      "The study runner's command line as declared once in C++ (scene/study_switches.hpp): summary, about, "
      "positional, positional_help and switches, each a dict (name, type: flag|integer|text|choice, value, "
      "unit, default, help, group, min, required, hidden). `medspring study` and `python3 -m "
      "medspring.study` "
      "are both built from it.");

  py::class_<SceneRunner>(m, "SceneRunner",
                          "Builds and runs scenes, keeping every model it built (keyed by the scene's "
                          "`model` section and name) so that runs differing only in loads, integrator, "
                          "duration or local settings reuse it. One runner per thread.")
      .def(py::init<>())
      .def(
          "run",
          [](SceneRunner& self, const std::string& text, const std::string& base_dir,
             const std::string& origin, const std::vector<double>& field_times, bool fields) {
            RunOutput o;
            {
              py::gil_scoped_release release;
              o = self.run(self.parse(text, base_dir, origin), field_times);
            }
            return output_dict(o, fields);
          },
          py::arg("text"), py::arg("base_dir") = ".", py::arg("origin") = "scene",
          py::arg("field_times") = std::vector<double>{}, py::arg("fields") = true,
          "Parses, builds (the model only when not cached) and runs a scene given as JSON text, without "
          "the GIL. Returns a dict: summary (updates, wall_seconds, median_update_us, substeps, warnings, "
          "contact_peak_mm, contact_hold_mm, max_disp_peak_mm, atom_hold_mm, local_hold_mm, return_ms, "
          "final_max_disp_mm), load_node and load_force (N) of the first load, build_seconds, "
          "run_seconds, model_built, field_times (ms of the frames returned: the first frame reaching "
          "each requested time) and, with fields=True, fields: (T, S, 3) surface displacement in mm.")
      .def(
          "model",
          [](SceneRunner& self, const std::string& text, const std::string& base_dir,
             const std::string& origin) {
            const BuiltScene* built = nullptr;
            {
              py::gil_scoped_release release;
              bool fresh = false;
              built = &self.model_of(self.parse(text, base_dir, origin), &fresh);
            }
            const Body& body = *built->body;
            MatX3 normals;
            vertex_normals(body.rest_surface(), body.faces(), normals);
            py::dict d;
            d["rest_surface"] = copy_of(body.rest_surface());
            d["faces"] = copy_of(body.faces());
            d["normals"] = copy_of(normals);
            d["atoms_rest"] = copy_of(built->atoms_rest);
            d["num_surface_nodes"] = body.num_surface_nodes();
            d["notes"] = built->notes;
            d["build_seconds"] = built->build_seconds;
            return d;
          },
          py::arg("text"), py::arg("base_dir") = ".", py::arg("origin") = "scene",
          "Builds (or finds in the cache) the model of a scene: dict of rest_surface (S, 3), faces, rest "
          "vertex normals, atoms_rest, num_surface_nodes, notes, build_seconds.")
      .def(
          "run_batch",
          [](SceneRunner& self, const std::vector<std::string>& texts, const std::string& base_dir,
             const std::vector<double>& field_times, bool fields, const std::string& device,
             const std::vector<std::string>& origins) {
            if (!origins.empty() && origins.size() != texts.size())
              throw InvalidInput(
                  cat("run_batch: origins: ", origins.size(), " names for ", texts.size(), " runs"));
            BatchStepperFactory make;
            if (device == "cpu")
              make = make_cpu_batch_stepper;
            else if (device == "cuda")
              make = gpu_batch_factory();
            else
              throw InvalidInput(cat("run_batch: device: expected 'cpu' or 'cuda'; got '", device, "'"));
            if (!make)
              throw Error(
                  "run_batch: device 'cuda': this build has no CUDA backend (MEDSPRING_CUDA, "
                  "docs/gpu.md); use the CPU engine");
            std::vector<RunOutput> o;
            std::vector<std::string> errors;
            {
              py::gil_scoped_release release;
              std::vector<Scene> parsed;
              for (std::size_t i = 0; i < texts.size(); ++i) {
                try {
                  parsed.push_back(
                      self.parse(texts[i], base_dir, origins.empty() ? cat("run ", i) : origins[i]));
                } catch (const Error& e) {
                  throw InvalidInput(e.what());
                }
              }
              o = self.run_batch(parsed, field_times, make, errors);
            }
            py::list out;
            for (std::size_t i = 0; i < o.size(); ++i)
              out.append(errors[i].empty() ? py::object(output_dict(o[i], fields))
                                           : py::object(py::str(errors[i])));
            return out;
          },
          py::arg("texts"), py::arg("base_dir") = ".", py::arg("field_times") = std::vector<double>{},
          py::arg("fields") = true, py::arg("device") = "cpu",
          py::arg("origins") = std::vector<std::string>{},
          "Runs scenes (JSON texts) in batches (docs/gpu.md, 'Study runs on the GPU'): runs whose models "
          "share "
          "a topology, step settings and duration are stepped together by a batch engine — device='cuda': "
          "the CUDA backend's gpu.Engine; device='cpu': the CPU reference (step() per model). Returns a list "
          "in the runs' order: for each run the dict of run(), or the error text of a run whose build failed "
          "('InvalidInput: ...'); origins: a name per run for its messages. "
          "median_update_us is the batch's frame time; run_seconds the run's share of its batch. Raises "
          "InvalidInput for a scene with local deformation or tools, gpu.GpuError for a GPU failure.")
      .def_property_readonly("cached_models", &SceneRunner::cached_models,
                             "How many models this runner holds.");
}

}  // namespace medspring::python
