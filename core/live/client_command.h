#pragma once
// The text commands a live client sends as OpenIGTLink STRING messages
// (docs/live.md#commands), parsed from the text alone: the session decides
// what they do. Any device name carries them; the text is one command,
// upper or lower case, with spaces around it ignored.
//
//   CUT                 a cut at the tool's pose, the default blade (depth and width 20 mm)
//   CUT DEPTH WIDTH     the same with the blade's depth and sweep width in the client's units
#include <optional>
#include <string>
#include <variant>

#include "core/live/client_frame.h"

namespace organsim {

// A cut at the tool's pose (docs/live.md#commands): the blade runs from the
// tool centre `depth` along the instrument's axis (the z axis of the client's
// TRANSFORM rotation) and sweeps `width` along its x axis, centred on the
// tool, over one tick. Lengths in the client's units until ClientFrame makes
// them metres.
struct CutCommand {
  std::optional<double> depth, width;  // client units; absent: the defaults below
  static constexpr double kDefaultDepth = 0.02;  // m
  static constexpr double kDefaultWidth = 0.02;  // m
};

// A command, or why the text is none (for the refusal log).
using ParsedCommand = std::variant<CutCommand, std::string>;
ParsedCommand parse_client_command(const std::string& text);

// The text as it may appear in a log line: printable ASCII, other bytes as
// \xNN, at most `max` characters of it.
std::string printable_text(const std::string& text, size_t max = 40);

// The blade of a cut at a pose (row-major 4x4 in the client's frame and
// units) over one tick: its edge (a, b) at the tick's start and end, m, in
// the scene.
struct CutBlade {
  Vec3 a0, b0, a1, b1;
};
CutBlade cut_blade(const ClientFrame& frame, const std::array<double, 16>& pose, const CutCommand& cut);

}  // namespace organsim
