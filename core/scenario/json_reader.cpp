#include "core/scenario/json_reader.h"

#include <cmath>

#include "core/util/format.h"

namespace organsim {

namespace {
// A short name for the JSON type found, for "expected a number, got a string".
std::string type_name(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::null: return "null";
    case nlohmann::json::value_t::object: return "an object";
    case nlohmann::json::value_t::array: return "an array";
    case nlohmann::json::value_t::string: return "a string";
    case nlohmann::json::value_t::boolean: return "a boolean";
    default: return "a number";
  }
}
}  // namespace

JsonPath JsonPath::field(const std::string& key) const {
  return {file, path.empty() ? key : path + "." + key};
}

JsonPath JsonPath::index(size_t i) const {
  return {file, path + "[" + std::to_string(i) + "]"};
}

std::string JsonPath::describe() const { return path.empty() ? "the scenario root" : path; }

Error JsonPath::error(const std::string& message) const {
  std::string text = file.empty() ? std::string() : file + ": ";
  if (!path.empty()) text += path + ": ";
  return Error(ErrorKind::Scenario, text + message);
}

double read_number(const nlohmann::json& j, const JsonPath& at) {
  if (!j.is_number()) throw at.error("expected a number, got " + type_name(j));
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw at.error("expected a finite number");
  return v;
}

int64_t read_integer(const nlohmann::json& j, const JsonPath& at) {
  if (j.is_number_integer()) return j.get<int64_t>();
  // 2.0 is accepted as 2 (JSON writers often emit floats), 2.5 is not.
  if (j.is_number_float()) {
    const double v = j.get<double>();
    if (std::isfinite(v) && v == std::floor(v) && std::abs(v) < 9e15) return static_cast<int64_t>(v);
  }
  throw at.error("expected an integer, got " + (j.is_number() ? format_number(j.get<double>(), "%.6g") : type_name(j)));
}

bool read_bool(const nlohmann::json& j, const JsonPath& at) {
  if (!j.is_boolean()) throw at.error("expected true or false, got " + type_name(j));
  return j.get<bool>();
}

std::string read_string(const nlohmann::json& j, const JsonPath& at) {
  if (!j.is_string()) throw at.error("expected a string, got " + type_name(j));
  return j.get<std::string>();
}

std::vector<double> read_numbers(const nlohmann::json& j, const JsonPath& at, size_t n) {
  if (!j.is_array() || j.size() != n) {
    throw at.error("expected an array of " + std::to_string(n) + " numbers, got " +
                   (j.is_array() ? "an array of " + std::to_string(j.size()) : type_name(j)));
  }
  std::vector<double> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = read_number(j[i], at.index(i));
  return out;
}

Vec3 read_vec3(const nlohmann::json& j, const JsonPath& at) {
  const auto v = read_numbers(j, at, 3);
  return {v[0], v[1], v[2]};
}

double require_positive(double value, const JsonPath& at) {
  if (!(value > 0)) throw at.error("expected a value > 0 (got " + format_number(value, "%.6g") + ")");
  return value;
}

double require_non_negative(double value, const JsonPath& at) {
  if (!(value >= 0)) throw at.error("expected a value >= 0 (got " + format_number(value, "%.6g") + ")");
  return value;
}

ObjectReader::ObjectReader(const nlohmann::json& j, JsonPath at) : j_(j), at_(std::move(at)) {
  if (!j_.is_object()) throw at_.error("expected an object, got " + type_name(j_));
}

bool ObjectReader::has(const std::string& key) const { return j_.contains(key); }

const nlohmann::json* ObjectReader::get(const std::string& key) {
  auto it = j_.find(key);
  if (it == j_.end()) return nullptr;
  read_.insert(key);
  return &*it;
}

const nlohmann::json& ObjectReader::require(const std::string& key) {
  const nlohmann::json* j = get(key);
  if (!j) throw at(key).error("missing (required)");
  return *j;
}

std::optional<double> ObjectReader::number(const std::string& key) {
  const nlohmann::json* j = get(key);
  if (!j) return std::nullopt;
  return read_number(*j, at(key));
}

std::optional<int64_t> ObjectReader::integer(const std::string& key) {
  const nlohmann::json* j = get(key);
  if (!j) return std::nullopt;
  return read_integer(*j, at(key));
}

std::optional<bool> ObjectReader::boolean(const std::string& key) {
  const nlohmann::json* j = get(key);
  if (!j) return std::nullopt;
  return read_bool(*j, at(key));
}

std::optional<std::string> ObjectReader::string(const std::string& key) {
  const nlohmann::json* j = get(key);
  if (!j) return std::nullopt;
  return read_string(*j, at(key));
}

std::optional<Vec3> ObjectReader::vec3(const std::string& key) {
  const nlohmann::json* j = get(key);
  if (!j) return std::nullopt;
  return read_vec3(*j, at(key));
}

void ObjectReader::finish() const {
  for (const auto& item : j_.items()) {
    if (!read_.count(item.key())) throw at(item.key()).error("unknown field");
  }
}

std::string one_of(const std::vector<std::string>& choices) {
  std::string s;
  for (size_t i = 0; i < choices.size(); ++i) {
    if (i) s += i + 1 == choices.size() ? " or " : ", ";
    s += "\"" + choices[i] + "\"";
  }
  return s;
}

}  // namespace organsim
