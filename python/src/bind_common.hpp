// Shared helpers of the Python bindings: checked conversion of NumPy arguments into engine types, and
// zero-copy NumPy views of engine buffers.
//
// Every argument check throws medspring::InvalidInput (Python: medspring.InvalidInput, a ValueError)
// whose message names the argument and the expected shape, e.g.
//   "x: expected a C-contiguous float64 array of shape (458, 3); got a float32 array of shape (458, 3)".
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cctype>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/core/types.hpp"

namespace medspring::python {

namespace py = pybind11;

void bind_geometry(py::module_& m);
void bind_physics(py::module_& m);
void bind_local(py::module_& m);
void bind_models(py::module_& m);
void bind_sim(py::module_& m);
void bind_io(py::module_& m);
void bind_tools(py::module_& m);  // bind_tools.cpp (docs/tools.md)

/// "a float32 array of shape (5, 3)", "a non-contiguous float64 array of shape (5, 3)", "a list".
std::string describe_object(py::handle obj);

/// "(N, 3)" or "(458, 3)" when rows >= 0.
std::string shape_text(Index rows, const char* rows_name, Index cols);

/// A float64, C-contiguous array holding obj: NumPy arrays must already be float64 and C-contiguous
/// (no silent copy or cast); other sequences (lists, tuples) are converted. Throws InvalidInput.
py::array_t<double> float_array_arg(py::handle obj, const std::string& name, const std::string& expected);

/// #rows x 3 points (float64, C-contiguous, finite). rows < 0: any number of rows.
MatX3 points_arg(py::handle obj, const std::string& name, Index rows = -1, const char* rows_name = "N");

/// Copies obj (checked like points_arg) into an existing #N x 3 buffer without reallocating it.
void assign_points(MatX3& target, py::handle obj, const std::string& name);

/// A (n,) float64 vector (finite). n < 0: any length.
VecX vector_arg(py::handle obj, const std::string& name, Index n = -1, const char* n_name = "N");

/// Three finite real numbers (a tuple, list or NumPy array of shape (3,)).
Vec3 vec3_arg(py::handle obj, const std::string& name);

/// A #rows x cols integer matrix (NumPy integer array, C-contiguous; or a nested list of ints), values
/// in [0, bound) when bound >= 0.
Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> index_matrix_arg(
    py::handle obj, const std::string& name, Index cols, Index bound = -1, const char* rows_name = "N");
MatX3i faces_arg(py::handle obj, const std::string& name, Index num_vertices = -1);
MatX2i edges_arg(py::handle obj, const std::string& name, Index num_nodes = -1);

/// A 1-D list of integer indices, each in [0, bound) when bound >= 0.
std::vector<Index> index_list_arg(py::handle obj, const std::string& name, Index bound = -1);

/// A 1-D list of booleans/0-1 flags of length n (n < 0: any).
std::vector<std::uint8_t> flags_arg(py::handle obj, const std::string& name, Index n = -1);

/// A NumPy view of rows x cols elements at data (row-major), kept alive by `base`. Read-only unless
/// writable. No copy.
template <class T>
py::array matrix_view(const T* data, Index rows, Index cols, py::handle base, bool writable) {
  py::array_t<T> a({static_cast<py::ssize_t>(rows), static_cast<py::ssize_t>(cols)},
                   {static_cast<py::ssize_t>(cols * sizeof(T)), static_cast<py::ssize_t>(sizeof(T))}, data,
                   base);
  if (!writable) py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

/// A 1-D NumPy view of n elements at data, kept alive by `base`. Read-only unless writable.
template <class T>
py::array vector_view(const T* data, Index n, py::handle base, bool writable) {
  py::array_t<T> a({static_cast<py::ssize_t>(n)}, {static_cast<py::ssize_t>(sizeof(T))}, data, base);
  if (!writable) py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

/// Read-only views of an Eigen row-major matrix / vector / std::vector owned by `base`.
template <class Derived>
py::array view_of(const Eigen::PlainObjectBase<Derived>& M, py::handle base, bool writable = false) {
  using T = typename Derived::Scalar;
  if constexpr (Derived::ColsAtCompileTime == 1)
    return vector_view<T>(M.data(), static_cast<Index>(M.size()), base, writable);
  else {
    static_assert(Derived::IsRowMajor || Derived::ColsAtCompileTime == 1, "row-major matrices only");
    return matrix_view<T>(M.data(), static_cast<Index>(M.rows()), static_cast<Index>(M.cols()), base,
                          writable);
  }
}
template <class T>
py::array view_of(const std::vector<T>& v, py::handle base) {
  return vector_view<T>(v.data(), static_cast<Index>(v.size()), base, false);
}

/// New NumPy arrays holding a copy (for values computed on the fly).
template <class Derived>
py::array copy_of(const Eigen::PlainObjectBase<Derived>& M) {
  using T = typename Derived::Scalar;
  if constexpr (Derived::ColsAtCompileTime == 1) {
    py::array_t<T> a(static_cast<py::ssize_t>(M.size()));
    if (M.size() > 0) std::memcpy(a.mutable_data(), M.data(), sizeof(T) * static_cast<std::size_t>(M.size()));
    return a;
  } else {
    static_assert(Derived::IsRowMajor, "row-major matrices only");
    py::array_t<T> a({static_cast<py::ssize_t>(M.rows()), static_cast<py::ssize_t>(M.cols())});
    if (M.size() > 0) std::memcpy(a.mutable_data(), M.data(), sizeof(T) * static_cast<std::size_t>(M.size()));
    return a;
  }
}
template <class T>
py::array copy_of(const std::vector<T>& v) {
  py::array_t<T> a(static_cast<py::ssize_t>(v.size()));
  if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), sizeof(T) * v.size());
  return a;
}
inline py::array copy_of(const Vec3& p) {
  py::array_t<double> a(3);
  for (int d = 0; d < 3; ++d) a.mutable_at(d) = p[d];
  return a;
}
inline py::array copy_of(const Mat3& R) {
  py::array_t<double> a({3, 3});
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a.mutable_at(r, c) = R(r, c);
  return a;
}

/// Lets a Python str stand for a value of the bound enum E wherever E is expected: the text is parsed by
/// `parse` when given, else matched against the member names ignoring case and underscores
/// ("symplectic_euler" == SymplecticEuler). Unknown text raises InvalidInput listing the names.
/// The Python type of the bound enum E. Through an instance: pybind11 3's enum caster is not a
/// type_caster_generic, so py::type::of<E>() does not compile there (the GPU machine's pybind11 3.1).
template <class E>
py::object enum_type() {
  return py::type::of(py::cast(E{}));
}

template <class E>
void enum_accepts_strings(py::enum_<E>& cls, E (*parse)(const std::string&) = nullptr) {
  cls.def(py::init([parse](const std::string& text) -> E {
            if (parse != nullptr) return parse(text);
            auto norm = [](std::string s) {
              std::string out;
              for (char c : s)
                if (c != '_' && c != '-' && c != ' ')
                  out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
              return out;
            };
            const py::dict members = enum_type<E>().attr("__members__");
            std::string names;
            for (auto item : members) {
              const std::string name = py::str(item.first).cast<std::string>();
              if (norm(name) == norm(text)) return item.second.cast<E>();
              names += (names.empty() ? "" : ", ") + name;
            }
            throw InvalidInput(cat(py::str(enum_type<E>().attr("__name__")).cast<std::string>(),
                                   ": unknown value '", text, "' (expected one of ", names, ")"));
          }),
          py::arg("name"),
          "Parses a name such as 'strain' or 'symplectic_euler' (case and underscores ignored).");
  py::implicitly_convertible<py::str, E>();
}

/// A value of the bound enum E from an E or its name (a str raises InvalidInput naming the accepted
/// names when unknown; a wrong type raises TypeError).
template <class E>
E enum_arg(py::handle obj, const char* name) {
  if (py::isinstance<py::str>(obj)) return enum_type<E>()(obj).template cast<E>();
  try {
    return obj.cast<E>();
  } catch (const py::cast_error&) {
    throw py::type_error(cat(name, ": expected a ",
                             py::str(enum_type<E>().attr("__name__")).cast<std::string>(),
                             " or its name; got ", describe_object(obj)));
  }
}

/// A read-write enum field of an options struct that also accepts the value's name.
template <class T, class E, class... Extra>
void def_enum_field(py::class_<T, Extra...>& cls, const char* name, E T::*member, const char* doc) {
  cls.def_property(
      name, [member](const T& t) { return t.*member; },
      [member, name](T& t, py::handle v) { t.*member = enum_arg<E>(v, name); }, doc);
}

/// Gives a bound options struct T a keyword constructor (every public property may be passed, unknown
/// names raise TypeError) and a __repr__ listing the properties: StepSettings(dt=0.25, substep=False).
template <class T, class... Extra>
void settings_helpers(py::class_<T, Extra...>& cls) {
  cls.def(py::init([](const py::kwargs& kwargs) {
            T value{};
            const py::object type = py::type::of<T>();
            py::object tmp = py::cast(&value, py::return_value_policy::reference);
            const py::object property = py::module_::import("builtins").attr("property");
            for (auto item : kwargs) {
              const std::string key = py::str(item.first).cast<std::string>();
              const py::object attr = py::getattr(type, key.c_str(), py::none());
              if (attr.is_none() || !py::isinstance(attr, property) || key[0] == '_') {
                std::string names;
                for (auto entry : type.attr("__dict__").cast<py::dict>()) {
                  const std::string n = py::str(entry.first).cast<std::string>();
                  if (n[0] != '_' && py::isinstance(entry.second, property))
                    names += (names.empty() ? "" : ", ") + n;
                }
                throw py::type_error(cat(py::str(type.attr("__name__")).cast<std::string>(),
                                         ": unknown field '", key, "' (fields: ", names, ")"));
              }
              tmp.attr(key.c_str()) = item.second;
            }
            return value;
          }),
          "Default values, overridden by keyword arguments named like the fields.");
  cls.def("__repr__", [](py::object self) {
    const py::object type = py::type::of<T>();
    const py::object property = py::module_::import("builtins").attr("property");
    std::string out = py::str(type.attr("__name__")).cast<std::string>() + "(";
    bool first = true;
    for (auto entry : type.attr("__dict__").cast<py::dict>()) {
      const std::string n = py::str(entry.first).cast<std::string>();
      if (n[0] == '_' || !py::isinstance(entry.second, property)) continue;
      out += (first ? "" : ", ") + n + "=" + py::repr(self.attr(n.c_str())).cast<std::string>();
      first = false;
    }
    return out + ")";
  });
}

/// A bool array from 0/1 flags.
py::array bool_array(const std::vector<std::uint8_t>& flags);

}  // namespace medspring::python
