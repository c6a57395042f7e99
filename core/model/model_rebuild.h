#pragma once
// Topology changes (cuts, tears, sutures) make a new Model version from the
// previous one; backends then rebuild from it and carry their State over
// (Backend::rebuild). Ids are stable: tets keep their ids and order, points
// are only appended, nothing is deleted or renumbered, so tool attachments,
// observers' maps and every output's point numbering stay valid.
#include <cstdint>
#include <vector>

#include "core/model/model.h"

namespace organsim {

struct TopologyChange {
  // The new vertices of every tet (ntet x 4, internal ids, same tet ids and
  // order as the previous Model); a vertex may name an appended point.
  std::vector<Tet> tet_points;
  // For each appended point, in order, the internal id of the existing point
  // it copies (rest position, fixed flag and, in backends, its state).
  std::vector<int32_t> appended_origin;
};

// Builds version previous.version + 1 through the same assembly as
// build_model (without reordering): lumped masses from each point's own tets
// (so total mass is conserved to round-off), springs as the unique edges of
// the new tets with stiffness from their own tets' volumes (an edge whose tets
// now lie on both sides of a cut becomes one spring per side, each with its
// share), then the previous version's sutures (suture.h), unchanged rest
// volumes and the gather layout rebuilt in full.
// Throws Error(Input) for a malformed change (wrong tet count, ids out of
// range, a tet whose rest volume the new vertices do not reproduce).
Model rebuild_model(const Model& previous, const TopologyChange& change);

// Version previous.version + 1 with `sutures` tied after the previous ones
// (same tets, points, masses: a suture adds no mass), through the same
// assembly. Throws Error(Input) for a suture whose ends are out of range,
// equal or not in increasing order, or with k <= 0 or a negative length,
// min_length or rate.
Model add_sutures(const Model& previous, const std::vector<Suture>& sutures);

}  // namespace organsim
