#include "core/sweep/field_path.h"

#include <cctype>

#include "core/scenario/scenario.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"

namespace organsim {

namespace {

Error path_error(const std::string& path, const std::string& message) {
  return Error(ErrorKind::Scenario, path + ": " + message);
}

bool is_key_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// What the document holds where the path needs an object or an array.
std::string kind_of(const nlohmann::json& j) {
  if (j.is_object()) return "an object";
  if (j.is_array()) return "an array";
  if (j.is_string()) return "a string";
  if (j.is_boolean()) return "a boolean";
  if (j.is_null()) return "null";
  return "a number";
}

}  // namespace

std::vector<FieldStep> parse_field_path(const std::string& path) {
  if (path.empty()) throw Error(ErrorKind::Scenario, "an empty field path");
  std::vector<FieldStep> steps;
  size_t i = 0;
  while (true) {
    FieldStep step;
    while (i < path.size() && is_key_char(path[i])) step.key += path[i++];
    if (step.key.empty())
      throw path_error(path, "expected a field name at character " + std::to_string(i + 1) +
                                 " (a path is like material.young_modulus or tool.keyframes[1].position[2])");
    while (i < path.size() && path[i] == '[') {
      size_t close = path.find(']', i);
      const std::string digits = close == std::string::npos ? "" : path.substr(i + 1, close - i - 1);
      if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos)
        throw path_error(path, "expected an index [N] at character " + std::to_string(i + 1));
      step.indices.push_back(std::stoul(digits));
      i = close + 1;
    }
    steps.push_back(std::move(step));
    if (i == path.size()) return steps;
    if (path[i] != '.')
      throw path_error(
          path, std::string("unexpected '").append(1, path[i]).append("' at character ").append(std::to_string(i + 1)));
    ++i;
  }
}

void set_field(nlohmann::json& root, const std::string& path, const nlohmann::json& value) {
  const std::vector<FieldStep> steps = parse_field_path(path);
  nlohmann::json* at = &root;
  std::string walked;
  for (size_t s = 0; s < steps.size(); ++s) {
    const FieldStep& step = steps[s];
    if (!at->is_object())
      throw path_error(path, (walked.empty() ? std::string("the scenario") : walked) + " is " + kind_of(*at) +
                                 " in the base scenario, not an object with field \"" + step.key + "\"");
    if (!walked.empty()) walked += '.';
    walked += step.key;
    const bool last = s + 1 == steps.size();
    if (last && step.indices.empty() && value.is_null()) {
      at->erase(step.key);  // null removes the field (e.g. mesh.tet to give mesh.surface instead)
      return;
    }
    if (!at->contains(step.key)) {
      if (!step.indices.empty())
        throw path_error(path, walked + " is not in the base scenario, so it has no element to index");
      // A new field (e.g. material.poisson_ratio where the base has none);
      // objects on the way are created and the parser judges the result.
      (*at)[step.key] = last ? value : nlohmann::json::object();
      at = &(*at)[step.key];
      continue;
    }
    at = &(*at)[step.key];
    for (size_t index : step.indices) {
      if (!at->is_array())
        throw path_error(path, walked + " is " + kind_of(*at) + " in the base scenario, not an array");
      if (index >= at->size())
        throw path_error(path, walked + "[" + std::to_string(index) +
                                   "]: index out of range (the base scenario's array has " +
                                   std::to_string(at->size()) + " elements)");
      walked.append("[").append(std::to_string(index)).append("]");
      at = &(*at)[index];
    }
    if (last) *at = value;
  }
}

const nlohmann::json* find_field(const nlohmann::json& root, const std::string& path) {
  const nlohmann::json* at = &root;
  for (const FieldStep& step : parse_field_path(path)) {
    if (!at->is_object() || !at->contains(step.key)) return nullptr;
    at = &(*at)[step.key];
    for (size_t index : step.indices) {
      if (!at->is_array() || index >= at->size()) return nullptr;
      at = &(*at)[index];
    }
  }
  return at;
}

nlohmann::json scenario_json_with_absolute_paths(const std::filesystem::path& scenario_file) {
  namespace fs = std::filesystem;
  nlohmann::json base = nlohmann::json::parse(read_text_file(scenario_file));
  const fs::path dir = scenario_file.has_parent_path() ? scenario_file.parent_path() : fs::path(".");
  for (const std::string& field : scenario_file_fields()) {
    const nlohmann::json* v = find_field(base, field);
    if (!v || !v->is_string()) continue;
    fs::path p(v->get<std::string>());
    if (p.is_relative()) p = dir / p;
    set_field(base, field, fs::absolute(p).lexically_normal().string());
  }
  return base;
}

}  // namespace organsim
