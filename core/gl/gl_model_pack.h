#pragma once
// The immutable Model packed into the std430 arrays the step kernel reads
// (shaders/step.comp, bindings in shaders/bindings.glsl.h). Pure CPU code, no
// GL: the GL backend uploads these arrays once.
#include <cstdint>
#include <vector>

#include "core/model/model.h"

namespace organsim::gl {

// One gathered spring seen from its point: mirrors `SpringEntry` in step.comp.
struct SpringEntry {
  int32_t other;  // other end (internal id); the point itself for padding
  float rest;     // m (a suture's follows its schedule, see GlBackend::tick)
  float k;        // N/m; -k for a suture (tension only)
  float d;        // N s/m
};
static_assert(sizeof(SpringEntry) == 16);

// One gathered tet seen from its vertex p: (p, a, b, c) positively oriented.
struct TetEntry {
  int32_t a, b, c;  // the point itself for padding
  float k_v;        // N/m^5, 0 for padding
  float v_r;        // rest volume, m^3
};
static_assert(sizeof(TetEntry) == 20);  // std430: a struct of scalars has stride 20

// The shear element's parameters of one gathered tet (p, a, b, c): the rest
// gradients of a's, b's and c's barycentric coordinates (1/m), k_t =
// mu_e V_t^r (J), its damper d_t = tau k_t (J s) and, smoothed, the tet's
// weight w = k_t / K_p in p's averaged gradient Fbar_p (0 otherwise);
// mirrors `ShearEntry` in shaders/shear_element.glsl (three vec4).
struct ShearEntry {
  float ga[3], k;
  float gb[3], d;
  float gc[3], w;
};
static_assert(sizeof(ShearEntry) == 48);

// One surface triangle for the Hertz layer's solve (hertz_layer.comp's
// `LayerTri`): its corners and core/model/contact_layer.h's values.
struct LayerTri {
  int32_t corners[4];    // the fourth unused
  float punch_radius;    // m, before force_law::kHertzLayerPunchFactor
  float e_star;          // Pa
  float unused[2];
};
static_assert(sizeof(LayerTri) == 32);

struct PackedModel {
  int32_t npoint = 0, nchunk = 0, npad = 0;  // npad = nchunk * C
  std::vector<float> rest;        // vec4 rest positions, m, w = 1 (npad x 4); padding copies the last point
  // vec4 {1/m (0 = fixed or padding), m (kg), tool stiffness scale s, s / n
  // with n the point's surface triangles (0 off the surface)} (npad x 4)
  std::vector<float> mass;
  std::vector<int32_t> chunks;    // ivec4 {spring offset, spring slots, tet offset, tet slots} (nchunk x 4)
  std::vector<SpringEntry> springs;  // per (chunk, slot, lane) (nspring_entry)
  std::vector<TetEntry> tets;        // per (chunk, slot, lane), empty without volume or shear element (ntet_entry)
  std::vector<ShearEntry> shear;     // per (chunk, slot, lane), empty without the shear element (ntet_entry)
  std::vector<int32_t> suture_entries;  // entries of suture springs, 2 per suture
  // Nodal volume term: vec2 {k_a (N/m^5), V_a^r (m^3)} per point, zero for
  // padding (npad x 2); empty unless the model has it.
  std::vector<float> nodal;
  // Surface contact: each point's triangles (Model::surface_offset,
  // surface_tri) as ivec2 {first entry, count} (npad x 2; padding: none) and
  // per entry ivec4 {corner ids, which corner the point is}.
  std::vector<int32_t> surface_range;
  std::vector<int32_t> surface_entries;
  // The Hertz layer's triangles in Morton order of their rest centroids, so
  // that a tool's contact falls in few blocks of ORGANSIM_GL_LAYER_SIZE
  // (hertz_layer.comp reads only those); empty unless asked.
  std::vector<LayerTri> layer_tris;
};

// Padding entries point at the lane's own point with zero parameters: a
// zero-length spring and a zero-volume tet with k_v = 0 add no force, so
// every lane of a chunk runs the same number of slots (uniform control
// flow). A suture's entry has k < 0 (it pulls only) and its rest length when
// tied. Throws Error(Backend) when the layout's chunk size is not the
// kernel's workgroup size. `hertz_layer` also packs layer_tris (Error(Backend)
// beyond ORGANSIM_GL_LAYER_MAX_BLOCKS blocks of them).
PackedModel pack_model(const Model& model, bool hertz_layer = false);

// Blocks of ORGANSIM_GL_LAYER_SIZE layer triangles (the touch pass's workgroups).
int32_t layer_blocks(const PackedModel& packed);

}  // namespace organsim::gl
