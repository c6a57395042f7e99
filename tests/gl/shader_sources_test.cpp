// The assembly of embedded shaders: `#include "file"` lines are replaced by
// the embedded file between #line directives, so a driver log still points
// into the right file and line.
#include <gtest/gtest.h>

#include "core/gl/shader_sources.h"
#include "core/util/error.h"

namespace organsim {
namespace shader_sources_test {
namespace {

TEST(GlShaderSources, IncludeIsExpandedBetweenLineDirectives) {
  const std::string text = gl::expand_includes("k.comp", "a\n#include \"bindings.glsl.h\"\nb\n");
  const std::string included(gl::shader_source("bindings.glsl.h"));
  EXPECT_EQ(text, "a\n#line 1 3\n" + included + "\n#line 3 2\nb\n");
}

TEST(GlShaderSources, MalformedOrMissingIncludeIsAnError) {
  for (const char* bad : {"#include <x.glsl>\n", "#include \"no_such_file.glsl\"\n"}) {
    try {
      gl::expand_includes("k.comp", bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Backend);
    }
  }
}

}  // namespace
}  // namespace shader_sources_test
}  // namespace organsim
