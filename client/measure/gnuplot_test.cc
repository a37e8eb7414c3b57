#include "client/measure/gnuplot.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace pdsm {
namespace {

class GnuplotTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) GTEST_SKIP() << "no gnuplot";
  }
};

TEST_F(GnuplotTest, ReturnsWhatItPrints) {
  absl::StatusOr<std::string> out = RunGnuplot("print 'a'\nset print '-'\nprint 6*7\n");
  ASSERT_TRUE(out.ok()) << out.status();
  EXPECT_EQ(*out, "42\n");  // `print` goes to stderr until `set print '-'`
}

// A script larger than a pipe's default 64 KiB still goes in whole before gnuplot starts.
TEST_F(GnuplotTest, LargeScript) {
  std::string script = "set print '-'\n";
  for (int i = 0; i < 20000; ++i) script += "x = " + std::to_string(i) + "\n";
  script += "print x\n";
  ASSERT_GT(script.size(), 65536u);
  absl::StatusOr<std::string> out = RunGnuplot(script);
  ASSERT_TRUE(out.ok()) << out.status();
  EXPECT_EQ(*out, "19999\n");
}

TEST_F(GnuplotTest, FailingScriptIsInternal) {
  const absl::Status s = RunGnuplot("this is not gnuplot\n").status();
  EXPECT_EQ(s.code(), absl::StatusCode::kInternal) << s;
}

}  // namespace
}  // namespace pdsm
