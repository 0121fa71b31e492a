// Helpers shared by the embind sources of web/src (docs/web.md): C++ errors to JavaScript Errors, bytes
// from a Uint8Array, zero-copy typed-array views of C++ vectors.
#pragma once

#include <emscripten/val.h>

#include <cstddef>
#include <exception>
#include <string>
#include <vector>

#include "medspring/core/error.hpp"

namespace medspring::web {

using emscripten::val;

/// Throws a JavaScript Error with the message (never returns).
[[noreturn]] inline void throw_js(const std::string& message) {
  val::global("Error").new_(message).throw_();
}

/// Runs f, turning a C++ exception into a JavaScript Error with its message.
template <class F>
auto guarded(F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const std::exception& e) {
    throw_js(e.what());
  }
}

inline std::string bytes_of(const val& array) {
  const std::string type = array.typeOf().as<std::string>();
  if (type != "object" || !array["length"].isNumber())
    throw InvalidInput("model: expected a model name or the bytes of a model package (Uint8Array)");
  const auto n = array["length"].as<std::size_t>();
  std::string bytes(n, '\0');
  // Copy with one TypedArray.set into a view of the C++ buffer (no per-byte crossing).
  val view(emscripten::typed_memory_view(n, reinterpret_cast<unsigned char*>(bytes.data())));
  view.call<void>("set", val::global("Uint8Array").new_(array));
  return bytes;
}

template <class T>
val float_array(const std::vector<T>& v) {
  return val(emscripten::typed_memory_view(v.size(), v.data()));
}

}  // namespace medspring::web
