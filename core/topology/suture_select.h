#pragma once
// Which sutures a scenario `suture` event ties, at the positions of the tick
// it fires in: the given point pairs, or pairs across a named cut. Throws
// Error(Scenario) naming the event and field for ids out of range, a cut
// that separated nothing, or a point with no partner within max_distance.
#include <vector>

#include "core/model/model.h"
#include "core/scenario/events.h"
#include "core/topology/tet_faces.h"

namespace organsim {

struct CutRecord {
  const CutEvent* cut = nullptr;
  std::vector<int32_t> faces;  // faces its blade separated (sorted; some may have stayed joined)
};

// The sutures `event` ties at time t on `model` at positions x (internal
// numbering). `cut` is the record of the event's `along` cut (unused for
// explicit pairs); `faces` and `separated` are the run's face adjacency and
// separated flags.
//
// Along a cut, the cut's separated faces are given sides by the blade's
// sweep normal; points on faces of one side only are candidates, taken along
// the cut's longest extent (rest positions), each at least `spacing` from
// the last ones taken, and each joined to its partner on the other side:
// the copy of the same mesh point (the point the cut separated it from) if
// there is one, else the nearest point (current positions). Stiffness is scaled by the lighter end's
// Model::tool_scale, as the tool's is, so a light point does not lower dt_crit.
std::vector<Suture> tie_sutures(const SutureEvent& event, double t, const Model& model, const std::vector<Vec3>& x,
                                const CutRecord* cut, const TetFaces& faces, const std::vector<uint8_t>& separated);

}  // namespace organsim
