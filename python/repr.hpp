// The module's __repr__s: Class(key=value, ...) from the object's own Python attributes, each shown as
// Python's repr shows it; an array of more than three values shows its shape instead of its values.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>
#include <vector>

namespace drom::python {

inline std::string fields_repr(pybind11::handle self, const std::vector<const char*>& names) {
  namespace py = pybind11;
  std::string out = py::type::handle_of(self).attr("__name__").cast<std::string>() + "(";
  for (std::size_t i = 0; i < names.size(); ++i) {
    const py::object value = self.attr(names[i]);
    std::string shown;
    if (py::isinstance<py::array>(value) && py::reinterpret_borrow<py::array>(value).size() > 3)
      shown = "<array of shape " + py::repr(value.attr("shape")).cast<std::string>() + ">";
    else if (py::isinstance<py::array>(value))
      shown = py::repr(value.attr("tolist")()).cast<std::string>();
    else
      shown = py::repr(value).cast<std::string>();
    out += (i ? ", " : "") + std::string(names[i]) + "=" + shown;
  }
  return out + ")";
}

// .def("__repr__", fields<T>({"a", "b"})) on a py::class_<T>: T(a=..., b=...), read through the bound
// attributes, so the repr shows what Python sees.
template <class T>
auto fields(std::vector<const char*> names) {
  return [names = std::move(names)](const T& self) {
    return fields_repr(pybind11::cast(&self, pybind11::return_value_policy::reference), names);
  };
}

}  // namespace drom::python
