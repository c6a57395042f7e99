#pragma once
// What every harness asserts. An input either reads into something the next
// stage can trust, or throws organsim::Error whose message names the file;
// anything else (a signal, a sanitizer report, another exception, a broken
// invariant) stops the fuzzer with the input that caused it.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/mesh/tet_mesh.h"
#include "core/util/error.h"

namespace organsim::fuzz {

inline std::string_view as_text(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

[[noreturn]] inline void broken(const std::string& what) {
  std::fprintf(stderr, "fuzz invariant broken: %s\n", what.c_str());
  std::abort();
}

inline void require(bool ok, const std::string& what) {
  if (!ok) broken(what);
}

// A clean error names the file first ("fuzz.off: line 3: ...").
inline void require_names_file(const Error& e, const std::string& source) {
  const std::string message = e.what();
  require(message.rfind(source + ": ", 0) == 0, "error message does not start with the file name: " + message);
}

#ifdef ORGANSIM_FUZZ_HARNESS
// The row's extension, defined in the harness executable's own small unit
// (tests/fuzz/CMakeLists.txt), so that each kind's source is compiled once
// for all its rows.
extern const char* const kExtension;
// The file name every harness reads its input as: "fuzz" + the row's extension.
inline const std::string kSource = std::string("fuzz") + kExtension;

// The body of most harnesses: `read` (a fuzz_inputs.h function) either takes
// the input, checking what it read, or throws an Error naming the file.
template <class Read>
int read_as_file(const uint8_t* data, size_t size, Read read) {
  try {
    read(as_text(data, size), kSource);
  } catch (const Error& e) {
    require_names_file(e, kSource);
  }
  return 0;
}
#endif

inline void require_valid_surface(const TriangleMesh& mesh) {
  const auto n = static_cast<int64_t>(mesh.points.size());
  for (const Vec3& p : mesh.points) require(p.allFinite(), "surface accepted with a non-finite point");
  for (const Tri& f : mesh.faces) {
    for (int32_t v : f) require(v >= 0 && v < n, "surface accepted with a face index out of range");
  }
}

inline void require_valid_tet_mesh(const TetMesh& mesh) {
  const auto n = static_cast<int64_t>(mesh.points.size());
  require(!mesh.tets.empty(), "tet mesh accepted without tets");
  for (const Vec3& p : mesh.points) require(p.allFinite(), "tet mesh accepted with a non-finite point");
  for (const Tet& t : mesh.tets) {
    for (int32_t v : t) require(v >= 0 && v < n, "tet mesh accepted with an index out of range");
    const double volume = signed_volume(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]);
    require(volume > 0, "tet mesh accepted with a tet of non-positive volume");
  }
}

}  // namespace organsim::fuzz
