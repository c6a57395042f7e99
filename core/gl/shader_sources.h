#pragma once
// GLSL sources embedded at build time (shaders/CMakeLists.txt) and the
// assembly of a compilable source: "#version 450", the variant's #define
// lines, the shared bindings header, then the kernel file (STYLE #12, #13).
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace organsim::gl {

// Every file of shaders/ by file name, e.g. "step.comp" (generated).
const std::vector<std::pair<std::string_view, std::string_view>>& embedded_shaders();

// The embedded file `name`; throws Error(Backend) naming it when absent.
std::string_view shader_source(std::string_view name);

// `source` (the file `name`) with each line `#include "file"` replaced by
// that embedded file, between #line directives (source string 3 for the
// included text, 2 again after it). Throws Error(Backend) naming `name` on a
// malformed #include or a file that is not embedded.
std::string expand_includes(std::string_view name, std::string_view source);

// "#version 450 core", each define as "#define <d>", bindings.glsl.h, then
// the file `name` with its includes expanded, with #line directives so driver
// logs point into the files.
std::string assemble_shader(std::string_view name, const std::vector<std::string>& defines);

}  // namespace organsim::gl
