// A child process with its output in a log file, waited for with a timeout (child_run.hpp).
#include "mtled/analysis/child_run.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "mtled/interfaces/process_group.hpp"

namespace fs = std::filesystem;

namespace mtled {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

RunOutcome run_child(const fs::path& executable, const std::vector<std::string>& arguments, const fs::path& log_file,
                     double timeout_s) {
  std::vector<std::string> args{executable.string()};
  args.insert(args.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  // A run is its own job: a launcher's variables (a study spread over ranks) would make it join the study's.
  std::vector<char*> envp;
  for (char** e = environ; *e != nullptr; ++e)
    if (!launcher_variable(*e)) envp.push_back(*e);
  envp.push_back(nullptr);
  const std::string log_path = log_file.string();

  const auto start = Clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(fmt::format("cannot start a run: fork failed ({})", std::strerror(errno)));
  if (pid == 0) {  // the child: only async-signal-safe calls until exec
    const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ::dup2(fd, STDOUT_FILENO);
      ::dup2(fd, STDERR_FILENO);
      ::close(fd);
    }
    const int null = ::open("/dev/null", O_RDONLY);
    if (null >= 0) ::dup2(null, STDIN_FILENO);
    ::execve(argv[0], argv.data(), envp.data());
    ::_exit(127);
  }
  RunOutcome outcome;
  int status = 0;
  rusage usage{};
  bool terminated = false;
  while (true) {
    const pid_t done = ::wait4(pid, &status, timeout_s > 0.0 ? WNOHANG : 0, &usage);
    if (done == pid) break;
    if (done < 0 && errno != EINTR)
      throw std::runtime_error(fmt::format("waiting for a run failed ({})", std::strerror(errno)));
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    if (timeout_s > 0.0 && elapsed > timeout_s && !terminated) {
      ::kill(pid, SIGTERM);  // mtled run writes summary.json with status "interrupted" and exits
      terminated = outcome.timed_out = true;
    }
    if (terminated && elapsed > timeout_s + 30.0) ::kill(pid, SIGKILL);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  outcome.elapsed_s = std::chrono::duration<double>(Clock::now() - start).count();
  outcome.max_rss_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;
  if (WIFEXITED(status)) outcome.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) outcome.signal = WTERMSIG(status);
  return outcome;
}

std::filesystem::path find_program(const std::string& name) {
  const auto executable = [](const fs::path& p) { return ::access(p.c_str(), X_OK) == 0 && !fs::is_directory(p); };
  if (name.find('/') != std::string::npos) return executable(name) ? fs::absolute(name) : fs::path();
  const char* path = std::getenv("PATH");
  std::string directories = path != nullptr ? path : "/usr/local/bin:/usr/bin:/bin";
  for (std::size_t begin = 0; begin <= directories.size();) {
    const std::size_t end = std::min(directories.find(':', begin), directories.size());
    const fs::path candidate = fs::path(end > begin ? directories.substr(begin, end - begin) : ".") / name;
    if (executable(candidate)) return fs::absolute(candidate);
    begin = end + 1;
  }
  return {};
}

}  // namespace mtled
