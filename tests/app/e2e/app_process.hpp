#pragma once
// The pepper_app binary run as a subprocess, as an operator runs it, for the end-to-end tests:
// stdin /dev/null, stdout and stderr in files of a test folder, killed when the test lets go of
// it. Also the URL a `mock-robot` subprocess announces.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace pepper::app::test {

inline const std::string kPepperAppBinary =
    std::string(PEPPER_BINARY_DIR) + "/pepper_app/pepper_app";

/// A running pepper_app subprocess with stdout/stderr in DIR/NAME.stdout and DIR/NAME.stderr.
class AppProcess {
 public:
  /// `cwd`: the working folder of the process (default: the test's), for commands with
  /// relative paths as an operator types them.
  AppProcess(std::vector<std::string> args, const std::filesystem::path& dir,
             const std::string& name, const std::filesystem::path& cwd = {})
      : out_(std::filesystem::absolute(dir / (name + ".stdout"))),
        err_(std::filesystem::absolute(dir / (name + ".stderr"))) {
    args.insert(args.begin(), kPepperAppBinary);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 2, err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (!cwd.empty()) posix_spawn_file_actions_addchdir_np(&fa, cwd.c_str());  // after the opens
    const int rc =
        posix_spawn(&pid_, kPepperAppBinary.c_str(), &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0) throw std::runtime_error("cannot start " + kPepperAppBinary);
  }
  ~AppProcess() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  AppProcess(const AppProcess&) = delete;
  AppProcess& operator=(const AppProcess&) = delete;

  /// Exit code (128 + signal when killed), or -1 after `limit` (the process then keeps running
  /// until the destructor kills it).
  int wait(std::chrono::seconds limit = std::chrono::seconds(120)) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < end) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return -1;
  }
  void signal(int sig) const { kill(pid_, sig); }
  std::string out() const { return slurp(out_); }
  std::string err() const { return slurp(err_); }
  std::string both() const { return "stdout:\n" + out() + "\nstderr:\n" + err(); }
  static std::string slurp(const std::filesystem::path& p) {
    std::ifstream f(p);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  }

 private:
  std::filesystem::path out_, err_;
  pid_t pid_ = -1;
};

/// The tcp:// URL a `mock-robot` subprocess prints once it listens ("" after 20 s).
inline std::string mock_robot_url(const AppProcess& mock) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < end) {
    const std::string out = mock.out();
    const auto at = out.find(" on tcp://");
    if (at != std::string::npos) {
      const auto start = at + 4;
      return out.substr(start, out.find_first_of(" \n", start) - start);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return "";
}

/// `a` followed by `b`.
inline std::vector<std::string> cat(std::vector<std::string> a,
                                    const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace pepper::app::test
