// The compiled part of the phri Python package (phri/_phri*.so). phri/__init__.py re-exports it;
// each phri module's bindings are in bind_<module>.cpp.
#include "bindings.hpp"

PYBIND11_MODULE(_phri, m) {
  m.doc() = "phri: control framework for physical human-robot interaction (C++20), Python bindings.";
  using namespace phri::python;
  bind_core(m);
  bind_model(m);
  bind_robot(m);
  bind_sim(m);
  bind_control(m);
  bind_app(m);
  bind_closed_loop(m);
  bind_log(m);
  bind_experiments(m);
}
