#pragma once
// Naive per-spring / per-tet scatter of the force law (core/physics/force_law.h) in
// double precision. The test oracle for every gather kernel (CPU and GL):
// simple enough to check by eye.
#include <vector>

#include "core/model/contact_layer.h"
#include "core/model/model.h"
#include "core/sim/tool.h"

namespace organsim {

// Forces on every point (internal numbering) for positions x and velocities v:
// springs + dampers, volume conservation (per tet or nodal, if the model has
// it), the shear element and its damper (if it has it), gravity. Fixed points
// get their force too (integration ignores it).
// Sutures pull only (no force while slack, never a push) with their rest
// length at time t.
void reference_internal_forces(const Model& model, const std::vector<Vec3>& x,
                               const std::vector<Vec3>& v, std::vector<Vec3>& force, double t = 0);

// Push contact of a sphere tool (center c, radius R, stiffness k): for points
// with |x - c| < R, f_i = k s_i (R - |x - c|) (x - c)/|x - c|, s_i from
// `scale` (Model::tool_k_scale; empty = 1). Adds into force and returns the
// reaction on the tool.
Reaction reference_push_forces(const std::vector<Vec3>& x, const Vec3& center, double radius,
                               double stiffness, std::vector<Vec3>& force, const std::vector<double>& scale = {});
// Any shape: the offset from the segment's closest point, the torque about
// the tool frame's origin.
Reaction reference_push_forces(const std::vector<Vec3>& x, const ToolPlacement& tool, double stiffness,
                               std::vector<Vec3>& force, const std::vector<double>& scale = {});

// Surface contact of a sphere tool with the Model's boundary triangles
// (force_law::sphere_triangle_penalty): each touching triangle's penalty f_t
// at its closest point, w_i f_t to its corner i, with share_i =
// s_i / (surface triangles of i). Adds into force and returns the reaction
// (F = -sum f_t, T = sum (q_t - c) x (-f_t)); contacts counts the points that
// received a force. With `layer`, the contact in series with the sub-cell
// Hertz layer: each penalty times its force_law::HertzLayer factor.
Reaction reference_surface_forces(const Model& model, const std::vector<Vec3>& x, const Vec3& center,
                                  double radius, double stiffness, std::vector<Vec3>& force,
                                  const ContactLayer* layer = nullptr);
// Any shape (force_law::capsule_triangle_penalty, jaw by jaw for a
// grasper; the torque about the tool frame's origin; a grasper's grip its
// jaws' penalties along their closing directions). No friction: it has state (the anchors), which
// the CPU backend in double precision keeps as the reference.
Reaction reference_surface_forces(const Model& model, const std::vector<Vec3>& x, const ToolPlacement& tool,
                                  double stiffness, std::vector<Vec3>& force, const ContactLayer* layer = nullptr);

// Pull attachments: f_i = k s_i (c + o_i - x_i). Adds into force, returns reaction.
Reaction reference_pull_forces(const std::vector<Vec3>& x, const Attachment& attachment,
                               const Vec3& center, double stiffness, std::vector<Vec3>& force,
                               const std::vector<double>& scale = {});

}  // namespace organsim
