// phri: the command-line entry point.
#include <phri/core/version.hpp>

#include <CLI/CLI.hpp>

int main(int argc, char** argv) {
  CLI::App app{"phri: control framework for physical human-robot interaction"};
  app.set_version_flag("--version", std::string("phri ") + phri::version());
  CLI11_PARSE(app, argc, argv);
  return 0;
}
