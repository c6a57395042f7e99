#pragma once
// Reading the JSON files organsim writes for itself and reads back (a
// sharded study's plan and runs, a sweep's plan, status files and force
// logs) field by field: every refusal is Error(Input) "SOURCE: WHERE:
// expected WHAT", WHERE the JSON path of the value at fault. (A scenario,
// which people write, has its own reader with unknown-field checks:
// core/scenario/json_reader.h.)
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/util/error.h"
#include "core/util/vec.h"

namespace organsim {

class JsonFields {
 public:
  using json = nlohmann::json;

  explicit JsonFields(std::string source) : source_(std::move(source)) {}

  // The text parsed, or "SOURCE: invalid JSON: ...".
  json parse(const std::string& text) const {
    try {
      return json::parse(text);
    } catch (const json::exception& e) {
      throw input_error(source_, std::string("invalid JSON: ") + e.what());
    }
  }

  Error error(const std::string& where, const std::string& expected) const {
    return input_error(source_, where + ": expected " + expected);
  }
  const json& field(const json& object, const char* name, const std::string& where) const {
    if (!object.is_object()) throw error(where, "an object");
    const auto it = object.find(name);
    if (it == object.end()) throw error(where + "." + name, "a value (missing)");
    return *it;
  }
  // A number, or one of the strings "inf", "-inf", "nan" that organsim
  // writes for the values JSON cannot hold.
  double number(const json& v, const std::string& where) const {
    if (v.is_number()) return v.get<double>();
    if (v == "inf") return std::numeric_limits<double>::infinity();
    if (v == "-inf") return -std::numeric_limits<double>::infinity();
    if (v == "nan") return std::numeric_limits<double>::quiet_NaN();
    throw error(where, "a number");
  }
  double number(const json& object, const char* name, const std::string& where) const {
    return number(field(object, name, where), where + "." + name);
  }
  int64_t whole(const json& object, const char* name, const std::string& where, int64_t min, int64_t max) const {
    const json& v = field(object, name, where);
    const bool too_large = v.is_number_unsigned() && v.get<uint64_t>() > static_cast<uint64_t>(max);
    if (!v.is_number_integer() || too_large || v.get<int64_t>() < min || v.get<int64_t>() > max)
      throw error(where + "." + name, "a whole number in " + std::to_string(min) + ".." + std::to_string(max));
    return v.get<int64_t>();
  }
  std::string text(const json& object, const char* name, const std::string& where) const {
    const json& v = field(object, name, where);
    if (!v.is_string()) throw error(where + "." + name, "a string");
    return v.get<std::string>();
  }
  bool flag(const json& object, const char* name, const std::string& where) const {
    const json& v = field(object, name, where);
    if (!v.is_boolean()) throw error(where + "." + name, "true or false");
    return v.get<bool>();
  }
  const json& array(const json& object, const char* name, const std::string& where) const {
    const json& v = field(object, name, where);
    if (!v.is_array()) throw error(where + "." + name, "an array");
    return v;
  }
  const json& object(const json& object, const char* name, const std::string& where) const {
    const json& v = field(object, name, where);
    if (!v.is_object()) throw error(where + "." + name, "an object");
    return v;
  }
  // The file's "format" entry must be `expected`.
  void format(const json& j, const char* expected) const {
    if (text(j, "format", "file") != expected) throw error("file.format", std::string("\"") + expected + "\"");
  }
  // A flat array of x, y, z numbers as points.
  std::vector<Vec3> points(const json& v, const std::string& where) const {
    if (!v.is_array() || v.size() % 3 != 0) throw error(where, "an array of x, y, z numbers");
    std::vector<Vec3> out(v.size() / 3);
    for (size_t i = 0; i < v.size(); ++i)
      out[i / 3][static_cast<int>(i % 3)] = number(v[i], where + "[" + std::to_string(i) + "]");
    return out;
  }

 private:
  std::string source_;
};

}  // namespace organsim
