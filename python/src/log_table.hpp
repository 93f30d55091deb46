#pragma once
// phri logs as tables of 8-byte cells: the columns of a LogRow (config/log_row.hpp, the one definition
// the CSV header and rows share), a LogRow written as one record of them, and a CSV log read back
// into records, and an MCAP log too. The Python side wraps the records in a numpy structured array (float64 for real
// columns, int64 for integer ones), so a recorded run and a loaded log have the same dtype.
#include <phri/config/log_row.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace phri::python {

struct LogColumn {
  std::string name;
  bool integer = false;  ///< int64 cell; float64 otherwise
};

/// The columns of a log with `dof` joints, in CSV order.
std::vector<LogColumn> log_columns(int dof);

/// Writes `row` as consecutive 8-byte cells (double or int64_t), one per column of log_columns(dof).
void write_log_record(const LogRow& row, int dof, unsigned char* record);

/// A log read into 8-byte cells, row-major. Columns named like an integer column of a phri log
/// are int64; every other column is float64. Throws IoError(path, "line N, column 'c': ...") on a
/// file that cannot be read or a cell that is not a number, and on rows of the wrong length.
struct LogTable {
  std::vector<LogColumn> columns;
  std::vector<unsigned char> cells;  ///< rows x columns x 8 bytes
  long rows = 0;
};
LogTable read_csv_table(const std::string& path);
/// A phri MCAP log (app/mcap_log.hpp) read into the cells of its columns, as its CSV would read.
LogTable read_mcap_table(const std::string& path);

}  // namespace phri::python
