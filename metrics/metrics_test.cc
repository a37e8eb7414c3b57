#include <httplib.h>

#include <string>

#include <gtest/gtest.h>

#include "metrics/histogram.h"
#include "metrics/metrics_http_server.h"
#include "metrics/prometheus_text.h"

namespace pdsm {
namespace {

TEST(HistogramTest, BucketsAreCumulativeAndTheTotalsAddUp) {
  Histogram h({1, 10});
  for (double v : {0.5, 1.0, 3.0, 10.0, 50.0}) h.Observe(v);
  h.Observe(std::numeric_limits<double>::quiet_NaN());  // not recorded
  const Histogram::Snapshot s = h.Read();
  ASSERT_EQ(s.cumulative.size(), 3u);
  EXPECT_EQ(s.cumulative[0], 2u);  // <= 1: bounds are inclusive
  EXPECT_EQ(s.cumulative[1], 4u);  // <= 10
  EXPECT_EQ(s.cumulative[2], 5u);  // +Inf
  EXPECT_EQ(s.count, 5u);
  EXPECT_DOUBLE_EQ(s.sum, 64.5);
}

TEST(PrometheusTextTest, FamiliesSamplesAndEscapes) {
  PrometheusText out;
  out.Counter("pdsm_things_total", "Things.", 3);
  out.Family("pdsm_labelled", "gauge", "Labelled.");
  out.Sample("pdsm_labelled", 0.25, {{"job", "a\"b\\c\nd"}, {"kind", "x"}});
  Histogram h({0.025, 1});
  h.Observe(0.01);
  h.Observe(2);
  out.HistogramFamily("pdsm_h_seconds", "H.", h.Read());
  EXPECT_EQ(out.text(),
            "# HELP pdsm_things_total Things.\n# TYPE pdsm_things_total counter\n"
            "pdsm_things_total 3\n"
            "# HELP pdsm_labelled Labelled.\n# TYPE pdsm_labelled gauge\n"
            "pdsm_labelled{job=\"a\\\"b\\\\c\\nd\",kind=\"x\"} 0.25\n"
            "# HELP pdsm_h_seconds H.\n# TYPE pdsm_h_seconds histogram\n"
            "pdsm_h_seconds_bucket{le=\"0.025\"} 1\npdsm_h_seconds_bucket{le=\"1\"} 1\n"
            "pdsm_h_seconds_bucket{le=\"+Inf\"} 2\npdsm_h_seconds_sum 2.01\n"
            "pdsm_h_seconds_count 2\n");
}

TEST(MetricsHttpServerTest, ServesMetricsAndNothingElse) {
  int scrapes = 0;
  absl::StatusOr<std::unique_ptr<MetricsHttpServer>> server = MetricsHttpServer::Start(
      "127.0.0.1:0", [&scrapes] { return "pdsm_scrapes " + std::to_string(++scrapes) + "\n"; });
  ASSERT_TRUE(server.ok()) << server.status();
  const std::string address = (*server)->address();
  ASSERT_EQ(address.rfind("127.0.0.1:", 0), 0u) << address;
  httplib::Client client("http://" + address);
  for (int i = 1; i <= 2; ++i) {
    httplib::Result r = client.Get("/metrics");
    ASSERT_TRUE(r) << httplib::to_string(r.error());
    EXPECT_EQ(r->status, 200);
    EXPECT_EQ(r->body, "pdsm_scrapes " + std::to_string(i) + "\n");
    EXPECT_EQ(r->get_header_value("Content-Type"), "text/plain; version=0.0.4; charset=utf-8");
  }
  httplib::Result other = client.Get("/jobs");
  ASSERT_TRUE(other);
  EXPECT_EQ(other->status, 404);
}

TEST(MetricsHttpServerTest, BadAddressesAreRefusedNamingTheFlag) {
  for (const std::string bad : {"nocolon", ":9464", "127.0.0.1:99999", "127.0.0.1:x"}) {
    absl::StatusOr<std::unique_ptr<MetricsHttpServer>> server =
        MetricsHttpServer::Start(bad, [] { return std::string(); });
    ASSERT_FALSE(server.ok()) << bad;
    EXPECT_EQ(server.status().code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_NE(server.status().message().find("--metrics-listen"), absl::string_view::npos);
  }
  // A port already taken.
  absl::StatusOr<std::unique_ptr<MetricsHttpServer>> first =
      MetricsHttpServer::Start("127.0.0.1:0", [] { return std::string(); });
  ASSERT_TRUE(first.ok());
  absl::StatusOr<std::unique_ptr<MetricsHttpServer>> second =
      MetricsHttpServer::Start((*first)->address(), [] { return std::string(); });
  EXPECT_EQ(second.status().code(), absl::StatusCode::kUnavailable);
}

}  // namespace
}  // namespace pdsm
