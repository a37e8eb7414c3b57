#include "core/util/process_log.h"

#include <gtest/gtest.h>

namespace pdsm {
namespace {

TEST(JsonEscapedForLog, EscapesWhatJsonRequiresAndKeepsUtf8) {
  EXPECT_EQ(JsonEscapedForLog("plain text 123"), "plain text 123");
  EXPECT_EQ(JsonEscapedForLog("say \"hi\" \\ bye"), "say \\\"hi\\\" \\\\ bye");
  EXPECT_EQ(JsonEscapedForLog("a\nb\tc"), "a\\nb\\tc");
  EXPECT_EQ(JsonEscapedForLog(std::string_view("\x01\x1f\x7f", 3)), "\\u0001\\u001f\\u007f");
  EXPECT_EQ(JsonEscapedForLog(std::string_view("nul\0x", 5)), "nul\\u0000x");
  EXPECT_EQ(JsonEscapedForLog("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80"),
            "caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80");  // é, €, 😀 kept as they are
}

TEST(JsonEscapedForLog, ReplacesBytesThatAreNotUtf8) {
  EXPECT_EQ(JsonEscapedForLog("\xff"), "\\ufffd");
  EXPECT_EQ(JsonEscapedForLog("a\xc3"), "a\\ufffd");                      // truncated sequence
  EXPECT_EQ(JsonEscapedForLog("\xc0\xaf"), "\\ufffd\\ufffd");             // overlong '/'
  EXPECT_EQ(JsonEscapedForLog("\xed\xa0\x80"), "\\ufffd\\ufffd\\ufffd");  // a surrogate
  EXPECT_EQ(JsonEscapedForLog("\xf4\x90\x80\x80"), "\\ufffd\\ufffd\\ufffd\\ufffd");  // > U+10FFFF
  EXPECT_EQ(JsonEscapedForLog("\x80ok"), "\\ufffdok");  // lone continuation byte
}

}  // namespace
}  // namespace pdsm
