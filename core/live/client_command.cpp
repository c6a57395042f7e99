#include "core/live/client_command.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

namespace organsim {

namespace {

std::vector<std::string> words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// A finite length > 0 written as a plain decimal number; nullopt otherwise.
std::optional<double> length(const std::string& word) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(word, &used);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (used != word.size() || !std::isfinite(v) || !(v > 0)) return std::nullopt;
  return v;
}

}  // namespace

ParsedCommand parse_client_command(const std::string& text) {
  const std::vector<std::string> w = words(text);
  if (w.empty()) return std::string("an empty command (expected CUT or CUT DEPTH WIDTH)");
  // Appended, not "..." + ...: gcc 12 warns falsely (-Wrestrict) on that.
  const std::string quoted = std::string("\"").append(printable_text(text)).append("\"");
  if (upper(w[0]) != "CUT") return std::string("an unknown command ").append(quoted).append(" (expected CUT or CUT DEPTH WIDTH)");
  CutCommand cut;
  if (w.size() == 1) return cut;
  if (w.size() == 3) {
    cut.depth = length(w[1]);
    cut.width = length(w[2]);
    if (cut.depth && cut.width) return cut;
  }
  return std::string(quoted).append(": expected CUT or CUT DEPTH WIDTH (two lengths > 0 in the client's units)");
}

std::string printable_text(const std::string& text, size_t max) {
  std::string out;
  for (size_t i = 0; i < text.size() && i < max; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    }
  }
  if (text.size() > max) out += "...";
  return out;
}

CutBlade cut_blade(const ClientFrame& frame, const std::array<double, 16>& pose, const CutCommand& cut) {
  const Vec3 centre = frame.scene_position(pose);
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = pose[static_cast<size_t>(4 * i + j)];
  // The client's axes in the scene: the registration's rotation after the pose's.
  const Eigen::Matrix3d scene = frame.to_scene.topLeftCorner<3, 3>() * r;
  const Vec3 axis = scene.col(2).normalized(), sweep = scene.col(0).normalized();
  const double depth = cut.depth ? *cut.depth * frame.metres_per_unit : CutCommand::kDefaultDepth;
  const double width = cut.width ? *cut.width * frame.metres_per_unit : CutCommand::kDefaultWidth;
  CutBlade b;
  b.a0 = centre - 0.5 * width * sweep;
  b.b0 = b.a0 + depth * axis;
  b.a1 = centre + 0.5 * width * sweep;
  b.b1 = b.a1 + depth * axis;
  return b;
}

}  // namespace organsim
