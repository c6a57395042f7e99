#pragma once
// Subcommands register themselves here so that each lives in its own file.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace organsim::app {

// `add` creates the subcommand on the root app and sets its callback. The
// callback may throw organsim::Error; main() turns it into a message and exit code.
struct CommandRegistration {
  std::string name;
  int order;  // position in --help
  std::function<void(CLI::App& root)> add;
};

std::vector<CommandRegistration>& command_registry();

inline bool register_command(std::string name, int order, std::function<void(CLI::App&)> add) {
  command_registry().push_back({std::move(name), order, std::move(add)});
  return true;
}

}  // namespace organsim::app
