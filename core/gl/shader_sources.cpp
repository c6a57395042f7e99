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

std::string expand_includes(std::string_view name, std::string_view source) {
  // Core GLSL has no #include; kernels sharing formulas name an embedded
  // file on a line `#include "file"`, replaced here by its text. One level
  // only (an included file's own #include is left to fail in the compiler).
  constexpr std::string_view kDirective = "#include \"";
  std::string text;
  int line = 1;
  for (size_t start = 0; start < source.size(); ++line) {
    size_t end = source.find('\n', start);
    if (end == std::string_view::npos) end = source.size();
    const std::string_view l = source.substr(start, end - start);
    const size_t close = l.rfind('"');
    if (l.substr(0, kDirective.size()) == kDirective && close >= kDirective.size()) {
      const std::string_view file = l.substr(kDirective.size(), close - kDirective.size());
      // Source-string number 3 = an included file; then back to the kernel's next line.
      text += "#line 1 3\n";
      text += shader_source(file);
      text += "\n#line " + std::to_string(line + 1) + " 2\n";
    } else if (l.substr(0, 8) == "#include") {
      throw Error(ErrorKind::Backend, "shader '" + std::string(name) + "' line " + std::to_string(line) +
                                          ": expected #include \"file\"");
    } else {
      text += l;
      text += '\n';
    }
    start = end + 1;
  }
  return text;
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
  text += expand_includes(name, shader_source(name));
  return text;
}

}  // namespace organsim::gl
