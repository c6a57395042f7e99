#pragma once
// Tearing (docs/topology.md): from a time on, a spring whose strain
// (L - r) / r stays above a threshold for a number of consecutive ticks
// separates, in one of the tets it belongs to, the interior face most
// perpendicular to its stretch (largest |n . l/L|). At most a fixed number of
// faces separate per tick, springs taken in id order, so a tear is
// progressive and the same on every run.
#include <cstdint>
#include <vector>

#include "core/model/model.h"
#include "core/topology/tet_faces.h"

namespace organsim {

struct TearSettings {
  double strain = 0.5;         // threshold on (L - r) / r, dimensionless
  int32_t ticks = 3;           // consecutive ticks above it before a face separates
  int32_t max_per_tick = 4;    // faces separated per tick at most
};

class TearDetector {
 public:
  explicit TearDetector(TearSettings settings) : settings_(settings) {}

  // One tick at positions x of `model`: counts each spring's consecutive
  // ticks over the threshold and returns the faces to separate now
  // (ascending id, not yet separated).
  std::vector<int32_t> update(const Model& model, const std::vector<Vec3>& x, const TetFaces& faces,
                              const std::vector<uint8_t>& separated);

  // Carries each spring's count over to `next` (same ends); new springs start at 0.
  void model_changed(const Model& previous, const Model& next);

  const TearSettings& settings() const { return settings_; }

 private:
  TearSettings settings_;
  std::vector<int32_t> over_;  // consecutive ticks over the threshold, per spring (nspring)
};

}  // namespace organsim
