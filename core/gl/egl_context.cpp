#include "core/gl/egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <vector>

#include "core/gl/gl_api.h"
#include "core/util/error.h"

namespace organsim::gl {
namespace {

std::string hex(unsigned value) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%04X", value);
  return text;
}

[[noreturn]] void fail(const std::string& call, const std::string& what = "") {
  const EGLint code = eglGetError();
  throw Error(ErrorKind::Backend, "EGL: " + call + " failed, error " + hex(static_cast<unsigned>(code)) +
                                      (what.empty() ? "" : " (" + what + ")"));
}

bool has_extension(const char* list, const char* name) {
  if (!list) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[n] == ' ' || p[n] == '\0';
    if (starts && ends) return true;
  }
  return false;
}

// EGL displays are per-process singletons and one eglTerminate ends every
// context on them, so contexts count their users and the last one terminates.
std::mutex g_display_mutex;
std::map<EGLDisplay, int> g_display_users;

void acquire_display(EGLDisplay display, const std::string& which) {
  std::lock_guard<std::mutex> lock(g_display_mutex);
  if (g_display_users[display]++ == 0) {
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display, &major, &minor)) {
      g_display_users.erase(display);
      fail("eglInitialize", which);
    }
  }
}

void release_display(EGLDisplay display) {
  std::lock_guard<std::mutex> lock(g_display_mutex);
  if (--g_display_users[display] == 0) {
    g_display_users.erase(display);
    eglTerminate(display);
  }
}

struct Candidate {
  EGLDisplay display = EGL_NO_DISPLAY;
  std::string platform;
};

// EGL device platform: hardware devices first, then Mesa's software device.
std::vector<Candidate> device_displays() {
  std::vector<Candidate> result;
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!has_extension(client, "EGL_EXT_platform_device")) return result;
  auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  auto query_device_string =
      reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
  if (!query_devices || !query_device_string) return result;
  EGLint count = 0;
  if (!query_devices(0, nullptr, &count) || count <= 0) return result;
  std::vector<EGLDeviceEXT> devices(static_cast<size_t>(count));
  if (!query_devices(count, devices.data(), &count)) return result;
  std::vector<Candidate> software;
  for (EGLint i = 0; i < count; ++i) {
    const char* extensions = query_device_string(devices[static_cast<size_t>(i)], EGL_EXTENSIONS);
    const bool is_software = has_extension(extensions, "EGL_MESA_device_software");
    EGLDisplay display = eglGetPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[static_cast<size_t>(i)], nullptr);
    if (display == EGL_NO_DISPLAY) continue;
    Candidate c{display, is_software ? "device (software)" : "device (hardware)"};
    (is_software ? software : result).push_back(c);
  }
  result.insert(result.end(), software.begin(), software.end());
  return result;
}

}  // namespace

struct EglContext::DebugLog {
  std::mutex mutex;
  std::string first_error;  // empty: none since the last check
};

namespace {
void APIENTRY on_gl_debug(GLenum /*source*/, GLenum type, GLuint id, GLenum severity, GLsizei length,
                            const GLchar* message, const void* user) {
  // Only errors (and undefined behaviour) fail; performance notes do not.
  if (type != GL_DEBUG_TYPE_ERROR && type != GL_DEBUG_TYPE_UNDEFINED_BEHAVIOR) return;
  if (severity == GL_DEBUG_SEVERITY_NOTIFICATION) return;
  // A C callback inside the driver must not throw: record, check_errors() throws.
  auto* log = static_cast<EglContext::DebugLog*>(const_cast<void*>(user));
  std::lock_guard<std::mutex> lock(log->mutex);
  if (log->first_error.empty()) {
    log->first_error = "GL error " + hex(id) + ": " +
                       std::string(message, length >= 0 ? static_cast<size_t>(length) : std::strlen(message));
  }
}
}  // namespace

bool EglContextOptions::default_debug() {
#if defined(ORGANSIM_GL_DEBUG_DEFAULT)
  return true;
#else
  return false;
#endif
}

EglContext::EglContext(const EglContextOptions& options) : debug_(options.debug) {
  std::vector<Candidate> candidates = device_displays();
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (has_extension(client, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay d = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (d != EGL_NO_DISPLAY) candidates.push_back({d, "surfaceless"});
  }
  if (options.share) {
    // A shared context must live on the same display.
    candidates = {{static_cast<EGLDisplay>(options.share->display_), options.share->platform_}};
  }
  if (candidates.empty()) {
    throw Error(ErrorKind::Backend,
                "EGL: no headless display: neither EGL_EXT_platform_device nor EGL_MESA_platform_surfaceless "
                "gave one (client extensions: " + std::string(client ? client : "none") +
                    "); install libegl-mesa0 and libgl1-mesa-dri");
  }

  // Try each display in order; keep the first failure to report if none works.
  std::string first_failure;
  for (const Candidate& c : candidates) {
    try {
      acquire_display(c.display, c.platform);
      const char* display_ext = eglQueryString(c.display, EGL_EXTENSIONS);
      if (!has_extension(display_ext, "EGL_KHR_no_config_context") &&
          !has_extension(display_ext, "EGL_MESA_configless_context")) {
        release_display(c.display);
        throw Error(ErrorKind::Backend, "EGL: display (" + c.platform + ") lacks EGL_KHR_no_config_context");
      }
      if (!eglBindAPI(EGL_OPENGL_API)) {
        release_display(c.display);
        fail("eglBindAPI(EGL_OPENGL_API)", c.platform);
      }
      // 4.5 core: Mesa's llvmpipe refuses 4.6 with EGL_BAD_MATCH.
      const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4,
                                   EGL_CONTEXT_MINOR_VERSION, 5,
                                   EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                   EGL_CONTEXT_OPENGL_DEBUG, debug_ ? EGL_TRUE : EGL_FALSE,
                                   EGL_NONE};
      EGLContext share = options.share ? static_cast<EGLContext>(options.share->context_) : EGL_NO_CONTEXT;
      EGLContext ctx = eglCreateContext(c.display, EGL_NO_CONFIG_KHR, share, attributes);
      if (ctx == EGL_NO_CONTEXT) {
        const EGLint code = eglGetError();
        release_display(c.display);
        throw Error(ErrorKind::Backend, "EGL: eglCreateContext(OpenGL 4.5 core, EGL_NO_CONFIG_KHR) failed on " +
                                            c.platform + ", error " + hex(static_cast<unsigned>(code)));
      }
      if (!eglMakeCurrent(c.display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
        const EGLint code = eglGetError();
        eglDestroyContext(c.display, ctx);
        release_display(c.display);
        throw Error(ErrorKind::Backend, "EGL: eglMakeCurrent(no surface) failed on " + c.platform + ", error " +
                                            hex(static_cast<unsigned>(code)));
      }
      display_ = c.display;
      context_ = ctx;
      platform_ = c.platform;
      break;
    } catch (const Error& e) {
      if (first_failure.empty()) first_failure = e.what();
    }
  }
  if (!context_) {
    throw Error(ErrorKind::Backend, first_failure + " (tried " + std::to_string(candidates.size()) +
                                        " display(s); no fallback to the CPU)");
  }

  auto str = [](GLenum name) {
    const GLubyte* s = glGetString(name);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string();
  };
  vendor_ = str(GL_VENDOR);
  renderer_ = str(GL_RENDERER);
  version_ = str(GL_VERSION);
  glGetIntegerv(GL_MAJOR_VERSION, &major_);
  glGetIntegerv(GL_MINOR_VERSION, &minor_);
  if (major_ < 4 || (major_ == 4 && minor_ < 5)) {
    const std::string got = version_;
    destroy();
    throw Error(ErrorKind::Backend, "EGL: context reports OpenGL " + got + ", need 4.5 core");
  }

  if (debug_) {
    log_ = std::make_unique<DebugLog>();
    glEnable(GL_DEBUG_OUTPUT);
    glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);  // the error is recorded inside the failing call
    glDebugMessageCallback(on_gl_debug, log_.get());
    glDebugMessageControl(GL_DONT_CARE, GL_DONT_CARE, GL_DONT_CARE, 0, nullptr, GL_TRUE);
  }
}

EglContext::~EglContext() { destroy(); }

void EglContext::destroy() {
  if (!context_) return;
  auto display = static_cast<EGLDisplay>(display_);
  if (eglGetCurrentContext() == static_cast<EGLContext>(context_)) {
    if (debug_) glDebugMessageCallback(nullptr, nullptr);
    eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  }
  eglDestroyContext(display, static_cast<EGLContext>(context_));
  release_display(display);
  context_ = nullptr;
}

void EglContext::make_current() const {
  if (!eglMakeCurrent(static_cast<EGLDisplay>(display_), EGL_NO_SURFACE, EGL_NO_SURFACE,
                      static_cast<EGLContext>(context_))) {
    fail("eglMakeCurrent", platform_);
  }
}

void EglContext::release_current() const {
  if (!eglMakeCurrent(static_cast<EGLDisplay>(display_), EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT)) {
    fail("eglMakeCurrent(EGL_NO_CONTEXT)", platform_);
  }
}

bool EglContext::software() const {
  return renderer_.find("llvmpipe") != std::string::npos || renderer_.find("softpipe") != std::string::npos ||
         platform_ == "device (software)";
}

void EglContext::check_errors(const std::string& where) const {
  if (log_) {
    std::string message;
    {
      std::lock_guard<std::mutex> lock(log_->mutex);
      message.swap(log_->first_error);
    }
    if (!message.empty()) {
      while (glGetError() != GL_NO_ERROR) {
      }  // the same error is also queued for glGetError: consume it
      throw Error(ErrorKind::Backend, where + ": " + message);
    }
  }
  const GLenum code = glGetError();
  if (code != GL_NO_ERROR) {
    throw Error(ErrorKind::Backend, where + ": glGetError() = " + hex(code));
  }
}

}  // namespace organsim::gl
