// Storage-buffer bindings, uniform locations and workgroup sizes shared by the
// C++ GL backend (core/gl) and every GLSL kernel (prepended to each one by
// core/gl/shader_sources.cpp). Written in the common subset of C++ and GLSL:
// #define lines of integer literals and // comments only (STYLE #13).
#ifndef ORGANSIM_GL_BINDINGS_GLSL_H
#define ORGANSIM_GL_BINDINGS_GLSL_H

// Workgroup size of the step kernel = chunk size C of the gather layout
// (core/model/layout.h): one workgroup gathers one chunk, one lane one point.
#define ORGANSIM_GL_CHUNK 64
// Workgroup size of the reaction reduction (one workgroup sums all partials).
#define ORGANSIM_GL_REDUCE_SIZE 64
// Workgroup size of the Hertz layer's passes: its touch pass takes one
// triangle per invocation, and its solve (one workgroup per substep) one
// entry of each block of this many triangles in contact.
#define ORGANSIM_GL_LAYER_SIZE 256
// Most blocks of LAYER_SIZE triangles the solve can list (shared memory):
// 524,288 surface triangles.
#define ORGANSIM_GL_LAYER_MAX_BLOCKS 2048
// Slots of the persistently mapped reaction ring read back one tick late.
#define ORGANSIM_GL_READBACK_SLOTS 4

// Shader storage buffer bindings (std430). Sizes: npad = nchunk * C points.
// State: x_t and d_t = x_t - x_{t-1} (equivalent to storing x_{t-1}, but in
// float the difference of two nearby positions loses the velocity; see docs/gl.md).
#define ORGANSIM_GL_B_X_CUR 0     // vec4 x_t, m (npad); w = 1
#define ORGANSIM_GL_B_D_CUR 1     // vec4 d_t = x_t - x_{t-1}, m (npad)
#define ORGANSIM_GL_B_X_NEXT 2    // vec4 x_{t+1}, m (npad); written by the step
#define ORGANSIM_GL_B_D_NEXT 3    // vec4 d_{t+1}, m (npad); written by the step
#define ORGANSIM_GL_B_MASS 4      // vec4 {1/m (0 = fixed or padding), m (kg), tool k scale, its share s/n per surface triangle} (npad)
#define ORGANSIM_GL_B_CHUNKS 5    // ivec4 {spring offset, spring slots, tet offset, tet slots} (nchunk)
#define ORGANSIM_GL_B_SPRINGS 6   // {int other; float rest, k, d} per (chunk, slot, lane) (nspring_entry)
#define ORGANSIM_GL_B_TETS 7      // {int a, b, c; float k_v, V_r} per (chunk, slot, lane) (ntet_entry)
#define ORGANSIM_GL_B_ATTACH 8    // vec4 {offset from tool centre (m), attached 0/1} (npad)
#define ORGANSIM_GL_B_PARTIALS 9  // vec4 pairs {F.xyz, contacts}, {T.xyz, grip} per workgroup (nchunk x 2)
#define ORGANSIM_GL_B_REACTION 10 // vec4 pairs as above per ring slot (READBACK_SLOTS x 2), mapped
#define ORGANSIM_GL_B_FORCE 11    // vec4 total force per point, N (npad); RECORD_FORCE variant (tests) only
#define ORGANSIM_GL_B_STATUS 12   // uint per ring slot: lowest point whose x_{t+1} is not finite, or ~0u; mapped
#define ORGANSIM_GL_B_NODAL 13    // vec2 {k_a (N/m^5), V_a^r (m^3)} of the nodal volume term (npad); 0 for padding
#define ORGANSIM_GL_B_PRESSURE 14 // float nodal pressure q_a = k_a (V_a - V_a^r), Pa (npad); nodal_pressure.comp
#define ORGANSIM_GL_B_REST 15     // vec4 rest positions X, m (npad); the shear element's displacements x - X
#define ORGANSIM_GL_B_SHEAR 16    // {vec4 g_a k_t, g_b d_t, g_c k_t/K_p} shear element per tet entry (ntet_entry)
#define ORGANSIM_GL_B_SHEAR_STRESS 17  // vec4 x 3 per point: P(Fbar_p)'s columns (npad x 3); shear_smoothing.comp
#define ORGANSIM_GL_B_SURFACE 18  // ivec2 {first entry, count} of each point's surface triangles (npad); surface contact
#define ORGANSIM_GL_B_SURFACE_TRIS 19  // ivec4 {corners 0, 1, 2, the point's corner} per (point, triangle), ascending
#define ORGANSIM_GL_B_ANCHOR 20   // vec4 {friction anchor in the tool frame (m), anchored 0/1} (npad); FRICTION
#define ORGANSIM_GL_B_CARRY 21    // int: the old point each appended lane copies (carry_state.comp, an adopt)
#define ORGANSIM_GL_B_LAYER_TRIS 22   // {ivec4 corners, vec4 {punch radius (before the factor), E*, 0, 0}} per surface triangle; HERTZ_LAYER
#define ORGANSIM_GL_B_LAYER_TOUCH 23  // vec4 {f_t (N), k_t (N/m)} per surface triangle, k_t 0 when it does not touch (hertz_layer_touch.comp)
#define ORGANSIM_GL_B_LAYER_OUT 24    // vec4 {n, delta (m)}: the contact's direction and the layer's offset this substep
#define ORGANSIM_GL_B_LAYER_BLOCKS 25 // uint per block of LAYER_SIZE layer triangles: how many touch (hertz_layer_touch.comp)

// Uniform locations (layout(location = N) uniform ...).
#define ORGANSIM_GL_U_DT 0            // float dt, s
#define ORGANSIM_GL_U_DAMPING 1       // float alpha dt (viscous drag in Verlet form: d *= 1 - alpha dt)
#define ORGANSIM_GL_U_GRAVITY 2       // vec3 g, m/s^2
#define ORGANSIM_GL_U_TOOL_CENTER 3   // vec3 tool frame's origin during this step (torque reference), m
#define ORGANSIM_GL_U_TOOL_ACTIVE 4   // int: 1 when the tool acts in this step
#define ORGANSIM_GL_U_TOOL_RADIUS 5   // float R, m
#define ORGANSIM_GL_U_TOOL_K 6        // float contact / attachment stiffness, N/m
#define ORGANSIM_GL_U_REDUCE 7        // int: 1 when this step writes reaction partials
#define ORGANSIM_GL_U_NPARTIAL 8      // int: partials to sum (reduce kernel)
#define ORGANSIM_GL_U_SLOT 9          // int: ring slot of this tick (reduce: reaction; step: status)
#define ORGANSIM_GL_U_DT2 10          // float dt^2, s^2 (rounded once from double)
#define ORGANSIM_GL_U_TOOL_A 11       // vec3 the tool shape's segment, first end, m (the centre for a sphere); push only
#define ORGANSIM_GL_U_TOOL_B 12       // vec3 its second end, m (the centre for a sphere); push only
#define ORGANSIM_GL_U_TOOL_A2 13      // vec3 a grasper's second jaw, first end, m; GRASPER
#define ORGANSIM_GL_U_TOOL_B2 14      // vec3 its second end, m; GRASPER
#define ORGANSIM_GL_U_FRICTION 15     // vec2 {mu_s, mu_k}; FRICTION
#define ORGANSIM_GL_U_TOOL_ROTATION 16  // mat3 the tool frame's rotation into the world (locations 16-18); FRICTION
#define ORGANSIM_GL_U_JAW_AXIS 19     // vec3 the grasper's jaw axis in the world (its first jaw closes along -it); GRASPER
#define ORGANSIM_GL_U_CARRY_FIRST 20  // int: the first appended lane (carry_state.comp)
#define ORGANSIM_GL_U_CARRY_COUNT 21  // int: appended lanes to fill (carry_state.comp)
#define ORGANSIM_GL_U_LAYER_TRIS 22   // int: surface triangles (hertz_layer_touch.comp, hertz_layer.comp)
#define ORGANSIM_GL_U_LAYER_FACTOR 23 // float: force_law::kHertzLayerPunchFactor (hertz_layer.comp)
#define ORGANSIM_GL_U_LAYER_LINE_FACTOR 24  // float: force_law::kLineLayerHalfWidthFactor (hertz_layer.comp)

#endif
