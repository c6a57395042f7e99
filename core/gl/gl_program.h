#pragma once
// Compute programs built from the embedded shaders (core/gl/shader_sources.h).
// A shader that fails to compile or link throws Error(Backend) naming the
// shader file, its #define variant and the driver's log.
#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "core/gl/gl_api.h"

namespace organsim::gl {

class ComputeProgram {
 public:
  ComputeProgram() = default;
  ComputeProgram(std::string_view shader_name, const std::vector<std::string>& defines);
  ~ComputeProgram();
  ComputeProgram(ComputeProgram&& other) noexcept;
  ComputeProgram& operator=(ComputeProgram&& other) noexcept;
  ComputeProgram(const ComputeProgram&) = delete;
  ComputeProgram& operator=(const ComputeProgram&) = delete;

  GLuint id() const { return id_; }
  const std::string& name() const { return name_; }
  // gl_WorkGroupSize as the driver sees it (GL_COMPUTE_WORK_GROUP_SIZE).
  std::array<GLint, 3> workgroup_size() const;
  // Binding point of the shader storage block `block`, -1 when the program
  // has no such (active) block.
  GLint storage_block_binding(const char* block) const;

 private:
  GLuint id_ = 0;
  std::string name_;
};

}  // namespace organsim::gl
