#pragma once
// The examples printed by `pepper_app ... --help` (issue 30, "examples that run"): every command
// path of the binary, from the "Subcommands:" sections, and each command's example lines, which
// the end-to-end tests check (the files they name exist; the ones that can run offline run).
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "app/e2e/app_process.hpp"

namespace pepper::app::test {

/// Every (sub)command path of the binary, from the "Subcommands:" sections of --help.
inline std::vector<std::vector<std::string>> command_paths(const std::filesystem::path& dir) {
  std::vector<std::vector<std::string>> out;
  std::vector<std::vector<std::string>> todo = {{}};
  while (!todo.empty()) {
    const auto path = todo.back();
    todo.pop_back();
    if (!path.empty()) out.push_back(path);
    auto args = path;
    args.push_back("--help");
    AppProcess help(args, dir, "help");
    help.wait();
    std::istringstream in(help.out());
    bool in_subcommands = false;
    for (std::string line; std::getline(in, line);) {
      if (line.rfind("Subcommands:", 0) == 0 || line.rfind("SUBCOMMANDS:", 0) == 0) {
        in_subcommands = true;
        continue;
      }
      if (!in_subcommands) continue;
      if (line.empty() || line[0] != ' ') {
        in_subcommands = false;
        continue;
      }
      if (line.size() < 3 || line[2] == ' ') continue;  // a description's continuation
      std::istringstream words(line);
      std::string name;
      words >> name;
      if (name.empty() || name == "help") continue;
      auto sub = path;
      sub.push_back(name);
      todo.push_back(sub);
    }
  }
  return out;
}

/// One example line of a command's --help: the command path it was printed by and the line
/// (continuations joined, the leading indentation kept).
struct HelpExample {
  std::vector<std::string> command;
  std::string line;
};

/// The example lines of every command's --help: indented lines containing "pepper_app " after
/// the "Example(s):" heading. Fails (an empty list) when a --help does not exit 0.
inline std::vector<HelpExample> help_examples(const std::filesystem::path& dir,
                                              std::string* problems = nullptr) {
  std::vector<HelpExample> out;
  for (const auto& path : command_paths(dir)) {
    auto args = path;
    args.push_back("--help");
    AppProcess help(args, dir, "help");
    if (help.wait() != 0) {
      if (problems) *problems += "--help of " + path.front() + " failed: " + help.both() + "\n";
      continue;
    }
    std::istringstream in(help.out());
    bool in_examples = false;
    for (std::string line; std::getline(in, line);) {
      // An example continued with a trailing backslash is one command.
      for (std::string more; !line.empty() && line.back() == '\\' && std::getline(in, more);) {
        line = line.substr(0, line.size() - 1) + " " + more;
      }
      if (line.rfind("Example", 0) == 0) in_examples = true;
      if (!in_examples || line.find("pepper_app ") == std::string::npos ||
          line.rfind("  ", 0) != 0) {
        continue;
      }
      out.push_back({path, line});
    }
  }
  return out;
}

}  // namespace pepper::app::test
