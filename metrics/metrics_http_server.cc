#include "metrics/metrics_http_server.h"

#include <httplib.h>
#include <sys/socket.h>

#include <atomic>
#include <chrono>
#include <memory>

#include <spdlog/spdlog.h>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"

namespace pdsm {
namespace {

struct HostPort {
  std::string host;
  int port = 0;
};

absl::StatusOr<HostPort> ParseAddress(const std::string& address) {
  const size_t colon = address.rfind(':');
  if (colon == std::string::npos || colon == 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("--metrics-listen ", address, ": expected HOST:PORT, e.g. 127.0.0.1:9464"));
  }
  HostPort out;
  out.host = address.substr(0, colon);
  if (out.host.size() >= 2 && out.host.front() == '[' && out.host.back() == ']') {
    out.host = out.host.substr(1, out.host.size() - 2);  // [::1]:9464
  }
  if (!absl::SimpleAtoi(address.substr(colon + 1), &out.port) || out.port < 0 || out.port > 65535) {
    return absl::InvalidArgumentError(
        absl::StrCat("--metrics-listen ", address, ": the port must be 0 to 65535"));
  }
  return out;
}

}  // namespace

absl::StatusOr<std::unique_ptr<MetricsHttpServer>> MetricsHttpServer::Start(
    const std::string& address, std::function<std::string()> render) {
  absl::StatusOr<HostPort> where = ParseAddress(address);
  if (!where.ok()) return where.status();
  std::unique_ptr<MetricsHttpServer> server(new MetricsHttpServer());
  server->server_ = std::make_unique<httplib::Server>();
  // cpp-httplib sets SO_REUSEPORT by default, which lets a second process bind the same port
  // and take half the scrapes. SO_REUSEADDR alone: a restart may reuse a port in TIME_WAIT,
  // a port someone listens on is refused.
  server->server_->set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  server->server_->Get("/metrics", [render = std::move(render)](const httplib::Request&,
                                                                httplib::Response& response) {
    response.set_content(render(), "text/plain; version=0.0.4; charset=utf-8");
  });
  int port = where->port;
  if (port == 0) {
    port = server->server_->bind_to_any_port(where->host);
  } else if (!server->server_->bind_to_port(where->host, port)) {
    port = -1;
  }
  if (port < 0) {
    return absl::UnavailableError(absl::StrCat("--metrics-listen ", address, ": cannot bind"));
  }
  const bool v6 = where->host.find(':') != std::string::npos;
  server->address_ =
      v6 ? absl::StrCat("[", where->host, "]:", port) : absl::StrCat(where->host, ":", port);
  httplib::Server* raw = server->server_.get();
  auto ended = std::make_shared<std::atomic<bool>>(false);
  server->thread_ = std::thread([raw, ended] {
    raw->listen_after_bind();
    *ended = true;
  });
  // Until the loop runs, stop() would do nothing and the destructor's join would wait forever:
  // return once it serves (or once it has given up).
  while (!raw->is_running() && !*ended) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (*ended) {
    return absl::UnavailableError(absl::StrCat("--metrics-listen ", address, ": cannot serve"));
  }
  spdlog::info("metrics on http://{}/metrics (no token: keep this port private)", server->address_);
  return server;
}

MetricsHttpServer::~MetricsHttpServer() {
  if (server_) server_->stop();
  if (thread_.joinable()) thread_.join();
}

}  // namespace pdsm
