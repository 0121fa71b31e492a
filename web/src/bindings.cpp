// JavaScript API of the engine (embind), compiled by web/build.sh (docs/web.md). One Engine = one
// Simulation of a model (a bundled phantom or a model package, models/model_package.hpp) plus a haptic
// virtual coupling (sim/haptics.hpp) for the mouse tool, or a rigid tool (sphere probe, grasper:
// sim/tool_sim.hpp, docs/tools.md) that presses, slides and grasps through the contact model.
//
//   const ms = await createMedSpring();
//   const e = new ms.Engine('kidney_phantom', true, false);    // or new ms.Engine(uint8array, true, false)
//   e.grab(223, 0.1, 0.01, 3); e.moveTool(x, y, z); e.ticks(16);   // 16 fixed 1 ms ticks
//   const P = e.positions();                                    // Float32Array view (#S*3), zero-copy
//
// Every C++ error reaches JavaScript as an Error carrying the C++ message.
//
// The Engine lives in engine.hpp / engine.cpp / engine_tools.cpp, the JavaScript interop helpers in
// js_interop.hpp; this file binds them.
#include <emscripten/bind.h>
#include <emscripten/val.h>

#include <cstdint>
#include <exception>
#include <string>
#include <utility>

#include "engine.hpp"
#include "js_interop.hpp"
#include "medspring/models/model_package.hpp"

namespace medspring::web {

Engine* make_engine(val model, bool nonlinear, bool local) {
  return guarded([&] { return new Engine(model, nonlinear, local); });
}
Engine* make_engine_default(val model) {
  return make_engine(std::move(model), true, false);
}

/// Checks a model package without building an engine: {name, kind, description, params} or an Error.
val inspect_package(const val& bytes) {
  return guarded([&] {
    const ModelPackage p = decode_model_package(bytes_of(bytes), "model package");
    val o = val::object();
    o.set("name", p.name);
    o.set("kind", p.kind);
    o.set("description", p.description);
    o.set("surfaceNodes", static_cast<double>(p.surface.V.rows()));
    return o;
  });
}

std::string error_message(std::intptr_t ptr) {
  return reinterpret_cast<std::exception*>(ptr)->what();
}

EMSCRIPTEN_BINDINGS(medspring) {
  emscripten::class_<Engine>("Engine")
      .constructor(&make_engine)
      .constructor(&make_engine_default)
      .function("numSurfaceNodes", &Engine::numSurfaceNodes)
      .function("numAtoms", &Engine::numAtoms)
      .function("numMasses", &Engine::numMasses)
      .function("numSprings", &Engine::numSprings)
      .function("kind", &Engine::kind)
      .function("name", &Engine::name)
      .function("description", &Engine::description)
      .function("size", &Engine::size)
      .function("time", &Engine::time)
      .function("positions", &Engine::positions)
      .function("restPositions", &Engine::restPositions)
      .function("faces", &Engine::faces)
      .function("atoms", &Engine::atoms)
      .function("centerline", &Engine::centerline)
      .function("spokes", &Engine::spokes)
      .function("centerlineEdges", &Engine::centerlineEdges)
      .function("node", &Engine::node)
      .function("maxDisplacement", &Engine::maxDisplacement)
      .function("grab", &Engine::grab)
      .function("moveTool", &Engine::moveTool)
      .function("release", &Engine::release)
      .function("grabbed", &Engine::grabbed)
      .function("placeTool", &Engine::placeTool)
      .function("setOpening", &Engine::setOpening)
      .function("hasTool", &Engine::hasTool)
      .function("toolState", &Engine::toolState)
      .function("runToolTrajectory", &Engine::runToolTrajectory)
      .function("contact", &Engine::contact)
      .function("tool", &Engine::tool)
      .function("reaction", &Engine::reaction)
      .function("tick", &Engine::tick)
      .function("ticks", &Engine::ticks)
      .function("tickStats", &Engine::tickStats)
      .function("finite", &Engine::finite)
      .function("message", &Engine::message)
      .function("clearMessage", &Engine::clearMessage)
      .function("autoResets", &Engine::autoResets)
      .function("injectNaN", &Engine::injectNaN)
      .function("reset", &Engine::reset)
      .function("setLocal", &Engine::setLocal)
      .function("local", &Engine::local)
      .function("params", &Engine::params)
      .function("setParams", &Engine::setParams)
      .function("runTrajectory", &Engine::runTrajectory)
      .function("benchTrajectory", &Engine::benchTrajectory);
  emscripten::function("inspectPackage", &inspect_package);
  emscripten::function("errorMessage", &error_message);
}

}  // namespace medspring::web
