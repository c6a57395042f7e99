#include "core/gl/shader_sources.h"

#include "core/util/error.h"

namespace organsim::gl {

std::string_view shader_source(std::string_view name) {
  for (const auto& [file, text] : embedded_shaders()) {
    if (file == name) return text;
  }
  throw Error(ErrorKind::Backend, "shader '" + std::string(name) +
                                      "' is not embedded in this binary (is it in shaders/?)");
}

std::string assemble_shader(std::string_view name, const std::vector<std::string>& defines) {
  std::string text = "#version 450 core\n";
  for (const auto& d : defines) text += "#define " + d + "\n";
  // The shared header is C and GLSL at once: its `#pragma once` means nothing
  // to GLSL, which ignores unknown pragmas.
  text += "#line 1 1\n";
  text += shader_source("bindings.glsl.h");
  // Source-string number 2 = the kernel file, so "2(17)" in a log is its line 17.
  text += "\n#line 1 2\n";
  text += shader_source(name);
  return text;
}

}  // namespace organsim::gl
