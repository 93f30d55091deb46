// The closed loop a script drives (ClosedLoop: step() per period, run(n) in C++ with the GIL
// released) and phri logs as numpy structured arrays (load_log, ClosedLoop.record).
#include "bindings.hpp"
#include "closed_loop.hpp"
#include "log_table.hpp"

#include <phri/app/mcap_log.hpp>

#include <cstring>

namespace phri::python {
namespace {

// Periods run with the GIL released between two looks at Python's signals (Ctrl-C stops a long run).
constexpr long kCyclesBetweenSignalChecks = 1000;

py::dtype table_dtype(const std::vector<LogColumn>& columns) {
  py::list names, formats, offsets;
  for (std::size_t i = 0; i < columns.size(); ++i) {
    names.append(columns[i].name);
    formats.append(columns[i].integer ? py::dtype("<i8") : py::dtype("<f8"));
    offsets.append(8 * i);
  }
  return py::dtype(names, formats, offsets, static_cast<py::ssize_t>(8 * columns.size()));
}

py::array records_array(const std::vector<LogColumn>& columns, long rows) {
  const py::dtype dtype = table_dtype(columns);
  return py::array(dtype, {rows}, {dtype.itemsize()});
}

// Runs `cycles` periods in slices, the GIL released during each; records (if any) get the log rows.
long run_released(ClosedLoop& loop, long cycles, const ControllerTargets* targets, unsigned char* records,
                  std::size_t record_size) {
  long done = 0;
  while (done < cycles && !loop.finished()) {
    const long slice = std::min(kCyclesBetweenSignalChecks, cycles - done);
    long ran = 0;
    {
      const py::gil_scoped_release release;
      ran = loop.run(slice, done == 0 ? targets : nullptr, records != nullptr ? records + record_size * done : nullptr);
    }
    done += ran;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  }
  return done;
}

py::array record(ClosedLoop& loop, long cycles, const ControllerTargets* targets) {
  if (cycles < 0) throw ArgumentError("ClosedLoop.record: cycles must be >= 0, got " + std::to_string(cycles));
  const std::vector<LogColumn> columns = log_columns(loop.dof());
  py::array table = records_array(columns, cycles);  // the rows go straight into it, no other copy
  const long done = run_released(loop, cycles, targets, static_cast<unsigned char*>(table.mutable_data()),
                                 8 * columns.size());
  return done == cycles ? table : py::array(table[py::slice(0, done, 1)]);
}

void bind_closed_loop_class(py::module_& m) {
  py::class_<ClosedLoop> c(m, "ClosedLoop",
                           "The lockstep loop a script drives: each period reads the robot, takes the targets (the "
                           "FSM's, or the ones given), steps the controller, writes the command (a refusal is a fault "
                           "for the controller) and logs. step() is one period; run(n) and record(n) are n periods "
                           "in C++ with the GIL released.");
  c.def(py::init<RobotInterface&, Controller&, Fsm*, Logger*>(), py::arg("robot"), py::arg("controller"),
        py::arg("fsm") = nullptr, py::arg("logger") = nullptr, py::keep_alive<1, 2>(), py::keep_alive<1, 3>(),
        py::keep_alive<1, 4>(), py::keep_alive<1, 5>())
      .def("step", &ClosedLoop::step, py::arg("targets") = nullptr,
           "One period; `targets` (None: no change) act in this period. Returns the controller's CycleStatus.")
      .def("run", [](ClosedLoop& loop, long cycles, const ControllerTargets* targets) {
             return run_released(loop, cycles, targets, nullptr, 0);
           },
           py::arg("cycles"), py::arg("targets") = nullptr,
           "`cycles` periods in C++, GIL released (targets, if given, in the first); stops early when the FSM has "
           "finished. Returns the number of periods run.")
      .def("record", &record, py::arg("cycles"), py::arg("targets") = nullptr,
           "As run(), returning every period's log row as a numpy structured array (the dtype of load_log).")
      .def_property_readonly("state", [](const ClosedLoop& loop) { return loop.state(); }, py::return_value_policy::reference_internal,
                             "The latest state read (None before the first period).")
      .def_property_readonly("command", py::overload_cast<>(&ClosedLoop::command), py::return_value_policy::reference_internal,
                             "The command written last (its vectors are views).")
      .def_property_readonly("cycles", &ClosedLoop::cycles, "Periods run so far.")
      .def_property_readonly("refused_writes", &ClosedLoop::refused_writes)
      .def_property_readonly("status", &ClosedLoop::status, "The last step's CycleStatus.")
      .def_property_readonly("finished", &ClosedLoop::finished, "The FSM handled `stop` and the arm is at rest.");
}

}  // namespace

void bind_closed_loop(py::module_& m) { bind_closed_loop_class(m); }

void bind_log(py::module_& m) {
  m.def("log_columns", [](int dof) {
        py::list out;
        for (const LogColumn& c : log_columns(dof)) out.append(py::make_tuple(c.name, c.integer ? "int64" : "float64"));
        return out;
      }, py::arg("dof") = kLogMaxJoints, "(name, 'float64' | 'int64') of every column of a phri log, in CSV order.");
  m.def("log_dtype", [](int dof) { return table_dtype(log_columns(dof)); }, py::arg("dof") = kLogMaxJoints,
        "The numpy dtype of a phri log with `dof` joints (load_log and ClosedLoop.record).");
  m.def("load_log", [](const std::filesystem::path& file) {
        const std::string path = file.string();
        LogTable table;
        {
          const py::gil_scoped_release release;
          table = is_mcap_file(path) ? read_mcap_table(path) : read_csv_table(path);
        }
        py::array out = records_array(table.columns, table.rows);
        if (!table.cells.empty()) std::memcpy(out.mutable_data(), table.cells.data(), table.cells.size());
        return out;
      }, py::arg("path"),
      "A phri log, CSV or MCAP (phri run --log mcap; one cut short by a crash is read up to its last chunk), or any "
      "numeric CSV with a header, as a numpy structured array, one field per column: int64 for the integer codes of "
      "a phri log, float64 otherwise, exactly as written. IoError naming the line and column of a bad cell.");
}

}  // namespace phri::python
