// The headless context and the shader plumbing. No skips: if EGL cannot make
// a context the test fails with the EGL call and code (CI runs on llvmpipe).
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "core/gl/egl_context.h"
#include "core/gl/gl_api.h"
#include "core/gl/gl_program.h"
#include "core/gl/shader_sources.h"
#include "core/util/error.h"
#include "shaders/bindings.glsl.h"

namespace organsim::gl {
namespace egl_context_test {
namespace {

TEST(EglContext, CreatesOpenGL45CoreWithoutAWindow) {
  EglContext context;
  // 4.5 is what the kernels need (DSA, glNamedBufferStorage, compute).
  EXPECT_TRUE(context.major_version() > 4 || (context.major_version() == 4 && context.minor_version() >= 5))
      << context.version();
  EXPECT_FALSE(context.renderer().empty());
  EXPECT_FALSE(context.vendor().empty());
  // The profile from the context itself: GL_VERSION's wording is the
  // driver's ("4.5 (Core Profile) Mesa ..." on llvmpipe, "4.5.0 NVIDIA ..."
  // on NVIDIA's EGL, which names no profile).
  GLint profile = 0;
  glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
  EXPECT_NE(profile & GL_CONTEXT_CORE_PROFILE_BIT, 0) << "GL_CONTEXT_PROFILE_MASK " << profile;
  std::cout << "GL_RENDERER " << context.renderer() << " | GL_VERSION " << context.version() << " | platform "
            << context.platform() << "\n";
  context.check_errors("after creation");
}

TEST(EglContext, DebugContextTurnsGlErrorsIntoFailures) {
  EglContextOptions options;
  options.debug = true;
  EglContext context(options);
  // Uploading into an immutable buffer without GL_DYNAMIC_STORAGE_BIT is the
  // GL_INVALID_OPERATION that Mesa raises silently without a debug callback
  // (docs/gl.md, "Context"): it must become an Error.
  GLuint buffer = 0;
  glCreateBuffers(1, &buffer);
  glNamedBufferStorage(buffer, 16, nullptr, 0);
  const float data[4] = {1, 2, 3, 4};
  glNamedBufferSubData(buffer, 0, sizeof data, data);
  try {
    context.check_errors("upload");
    ADD_FAILURE() << "GL error not reported";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Backend);
    EXPECT_NE(std::string(e.what()).find("upload"), std::string::npos) << e.what();
  }
  glDeleteBuffers(1, &buffer);
  context.check_errors("after the reported error");  // the log was consumed
}

TEST(EglContext, SharedContextSeesTheSameBuffers) {
  EglContext first;
  GLuint buffer = 0;
  glCreateBuffers(1, &buffer);
  const float value = 42.0f;
  glNamedBufferStorage(buffer, sizeof value, &value, 0);
  glFinish();
  EglContextOptions options;
  options.share = &first;
  EglContext second(options);
  float read = 0;
  glGetNamedBufferSubData(buffer, 0, sizeof read, &read);
  EXPECT_EQ(read, 42.0f);
  glDeleteBuffers(1, &buffer);
  second.check_errors("shared read");
}

TEST(Shaders, EmbeddedBindingsHeaderIsTheSourceFile) {
  std::ifstream file(std::string(ORGANSIM_SOURCE_DIR) + "/shaders/bindings.glsl.h", std::ios::binary);
  ASSERT_TRUE(file) << "cannot read shaders/bindings.glsl.h";
  std::stringstream text;
  text << file.rdbuf();
  EXPECT_EQ(std::string(shader_source("bindings.glsl.h")), text.str());
}

TEST(Shaders, UnknownShaderNameIsAnError) {
  try {
    shader_source("no_such_kernel.comp");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_kernel.comp"), std::string::npos);
  }
}

TEST(Shaders, ReduceKernelCompilesWithTheSharedWorkgroupSizeAndBindings) {
  EglContext context;
  ComputeProgram program("reduce_reaction.comp", {});
  EXPECT_EQ(program.workgroup_size()[0], ORGANSIM_GL_REDUCE_SIZE);
  EXPECT_EQ(program.storage_block_binding("Partials"), ORGANSIM_GL_B_PARTIALS);
  EXPECT_EQ(program.storage_block_binding("Reaction"), ORGANSIM_GL_B_REACTION);
  context.check_errors("compile");
}

TEST(Shaders, CompileFailureNamesTheShaderAndGivesTheDriverLog) {
  EglContext context;
  try {
    // An undefined macro used as an array size cannot compile.
    ComputeProgram program("reduce_reaction.comp", {"ORGANSIM_GL_REDUCE_SIZE_BROKEN", "main main_is_gone"});
    ADD_FAILURE() << "compiled";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.kind(), ErrorKind::Backend);
    EXPECT_NE(what.find("reduce_reaction.comp"), std::string::npos) << what;
    EXPECT_NE(what.find("main main_is_gone"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace egl_context_test
}  // namespace organsim::gl
