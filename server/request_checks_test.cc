#include "server/request_checks.h"

#include <gtest/gtest.h>

#include <string>

namespace pdsm {
namespace {

TEST(RequestChecks, JobIdsAreShortAndPlain) {
  EXPECT_TRUE(CheckJobId("0123456789abcdef").ok());
  EXPECT_TRUE(CheckJobId(std::string(64, 'a')).ok());
  for (const std::string& bad : {std::string(), std::string(65, 'a'), std::string("a b"),
                                 std::string("a\nb"), std::string("../x")}) {
    const absl::Status s = CheckJobId(bad);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_EQ(s.message().find(bad.empty() ? "\x01" : bad), std::string::npos) << "echoed";
  }
}

TEST(RequestChecks, WorkerIdsArePrintable) {
  EXPECT_TRUE(CheckWorkerId("host-1234-beef").ok());
  EXPECT_TRUE(CheckWorkerId("a worker with spaces").ok());
  for (const std::string& bad :
       {std::string(), std::string(257, 'w'), std::string("w\n1"), std::string("w\r"),
        std::string("w\x1b[2J"), std::string("caf\xc3\xa9")}) {
    EXPECT_EQ(CheckWorkerId(bad).code(), absl::StatusCode::kInvalidArgument) << bad;
  }
}

TEST(RequestChecks, PrintableEscapesAndBounds) {
  EXPECT_EQ(Printable("plain text", 100), "plain text");
  EXPECT_EQ(Printable("a\nb\x1b", 100), "a\\nb\\x1b");
  const std::string cut = Printable(std::string(1000, 'x'), 10);
  EXPECT_EQ(cut, "xxxxxxxxxx...(1000 bytes)");
  // Never cut inside an escape: "\x1" would read as another byte.
  const std::string escapes = Printable(std::string(10, '\x01'), 9);
  EXPECT_EQ(escapes, "\\x01\\x01...(10 bytes)");
  EXPECT_EQ(escapes.find('\n'), std::string::npos);
}

}  // namespace
}  // namespace pdsm
