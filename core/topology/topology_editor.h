#pragma once
// The topology of a run as it changes: face adjacency by tet id (fixed),
// which faces are separated (they stay separated), and the step from one
// Model version to the next when new faces separate. Built only when a
// scenario has events; a scene without them never constructs one.
#include <cstdint>
#include <vector>

#include "core/model/model.h"
#include "core/topology/point_split.h"
#include "core/topology/tet_faces.h"

namespace organsim {

// What one change did, for the force log's meta.events.
struct ChangeCounts {
  int32_t faces_separated = 0;  // faces newly marked separated
  int32_t points_split = 0;     // existing points that got copies
  int32_t points_added = 0;     // copies appended
  int32_t springs_added = 0;    // springs (by end ids) in the new Model and not the old
  int32_t springs_removed = 0;  // springs in the old Model and not the new
};

// Tissue springs (by their end ids) present in `next` and not in `previous`,
// and the reverse; sutures are not counted here.
void count_spring_changes(const Model& previous, const Model& next, ChangeCounts& counts);

class TopologyEditor {
 public:
  explicit TopologyEditor(const Model& initial);

  const TetFaces& faces() const { return faces_; }
  const std::vector<uint8_t>& separated() const { return separated_; }  // (nface)

  // Marks `faces` (face ids; already separated ones are skipped) separated
  // and splits their points. When a point was split, builds the next Model
  // version from `current` through rebuild_model into `next` and returns
  // true; otherwise leaves `next` alone and returns false. `counts` says what
  // happened either way (faces_separated may be > 0 with no new Model).
  bool separate(const Model& current, const std::vector<int32_t>& faces, Model& next, ChangeCounts& counts);

 private:
  // New faces to keep joined because the split would make `bad` edges non-manifold.
  std::vector<int32_t> faces_to_keep(const std::vector<Edge>& bad, const PointSplit& split, int32_t npoint,
                                     const std::vector<int32_t>& fresh) const;

  TetFaces faces_;
  std::vector<uint8_t> separated_;
};

}  // namespace organsim
