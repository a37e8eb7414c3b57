#include "metrics/prometheus_text.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace pdsm {
namespace {

// The format's escapes in label values: backslash, double quote, newline.
std::string EscapeLabelValue(const std::string& value) {
  std::string out;
  for (char c : value) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '"') {
      out += "\\\"";
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out += c;
    }
  }
  return out;
}

std::string FormatValue(double value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "+Inf" : "-Inf";
  return absl::StrFormat("%.15g", value);  // integers exact below 1e15; short bucket bounds
}

}  // namespace

void PrometheusText::Family(const std::string& name, const std::string& type,
                            const std::string& help) {
  absl::StrAppend(&text_, "# HELP ", name, " ", help, "\n# TYPE ", name, " ", type, "\n");
}

void PrometheusText::Sample(const std::string& name, double value, const MetricLabels& labels) {
  absl::StrAppend(&text_, name);
  if (!labels.empty()) {
    text_ += '{';
    for (size_t i = 0; i < labels.size(); ++i) {
      absl::StrAppend(&text_, i ? "," : "", labels[i].first, "=\"",
                      EscapeLabelValue(labels[i].second), "\"");
    }
    text_ += '}';
  }
  absl::StrAppend(&text_, " ", FormatValue(value), "\n");
}

void PrometheusText::Gauge(const std::string& name, const std::string& help, double value) {
  Family(name, "gauge", help);
  Sample(name, value);
}

void PrometheusText::Counter(const std::string& name, const std::string& help, double value) {
  Family(name, "counter", help);
  Sample(name, value);
}

void PrometheusText::HistogramFamily(const std::string& name, const std::string& help,
                                     const Histogram::Snapshot& s) {
  Family(name, "histogram", help);
  for (size_t b = 0; b < s.upper_bounds.size(); ++b) {
    Sample(name + "_bucket", static_cast<double>(s.cumulative[b]),
           {{"le", FormatValue(s.upper_bounds[b])}});
  }
  Sample(name + "_bucket", static_cast<double>(s.count), {{"le", "+Inf"}});
  Sample(name + "_sum", s.sum);
  Sample(name + "_count", static_cast<double>(s.count));
}

}  // namespace pdsm
