#pragma once
// A scenario field named by its JSON path, as sweep files write it:
// "material.young_modulus", "tool.keyframes[1].position[2]". Keys are
// letters, digits and '_' (every scenario key is snake_case); each key may
// be followed by array indices.
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace organsim {

struct FieldStep {
  std::string key;
  std::vector<size_t> indices;  // [i][j] after the key, outermost first
};

// Throws Error(Scenario, "PATH: <what is wrong>") for a malformed path.
std::vector<FieldStep> parse_field_path(const std::string& path);

// Sets the field at `path` in `root` to `value`; a null value removes a
// field (not an array element). A missing key is added (the
// scenario parser then refuses a key it does not know, naming it), and so are
// missing objects on the way; an index must name an existing array element.
// Throws Error(Scenario, "PATH: <what is wrong>") when the path does not fit
// the document (an index into a non-array, a key below a number, ...).
void set_field(nlohmann::json& root, const std::string& path, const nlohmann::json& value);

// The JSON value at `path`, or nullptr when any part of it is absent.
const nlohmann::json* find_field(const nlohmann::json& root, const std::string& path);

// A scenario file's JSON with its own file names (scenario_file_fields) made
// absolute, so a scenario built from it can be written anywhere (a sweep's
// cases, a live session's session.json).
nlohmann::json scenario_json_with_absolute_paths(const std::filesystem::path& scenario_file);

}  // namespace organsim
