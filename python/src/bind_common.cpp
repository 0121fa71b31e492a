#include "bind_common.hpp"

#include <limits>

namespace medspring::python {

using namespace pybind11::literals;

namespace {

py::module_ numpy() {
  return py::module_::import("numpy");
}

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) {
    if (d) s += ", ";
    s += std::to_string(a.shape(d));
  }
  if (a.ndim() == 1) s += ",";
  return s + ")";
}

bool c_contiguous(const py::array& a) {
  return (a.flags() & py::array::c_style) != 0;
}

char dtype_kind(const py::array& a) {
  return a.dtype().kind();
}

[[noreturn]] void fail(const std::string& name, const std::string& expected, py::handle obj) {
  throw InvalidInput(cat(name, ": expected ", expected, "; got ", describe_object(obj)));
}

// An integer array (any integer dtype) as int64, C-contiguous; lists are converted.
py::array_t<std::int64_t> integer_array(py::handle obj, const std::string& name,
                                        const std::string& expected) {
  py::array a;
  if (py::isinstance<py::array>(obj)) {
    a = py::reinterpret_borrow<py::array>(obj);
    if (!c_contiguous(a)) fail(name, expected, obj);
  } else {
    try {
      a = numpy().attr("asarray")(obj);
    } catch (const py::error_already_set&) {
      fail(name, expected, obj);
    }
    if (a.size() == 0) a = numpy().attr("asarray")(obj, "dtype"_a = "int64");
  }
  const char k = dtype_kind(a);
  if (k != 'i' && k != 'u') fail(name, expected, obj);
  return numpy().attr("ascontiguousarray")(a, "dtype"_a = "int64");
}

}  // namespace

std::string describe_object(py::handle obj) {
  if (py::isinstance<py::array>(obj)) {
    const auto a = py::reinterpret_borrow<py::array>(obj);
    std::string s = c_contiguous(a) ? "a " : "a non-contiguous ";
    return s + py::str(a.dtype()).cast<std::string>() + " array of shape " + shape_of(a);
  }
  if (obj.is_none()) return "None";
  return "a " + py::str(obj.get_type().attr("__name__")).cast<std::string>();
}

std::string shape_text(Index rows, const char* rows_name, Index cols) {
  return cat("(", rows >= 0 ? std::to_string(rows) : std::string(rows_name), ", ", cols, ")");
}

py::array_t<double> float_array_arg(py::handle obj, const std::string& name, const std::string& expected) {
  if (py::isinstance<py::array>(obj)) {
    auto a = py::reinterpret_borrow<py::array>(obj);
    if (dtype_kind(a) != 'f' || a.itemsize() != 8 || !a.dtype().attr("isnative").cast<bool>())
      fail(name, expected, obj);
    if (!c_contiguous(a)) fail(name, expected, obj);
    return py::reinterpret_borrow<py::array_t<double>>(obj);
  }
  if (obj.is_none() || py::isinstance<py::str>(obj) || py::isinstance<py::bytes>(obj))
    fail(name, expected, obj);
  try {
    return numpy().attr("asarray")(obj, "dtype"_a = "float64");
  } catch (const py::error_already_set&) {
    fail(name, expected, obj);
  }
}

MatX3 points_arg(py::handle obj, const std::string& name, Index rows, const char* rows_name) {
  const std::string expected = "a C-contiguous float64 array of shape " + shape_text(rows, rows_name, 3);
  const auto a = float_array_arg(obj, name, expected);
  const bool empty_list = !py::isinstance<py::array>(obj) && a.size() == 0;
  if (!empty_list && (a.ndim() != 2 || a.shape(1) != 3)) fail(name, expected, obj);
  const Index n = empty_list ? 0 : static_cast<Index>(a.shape(0));
  if (rows >= 0 && n != rows) fail(name, expected, obj);
  MatX3 P(n, 3);
  if (n > 0) std::memcpy(P.data(), a.data(), sizeof(double) * static_cast<std::size_t>(3 * n));
  const Index bad = first_nonfinite_row(P);
  if (bad >= 0)
    throw InvalidInput(cat(name, ": expected finite values in ", expected, "; row ", bad, " is (", P(bad, 0),
                           ", ", P(bad, 1), ", ", P(bad, 2), ")"));
  return P;
}

void assign_points(MatX3& target, py::handle obj, const std::string& name) {
  const MatX3 P = points_arg(obj, name, static_cast<Index>(target.rows()));
  if (P.size() > 0) std::memcpy(target.data(), P.data(), sizeof(double) * static_cast<std::size_t>(P.size()));
}

VecX vector_arg(py::handle obj, const std::string& name, Index n, const char* n_name) {
  const std::string expected =
      cat("a C-contiguous float64 array of shape (", n >= 0 ? std::to_string(n) : std::string(n_name), ",)");
  const auto a = float_array_arg(obj, name, expected);
  if (a.ndim() != 1) fail(name, expected, obj);
  const Index len = static_cast<Index>(a.shape(0));
  if (n >= 0 && len != n) fail(name, expected, obj);
  VecX v(len);
  if (len > 0) std::memcpy(v.data(), a.data(), sizeof(double) * static_cast<std::size_t>(len));
  for (Index i = 0; i < len; ++i)
    if (!std::isfinite(v[i]))
      throw InvalidInput(cat(name, ": expected finite values in ", expected, "; element ", i, " is ", v[i]));
  return v;
}

Vec3 vec3_arg(py::handle obj, const std::string& name) {
  const std::string expected = "3 finite numbers (a tuple, list or array of shape (3,))";
  py::array a;
  try {
    if (obj.is_none() || py::isinstance<py::str>(obj)) fail(name, expected, obj);
    a = numpy().attr("asarray")(obj);
  } catch (const py::error_already_set&) {
    fail(name, expected, obj);
  }
  const char k = dtype_kind(a);
  if ((k != 'f' && k != 'i' && k != 'u') || a.ndim() != 1 || a.shape(0) != 3) fail(name, expected, obj);
  const auto d = numpy().attr("asarray")(a, "dtype"_a = "float64").cast<py::array_t<double>>();
  const Vec3 p(d.at(0), d.at(1), d.at(2));
  if (!p.allFinite())
    throw InvalidInput(cat(name, ": expected ", expected, "; got (", p[0], ", ", p[1], ", ", p[2], ")"));
  return p;
}

Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> index_matrix_arg(
    py::handle obj, const std::string& name, Index cols, Index bound, const char* rows_name) {
  const std::string expected = "a C-contiguous integer array of shape " + shape_text(-1, rows_name, cols);
  const auto a = integer_array(obj, name, expected);
  const bool empty_list = !py::isinstance<py::array>(obj) && a.size() == 0;
  if (!empty_list && (a.ndim() != 2 || a.shape(1) != cols)) fail(name, expected, obj);
  const Index n = empty_list ? 0 : static_cast<Index>(a.shape(0));
  Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> M(n, cols);
  const std::int64_t* src = a.data();
  const std::int64_t hi = bound >= 0 ? bound : std::numeric_limits<Index>::max();
  for (Index r = 0; r < n; ++r)
    for (Index c = 0; c < cols; ++c) {
      const std::int64_t v = src[static_cast<std::size_t>(r) * cols + c];
      if (v < 0 || v >= hi)
        throw InvalidInput(cat(name, "[", r, "]: index ", v, " out of range [0, ", hi, ") in ", expected));
      M(r, c) = static_cast<Index>(v);
    }
  return M;
}

MatX3i faces_arg(py::handle obj, const std::string& name, Index num_vertices) {
  return index_matrix_arg(obj, name, 3, num_vertices, "F");
}

MatX2i edges_arg(py::handle obj, const std::string& name, Index num_nodes) {
  return index_matrix_arg(obj, name, 2, num_nodes, "E");
}

std::vector<Index> index_list_arg(py::handle obj, const std::string& name, Index bound) {
  const std::string expected = "a sequence of integer indices (shape (K,))";
  const auto a = integer_array(obj, name, expected);
  if (a.ndim() != 1) fail(name, expected, obj);
  std::vector<Index> out(static_cast<std::size_t>(a.shape(0)));
  const std::int64_t hi = bound >= 0 ? bound : std::numeric_limits<Index>::max();
  for (std::size_t i = 0; i < out.size(); ++i) {
    const std::int64_t v = a.data()[i];
    if (v < 0 || v >= hi)
      throw InvalidInput(cat(name, "[", i, "]: index ", v, " out of range [0, ", hi, ")"));
    out[i] = static_cast<Index>(v);
  }
  return out;
}

std::vector<std::uint8_t> flags_arg(py::handle obj, const std::string& name, Index n) {
  const std::string expected =
      cat("a boolean array of shape (", n >= 0 ? std::to_string(n) : std::string("N"), ",)");
  py::array a;
  try {
    a = numpy().attr("asarray")(obj);
  } catch (const py::error_already_set&) {
    fail(name, expected, obj);
  }
  const char k = dtype_kind(a);
  if ((k != 'b' && k != 'i' && k != 'u') || a.ndim() != 1 || (n >= 0 && a.shape(0) != n))
    fail(name, expected, obj);
  const auto b = numpy().attr("ascontiguousarray")(a, "dtype"_a = "uint8").cast<py::array_t<std::uint8_t>>();
  std::vector<std::uint8_t> out(static_cast<std::size_t>(b.shape(0)));
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = b.data()[i] != 0 ? 1 : 0;
  return out;
}

py::array bool_array(const std::vector<std::uint8_t>& flags) {
  py::array_t<bool> a(static_cast<py::ssize_t>(flags.size()));
  for (std::size_t i = 0; i < flags.size(); ++i) a.mutable_data()[i] = flags[i] != 0;
  return a;
}

}  // namespace medspring::python
