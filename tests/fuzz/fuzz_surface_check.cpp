// Harness for the checks that guard CGAL Mesh_3 (meshing/surface_check.h),
// on small OFF surfaces the fuzzer mutates: a surface either passes, and is
// then closed, finite and of a size Mesh_3 handles, or is refused with an
// error naming the file. Mesh_3 itself is too slow to run per input.
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_stats.h"
#include "meshing/surface_check.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace organsim;
  TriangleMesh checked;
  try {
    const TriangleMesh surface = parse_surface(fuzz::as_text(data, size), fuzz::kSource);
    std::vector<std::string> notes;
    checked = check_surface(surface, fuzz::kSource, notes);
  } catch (const Error& e) {
    fuzz::require_names_file(e);
    return 0;
  }
  fuzz::require_valid_surface(checked);
  fuzz::require(checked.faces.size() >= 4, "a closed surface with fewer than 4 faces passed");
  fuzz::require(surface_volume(checked) > 0, "a surface enclosing no positive volume passed");
  return 0;
}
