#include "gl/gl_functions.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

namespace pdsm::gl {
namespace {

// A loader that lacks one entry point: Load names it.
GlProc LoaderWithoutClipControl(const char* name) {
  if (std::string(name) == "glClipControl") return nullptr;
  return reinterpret_cast<GlProc>(&LoaderWithoutClipControl);  // any non-null pointer
}

TEST(GlFunctionsTest, MissingEntryPointIsNamed) {
  absl::StatusOr<GlFunctions> gl = GlFunctions::Load(&LoaderWithoutClipControl);
  ASSERT_FALSE(gl.ok());
  EXPECT_EQ(gl.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(gl.status().message()), ::testing::HasSubstr("glClipControl"));
}

TEST(GlFunctionsTest, NullLoaderIsRejected) {
  EXPECT_EQ(GlFunctions::Load(nullptr).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace pdsm::gl
