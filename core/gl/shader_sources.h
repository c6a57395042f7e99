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

// "#version 450 core", each define as "#define <d>", bindings.glsl.h, then
// the file `name`, with a #line directive so driver logs point into the file.
std::string assemble_shader(std::string_view name, const std::vector<std::string>& defines);

}  // namespace organsim::gl
