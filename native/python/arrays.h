// python/arrays.h — what the binding files share: numpy ↔ Eigen conversions that check
// shapes and index ranges, and `guarded`, which turns a genbrep::Error into the Python
// genbrep_native.ConversionError (CancelledError when cancelled) with .code and .stage.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/types.h"

namespace genbrep::python {

namespace py = pybind11;

// Sets the Python error for `e` (module.cpp owns the exception types).
void set_python_error(const Error& e);

template <typename Fn>
auto guarded(Fn&& fn) {
  try {
    return fn();
  } catch (const Error& e) {
    set_python_error(e);
    throw py::error_already_set();
  }
}

// An N×3 float array; `what` names it in the error ("design 'd': vertices").
inline Vertices to_vertices(const py::handle& obj, const std::string& what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a || a.ndim() != 2 || a.shape(1) != 3) {
    throw Error(Code::InvalidInput, what + " must be an N×3 float array");
  }
  Vertices v(a.shape(0), 3);
  std::copy(a.data(), a.data() + a.size(), v.data());
  return v;
}

// An M×Columns array of non-negative int32 indices.
template <int Columns>
Eigen::Matrix<int, Eigen::Dynamic, Columns, Eigen::RowMajor> to_indices(const py::handle& obj,
                                                                        const std::string& what) {
  auto a = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a || a.ndim() != 2 || a.shape(1) != Columns) {
    throw Error(Code::InvalidInput,
                what + " must be an M×" + std::to_string(Columns) + " integer array");
  }
  Eigen::Matrix<int, Eigen::Dynamic, Columns, Eigen::RowMajor> m(a.shape(0), Columns);
  for (py::ssize_t i = 0; i < a.size(); ++i) {
    const int64_t value = a.data()[i];
    if (value < 0 || value > INT32_MAX) {
      throw Error(Code::InvalidInput, what + ": index " + std::to_string(value) + " is out of range");
    }
    m.data()[i] = static_cast<int>(value);
  }
  return m;
}

template <typename Matrix>
py::array matrix_to_array(const Matrix& m) {
  using Scalar = typename Matrix::Scalar;
  py::array_t<Scalar> out({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  std::copy(m.data(), m.data() + m.size(), out.mutable_data());
  return std::move(out);
}

inline py::array_t<int32_t> vector_to_array(const std::vector<int>& v) {
  py::array_t<int32_t> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

}  // namespace genbrep::python
