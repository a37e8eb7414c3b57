#include "gl/platform/osmesa_context.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <thread>

#include "gl/gl_functions.h"
#include "gl/gl_program.h"

namespace pdsm::gl {
namespace {

TEST(OsMesaContextTest, IsCurrentAndMovable) {
  absl::StatusOr<OsMesaContext> context = OsMesaContext::Create();
  ASSERT_TRUE(context.ok()) << context.status();
  EXPECT_TRUE(context->IsCurrent());
  EXPECT_EQ(context->major_version(), 4);  // Mesa 22 llvmpipe: 4.5 core
  OsMesaContext moved = *std::move(context);
  EXPECT_TRUE(moved.IsCurrent());
  EXPECT_FALSE(context->IsCurrent());
  EXPECT_EQ(context->MakeCurrent().code(), absl::StatusCode::kFailedPrecondition);
  absl::StatusOr<GlFunctions> gl = GlFunctions::Load(&OsMesaContext::GetProcAddress);
  ASSERT_TRUE(gl.ok()) << gl.status();
  GLint major = 0;
  gl->GetIntegerv(GL_MAJOR_VERSION, &major);
  EXPECT_EQ(major, moved.major_version());
}

// A context released on one thread is made current on another and used there: how the local
// bake's threads hand their renderers on from one light to the next.
TEST(OsMesaContextTest, ReleasedOnOneThreadUsableOnAnother) {
  absl::StatusOr<OsMesaContext> context = OsMesaContext::Create();
  ASSERT_TRUE(context.ok()) << context.status();
  context->Release();
  EXPECT_FALSE(context->IsCurrent());
  context->Release();  // a no-op when not current
  GLint major = 0;
  std::thread other([&] {
    ASSERT_TRUE(context->MakeCurrent().ok());
    EXPECT_TRUE(context->IsCurrent());
    absl::StatusOr<GlFunctions> gl = GlFunctions::Load(&OsMesaContext::GetProcAddress);
    ASSERT_TRUE(gl.ok()) << gl.status();
    gl->GetIntegerv(GL_MAJOR_VERSION, &major);
    context->Release();
  });
  other.join();
  EXPECT_EQ(major, context->major_version());
  EXPECT_FALSE(context->IsCurrent());
  EXPECT_TRUE(context->MakeCurrent().ok());
  EXPECT_TRUE(context->IsCurrent());
}

// The driver part on the platform part: a program builds, and a compile error reaches the
// caller with the program's name and the driver's log.
TEST(OsMesaContextTest, BuildProgramReportsTheDriversLog) {
  absl::StatusOr<OsMesaContext> context = OsMesaContext::Create();
  ASSERT_TRUE(context.ok()) << context.status();
  absl::StatusOr<GlFunctions> gl = GlFunctions::Load(&OsMesaContext::GetProcAddress);
  ASSERT_TRUE(gl.ok()) << gl.status();
  constexpr char kVertex[] =
      "#version 330 core\nvoid main() { gl_Position = vec4(0.0, 0.0, 0.0, 1.0); }\n";
  constexpr char kFragment[] =
      "#version 330 core\nout vec4 colour;\nvoid main() { colour = vec4(1.0); }\n";
  constexpr char kBroken[] =
      "#version 330 core\nout vec4 colour;\nvoid main() { colour = undeclared; }\n";
  {
    absl::StatusOr<Program> program = BuildProgram(*gl, kVertex, kFragment, "tiny");
    ASSERT_TRUE(program.ok()) << program.status();
    EXPECT_NE(program->name(), 0u);
  }
  absl::StatusOr<Program> broken = BuildProgram(*gl, kVertex, kBroken, "broken");
  ASSERT_FALSE(broken.ok());
  EXPECT_EQ(broken.status().code(), absl::StatusCode::kInternal);
  EXPECT_THAT(std::string(broken.status().message()),
              ::testing::AllOf(::testing::HasSubstr("broken (fragment)"),
                               ::testing::HasSubstr("undeclared")));
  EXPECT_TRUE(CheckGlError(*gl, "after the tests").ok());
}

}  // namespace
}  // namespace pdsm::gl
