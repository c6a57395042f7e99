#include "core/render/surface_renderer.h"


#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <string>

#include "core/gl/gl_api.h"
#include "core/gl/shader_sources.h"
#include "core/util/error.h"

namespace organsim {

namespace {

GLuint compile(GLenum type, const std::string& name) {
  // The render shaders carry their own #version line: no compute bindings.
  const std::string text(gl::shader_source(name));
  const char* source = text.c_str();
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
    glGetShaderInfoLog(shader, length, nullptr, log.data());
    glDeleteShader(shader);
    throw Error(ErrorKind::Backend, "shaders/" + name + ": does not compile: " + log);
  }
  return shader;
}

GLuint link(const std::string& vert, const std::string& frag) {
  const GLuint vs = compile(GL_VERTEX_SHADER, vert);
  const GLuint fs = compile(GL_FRAGMENT_SHADER, frag);
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
    glGetProgramInfoLog(program, length, nullptr, log.data());
    glDeleteProgram(program);
    throw Error(ErrorKind::Backend, "shaders/" + vert + " + " + frag + ": do not link: " + log);
  }
  return program;
}

// Replaces a buffer's storage with `bytes` of data (mutable storage, so sizes
// may change with the topology).
void upload(GLuint buffer, const void* data, size_t bytes) {
  // A zero-sized store cannot be bound; keep 16 bytes.
  static const float zero[4] = {0, 0, 0, 0};
  if (bytes == 0) {
    data = zero;
    bytes = sizeof zero;
  }
  glNamedBufferData(buffer, static_cast<GLsizeiptr>(bytes), data, GL_DYNAMIC_DRAW);
}

// Colours as the shaders' vec4 array (std430: 16 bytes each, alpha 1).
void upload_colors(GLuint buffer, const std::vector<Vec3f>& rgb) {
  std::vector<float> rgba(rgb.size() * 4);
  for (size_t i = 0; i < rgb.size(); ++i) {
    for (int k = 0; k < 3; ++k) rgba[4 * i + k] = rgb[i][k];
    rgba[4 * i + 3] = 1.0f;
  }
  upload(buffer, rgba.data(), rgba.size() * sizeof(float));
}

void set_matrix(GLuint program, const char* name, const Eigen::Matrix4f& m) {
  glProgramUniformMatrix4fv(program, glGetUniformLocation(program, name), 1, GL_FALSE, m.data());
}
void set_vec3(GLuint program, const char* name, const Vec3& v) {
  glProgramUniform3f(program, glGetUniformLocation(program, name), static_cast<float>(v.x()),
                     static_cast<float>(v.y()), static_cast<float>(v.z()));
}

// Unit sphere as latitude/longitude triangles, outward counter-clockwise.
std::vector<float> unit_sphere(int slices, int stacks, std::vector<uint32_t>& indices) {
  std::vector<float> v;
  for (int i = 0; i <= stacks; ++i) {
    const double theta = std::numbers::pi * i / stacks;
    for (int j = 0; j <= slices; ++j) {
      const double phi = 2 * std::numbers::pi * j / slices;
      v.push_back(static_cast<float>(std::sin(theta) * std::cos(phi)));
      v.push_back(static_cast<float>(std::sin(theta) * std::sin(phi)));
      v.push_back(static_cast<float>(std::cos(theta)));
    }
  }
  for (int i = 0; i < stacks; ++i) {
    for (int j = 0; j < slices; ++j) {
      const uint32_t a = i * (slices + 1) + j, b = a + slices + 1;
      indices.insert(indices.end(), {a, b, a + 1, a + 1, b, b + 1});
    }
  }
  return v;
}

}  // namespace

struct SurfaceRenderer::Impl {
  int width = 0, height = 0;
  GLuint fbo = 0, color_rb = 0, depth_rb = 0;
  GLuint surface_program = 0, tool_program = 0;
  GLuint surface_vao = 0, index_buffer = 0, ring_offset = 0, ring_pairs = 0, own_positions = 0, colors = 0;
  GLuint face_colors = 0;
  GLsizei index_count = 0;
  GLuint line_vao = 0, line_buffer = 0;
  GLsizei line_index_count = 0;
  bool per_face_colors = false;
  GLuint position_buffer = 0;  // own_positions or an external buffer
  int stride = 4, offset = 0;
  bool point_colors = false;
  GLuint tool_vao = 0, tool_vertices = 0, tool_indices = 0;
  GLsizei tool_index_count = 0;
  std::vector<float> staging;  // float copy of CPU positions (reused)
};

SurfaceRenderer::SurfaceRenderer(int width, int height) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  if (width < 16 || height < 16 || width > 8192 || height > 8192) {
    throw Error(ErrorKind::Usage, "frame size " + std::to_string(width) + "x" + std::to_string(height) +
                                      ": expected 16..8192 px on each side");
  }
  s.width = width;
  s.height = height;

  glCreateRenderbuffers(1, &s.color_rb);
  glNamedRenderbufferStorage(s.color_rb, GL_RGBA8, width, height);
  glCreateRenderbuffers(1, &s.depth_rb);
  glNamedRenderbufferStorage(s.depth_rb, GL_DEPTH_COMPONENT24, width, height);
  glCreateFramebuffers(1, &s.fbo);
  glNamedFramebufferRenderbuffer(s.fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, s.color_rb);
  glNamedFramebufferRenderbuffer(s.fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, s.depth_rb);
  const GLenum status = glCheckNamedFramebufferStatus(s.fbo, GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%04x", status);
    throw Error(ErrorKind::Backend, std::string("render framebuffer incomplete: glCheckNamedFramebufferStatus = ") + hex);
  }

  s.surface_program = link("render_surface.vert", "render_shade.frag");
  s.tool_program = link("render_tool.vert", "render_shade.frag");

  GLuint buffers[7];
  glCreateBuffers(7, buffers);
  s.index_buffer = buffers[0];
  s.ring_offset = buffers[1];
  s.ring_pairs = buffers[2];
  s.own_positions = buffers[3];
  s.colors = buffers[4];
  s.face_colors = buffers[5];
  s.line_buffer = buffers[6];
  for (GLuint b : buffers) upload(b, nullptr, 0);
  s.position_buffer = s.own_positions;
  // Surface points are pulled from storage buffers: the VAOs only hold indices
  // (triangles, and the lines drawn over them).
  glCreateVertexArrays(1, &s.surface_vao);
  glVertexArrayElementBuffer(s.surface_vao, s.index_buffer);
  glCreateVertexArrays(1, &s.line_vao);
  glVertexArrayElementBuffer(s.line_vao, s.line_buffer);

  std::vector<uint32_t> sphere_indices;
  const std::vector<float> sphere = unit_sphere(32, 16, sphere_indices);
  glCreateBuffers(1, &s.tool_vertices);
  glNamedBufferStorage(s.tool_vertices, static_cast<GLsizeiptr>(sphere.size() * sizeof(float)), sphere.data(), 0);
  glCreateBuffers(1, &s.tool_indices);
  glNamedBufferStorage(s.tool_indices, static_cast<GLsizeiptr>(sphere_indices.size() * sizeof(uint32_t)),
                       sphere_indices.data(), 0);
  s.tool_index_count = static_cast<GLsizei>(sphere_indices.size());
  glCreateVertexArrays(1, &s.tool_vao);
  glVertexArrayVertexBuffer(s.tool_vao, 0, s.tool_vertices, 0, 3 * sizeof(float));
  glVertexArrayElementBuffer(s.tool_vao, s.tool_indices);
  glEnableVertexArrayAttrib(s.tool_vao, 0);
  glVertexArrayAttribFormat(s.tool_vao, 0, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(s.tool_vao, 0, 0);
}

SurfaceRenderer::~SurfaceRenderer() {
  Impl& s = *impl_;
  const GLuint buffers[] = {s.index_buffer, s.ring_offset,   s.ring_pairs,   s.own_positions, s.colors,
                            s.face_colors,  s.line_buffer,   s.tool_vertices, s.tool_indices};
  glDeleteBuffers(9, buffers);
  const GLuint vaos[] = {s.surface_vao, s.line_vao, s.tool_vao};
  glDeleteVertexArrays(3, vaos);
  glDeleteProgram(s.surface_program);
  glDeleteProgram(s.tool_program);
  glDeleteFramebuffers(1, &s.fbo);
  const GLuint rbs[] = {s.color_rb, s.depth_rb};
  glDeleteRenderbuffers(2, rbs);
}

int SurfaceRenderer::width() const { return impl_->width; }
int SurfaceRenderer::height() const { return impl_->height; }

void SurfaceRenderer::set_faces(const std::vector<Tri>& faces, int32_t npoint) {
  Impl& s = *impl_;
  for (const Tri& f : faces) {
    for (int32_t v : f) {
      if (v < 0 || v >= npoint) {
        throw Error(ErrorKind::Input, "surface face vertex " + std::to_string(v) + " out of range [0, " +
                                          std::to_string(npoint) + ")");
      }
    }
  }
  upload(s.index_buffer, faces.data(), faces.size() * sizeof(Tri));
  s.index_count = static_cast<GLsizei>(faces.size() * 3);
  // Ring of each point: the other two corners of its faces, in the face's
  // counter-clockwise order, so cross(b - p, c - p) points outward.
  std::vector<int32_t> offset(static_cast<size_t>(npoint) + 1, 0);
  for (const Tri& f : faces) {
    for (int32_t v : f) ++offset[v + 1];
  }
  for (int32_t i = 0; i < npoint; ++i) offset[i + 1] += offset[i];
  std::vector<int32_t> fill(offset.begin(), offset.end() - 1);
  std::vector<int32_t> pairs(2 * static_cast<size_t>(offset[npoint]));
  for (const Tri& f : faces) {
    for (int k = 0; k < 3; ++k) {
      const int32_t r = fill[f[k]]++;
      pairs[2 * r] = f[(k + 1) % 3];
      pairs[2 * r + 1] = f[(k + 2) % 3];
    }
  }
  upload(s.ring_offset, offset.data(), offset.size() * sizeof(int32_t));
  upload(s.ring_pairs, pairs.data(), pairs.size() * sizeof(int32_t));
}

void SurfaceRenderer::set_positions(const std::vector<Vec3>& positions) {
  Impl& s = *impl_;
  s.staging.resize(positions.size() * 4);
  for (size_t i = 0; i < positions.size(); ++i) {
    for (int k = 0; k < 3; ++k) s.staging[4 * i + k] = static_cast<float>(positions[i][k]);
    s.staging[4 * i + 3] = 1.0f;
  }
  upload(s.own_positions, s.staging.data(), s.staging.size() * sizeof(float));
  s.position_buffer = s.own_positions;
  s.stride = 4;
  s.offset = 0;
}

void SurfaceRenderer::use_position_buffer(uint32_t buffer, int stride_floats, int offset_floats) {
  if (stride_floats < 3 || offset_floats < 0) {
    throw Error(ErrorKind::Usage, "use_position_buffer: stride must be >= 3 floats and offset >= 0");
  }
  impl_->position_buffer = buffer;
  impl_->stride = stride_floats;
  impl_->offset = offset_floats;
}

void SurfaceRenderer::set_point_colors(const std::vector<Vec3f>& rgb) {
  Impl& s = *impl_;
  s.point_colors = !rgb.empty();
  upload_colors(s.colors, rgb);
}

void SurfaceRenderer::set_face_colors(const std::vector<Vec3f>& rgb) {
  Impl& s = *impl_;
  s.per_face_colors = !rgb.empty();
  upload_colors(s.face_colors, rgb);
}

void SurfaceRenderer::set_lines(const std::vector<Edge>& edges) {
  Impl& s = *impl_;
  upload(s.line_buffer, edges.data(), edges.size() * sizeof(Edge));
  s.line_index_count = static_cast<GLsizei>(edges.size() * 2);
}

void SurfaceRenderer::draw(const Camera& camera, const StyleOptions& style, const ToolDraw& tool) {
  Impl& s = *impl_;
  glBindFramebuffer(GL_FRAMEBUFFER, s.fbo);
  glViewport(0, 0, s.width, s.height);
  glClearColor(static_cast<float>(style.background.x()), static_cast<float>(style.background.y()),
               static_cast<float>(style.background.z()), 1.0f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);  // two-sided: open surfaces show their inside

  const Eigen::Matrix4f view = camera.view();
  const Eigen::Matrix4f projection = camera.projection(static_cast<double>(s.width) / s.height);
  for (GLuint program : {s.surface_program, s.tool_program}) {
    set_matrix(program, "u_view", view);
    set_matrix(program, "u_projection", projection);
    glProgramUniform1i(program, glGetUniformLocation(program, "u_flat"), 0);
    glProgramUniform1i(program, glGetUniformLocation(program, "u_face_colors"), 0);
  }

  if (s.index_count > 0) {
    const GLuint p = s.surface_program;
    glProgramUniform1i(p, glGetUniformLocation(p, "u_stride"), s.stride);
    glProgramUniform1i(p, glGetUniformLocation(p, "u_offset"), s.offset);
    glProgramUniform1i(p, glGetUniformLocation(p, "u_point_colors"), s.point_colors ? 1 : 0);
    set_vec3(p, "u_color", style.surface_color);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, s.position_buffer);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, s.ring_offset);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, s.ring_pairs);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, s.colors);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, s.face_colors);
    glProgramUniform1i(p, glGetUniformLocation(p, "u_face_colors"), s.per_face_colors ? 1 : 0);
    glUseProgram(p);
    glBindVertexArray(s.surface_vao);
    // Fill pushed back slightly so the wireframe's lines win the depth test.
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.0f, 1.0f);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    glDrawElements(GL_TRIANGLES, s.index_count, GL_UNSIGNED_INT, nullptr);
    glDisable(GL_POLYGON_OFFSET_FILL);
    if (style.wireframe) {
      glProgramUniform1i(p, glGetUniformLocation(p, "u_flat"), 1);
      set_vec3(p, "u_flat_color", Vec3(0.12, 0.12, 0.12));
      glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
      glDrawElements(GL_TRIANGLES, s.index_count, GL_UNSIGNED_INT, nullptr);
      glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    }
    if (s.line_index_count > 0) {
      // Two pixels where the driver draws wide lines (llvmpipe does), so a
      // boundary between labels stays visible on a contact sheet's tile.
      GLfloat widths[2] = {1, 1};
      glGetFloatv(GL_ALIASED_LINE_WIDTH_RANGE, widths);
      glLineWidth(std::min(2.0f, widths[1]));
      glProgramUniform1i(p, glGetUniformLocation(p, "u_flat"), 1);
      set_vec3(p, "u_flat_color", Vec3(0.05, 0.05, 0.05));
      glBindVertexArray(s.line_vao);
      glDrawElements(GL_LINES, s.line_index_count, GL_UNSIGNED_INT, nullptr);
      glLineWidth(1.0f);
    }
    glProgramUniform1i(p, glGetUniformLocation(p, "u_face_colors"), 0);
  }
  for (int k = 0; tool.visible && tool.radius > 0 && k < tool.segments; ++k) {
    const GLuint p = s.tool_program;
    set_vec3(p, "u_end_a", k == 0 ? tool.a : tool.a2);
    set_vec3(p, "u_end_b", k == 0 ? tool.b : tool.b2);
    glProgramUniform1f(p, glGetUniformLocation(p, "u_radius"), static_cast<float>(tool.radius));
    set_vec3(p, "u_color", style.tool_color);
    glUseProgram(p);
    glBindVertexArray(s.tool_vao);
    glDrawElements(GL_TRIANGLES, s.tool_index_count, GL_UNSIGNED_INT, nullptr);
  }
  glBindVertexArray(0);
  glUseProgram(0);
}

cv::Mat SurfaceRenderer::read_back() {
  Impl& s = *impl_;
  cv::Mat bottom_up(s.height, s.width, CV_8UC3);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, s.fbo);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, s.width, s.height, GL_BGR, GL_UNSIGNED_BYTE, bottom_up.data);
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%04x", error);
    throw Error(ErrorKind::Backend, std::string("glReadPixels failed: GL error ") + hex);
  }
  // GL's rows start at the bottom; images start at the top.
  cv::Mat top_down;
  cv::flip(bottom_up, top_down, 0);
  return top_down;
}

cv::Mat SurfaceRenderer::render(const Camera& camera, const StyleOptions& style, const ToolDraw& tool) {
  draw(camera, style, tool);
  return read_back();
}

}  // namespace organsim
