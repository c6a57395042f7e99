#pragma once
// Observers that `organsim run` attaches to a run (frame recorder, checks)
// register here, like subcommands, so cmd_run.cpp needs no knowledge of them.
// A factory returns nullptr when the scenario does not ask for its output.
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/model/model.h"
#include "core/scenario/scenario.h"
#include "core/sim/run_observer.h"

namespace organsim::app {

struct RunObserverContext {
  const Scenario& scenario;
  const Model& model;
  std::filesystem::path outdir;
};

struct RunObserverRegistration {
  std::string name;
  // Which scenario output this observer produces ("frames" for the renderer),
  // so that a scenario asking for an output nobody produces is an error.
  std::string produces;
  std::function<std::unique_ptr<RunObserver>(const RunObserverContext&)> make;
};

std::vector<RunObserverRegistration>& run_observer_registry();

// The registered observers this scenario asks for (their names into `names`
// when given); an asked-for output that no observer produces is an error.
std::vector<std::unique_ptr<RunObserver>> make_observers(const Scenario& s, const Model& model,
                                                         const std::filesystem::path& outdir,
                                                         std::vector<std::string>* names);

inline bool register_run_observer(RunObserverRegistration registration) {
  run_observer_registry().push_back(std::move(registration));
  return true;
}

}  // namespace organsim::app
