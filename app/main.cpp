// organsim: headless, scripted, measured soft-tissue simulation (SI units).
#include <algorithm>
#include <iostream>

#include "app/command.h"
#include "core/util/error.h"

namespace organsim::app {
std::vector<CommandRegistration>& command_registry() {
  static std::vector<CommandRegistration> registry;
  return registry;
}
}  // namespace organsim::app

int main(int argc, char** argv) {
  using namespace organsim;
  CLI::App root{
      "organsim " ORGANSIM_VERSION
      ": tetrahedral mass-spring organ simulation with scripted tools.\n"
      "All quantities are SI: metres, kilograms, seconds, newtons, pascals."};
  root.require_subcommand(1);
  root.set_version_flag("--version", ORGANSIM_VERSION);
  auto registry = app::command_registry();
  std::sort(registry.begin(), registry.end(),
            [](const auto& a, const auto& b) { return a.order < b.order; });
  for (const auto& command : registry) command.add(root);
  try {
    root.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 prints the message (or the help); every real parse error exits
    // with the documented usage code, not CLI11's own numbers.
    return root.exit(e) == 0 ? 0 : static_cast<int>(ErrorKind::Usage);
  } catch (const Error& e) {
    std::cerr << "organsim: error: " << e.what() << "\n";
    return e.exit_code();
  } catch (const std::exception& e) {
    std::cerr << "organsim: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
