#pragma once
// Stable case names from the swept values, so a case keeps its folder
// (OUTDIR/cases/<name>/) across reruns and when values are added to an axis:
// "young_modulus=3000,position2=0.05". Names are safe as file names and in
// a shell without quoting.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace organsim {

inline constexpr size_t kMaxCaseNameLength = 100;

// A label per swept path: the shortest trailing run of its fields that no
// other swept path ends with, indices written as digits
// ("tool.keyframes[1].position[2]" -> "position2", or "keyframes1.position2"
// when another swept path also ends in position[2]).
std::vector<std::string> field_labels(const std::vector<std::string>& paths);

// The value as it appears in a name: numbers as JSON writes them (3000,
// 0.05, 1e-05), a string's last path component ("meshes/p07.off" ->
// "p07.off"), anything else compacted; characters outside the safe set
// (letters, digits, . _ - + =) become '-'.
std::string value_text(const nlohmann::json& value);

// The parts (an explicit case name, "label=value", ...) joined by ','; a
// name longer than kMaxCaseNameLength is cut and ends with '~' and a hash of
// the whole, so it stays unique and stable.
std::string case_name(const std::vector<std::string>& parts);

// Empty when `name` is a usable case name, else why not.
std::string case_name_problem(const std::string& name);

// 16 hex digits of the 64-bit FNV-1a hash of `text` (stable across builds
// and machines; identifies a case's scenario text).
std::string text_hash(const std::string& text);

}  // namespace organsim
