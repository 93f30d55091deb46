#pragma once
// phri::python::PythonStream: a std::ostream whose text goes to Python's sys.stdout, line by line.
// The experiments and run_session print progress to an ostream while they run with the GIL
// released; each complete line (or a flush) takes the GIL just long enough to write it, so the
// progress shows where Python's output goes (a notebook, a captured stdout) and when it happens.
#include <pybind11/pybind11.h>

#include <mutex>
#include <ostream>
#include <streambuf>
#include <string>

namespace phri::python {

class PythonLineBuffer : public std::streambuf {
public:
  ~PythonLineBuffer() override { flush_line(); }

protected:
  int_type overflow(int_type c) override {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    const std::lock_guard<std::mutex> lock(mutex_);
    line_ += traits_type::to_char_type(c);
    if (c == '\n') write_locked();
    return c;
  }
  std::streamsize xsputn(const char* text, std::streamsize n) override {
    const std::lock_guard<std::mutex> lock(mutex_);
    line_.append(text, static_cast<std::size_t>(n));
    if (line_.find('\n') != std::string::npos) write_locked();
    return n;
  }
  int sync() override {
    flush_line();
    return 0;
  }

private:
  void flush_line() {
    const std::lock_guard<std::mutex> lock(mutex_);
    write_locked();
  }
  // Under mutex_: hands the text so far to sys.stdout (GIL taken here, whichever thread we are on).
  void write_locked() {
    if (line_.empty()) return;
    pybind11::gil_scoped_acquire gil;
    pybind11::module_::import("sys").attr("stdout").attr("write")(line_);
    line_.clear();
  }

  std::mutex mutex_;
  std::string line_;
};

class PythonStream : public std::ostream {
public:
  PythonStream() : std::ostream(&buffer_) {}
  ~PythonStream() override { flush(); }

private:
  PythonLineBuffer buffer_;
};

}  // namespace phri::python
