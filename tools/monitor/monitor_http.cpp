#include "monitor_http.hpp"

#include <arpa/inet.h>
#include <microhttpd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "rgbdtam/runtime/board.hpp"

namespace rgbdtam {
namespace {

// The page, embedded at build time (CMake writes it into this header as a raw string).
#include "monitor_page.inc"

MHD_Result respond(MHD_Connection* connection, unsigned status, const char* type, void* body,
                   size_t size, MHD_ResponseMemoryMode mode) {
  MHD_Response* response = MHD_create_response_from_buffer(size, body, mode);
  if (response == nullptr) return MHD_NO;
  MHD_add_response_header(response, "Content-Type", type);
  MHD_add_response_header(response, "Cache-Control", "no-store");
  const MHD_Result queued = MHD_queue_response(connection, status, response);
  MHD_destroy_response(response);
  return queued;
}

MHD_Result on_request(void* context, MHD_Connection* connection, const char* url,
                      const char* method, const char*, const char*, size_t*, void**) {
  auto* http = static_cast<MonitorHttp*>(context);
  if (std::strcmp(method, "GET") != 0) {
    static char refused[] = "only GET\n";
    return respond(connection, MHD_HTTP_METHOD_NOT_ALLOWED, "text/plain", refused,
                   std::strlen(refused), MHD_RESPMEM_PERSISTENT);
  }
  if (std::strcmp(url, "/") == 0) {
    return respond(connection, MHD_HTTP_OK, "text/html; charset=utf-8",
                   const_cast<char*>(kMonitorPage), std::strlen(kMonitorPage),
                   MHD_RESPMEM_PERSISTENT);
  }
  if (std::strcmp(url, "/state.json") == 0) {
    const char* since_text =
        MHD_lookup_connection_value(connection, MHD_GET_ARGUMENT_KIND, "since");
    const long long since = since_text != nullptr ? std::atoll(since_text) : 0;
    char* body = nullptr;
    size_t size = 0;
    std::FILE* out = open_memstream(&body, &size);
    if (out == nullptr) return MHD_NO;
    {
      std::lock_guard<std::mutex> guard(*http->lock_);
      const size_t points = http->state_->track.size();
      http->state_->write_json(out, since < 0                             ? 0
                                    : static_cast<size_t>(since) > points ? points
                                                                          : since);
    }
    std::fclose(out);
    return respond(connection, MHD_HTTP_OK, "application/json", body, size, MHD_RESPMEM_MUST_FREE);
  }
  static char missing[] = "not found\n";
  return respond(connection, MHD_HTTP_NOT_FOUND, "text/plain", missing, std::strlen(missing),
                 MHD_RESPMEM_PERSISTENT);
}

}  // namespace

Status MonitorHttp::start(const char* address, const MonitorState* state, std::mutex* lock,
                          const HttpLimits& limits) {
  char ip[64];
  if (!split_endpoint(address, ip, sizeof(ip), &port_)) {
    return Status::error(StatusCode::kInvalidArgument, "--http '%s' is not ip:port", address);
  }
  sockaddr_in where{};
  where.sin_family = AF_INET;
  where.sin_port = htons(port_);
  if (inet_pton(AF_INET, ip, &where.sin_addr) != 1) {
    return Status::error(StatusCode::kInvalidArgument, "--http '%s': '%s' is not an IPv4 address",
                         address, ip);
  }
  state_ = state;
  lock_ = lock;
  // poll or epoll, not select: select cannot watch a descriptor numbered past FD_SETSIZE (1024),
  // and libmicrohttpd then resets every new connection.
  daemon_ =
      MHD_start_daemon(MHD_USE_AUTO_INTERNAL_THREAD | MHD_USE_ERROR_LOG, port_, nullptr, nullptr,
                       &on_request, this, MHD_OPTION_SOCK_ADDR, &where, MHD_OPTION_CONNECTION_LIMIT,
                       limits.connections, MHD_OPTION_PER_IP_CONNECTION_LIMIT, limits.per_client,
                       MHD_OPTION_CONNECTION_TIMEOUT, limits.idle_s, MHD_OPTION_END);
  if (daemon_ == nullptr) {
    return Status::error(StatusCode::kIoError, "--http %s: cannot listen there (in use?)", address);
  }
  return Status::ok();
}

void MonitorHttp::stop() {
  if (daemon_ != nullptr) MHD_stop_daemon(daemon_);
  daemon_ = nullptr;
}

}  // namespace rgbdtam
