#include "log_table.hpp"

#include <phri/app/mcap_log.hpp>
#include <phri/core/error.hpp>

#include <charconv>
#include <cstring>
#include <fstream>
#include <set>
#include <string_view>

namespace phri::python {
namespace {

// Visits the columns of a log (visit_log_columns) for their names and kinds.
struct ColumnCollector {
  std::vector<LogColumn> columns;
  void number(const char* name, double) { columns.push_back({name, false}); }
  void integer(const char* name, std::int64_t) { columns.push_back({name, true}); }
  void joints(const char* name, const LogRow::Joints&, int dof) {
    for (int i = 1; i <= dof; ++i) columns.push_back({std::string(name) + "_" + std::to_string(i), false});
  }
};

// Visits a row's values, writing each as the next 8-byte cell.
struct RecordWriter {
  unsigned char* cursor;
  void number(const char*, double value) { put(&value); }
  void integer(const char*, std::int64_t value) { put(&value); }
  void joints(const char*, const LogRow::Joints& values, int dof) {
    for (int i = 0; i < dof; ++i) put(&values[static_cast<std::size_t>(i)]);
  }
  void put(const void* value) {
    std::memcpy(cursor, value, 8);
    cursor += 8;
  }
};

const std::set<std::string>& integer_column_names() {
  static const std::set<std::string> names = [] {
    std::set<std::string> result;
    for (const LogColumn& c : log_columns(kLogMaxJoints)) {
      if (c.integer) result.insert(c.name);
    }
    return result;
  }();
  return names;
}

// The comma-separated fields of a line, as views into it.
std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> fields;
  for (std::size_t start = 0;;) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
    if (comma == std::string_view::npos) return fields;
    start = comma + 1;
  }
}

// One cell, parsed exactly (std::from_chars: the double the text names, as the logger's to_chars wrote it).
void parse_cell(const std::string& path, long line, const LogColumn& column, std::string_view text, unsigned char* cell) {
  const char* first = text.data();
  const char* last = text.data() + text.size();
  std::from_chars_result result{};
  if (column.integer) {
    std::int64_t value = 0;
    result = std::from_chars(first, last, value);
    std::memcpy(cell, &value, 8);
  } else {
    double value = 0.0;
    result = std::from_chars(first, last, value);
    std::memcpy(cell, &value, 8);
  }
  if (text.empty() || result.ec != std::errc() || result.ptr != last) {
    throw IoError(path, "line " + std::to_string(line) + ", column '" + column.name + "': not " +
                            (column.integer ? "an integer" : "a number") + ": '" + std::string(text) + "'");
  }
}

}  // namespace

std::vector<LogColumn> log_columns(int dof) {
  ColumnCollector collector;
  visit_log_columns(LogRow{}, dof, collector);
  return collector.columns;
}

void write_log_record(const LogRow& row, int dof, unsigned char* record) {
  visit_log_columns(row, dof, RecordWriter{record});
}

LogTable read_csv_table(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw IoError(path, "cannot open the file");
  std::string line;
  if (!std::getline(file, line) || line.empty()) throw IoError(path, "no header line");
  LogTable table;
  if (line.back() == '\r') line.pop_back();
  for (std::string_view name : split(line)) {
    const bool integer = integer_column_names().count(std::string(name)) > 0;
    table.columns.push_back({std::string(name), integer});
  }
  const std::size_t width = table.columns.size();
  for (long number = 2; std::getline(file, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const std::vector<std::string_view> fields = split(line);
    if (fields.size() != width) {
      throw IoError(path, "line " + std::to_string(number) + ": " + std::to_string(fields.size()) + " cells, the header has " +
                              std::to_string(width));
    }
    table.cells.resize(table.cells.size() + 8 * width);
    unsigned char* row = table.cells.data() + table.cells.size() - 8 * width;
    for (std::size_t c = 0; c < width; ++c) parse_cell(path, number, table.columns[c], fields[c], row + 8 * c);
    ++table.rows;
  }
  return table;
}

LogTable read_mcap_table(const std::string& path) {
  LogTable table;
  read_mcap_log(path, [&](const LogRow& row, int dof) {
    if (table.rows == 0) table.columns = log_columns(dof);
    const std::size_t width = table.columns.size();
    table.cells.resize(table.cells.size() + 8 * width);
    write_log_record(row, dof, table.cells.data() + table.cells.size() - 8 * width);
    ++table.rows;
  });
  return table;
}

}  // namespace phri::python
