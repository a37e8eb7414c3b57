// Writing the Prometheus text exposition format (version 0.0.4): one HELP and TYPE line per
// metric family, then its samples. Names are the caller's (snake case, "pdsm_" prefixed,
// counters ending in _total); label values are escaped here. Not thread-safe.
#ifndef PDSM_METRICS_PROMETHEUS_TEXT_H_
#define PDSM_METRICS_PROMETHEUS_TEXT_H_

#include <string>
#include <utility>
#include <vector>

#include "metrics/histogram.h"

namespace pdsm {

using MetricLabels = std::vector<std::pair<std::string, std::string>>;

class PrometheusText {
 public:
  // A family's header; its samples follow with Sample(). `type`: "gauge" or "counter".
  void Family(const std::string& name, const std::string& type, const std::string& help);
  void Sample(const std::string& name, double value, const MetricLabels& labels = {});
  // Family + one sample.
  void Gauge(const std::string& name, const std::string& help, double value);
  void Counter(const std::string& name, const std::string& help, double value);
  // A whole histogram family: NAME_bucket{le=...}, NAME_sum, NAME_count.
  void HistogramFamily(const std::string& name, const std::string& help,
                       const Histogram::Snapshot& snapshot);

  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

}  // namespace pdsm

#endif  // PDSM_METRICS_PROMETHEUS_TEXT_H_
