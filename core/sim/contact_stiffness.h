#pragma once
// The pushing tool's local contact stiffness K = dF/dc (N/m): how the
// reaction F on the tool changes as its centre c moves with the tissue held
// (force_law::push_penalty_center_jacobian summed over the contacts). A
// haptic device extrapolates the force between replies with it, F(c + dc) ~
// F(c) + K dc (docs/live.md). Evaluated in double precision from positions,
// like the reference forces (reference_forces.h), whose reaction it
// differentiates.
#include <Eigen/Dense>

#include <vector>

#include "core/model/contact_layer.h"
#include "core/model/model.h"
#include "core/sim/tool.h"

namespace organsim {

using Mat3 = Eigen::Matrix3d;

// Point contact (reference_push_forces): every point within R of c.
Mat3 reference_push_stiffness(const std::vector<Vec3>& x, const Vec3& center, double radius, double stiffness,
                              const std::vector<double>& scale = {});

// Surface contact (reference_surface_forces): every boundary triangle within
// R of c, its closest point following c on the face, edge or vertex it lies on.
Mat3 reference_surface_stiffness(const Model& model, const std::vector<Vec3>& x, const Vec3& center, double radius,
                                 double stiffness);

// Surface contact in series with the sub-cell Hertz layer
// (reference_surface_forces with `layer`): central differences of that
// reaction in c (h = 1e-7 m) over the triangles within reach, with the
// tissue held. The layer's offset, a_h, E* and every penalty's factor move
// with c, so the differences take them all in.
Mat3 layered_surface_stiffness(const Model& model, const std::vector<Vec3>& x, const Vec3& center, double radius,
                               double stiffness, const ContactLayer& layer);

// A pulling tool's K: each held point's attachment spring, f = k s_i (c +
// o_i - x_i) on the tissue (force_law::pull_attachment), gives dF/dc =
// -k s_i I, whatever the positions.
Mat3 attachment_stiffness(const Model& model, const Attachment& held, double stiffness);

// The pushing tool's K at positions x (internal ids) by its contact kind;
// zero for a pulling tool (attachment_stiffness: the attachment is not known
// here). With tool.hertz_layer, `layer` (contact_layer(model)) is required.
Mat3 tool_contact_stiffness(const Model& model, const std::vector<Vec3>& x, const BackendTool& tool,
                            const Vec3& center, const ContactLayer* layer = nullptr);

}  // namespace organsim
