#include "core/scenario/scenario.h"

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>

#include "core/mesh/units.h"
#include "core/model/stiffness.h"
#include "core/scenario/scenario_sections.h"
#include "core/util/atomic_file.h"

namespace organsim {

using scenario_detail::parse_events;
using scenario_detail::parse_outputs;
using scenario_detail::parse_tool;

int64_t TimeDef::ticks() const {
  // The last tick may end after `duration`; the 1e-9 keeps 1.0 / 0.001 at 1000.
  return static_cast<int64_t>(std::ceil(duration / tick() - 1e-9));
}

namespace {

std::filesystem::path resolve(const std::string& path, const std::filesystem::path& base_dir) {
  std::filesystem::path p(path);
  if (p.is_relative()) p = base_dir / p;
  return p.lexically_normal();
}

}  // namespace

const std::vector<std::string>& scenario_file_fields() {
  // Every field parse_mesh passes to resolve(); keep the two in step.
  static const std::vector<std::string> fields{"mesh.surface", "mesh.image", "mesh.tet"};
  return fields;
}

namespace {

MeshDef parse_mesh(const nlohmann::json& j, const JsonPath& at, const std::filesystem::path& base_dir) {
  ObjectReader r(j, at);
  MeshDef mesh;
  const auto surface = r.string("surface");
  const auto tet = r.string("tet");
  const auto image = r.string("image");
  if (int(surface.has_value()) + int(tet.has_value()) + int(image.has_value()) > 1) {
    throw at.error("give one of \"surface\", \"image\" or \"tet\"");
  }
  if (!surface && !tet && !image) {
    throw at.error("missing \"surface\" (a closed triangle surface to mesh), \"image\" (a labelled image to mesh) or "
                   "\"tet\" (a tet mesh)");
  }
  if (image) {
    mesh.kind = MeshDef::Kind::Image;
    if (image->empty()) throw r.at("image").error("expected a file name");
    mesh.path = resolve(*image, base_dir);
  } else if (surface) {
    mesh.kind = MeshDef::Kind::Surface;
    if (surface->empty()) throw r.at("surface").error("expected a file name");
    mesh.path = resolve(*surface, base_dir);
  } else {
    mesh.kind = MeshDef::Kind::Tet;
    if (tet->empty()) throw r.at("tet").error("expected a file name");
    mesh.path = resolve(*tet, base_dir);
  }
  mesh.scale_given = r.has("scale") || r.has("units");
  if (auto s = r.number("scale")) mesh.scale = require_positive(*s, r.at("scale"));
  if (auto u = r.string("units")) {
    if (r.has("scale")) throw at.error("give \"units\" or \"scale\", not both");
    const auto metres = metres_per_unit(*u);
    if (!metres) throw r.at("units").error("expected \"mm\", \"cm\" or \"m\" (got \"" + *u + "\")");
    mesh.units = *u;
    mesh.scale = *metres;
  }
  if (const nlohmann::json* o = r.get("options")) {
    const JsonPath oat = r.at("options");
    if (mesh.kind == MeshDef::Kind::Tet) throw oat.error("meshing options apply only to a \"surface\" or \"image\" mesh");
    ObjectReader opt(*o, oat);
    if (mesh.kind == MeshDef::Kind::Image) {
      if (const nlohmann::json* l = opt.get("labels")) {
        const JsonPath lat = opt.at("labels");
        if (!l->is_array() || l->empty()) throw lat.error("expected a non-empty array of labels");
        for (size_t i = 0; i < l->size(); ++i) {
          const int64_t v = read_integer((*l)[i], lat.index(i));
          if (v < 1 || v > INT32_MAX) throw lat.index(i).error("expected a label > 0 (got " + std::to_string(v) + ")");
          mesh.labels.push_back(static_cast<int32_t>(v));
        }
      }
      if (const nlohmann::json* sizes = opt.get("label_cell_size")) {
        const JsonPath sat = opt.at("label_cell_size");
        if (!sizes->is_object()) throw sat.error("expected an object {\"LABEL\": cell size in m}");
        for (const auto& [key, value] : sizes->items()) {
          int64_t label = 0;
          const auto [end, ec] = std::from_chars(key.data(), key.data() + key.size(), label);
          if (ec != std::errc() || end != key.data() + key.size() || label < 1 || label > INT32_MAX) {
            throw sat.field(key).error("expected a label > 0 as the key");
          }
          mesh.label_cell_size[static_cast<int32_t>(label)] = require_positive(read_number(value, sat.field(key)), sat.field(key));
        }
      }
    }
    if (auto n = opt.integer("target_points")) {
      if (*n < 10 || *n > 10'000'000) throw opt.at("target_points").error("expected an integer in 10..10000000 (got " + std::to_string(*n) + ")");
      mesh.target_points = static_cast<int32_t>(*n);
    }
    if (auto h = opt.number("cell_size")) mesh.cell_size = require_positive(*h, opt.at("cell_size"));
    // label_cell_size may go with target_points: the target sizes the other labels.
    if (mesh.target_points && mesh.cell_size) throw oat.error("give target_points or cell_size, not both");
    if (auto d = opt.number("facet_distance")) mesh.facet_distance = require_positive(*d, opt.at("facet_distance"));
    if (auto e = opt.boolean("exude")) mesh.exude = *e;
    opt.finish();
  }
  r.finish();
  return mesh;
}

Material parse_material(const nlohmann::json& j, const JsonPath& at) {
  ObjectReader r(j, at);
  Material m;
  if (auto v = r.number("density")) m.density = require_positive(*v, r.at("density"));
  const bool has_e = r.has("young_modulus");
  const bool has_k = r.has("spring_stiffness");
  if (has_e && has_k) throw at.error("give young_modulus or spring_stiffness, not both");
  if (auto v = r.number("young_modulus")) m.young_modulus = require_positive(*v, r.at("young_modulus"));
  if (auto v = r.number("spring_stiffness")) m.spring_stiffness = require_positive(*v, r.at("spring_stiffness"));
  if (auto v = r.number("spring_damping_time")) m.spring_damping_time = require_non_negative(*v, r.at("spring_damping_time"));
  if (auto v = r.number("viscous_damping")) m.viscous_damping = require_non_negative(*v, r.at("viscous_damping"));
  if (auto v = r.number("volume_modulus")) m.volume_modulus = require_non_negative(*v, r.at("volume_modulus"));
  if (auto f = r.string("volume_formulation")) {
    if (*f == "per_tet")
      m.volume_formulation = VolumeFormulation::PerTet;
    else if (*f == "nodal")
      m.volume_formulation = VolumeFormulation::Nodal;
    else
      throw r.at("volume_formulation").error("expected " + one_of({"per_tet", "nodal"}) + " (got \"" + *f + "\")");
  }
  if (auto f = r.string("shear_formulation")) {
    if (*f == "per_tet")
      m.shear_formulation = ShearFormulation::PerTet;
    else if (*f == "smoothed")
      m.shear_formulation = ShearFormulation::Smoothed;
    else
      throw r.at("shear_formulation").error("expected " + one_of({"smoothed", "per_tet"}) + " (got \"" + *f + "\")");
  }
  if (auto v = r.number("poisson_ratio")) {
    if (!(*v >= kMinPoissonRatio && *v < 0.5))
      throw r.at("poisson_ratio").error("expected a number in [0, 0.5) (got " + std::to_string(*v) + ")");
    if (has_k) throw at.error("poisson_ratio needs young_modulus, not spring_stiffness");
    if (m.volume_modulus > 0) throw at.error("give poisson_ratio or volume_modulus, not both (nu sets the volume term)");
    m.poisson_ratio = *v;
  }
  r.finish();
  return m;
}

// One `materials` entry: "labels" and the fields of a `material`.
LabelMaterial parse_label_material(const nlohmann::json& j, const JsonPath& at) {
  if (!j.is_object()) throw at.error("expected an object {\"labels\": [...], material fields...}");
  if (!j.contains("labels")) throw at.field("labels").error("missing (required): the tet labels this material is for");
  const nlohmann::json& labels = j["labels"];
  const JsonPath lat = at.field("labels");
  if (!labels.is_array() || labels.empty()) throw lat.error("expected a non-empty array of labels");
  LabelMaterial m;
  for (size_t i = 0; i < labels.size(); ++i) {
    const int64_t v = read_integer(labels[i], lat.index(i));
    if (v < INT32_MIN || v > INT32_MAX) throw lat.index(i).error("expected a 32-bit integer label");
    m.labels.push_back(static_cast<int32_t>(v));
  }
  nlohmann::json fields = j;
  fields.erase("labels");
  m.material = parse_material(fields, at);
  return m;
}

std::vector<LabelMaterial> parse_materials(const nlohmann::json& j, const JsonPath& at) {
  if (!j.is_array() || j.empty()) throw at.error("expected a non-empty array of {\"labels\": [...], material fields...}");
  std::vector<LabelMaterial> out;
  for (size_t i = 0; i < j.size(); ++i) out.push_back(parse_label_material(j[i], at.index(i)));
  return out;
}

FixedSelector parse_selector(const nlohmann::json& j, const JsonPath& at) {
  ObjectReader r(j, at);
  if (j.size() != 1) throw at.error("expected exactly one of \"box\", \"plane\", \"sphere\", \"indices\" or \"label\"");
  FixedSelector s;
  if (const nlohmann::json* b = r.get("box")) {
    ObjectReader box(*b, r.at("box"));
    s.kind = FixedSelector::Kind::Box;
    s.min = read_vec3(box.require("min"), box.at("min"));
    s.max = read_vec3(box.require("max"), box.at("max"));
    for (int c = 0; c < 3; ++c) {
      if (s.min[c] > s.max[c]) throw box.at("max").error("expected max >= min in every coordinate");
    }
    box.finish();
  } else if (const nlohmann::json* p = r.get("plane")) {
    ObjectReader plane(*p, r.at("plane"));
    s.kind = FixedSelector::Kind::Plane;
    s.point = read_vec3(plane.require("point"), plane.at("point"));
    const Vec3 n = read_vec3(plane.require("normal"), plane.at("normal"));
    if (!(n.norm() > 0)) throw plane.at("normal").error("expected a non-zero vector");
    s.normal = n.normalized();
    plane.finish();
  } else if (const nlohmann::json* sp = r.get("sphere")) {
    ObjectReader sphere(*sp, r.at("sphere"));
    s.kind = FixedSelector::Kind::Sphere;
    s.center = read_vec3(sphere.require("center"), sphere.at("center"));
    s.radius = require_positive(read_number(sphere.require("radius"), sphere.at("radius")), sphere.at("radius"));
    sphere.finish();
  } else if (const nlohmann::json* label = r.get("label")) {
    s.kind = FixedSelector::Kind::Label;
    const int64_t v = read_integer(*label, r.at("label"));
    if (v < INT32_MIN || v > INT32_MAX) throw r.at("label").error("expected a 32-bit integer label");
    s.label = static_cast<int32_t>(v);
  } else if (const nlohmann::json* ids = r.get("indices")) {
    const JsonPath iat = r.at("indices");
    if (!ids->is_array()) throw iat.error("expected an array of point indices");
    s.kind = FixedSelector::Kind::Indices;
    for (size_t i = 0; i < ids->size(); ++i) {
      const int64_t v = read_integer((*ids)[i], iat.index(i));
      if (v < 0 || v > INT32_MAX) throw iat.index(i).error("expected a point index >= 0 (got " + std::to_string(v) + ")");
      s.indices.push_back(static_cast<int32_t>(v));
    }
  }
  r.finish();  // names the unknown selector kind
  return s;
}

std::vector<FixedSelector> parse_fixed(const nlohmann::json& j, const JsonPath& at) {
  if (!j.is_array()) throw at.error("expected an array of selectors ({\"box\"|\"plane\"|\"sphere\"|\"indices\"|\"label\": ...})");
  std::vector<FixedSelector> out;
  for (size_t i = 0; i < j.size(); ++i) out.push_back(parse_selector(j[i], at.index(i)));
  return out;
}

TimeDef parse_time(const nlohmann::json& j, const JsonPath& at) {
  ObjectReader r(j, at);
  TimeDef t;
  if (auto v = r.number("duration")) t.duration = require_positive(*v, r.at("duration"));
  if (auto v = r.number("dt")) t.dt = require_positive(*v, r.at("dt"));
  if (auto v = r.integer("substeps")) {
    if (*v < 1 || *v > 1'000'000) throw r.at("substeps").error("expected an integer >= 1 (got " + std::to_string(*v) + ")");
    t.substeps = static_cast<int32_t>(*v);
  }
  if (auto v = r.number("settle")) t.settle = require_non_negative(*v, r.at("settle"));
  if (auto v = r.string("integrator")) {
    if (*v == "implicit_euler") t.integrator = Integrator::ImplicitEuler;
    else if (*v == "implicit_damping") t.integrator = Integrator::ImplicitDamping;
    else if (*v != "verlet")
      throw r.at("integrator").error("expected \"verlet\", \"implicit_euler\" or \"implicit_damping\" (got \"" + *v +
                                     "\")");
  }
  // The implicit solver's settings mean nothing to Verlet: refused there, not ignored.
  const auto implicit_only = [&](const char* key) {
    if (!solves_implicitly(t.integrator))
      throw r.at(key).error("applies only with \"integrator\": \"implicit_euler\" or \"implicit_damping\"");
  };
  if (auto v = r.integer("newton_iterations")) {
    implicit_only("newton_iterations");
    if (t.integrator == Integrator::ImplicitDamping && *v != 1)
      throw r.at("newton_iterations").error("must be 1 with implicit_damping (its system is linear in v)");
    if (*v < 1 || *v > 100) throw r.at("newton_iterations").error("expected an integer in 1..100 (got " + std::to_string(*v) + ")");
    t.implicit.newton_iterations = static_cast<int32_t>(*v);
  }
  if (auto v = r.number("cg_tolerance")) {
    implicit_only("cg_tolerance");
    t.implicit.cg_tolerance = require_non_negative(*v, r.at("cg_tolerance"));
  }
  if (auto v = r.integer("cg_max_iterations")) {
    implicit_only("cg_max_iterations");
    if (*v < 1 || *v > 100'000)
      throw r.at("cg_max_iterations").error("expected an integer in 1..100000 (got " + std::to_string(*v) + ")");
    t.implicit.cg_max_iterations = static_cast<int32_t>(*v);
  }
  if (auto v = r.string("preconditioner")) {
    implicit_only("preconditioner");
    if (*v == "rest_cholesky") t.implicit.preconditioner = Preconditioner::RestCholesky;
    else if (*v == "two_level") t.implicit.preconditioner = Preconditioner::TwoLevel;
    else if (*v != "block_jacobi")
      throw r.at("preconditioner")
          .error("expected \"block_jacobi\", \"two_level\" or \"rest_cholesky\" (got \"" + *v + "\")");
  }
  r.finish();
  if (t.ticks() > 100'000'000) throw at.error("duration / (dt * substeps) gives more than 1e8 ticks");
  return t;
}

BackendDef parse_backend(const nlohmann::json& j, const JsonPath& at) {
  BackendDef b;
  auto check_name = [&](const std::string& name, const JsonPath& p) {
    if (name != "auto" && name != "cpu" && name != "gl")
      throw p.error("expected " + one_of({"auto", "cpu", "gl"}) + " (got \"" + name + "\")");
    return name;
  };
  if (j.is_string()) {
    b.name = check_name(j.get<std::string>(), at);
    return b;
  }
  if (!j.is_object()) throw at.error("expected \"auto\", \"cpu\", \"gl\" or an object {name, precision, threads}");
  ObjectReader r(j, at);
  if (auto n = r.string("name")) b.name = check_name(*n, r.at("name"));
  if (auto p = r.string("precision")) {
    if (*p != "double" && *p != "float") throw r.at("precision").error("expected " + one_of({"double", "float"}) + " (got \"" + *p + "\")");
    b.precision = *p;
  }
  if (auto t = r.integer("threads")) {
    if (*t < 0 || *t > 4096) throw r.at("threads").error("expected an integer >= 0, 0 meaning all hardware threads");
    b.threads = static_cast<int32_t>(*t);
  }
  r.finish();
  return b;
}

}  // namespace

Scenario parse_scenario(const nlohmann::json& j, const std::filesystem::path& base_dir,
                        const std::string& source) {
  const JsonPath root{source, ""};
  ObjectReader r(j, root);
  Scenario s;
  s.file = source;
  r.string("description");  // free text for people; not used
  s.mesh = parse_mesh(r.require("mesh"), r.at("mesh"), base_dir);
  if (const auto* m = r.get("material")) s.material = parse_material(*m, r.at("material"));
  if (const auto* m = r.get("materials")) {
    if (r.has("material")) throw root.error("give \"material\" (one for every tet) or \"materials\" (per label), not both");
    s.materials = parse_materials(*m, r.at("materials"));
    s.material = s.materials.front().material;
  }
  if (const auto* f = r.get("fixed")) s.fixed = parse_fixed(*f, r.at("fixed"));
  if (auto g = r.vec3("gravity")) s.gravity = *g;
  if (const auto* t = r.get("time")) s.time = parse_time(*t, r.at("time"));
  if (const auto* t = r.get("tool")) {
    bool elastic = !s.material.spring_stiffness;
    for (const LabelMaterial& m : s.materials) elastic = elastic && !m.material.spring_stiffness;
    s.tool = parse_tool(*t, r.at("tool"), elastic);
  }
  if (const auto* b = r.get("backend")) s.backend = parse_backend(*b, r.at("backend"));
  if (const auto* o = r.get("outputs")) s.outputs = parse_outputs(*o, r.at("outputs"));
  if (const auto* e = r.get("events")) s.events = parse_events(*e, r.at("events"));
  r.finish();
  return s;
}

Scenario load_scenario(const std::filesystem::path& path) {
  return parse_scenario_text(read_text_file(path),
                             path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path(),
                             path.string());
}

Scenario parse_scenario_text(std::string_view text, const std::filesystem::path& base_dir,
                             const std::string& source) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // e.byte is the offset of the error; turn it into line:column.
    size_t line = 1, col = 1;
    for (size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
      if (text[i] == '\n') { ++line; col = 1; } else { ++col; }
    }
    throw input_error(source, "invalid JSON at line " + std::to_string(line) + ", column " + std::to_string(col));
  } catch (const nlohmann::json::out_of_range& e) {
    // A number beyond the double range (1e7580): the parser gives no position.
    const std::string what = e.what();
    throw input_error(source, "invalid JSON: " + what.substr(what.find(']') + 2) + " (too large for a number)");
  }
  return parse_scenario(j, base_dir, source);
}

}  // namespace organsim
