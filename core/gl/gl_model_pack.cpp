#include "core/gl/gl_model_pack.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "core/model/contact_layer.h"
#include "core/model/shear_element.h"
#include "core/util/error.h"
#include "shaders/bindings.glsl.h"

namespace organsim::gl {
namespace {

// Spreads the low 10 bits of v to every third bit.
uint32_t spread_bits(uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

// The surface triangles sorted by the Morton code of their rest centroids
// (10 bits per axis over the rest bounding box), ties in Model::surface order.
std::vector<int32_t> morton_order(const Model& model) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::max()), hi = -lo;
  for (const Vec3& x : model.rest_position) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  const Vec3 scale = (hi - lo).cwiseMax(Vec3::Constant(1e-12)).cwiseInverse() * 1023.0;
  std::vector<uint32_t> code(model.surface.size());
  for (size_t i = 0; i < model.surface.size(); ++i) {
    const Tri& t = model.surface[i];
    const Vec3 c = (model.rest_position[t[0]] + model.rest_position[t[1]] + model.rest_position[t[2]]) / 3.0;
    const Vec3 q = ((c - lo).cwiseProduct(scale)).cwiseMax(Vec3::Zero()).cwiseMin(Vec3::Constant(1023.0));
    code[i] = spread_bits(static_cast<uint32_t>(q.x())) | (spread_bits(static_cast<uint32_t>(q.y())) << 1) |
              (spread_bits(static_cast<uint32_t>(q.z())) << 2);
  }
  std::vector<int32_t> order(model.surface.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return code[a] < code[b]; });
  return order;
}

}  // namespace

int32_t layer_blocks(const PackedModel& packed) {
  const auto n = static_cast<int32_t>(packed.layer_tris.size());
  return (n + ORGANSIM_GL_LAYER_SIZE - 1) / ORGANSIM_GL_LAYER_SIZE;
}

PackedModel pack_model(const Model& model, bool hertz_layer) {
  const auto& L = model.layout;
  constexpr int32_t C = ORGANSIM_GL_CHUNK;
  if (L.chunk_size != C) {
    throw Error(ErrorKind::Backend, "GL backend: the model's layout chunk size is " + std::to_string(L.chunk_size) +
                                        " but the step kernel's workgroup is " + std::to_string(C) +
                                        " (shaders/bindings.glsl.h); build the model with chunk_size " +
                                        std::to_string(C));
  }
  PackedModel p;
  p.npoint = model.npoint();
  p.nchunk = L.nchunk;
  p.npad = p.nchunk * C;
  // Tet entries: for the volume term or the shear element (never both).
  const bool volume = model.has_volume() || model.has_shear_element();

  p.rest.assign(static_cast<size_t>(p.npad) * 4, 0.0f);
  p.mass.assign(static_cast<size_t>(p.npad) * 4, 0.0f);  // padding: 1/m = 0, never moves
  for (int32_t i = 0; i < p.npad; ++i) {
    const Vec3& r = model.rest_position[static_cast<size_t>(i < p.npoint ? i : p.npoint - 1)];
    for (int k = 0; k < 3; ++k) p.rest[4 * i + k] = static_cast<float>(r[k]);
    p.rest[4 * i + 3] = 1.0f;
  }
  for (int32_t i = 0; i < p.npoint; ++i) {
    p.mass[4 * i] = static_cast<float>(model.inv_mass[i]);
    p.mass[4 * i + 1] = static_cast<float>(model.mass[i]);
    p.mass[4 * i + 2] = static_cast<float>(model.tool_scale(i));
    const int32_t n = model.surface_count(i);
    p.mass[4 * i + 3] = n > 0 ? static_cast<float>(model.tool_scale(i) / n) : 0.0f;
  }
  p.surface_range.assign(static_cast<size_t>(p.npad) * 2, 0);
  for (int32_t i = 0; i < p.npoint; ++i) {
    p.surface_range[2 * i] = model.surface_offset[i];
    p.surface_range[2 * i + 1] = model.surface_count(i);
    for (int32_t e = model.surface_offset[i]; e < model.surface_offset[i + 1]; ++e) {
      const Tri& t = model.surface[model.surface_tri[e]];
      const int32_t corner = t[0] == i ? 0 : t[1] == i ? 1 : 2;
      p.surface_entries.insert(p.surface_entries.end(), {t[0], t[1], t[2], corner});
    }
  }
  if (hertz_layer) {
    const ContactLayer layer = contact_layer(model);
    for (const int32_t i : morton_order(model)) {
      const Tri& t = model.surface[i];
      const TriangleLayer tl = triangle_layer(layer, t);
      p.layer_tris.push_back({{t[0], t[1], t[2], 0}, static_cast<float>(tl.punch_radius),
                              static_cast<float>(tl.e_star), {0, 0}});
    }
    if (layer_blocks(p) > ORGANSIM_GL_LAYER_MAX_BLOCKS) {
      throw Error(ErrorKind::Backend, "GL backend: the Hertz layer's solve lists at most " +
                                          std::to_string(ORGANSIM_GL_LAYER_MAX_BLOCKS * ORGANSIM_GL_LAYER_SIZE) +
                                          " surface triangles, the model has " + std::to_string(model.nsurface()) +
                                          " (run it with \"hertz_layer\": false or on the CPU backend)");
    }
  }

  p.chunks.assign(static_cast<size_t>(p.nchunk) * 4, 0);
  for (int32_t c = 0; c < p.nchunk; ++c) {
    p.chunks[4 * c + 0] = L.springs.chunk_offset[c];
    p.chunks[4 * c + 1] = L.springs.chunk_width[c];
    p.chunks[4 * c + 2] = volume ? L.tets.chunk_offset[c] : 0;
    p.chunks[4 * c + 3] = volume ? L.tets.chunk_width[c] : 0;
  }

  // Entry e of chunk c belongs to lane (e - offset) mod C, i.e. point c C + lane.
  auto self = [&](const GatherTable& table, int32_t c, int32_t e) {
    return c * C + (e - table.chunk_offset[c]) % C;
  };
  p.springs.resize(L.springs.item.size());
  for (int32_t c = 0; c < p.nchunk; ++c) {
    for (int32_t e = L.springs.chunk_offset[c]; e < L.springs.chunk_offset[c + 1]; ++e) {
      const int32_t s = L.springs.item[e];
      p.springs[e] = s < 0 ? SpringEntry{self(L.springs, c, e), 0, 0, 0}
                           : SpringEntry{L.spring_other[e], static_cast<float>(model.spring_rest[s]),
                                         static_cast<float>(model.spring_k[s]), static_cast<float>(model.spring_d[s])};
      if (s >= model.first_suture()) {
        p.springs[e].k = -p.springs[e].k;
        p.suture_entries.push_back(e);
      }
    }
  }
  if (volume) {
    p.tets.resize(L.tets.item.size());
    for (int32_t c = 0; c < p.nchunk; ++c) {
      for (int32_t e = L.tets.chunk_offset[c]; e < L.tets.chunk_offset[c + 1]; ++e) {
        const int32_t t = L.tets.item[e];
        if (t < 0) {
          const int32_t q = self(L.tets, c, e);
          p.tets[e] = {q, q, q, 0, 0};
        } else {
          const auto& o = L.tet_others[e];
          // The nodal term and the shear element read only the vertices here.
          const bool per_tet = !model.tet_k.empty();
          p.tets[e] = {o[0], o[1], o[2], per_tet ? static_cast<float>(model.tet_k[t]) : 0.0f,
                       static_cast<float>(model.tet_rest_volume[t])};
        }
      }
    }
  }
  if (model.has_shear_element()) {
    p.shear.assign(L.tets.item.size(), ShearEntry{});  // padding: zero gradients, k_t and w, no force
    for (int32_t c = 0; c < p.nchunk; ++c) {
      for (int32_t e = L.tets.chunk_offset[c]; e < L.tets.chunk_offset[c + 1]; ++e) {
        const int32_t t = L.tets.item[e];
        if (t < 0) continue;
        float* g[3] = {p.shear[e].ga, p.shear[e].gb, p.shear[e].gc};
        for (int k = 0; k < 3; ++k)
          for (int axis = 0; axis < 3; ++axis)
            g[k][axis] = static_cast<float>(shape_gradient_of(model, t, L.tet_others[e][k])[axis]);
        p.shear[e].k = static_cast<float>(model.tet_shear_k[t]);
        p.shear[e].d = static_cast<float>(model.shear_damping_time * model.tet_shear_k[t]);
        // The entry's point holds tet t, so its K_p > 0.
        if (model.has_smoothed_shear())
          p.shear[e].w = static_cast<float>(model.tet_shear_k[t] / model.point_shear_k[self(L.tets, c, e)]);
      }
    }
  }
  if (model.has_nodal_volume()) {
    p.nodal.assign(static_cast<size_t>(p.npad) * 2, 0.0f);
    for (int32_t i = 0; i < p.npoint; ++i) {
      p.nodal[2 * i] = static_cast<float>(model.point_volume_k[i]);
      p.nodal[2 * i + 1] = static_cast<float>(model.point_rest_volume[i]);
    }
  }
  return p;
}

}  // namespace organsim::gl
