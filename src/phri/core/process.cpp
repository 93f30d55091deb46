#include <phri/core/process.hpp>

#include <phri/core/error.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace phri {
namespace {

std::string name_of(const std::string& entry) { return entry.substr(0, entry.find('=')); }

// The caller's environment with `overrides` ("NAME=value") replacing or adding entries.
std::vector<std::string> environment_with(const std::vector<std::string>& overrides) {
  std::vector<std::string> env;
  for (char** e = environ; e != nullptr && *e != nullptr; ++e) {
    const std::string entry(*e);
    bool replaced = false;
    for (const std::string& o : overrides) replaced = replaced || name_of(o) == name_of(entry);
    if (!replaced) env.push_back(entry);
  }
  env.insert(env.end(), overrides.begin(), overrides.end());
  return env;
}

// The char* array execve wants, pointing into `strings` (which must outlive it).
std::vector<char*> pointers(std::vector<std::string>& strings) {
  std::vector<char*> p;
  for (std::string& s : strings) p.push_back(s.data());
  p.push_back(nullptr);
  return p;
}

// Closes the descriptors and the spawn attributes however the run ends.
struct SpawnResources {
  posix_spawn_file_actions_t actions;
  int pipe_fds[2] = {-1, -1};
  SpawnResources() { posix_spawn_file_actions_init(&actions); }
  ~SpawnResources() {
    posix_spawn_file_actions_destroy(&actions);
    for (int fd : pipe_fds) {
      if (fd >= 0) ::close(fd);
    }
  }
  void close_write_end() {
    ::close(pipe_fds[1]);
    pipe_fds[1] = -1;
  }
};

void read_all(int fd, std::string& output) {
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof(buffer));
    if (n > 0) {
      output.append(buffer, static_cast<std::size_t>(n));
    } else if (n == 0 || errno != EINTR) {
      return;
    }
  }
}

int wait_for(pid_t pid, const std::string& program) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw IoError(program, std::string("cannot wait for the program: ") + std::strerror(errno));
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return status;
}

}  // namespace

int run_process(const std::vector<std::string>& argv, const ProcessOptions& options) {
  if (argv.empty() || argv.front().empty()) throw IoError("<process>", "no program to run");
  const std::string& program = argv.front();
  std::vector<std::string> args = argv;
  std::vector<std::string> env = environment_with(options.environment);
  const std::vector<char*> arg_pointers = pointers(args);
  const std::vector<char*> env_pointers = pointers(env);

  SpawnResources resources;
  if (options.output != nullptr) {
    // Both ends close on exec; dup2 gives the program its own copies as stdout and stderr.
    if (::pipe2(resources.pipe_fds, O_CLOEXEC) != 0) {
      throw IoError(program, std::string("cannot create a pipe: ") + std::strerror(errno));
    }
    posix_spawn_file_actions_adddup2(&resources.actions, resources.pipe_fds[1], STDOUT_FILENO);
    posix_spawn_file_actions_adddup2(&resources.actions, resources.pipe_fds[1], STDERR_FILENO);
  }
  std::fflush(nullptr);
  pid_t pid = 0;
  const int error = ::posix_spawnp(&pid, program.c_str(), &resources.actions, nullptr, arg_pointers.data(),
                                   env_pointers.data());
  if (error != 0) throw IoError(program, std::string("cannot start the program: ") + std::strerror(error));
  if (options.output != nullptr) {
    resources.close_write_end();  // so that the read sees the end when the program exits
    read_all(resources.pipe_fds[0], *options.output);
  }
  return wait_for(pid, program);
}

}  // namespace phri
