#include "core/sweep/case_names.h"

#include <cctype>
#include <cstdint>
#include <cstdio>

#include "core/sweep/field_path.h"

namespace organsim {

namespace {

bool is_safe(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-' || c == '+' || c == '=';
}

std::string step_text(const FieldStep& step) {
  std::string s = step.key;
  for (size_t i : step.indices) s += std::to_string(i);
  return s;
}

std::string suffix_label(const std::vector<FieldStep>& steps, size_t count) {
  std::string label;
  for (size_t i = steps.size() - count; i < steps.size(); ++i) {
    if (!label.empty()) label += '.';
    label += step_text(steps[i]);
  }
  return label;
}

}  // namespace

std::vector<std::string> field_labels(const std::vector<std::string>& paths) {
  std::vector<std::vector<FieldStep>> parsed;
  for (const std::string& p : paths) parsed.push_back(parse_field_path(p));
  std::vector<std::string> labels;
  for (size_t i = 0; i < parsed.size(); ++i) {
    size_t count = 1;
    for (; count < parsed[i].size(); ++count) {
      const std::string mine = suffix_label(parsed[i], count);
      bool shared = false;
      for (size_t j = 0; j < parsed.size() && !shared; ++j)
        shared = j != i && parsed[j].size() >= count && suffix_label(parsed[j], count) == mine;
      if (!shared) break;
    }
    labels.push_back(suffix_label(parsed[i], count));
  }
  return labels;
}

std::string value_text(const nlohmann::json& value) {
  std::string raw;
  if (value.is_string()) {
    raw = value.get<std::string>();
    const size_t slash = raw.find_last_of('/');
    if (slash != std::string::npos && slash + 1 < raw.size()) raw = raw.substr(slash + 1);
  } else {
    raw = value.dump();
  }
  std::string out;
  for (char c : raw) {
    if (c == '[' || c == ']' || c == '{' || c == '}' || c == '"')
      continue;  // compact arrays: 0.03,0,0.05 -> 0.03-0-0.05
    out += is_safe(c) ? c : '-';
  }
  return out.empty() ? "-" : out;
}

std::string case_name(const std::vector<std::string>& parts) {
  std::string name;
  for (const std::string& part : parts) {
    if (!name.empty()) name += ',';
    name += part;
  }
  if (name.size() <= kMaxCaseNameLength) return name;
  const std::string hash = text_hash(name).substr(0, 8);
  return name.substr(0, kMaxCaseNameLength - hash.size() - 1) + "~" + hash;
}

std::string case_name_problem(const std::string& name) {
  if (name.empty()) return "a case name must not be empty";
  if (name.size() > kMaxCaseNameLength)
    return "a case name is at most " + std::to_string(kMaxCaseNameLength) + " characters";
  if (name[0] == '.' || name[0] == '-') return "a case name must not start with '.' or '-'";
  for (char c : name) {
    if (!is_safe(c) && c != ',' && c != '~')
      return "a case name may hold letters, digits and . _ - + = , ~ only (it names a folder)";
  }
  return {};
}

std::string text_hash(const std::string& text) {
  uint64_t h = 14695981039346656037ull;  // FNV-1a offset basis
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;  // FNV prime
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

}  // namespace organsim
