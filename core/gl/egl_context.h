#pragma once
// A headless OpenGL 4.5 core context through EGL, without any window or
// surface (docs/gl.md, "Context"). Tries the EGL device platform first,
// preferring a hardware device over Mesa's software one, then Mesa's
// surfaceless platform. Every failure throws Error(ErrorKind::Backend) naming
// the EGL call and its error code in hex; there is no fallback to the CPU.
#include <memory>
#include <string>

namespace organsim::gl {

struct EglContextOptions {
  // Install a GL_KHR_debug callback that records GL errors; check_errors()
  // then throws on them. On by default in Debug builds (and with the CMake
  // option ORGANSIM_GL_DEBUG).
  bool debug = default_debug();
  // Share objects (buffers, programs) with this context, e.g. a renderer
  // drawing straight from the simulation's storage buffers.
  const class EglContext* share = nullptr;

  static bool default_debug();
};

class EglContext {
 public:
  explicit EglContext(const EglContextOptions& options = {});
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  // Makes this context current on the calling thread (the constructor does).
  void make_current() const;
  // Leaves the calling thread with no current context (a context must not
  // stay current on a thread that ends).
  void release_current() const;

  const std::string& vendor() const { return vendor_; }      // GL_VENDOR
  const std::string& renderer() const { return renderer_; }  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  const std::string& version() const { return version_; }    // GL_VERSION
  const std::string& platform() const { return platform_; }  // "device (hardware)", "device (software)" or "surfaceless"
  int major_version() const { return major_; }
  int minor_version() const { return minor_; }
  bool debug() const { return debug_; }
  bool software() const;  // llvmpipe / softpipe: timings are CPU timings

  // Debug contexts: throws Error(Backend) with the first GL error recorded
  // since the last check, prefixed by `where`. Otherwise checks glGetError().
  void check_errors(const std::string& where) const;

  // Native handles, for code that needs raw EGL (opaque here to keep EGL
  // headers out of users' translation units).
  void* egl_display() const { return display_; }
  void* egl_context() const { return context_; }

 // Recorded GL_KHR_debug errors (defined in the .cpp; public for the C callback).
  struct DebugLog;

 private:
  void destroy();

  void* display_ = nullptr;
  void* context_ = nullptr;
  std::string vendor_, renderer_, version_, platform_;
  int major_ = 0, minor_ = 0;
  bool debug_ = false;
  std::unique_ptr<DebugLog> log_;
};

}  // namespace organsim::gl
