#pragma once
// Which label's cells limit dt_crit: the top mode's kinetic energy split by
// label (StabilityReport::label_shares, `organsim run --plan`).
#include <vector>

#include "core/model/model.h"
#include "core/stability/critical_step.h"

namespace organsim {

// point_share: each point's share of the top mode's kinetic energy (internal
// numbering, npoint, summing to 1). A point's share goes to the labels of its
// tets in proportion to the lumped mass each tet gives it (rho V / 4), so a
// point on an interface counts for both sides. Largest share first; empty for
// an unlabelled model.
std::vector<LabelModeShare> mode_share_by_label(const Model& model, const std::vector<double>& point_share);

}  // namespace organsim
