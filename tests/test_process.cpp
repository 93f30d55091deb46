// ctest-labels: unit
// core/process: programs run with an argument vector, never through a shell. An output path full of
// quotes, semicolons and spaces reaches the program as one argument and runs nothing: not through
// run_process, not through the experiments' figure step, not through `phri run --out`.
#include <phri/core/error.hpp>
#include <phri/core/process.hpp>
#include <phri/experiments/experiment_files.hpp>

#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

// A path that a shell would split into three commands, the middle one creating `marker`.
std::string hostile_name(const fs::path& marker) { return "o'; touch " + marker.string() + "; 'x \"y\" z"; }

TEST(RunProcess, PassesEachArgumentVerbatimWithoutAShell) {
  const phri::test::TempDir dir("phri_test_process_verbatim");
  const fs::path marker = dir.path / "X";
  const std::string argument = hostile_name(marker) + " $HOME `id` | cat";
  std::string output;
  EXPECT_EQ(phri::run_process({"printf", "%s", argument}, {{}, &output}), 0);
  EXPECT_EQ(output, argument);
  EXPECT_FALSE(fs::exists(marker));
}

TEST(RunProcess, ReturnsTheExitStatus) {
  EXPECT_EQ(phri::run_process({"true"}), 0);
  EXPECT_EQ(phri::run_process({"false"}), 1);
  EXPECT_EQ(phri::run_process({"sh", "-c", "exit 7"}), 7);
  EXPECT_EQ(phri::run_process({"sh", "-c", "kill -TERM $$"}), 128 + 15);
}

TEST(RunProcess, SetsTheEnvironmentAndCollectsStandardError) {
  std::string output;
  EXPECT_EQ(phri::run_process({"sh", "-c", "echo \"$PHRI_TEST_VALUE\" >&2"}, {{"PHRI_TEST_VALUE=a b"}, &output}), 0);
  EXPECT_EQ(output, "a b\n");
}

TEST(RunProcess, ThrowsIoErrorWhenTheProgramCannotStart) {
  EXPECT_THROW(phri::run_process({"/nonexistent/program"}), phri::IoError);
  EXPECT_THROW(phri::run_process({}), phri::IoError);
}

TEST(FigureScript, AHostileOutputFolderIsOnlyAnArgument) {
  if (!fs::exists(phri::kSystemPython)) GTEST_SKIP() << phri::kSystemPython << " missing";
  const phri::test::TempDir dir("phri_test_process_figure");
  const fs::path marker = dir.path / "X";
  const std::string script = (dir.path / "echo_arguments.py").string();
  std::ofstream(script) << "import sys\nprint('|'.join(sys.argv[1:]))\n";
  const std::string folder = (dir.path / hostile_name(marker)).string();
  std::ostringstream out;
  EXPECT_TRUE(phri::run_figure_script(script, {folder, folder + "/figure.png"}, out));
  EXPECT_EQ(out.str(), "  " + folder + "|" + folder + "/figure.png\n");
  EXPECT_FALSE(fs::exists(marker));
}

// `phri run --out DIR` draws its figure with DIR in the script's arguments (the program that once
// pasted it, quoted, into a shell command).
TEST(PhriRun, AHostileOutFolderRunsNothing) {
  const fs::path phri = fs::read_symlink("/proc/self/exe").parent_path().parent_path() / "phri";
  if (!fs::exists(phri)) GTEST_SKIP() << phri << " not built";
  const phri::test::TempDir dir("phri_test_process_cli");
  const fs::path marker = dir.path / "X";
  const std::string out = (dir.path / hostile_name(marker)).string();
  std::string output;
  const int status = phri::run_process({phri.string(), "run", "--config", std::string(PHRI_SOURCE_DIR) + "/configs/demo.yaml",
                                        "--lockstep", "--duration", "0.05", "--out", out},
                                       {{}, &output});
  EXPECT_EQ(status, 0) << output;
  EXPECT_TRUE(fs::exists(fs::path(out) / "summary.md")) << output;
  EXPECT_FALSE(fs::exists(marker)) << output;
}

}  // namespace
