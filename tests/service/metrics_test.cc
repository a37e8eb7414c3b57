// pdsm-coordinator --metrics-listen: Prometheus text at GET /metrics, with no token although
// both APIs have one, whose values move as a real bake runs (queue depth, leases, results,
// task seconds, jobs by state, bytes stored, per-job progress).
#include <httplib.h>

#include <fstream>
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "core/util/version.h"
#include "tests/service/service_cluster.h"

namespace pdsm::testing {
namespace {

using std::chrono::seconds;

// The value of the sample `series` (name and labels exactly as exposed), or nullopt.
std::optional<double> SampleValue(const std::string& text, const std::string& series) {
  const std::string prefix = series + " ";
  size_t at = 0;
  while ((at = text.find(prefix, at)) != std::string::npos) {
    if (at == 0 || text[at - 1] == '\n') {
      return std::stod(text.substr(at + prefix.size(), text.find('\n', at) - at));
    }
    at += prefix.size();
  }
  return std::nullopt;
}

class CoordinatorMetrics : public ::testing::Test {
 protected:
  void SetUp() override {
    cluster_ = std::make_unique<ServiceCluster>(
        WithTokens({"--metrics-listen", "127.0.0.1:0", "--samples-per-task", "8"}));
    ASSERT_TRUE(cluster_->StartCoordinator()) << cluster_->Log("coordinator.log");
    // Line 2 of the ready file: "metrics HOST:PORT".
    std::ifstream ready(cluster_->dir().File("ready"));
    std::string grpc_line, metrics_line;
    std::getline(ready, grpc_line);
    std::getline(ready, metrics_line);
    ASSERT_EQ(metrics_line.rfind("metrics 127.0.0.1:", 0), 0u) << metrics_line;
    client_ = std::make_unique<httplib::Client>("http://" + metrics_line.substr(8));
  }

  std::string Scrape() {
    httplib::Result r = client_->Get("/metrics");  // no token
    EXPECT_TRUE(r) << httplib::to_string(r.error());
    if (!r) return "";
    EXPECT_EQ(r->status, 200);
    return r->body;
  }
  double Value(const std::string& text, const std::string& series) {
    const std::optional<double> v = SampleValue(text, series);
    EXPECT_TRUE(v) << series << " missing from:\n" << text;
    return v.value_or(-1);
  }

  std::unique_ptr<ServiceCluster> cluster_;
  std::unique_ptr<httplib::Client> client_;
};

TEST_F(CoordinatorMetrics, ValuesMoveDuringABakeAndNeedNoToken) {
  std::string text = Scrape();
  EXPECT_NE(text.find("# TYPE pdsm_task_seconds histogram"), std::string::npos) << text;
  EXPECT_EQ(Value(text, "pdsm_build_info{version=\"" + std::string(ProjectVersion()) +
                            "\",commit=\"" + std::string(GitCommit()) + "\"}"),
            1);
  EXPECT_EQ(Value(text, "pdsm_results_total{outcome=\"accepted\"}"), 0);
  EXPECT_EQ(Value(text, "pdsm_jobs{state=\"succeeded\"}"), 0);
  EXPECT_EQ(Value(text, "pdsm_workers_active"), 0);
  EXPECT_EQ(Value(text, "pdsm_task_seconds_count"), 0);
  // Failures by code: every code is there from the start, at zero.
  EXPECT_EQ(Value(text, "pdsm_task_failures_total{code=\"resource_exhausted\"}"), 0);
  EXPECT_EQ(Value(text, "pdsm_task_failures_total{code=\"internal\"}"), 0);

  // A job and no worker yet: it waits, its tasks are the queue, it is far from done.
  const std::string scene = WriteServiceScene(cluster_->dir(), 128, 128, 32, 512);
  const std::string job_id = cluster_->Submit(scene);
  text = Scrape();
  EXPECT_EQ(Value(text, "pdsm_jobs{state=\"queued\"}"), 1);
  EXPECT_GT(Value(text, "pdsm_tasks{state=\"pending\"}"), 0);
  EXPECT_EQ(Value(text, "pdsm_tasks{state=\"leased\"}"), 0);
  // Tiles no caster reaches are stored without a task, so a waiting job may be past 0.
  const double progress = Value(text, "pdsm_job_progress{job=\"" + job_id + "\"}");
  EXPECT_GE(progress, 0);
  EXPECT_LT(progress, 1);

  cluster_->AddWorker();
  const pdsm::v1::Job job = cluster_->WaitForEnd(job_id);
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  text = Scrape();
  const double accepted = Value(text, "pdsm_results_total{outcome=\"accepted\"}");
  EXPECT_GT(accepted, 0);
  EXPECT_GE(Value(text, "pdsm_leases_issued_total"), accepted);
  EXPECT_EQ(Value(text, "pdsm_task_seconds_count"), accepted);
  EXPECT_EQ(Value(text, "pdsm_task_seconds_bucket{le=\"+Inf\"}"), accepted);
  EXPECT_GT(Value(text, "pdsm_task_seconds_sum"), 0);
  EXPECT_EQ(Value(text, "pdsm_jobs{state=\"succeeded\"}"), 1);
  EXPECT_EQ(Value(text, "pdsm_jobs{state=\"queued\"}"), 0);
  EXPECT_EQ(Value(text, "pdsm_pdsm_bytes_stored"), static_cast<double>(job.pdsm_bytes()));
  EXPECT_EQ(Value(text, "pdsm_workers_active"), 1);
  EXPECT_EQ(Value(text, "pdsm_tasks{state=\"pending\"}"), 0);
  EXPECT_EQ(text.find("pdsm_job_progress{"), std::string::npos) << "the job has ended";
  // Nothing of the job but its id: no scene name, no error text.
  EXPECT_EQ(text.find(job.scene_name()), std::string::npos);
}

// pdsm-worker --metrics-listen: its own tasks and where their time goes.
TEST_F(CoordinatorMetrics, WorkerCountsItsTasksAndTheirTime) {
  const size_t worker = cluster_->AddWorker(1, {"--metrics-listen", "127.0.0.1:0"});
  // Its log names the address once it serves.
  std::string address;
  const auto deadline = std::chrono::steady_clock::now() + seconds(30);
  while (address.empty() && std::chrono::steady_clock::now() < deadline) {
    const std::string log = cluster_->Log("worker0.log");
    const size_t at = log.find("metrics on http://");
    if (at != std::string::npos) {
      const size_t begin = at + std::string("metrics on http://").size();
      address = log.substr(begin, log.find("/metrics", begin) - begin);
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  ASSERT_FALSE(address.empty()) << cluster_->Log("worker0.log");
  httplib::Client worker_metrics("http://" + address);
  const auto scrape = [&] {
    httplib::Result r = worker_metrics.Get("/metrics");
    EXPECT_TRUE(r) << httplib::to_string(r.error());
    return r ? r->body : std::string();
  };
  std::string text = scrape();
  EXPECT_EQ(Value(text, "pdsm_worker_threads"), 1);
  EXPECT_EQ(Value(text, "pdsm_worker_results_total{outcome=\"accepted\"}"), 0);

  const std::string scene = WriteServiceScene(cluster_->dir(), 128, 128, 32, 512);
  const pdsm::v1::Job job = cluster_->WaitForEnd(cluster_->Submit(scene));
  ASSERT_EQ(job.state(), pdsm::v1::SUCCEEDED) << job.error();
  text = scrape();
  const double accepted = Value(text, "pdsm_worker_results_total{outcome=\"accepted\"}");
  EXPECT_GT(accepted, 0);
  // The coordinator counted the same results (one worker).
  EXPECT_EQ(Value(Scrape(), "pdsm_results_total{outcome=\"accepted\"}"), accepted);
  EXPECT_EQ(Value(text, "pdsm_worker_task_seconds_count"), accepted);
  EXPECT_EQ(Value(text, "pdsm_worker_shadow_map_seconds_count"), accepted);
  EXPECT_GT(Value(text, "pdsm_worker_shadow_map_seconds_sum"), 0);
  EXPECT_GT(Value(text, "pdsm_worker_scan_seconds_sum"), 0);
  EXPECT_GT(Value(text, "pdsm_worker_events_total"), 0);
  EXPECT_EQ(Value(text, "pdsm_worker_tasks_running"), 0);
  EXPECT_EQ(Value(text, "pdsm_worker_task_returns_total{kind=\"failed\"}"), 0);
  EXPECT_TRUE(cluster_->worker(worker).running());
}

}  // namespace
}  // namespace pdsm::testing
