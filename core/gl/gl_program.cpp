#include "core/gl/gl_program.h"

#include <utility>

#include "core/gl/shader_sources.h"
#include "core/util/error.h"

namespace organsim::gl {
namespace {

std::string variant_text(const std::vector<std::string>& defines) {
  if (defines.empty()) return "no defines";
  std::string text;
  for (const auto& d : defines) text += (text.empty() ? "" : ", ") + d;
  return text;
}

std::string shader_log(GLuint shader) {
  GLint length = 0;
  glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<size_t>(length > 0 ? length : 0), '\0');
  if (length > 0) glGetShaderInfoLog(shader, length, nullptr, log.data());
  while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
  return log;
}

std::string program_log(GLuint program) {
  GLint length = 0;
  glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<size_t>(length > 0 ? length : 0), '\0');
  if (length > 0) glGetProgramInfoLog(program, length, nullptr, log.data());
  while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
  return log;
}

}  // namespace

ComputeProgram::ComputeProgram(std::string_view shader_name, const std::vector<std::string>& defines)
    : name_(shader_name) {
  const std::string source = assemble_shader(shader_name, defines);
  const std::string what = "shader '" + name_ + "' (" + variant_text(defines) + ")";
  GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
  if (!shader) throw Error(ErrorKind::Backend, what + ": glCreateShader(GL_COMPUTE_SHADER) returned 0");
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    const std::string log = shader_log(shader);
    glDeleteShader(shader);
    // Source string 2 is the kernel file, 1 the bindings header, 3 an included file (see assemble_shader).
    throw Error(ErrorKind::Backend, what + " failed to compile (in the log, 2(N) is line N of " + name_ +
                                        ", 1(N) of bindings.glsl.h, 3(N) of its #include):\n" + log);
  }
  id_ = glCreateProgram();
  glAttachShader(id_, shader);
  glLinkProgram(id_);
  glDetachShader(id_, shader);
  glDeleteShader(shader);
  glGetProgramiv(id_, GL_LINK_STATUS, &ok);
  if (!ok) {
    const std::string log = program_log(id_);
    glDeleteProgram(id_);
    id_ = 0;
    throw Error(ErrorKind::Backend, what + " failed to link:\n" + log);
  }
}

ComputeProgram::~ComputeProgram() {
  if (id_) glDeleteProgram(id_);
}

ComputeProgram::ComputeProgram(ComputeProgram&& other) noexcept
    : id_(std::exchange(other.id_, 0)), name_(std::move(other.name_)) {}

ComputeProgram& ComputeProgram::operator=(ComputeProgram&& other) noexcept {
  if (this != &other) {
    if (id_) glDeleteProgram(id_);
    id_ = std::exchange(other.id_, 0);
    name_ = std::move(other.name_);
  }
  return *this;
}

std::array<GLint, 3> ComputeProgram::workgroup_size() const {
  std::array<GLint, 3> size{0, 0, 0};
  glGetProgramiv(id_, GL_COMPUTE_WORK_GROUP_SIZE, size.data());
  return size;
}

GLint ComputeProgram::storage_block_binding(const char* block) const {
  const GLuint index = glGetProgramResourceIndex(id_, GL_SHADER_STORAGE_BLOCK, block);
  if (index == GL_INVALID_INDEX) return -1;
  const GLenum property = GL_BUFFER_BINDING;
  GLint binding = -1;
  glGetProgramResourceiv(id_, GL_SHADER_STORAGE_BLOCK, index, 1, &property, 1, nullptr, &binding);
  return binding;
}

}  // namespace organsim::gl
