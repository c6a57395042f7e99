#pragma once
// Reading JSON objects field by field with the JSON path in every error
// ("tool.keyframes[2].t: expected a number"). An ObjectReader remembers which
// keys were read, and finish() rejects the rest as unknown fields, so a typo
// in a scenario is an error instead of a silently ignored setting.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/util/error.h"
#include "core/util/vec.h"

namespace organsim {

// Where errors come from: the file name and the JSON path of the value.
struct JsonPath {
  std::string file;  // prefix of every message, e.g. "scenarios/liver_push.json"
  std::string path;  // e.g. "tool.keyframes[2]"; empty at the root

  JsonPath field(const std::string& key) const;  // path.key
  JsonPath index(size_t i) const;                // path[i]
  // Error(Scenario, "FILE: PATH: message"), or "FILE: message" at the root.
  Error error(const std::string& message) const;
  std::string describe() const;  // the path, or "the scenario root"
};

// Typed values with the path in their errors.
double read_number(const nlohmann::json& j, const JsonPath& at);
int64_t read_integer(const nlohmann::json& j, const JsonPath& at);
bool read_bool(const nlohmann::json& j, const JsonPath& at);
std::string read_string(const nlohmann::json& j, const JsonPath& at);
Vec3 read_vec3(const nlohmann::json& j, const JsonPath& at);
// An array of exactly `n` numbers.
std::vector<double> read_numbers(const nlohmann::json& j, const JsonPath& at, size_t n);

// Range checks: throw "PATH: expected ... (got V)".
double require_positive(double value, const JsonPath& at);
double require_non_negative(double value, const JsonPath& at);

class ObjectReader {
 public:
  // Throws "PATH: expected an object" unless j is an object.
  ObjectReader(const nlohmann::json& j, JsonPath at);

  const JsonPath& at() const { return at_; }
  JsonPath at(const std::string& key) const { return at_.field(key); }
  bool has(const std::string& key) const;
  // The raw value (marks the key as read), or nullptr when absent.
  const nlohmann::json* get(const std::string& key);
  // As get(), but "PATH.key: missing (required)" when absent.
  const nlohmann::json& require(const std::string& key);

  std::optional<double> number(const std::string& key);
  std::optional<int64_t> integer(const std::string& key);
  std::optional<bool> boolean(const std::string& key);
  std::optional<std::string> string(const std::string& key);
  std::optional<Vec3> vec3(const std::string& key);

  // Throws "PATH.key: unknown field" for the first key never read.
  void finish() const;

 private:
  const nlohmann::json& j_;
  JsonPath at_;
  std::set<std::string> read_;
};

// "one of a, b, c" for enum-like strings.
std::string one_of(const std::vector<std::string>& choices);

}  // namespace organsim
