// The scenario's `outputs` section (force log, ParaView series, frames, video, contact sheet).
#include <nlohmann/json.hpp>

#include "core/scenario/scenario_sections.h"

namespace organsim {

const char* colormap_name(Colormap c) {
  switch (c) {
    case Colormap::Strain: return "strain";
    case Colormap::Displacement: return "displacement";
    case Colormap::Label: return "label";
    default: return "none";
  }
}

namespace scenario_detail {

namespace {
CameraDef parse_camera(const nlohmann::json& j, const JsonPath& at) {
  CameraDef c;
  if (j.is_string()) {
    if (j.get<std::string>() != "auto") throw at.error("expected \"auto\" or {position, target, up, fov_deg}");
    return c;
  }
  ObjectReader r(j, at);
  c.auto_fit = false;
  c.position = read_vec3(r.require("position"), r.at("position"));
  c.target = read_vec3(r.require("target"), r.at("target"));
  if (!((c.position - c.target).norm() > 0)) throw r.at("target").error("expected a point different from position");
  if (auto up = r.vec3("up")) {
    if (!(up->norm() > 0)) throw r.at("up").error("expected a non-zero vector");
    if (!(up->normalized().cross((c.target - c.position).normalized()).norm() > 1e-6)) {
      throw r.at("up").error("expected a direction not parallel to the viewing direction");
    }
    c.up = *up;
  }
  if (auto f = r.number("fov_deg")) {
    if (!(*f > 0 && *f < 180)) throw r.at("fov_deg").error("expected an angle in (0, 180) degrees");
    c.fov_deg = *f;
  }
  r.finish();
  return c;
}

FrameStyle parse_style(const nlohmann::json& j, const JsonPath& at) {
  ObjectReader r(j, at);
  FrameStyle s;
  if (auto w = r.boolean("wireframe")) s.wireframe = *w;
  if (auto c = r.string("colormap")) {
    if (*c == "none") s.colormap = Colormap::None;
    else if (*c == "strain") s.colormap = Colormap::Strain;
    else if (*c == "displacement") s.colormap = Colormap::Displacement;
    else if (*c == "label") s.colormap = Colormap::Label;
    else throw r.at("colormap").error("expected " + one_of({"none", "strain", "displacement", "label"}) + " (got \"" + *c + "\")");
  }
  if (auto m = r.number("colormap_max")) {
    // Labels are categories with fixed colours: a scale's top means nothing.
    if (s.colormap == Colormap::Label) throw r.at("colormap_max").error("expected no colormap_max with colormap \"label\"");
    s.colormap_max = require_positive(*m, r.at("colormap_max"));
  }
  if (const auto* b = r.get("background")) {
    const auto rgb = read_numbers(*b, r.at("background"), 3);
    for (size_t i = 0; i < 3; ++i) {
      if (!(rgb[i] >= 0 && rgb[i] <= 1)) throw r.at("background").index(i).error("expected a colour component in 0..1");
      s.background[i] = rgb[i];
    }
  }
  r.finish();
  return s;
}

FramesDef parse_frames(const nlohmann::json& j, const JsonPath& at) {
  ObjectReader r(j, at);
  FramesDef f;
  if (auto v = r.number("rate")) f.rate = require_positive(*v, r.at("rate"));
  if (const auto* s = r.get("size")) {
    const JsonPath sat = r.at("size");
    if (!s->is_array() || s->size() != 2) throw sat.error("expected [width, height] in pixels");
    for (size_t i = 0; i < 2; ++i) {
      const int64_t v = read_integer((*s)[i], sat.index(i));
      if (v < 16 || v > 8192) throw sat.index(i).error("expected a size in 16..8192 pixels (got " + std::to_string(v) + ")");
      f.size[i] = static_cast<int32_t>(v);
    }
  }
  if (const auto* c = r.get("camera")) f.camera = parse_camera(*c, r.at("camera"));
  if (const auto* s = r.get("style")) f.style = parse_style(*s, r.at("style"));
  r.finish();
  return f;
}

VideoDef parse_video(const nlohmann::json& j, const JsonPath& at, double frame_rate) {
  ObjectReader r(j, at);
  VideoDef v;
  v.fps = frame_rate;  // real-time playback unless asked otherwise
  if (auto f = r.string("file")) {
    if (f->empty() || std::filesystem::path(*f).is_absolute() || f->find("..") != std::string::npos) {
      throw r.at("file").error("expected a file name inside the output folder");
    }
    v.file = *f;
  }
  if (auto c = r.string("codec")) {
    if (c->size() != 4) throw r.at("codec").error("expected a 4-character FourCC such as \"mp4v\" (got \"" + *c + "\")");
    v.codec = *c;
  }
  if (auto fps = r.number("fps")) v.fps = require_positive(*fps, r.at("fps"));
  r.finish();
  return v;
}

ContactSheetDef parse_contact_sheet(const nlohmann::json& j, const JsonPath& at) {
  ObjectReader r(j, at);
  ContactSheetDef c;
  if (auto n = r.integer("frames")) {
    if (*n < 1 || *n > 1000) throw r.at("frames").error("expected an integer in 1..1000 (got " + std::to_string(*n) + ")");
    c.frames = static_cast<int32_t>(*n);
  }
  if (auto n = r.integer("columns")) {
    if (*n < 1 || *n > 100) throw r.at("columns").error("expected an integer in 1..100 (got " + std::to_string(*n) + ")");
    c.columns = static_cast<int32_t>(*n);
  }
  r.finish();
  return c;
}
VtkSeriesDef parse_vtk(const nlohmann::json& j, const JsonPath& at) {
  ObjectReader r(j, at);
  VtkSeriesDef v;
  if (auto rate = r.number("rate")) v.rate = require_positive(*rate, r.at("rate"));
  if (auto s = r.boolean("surface_only")) v.surface_only = *s;
  r.finish();
  return v;
}
}  // namespace

OutputsDef parse_outputs(const nlohmann::json& j, const JsonPath& at) {
  ObjectReader r(j, at);
  OutputsDef o;
  if (auto f = r.boolean("forces")) o.forces = *f;
  if (const auto* v = r.get("vtk")) o.vtk = parse_vtk(*v, r.at("vtk"));
  if (const auto* f = r.get("frames")) o.frames = parse_frames(*f, r.at("frames"));
  for (const char* key : {"video", "contact_sheet"}) {
    if (r.has(key) && !o.frames) throw r.at(key).error("needs outputs.frames (the images it is made of)");
  }
  if (const auto* v = r.get("video")) o.video = parse_video(*v, r.at("video"), o.frames->rate);
  if (const auto* c = r.get("contact_sheet")) o.contact_sheet = parse_contact_sheet(*c, r.at("contact_sheet"));
  r.finish();
  return o;
}

}  // namespace scenario_detail
}  // namespace organsim
