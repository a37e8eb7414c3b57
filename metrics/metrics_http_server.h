// The /metrics endpoint of a pdsm service (`--metrics-listen ADDR`): plain HTTP/1.1 (Debian's
// cpp-httplib), GET /metrics answers the Prometheus text that `render` returns, anything else
// is 404. It carries no job contents and asks for no token: bind it to a private address or
// keep the port behind a firewall / NetworkPolicy (docs/service.md, "Metrics").
#ifndef PDSM_METRICS_METRICS_HTTP_SERVER_H_
#define PDSM_METRICS_METRICS_HTTP_SERVER_H_

#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "absl/status/statusor.h"

namespace httplib {
class Server;
}

namespace pdsm {

class MetricsHttpServer {
 public:
  // Listens on `address` ("host:port", "[v6]:port"; port 0 picks one) and serves from a thread
  // of its own. `render` runs on that thread for each scrape: it must be thread-safe against
  // the service. Logs "metrics on http://HOST:PORT/metrics" (the bound address) once it
  // serves. INVALID_ARGUMENT for a malformed address, UNAVAILABLE when it cannot bind.
  static absl::StatusOr<std::unique_ptr<MetricsHttpServer>> Start(
      const std::string& address, std::function<std::string()> render);
  ~MetricsHttpServer();  // stops serving and joins the thread

  // "host:port" with the port actually bound.
  const std::string& address() const { return address_; }

 private:
  MetricsHttpServer() = default;

  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  std::string address_;
};

}  // namespace pdsm

#endif  // PDSM_METRICS_METRICS_HTTP_SERVER_H_
