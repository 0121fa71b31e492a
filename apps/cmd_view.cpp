// `medspring view`: serves the browser page (web/index.html, app.js and its modules in app/, the wasm
// engine dist/medspring.mjs, three.js from web/node_modules/three) and a folder of model packages on
// 127.0.0.1 with a tiny single-threaded HTTP/1.1 server (POSIX sockets, poll; one response per
// connection). docs/web.md.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "scene_support.hpp"

#ifndef MEDSPRING_SOURCE_WEB_DIR
#define MEDSPRING_SOURCE_WEB_DIR "web"
#endif

namespace medspring::cli {

namespace {

namespace fs = std::filesystem;

volatile std::sig_atomic_t g_stop = 0;
extern "C" void on_stop_signal(int) {
  g_stop = 1;
}

constexpr std::size_t kMaxRequestHead = 16 * 1024;
constexpr double kConnectionTimeout = 10.0;  // s without progress: the connection is dropped

std::string mime_type(const fs::path& file) {
  std::string ext = file.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".html" || ext == ".htm") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".wasm") return "application/wasm";
  if (ext == ".json" || ext == ".map") return "application/json";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".png") return "image/png";
  if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".ico") return "image/x-icon";
  if (ext == ".txt" || ext == ".md") return "text/plain; charset=utf-8";
  if (ext == ".csv") return "text/csv; charset=utf-8";
  return "application/octet-stream";  // .msm model packages and anything else
}

/// Percent-decodes a URL path; false for a malformed escape or a decoded NUL.
bool url_decode(const std::string& in, std::string& out) {
  out.clear();
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (in[i] != '%') {
      out += in[i];
      continue;
    }
    if (i + 2 >= in.size() || !std::isxdigit(static_cast<unsigned char>(in[i + 1])) ||
        !std::isxdigit(static_cast<unsigned char>(in[i + 2])))
      return false;
    const char c = static_cast<char>(std::stoi(in.substr(i + 1, 2), nullptr, 16));
    if (c == '\0') return false;
    out += c;
    i += 2;
  }
  return true;
}

struct Response {
  int status = 200;
  std::string reason = "OK", type = "text/plain; charset=utf-8", body;
  bool head = false;  // HEAD: headers only
  std::vector<std::string> extra;
};

Response error_response(int status, const std::string& reason, const std::string& detail) {
  Response r;
  r.status = status;
  r.reason = reason;
  r.body = cat(status, " ", reason, ": ", detail, "\n");
  return r;
}

std::string serialize(const Response& r) {
  std::ostringstream os;
  os << "HTTP/1.1 " << r.status << " " << r.reason << "\r\n"
     << "Content-Type: " << r.type << "\r\n"
     << "Content-Length: " << r.body.size() << "\r\n"
     << "Cache-Control: no-cache\r\n"
     << "X-Content-Type-Options: nosniff\r\n"
     // Cross-origin isolation gives the page 5 µs timers (tick timing) instead of 100 µs.
     << "Cross-Origin-Opener-Policy: same-origin\r\n"
     << "Cross-Origin-Embedder-Policy: require-corp\r\n"
     << "Cross-Origin-Resource-Policy: same-origin\r\n";
  for (const std::string& h : r.extra) os << h << "\r\n";
  os << "Connection: close\r\n\r\n";
  std::string out = os.str();
  if (!r.head) out += r.body;
  return out;
}

struct Site {
  fs::path web;     // canonical web/ folder
  fs::path models;  // canonical models folder (empty: none)
};

bool within(const fs::path& root, const fs::path& p) {
  auto r = root.begin(), q = p.begin();
  for (; r != root.end(); ++r, ++q)
    if (q == p.end() || *r != *q) return false;
  return true;
}

/// Maps a request target to a file: "/" -> index.html, /models/... -> the models folder,
/// /node_modules/ -> only three.js (build/ and examples/jsm/), anything else under web/.
Response serve(const Site& site, const std::string& method, const std::string& target) {
  if (method != "GET" && method != "HEAD") {
    Response r = error_response(405, "Method Not Allowed", method);
    r.extra.push_back("Allow: GET, HEAD");
    return r;
  }
  std::string raw = target.substr(0, target.find_first_of("?#"));
  std::string path;
  if (raw.empty() || raw[0] != '/' || !url_decode(raw, path))
    return error_response(400, "Bad Request", target);
  if (path.find('\\') != std::string::npos) return error_response(403, "Forbidden", target);
  std::vector<std::string> parts;
  std::stringstream ss(path);
  for (std::string seg; std::getline(ss, seg, '/');) {
    if (seg.empty() || seg == ".") continue;
    if (seg == "..") return error_response(403, "Forbidden", cat(target, " (path traversal)"));
    parts.push_back(seg);
  }
  if (parts.empty()) parts.push_back("index.html");
  fs::path root = site.web, file = site.web;
  std::size_t first = 0;
  if (parts[0] == "models") {
    if (site.models.empty())
      return error_response(404, "Not Found", cat(target, " (no models folder: --models DIR)"));
    root = file = site.models;
    first = 1;
  } else if (parts[0] == "node_modules") {
    const bool three = parts.size() > 3 && parts[1] == "three" &&
                       (parts[2] == "build" || (parts[2] == "examples" && parts[3] == "jsm"));
    if (!three)
      return error_response(403, "Forbidden", cat(target, " (only three.js is served from node_modules)"));
  }
  for (std::size_t k = first; k < parts.size(); ++k) file /= parts[k];
  std::error_code ec;
  const fs::path real = fs::weakly_canonical(file, ec);
  if (ec || !within(root, real))
    return error_response(403, "Forbidden", cat(target, " (outside the served folders)"));
  if (!fs::is_regular_file(real, ec)) return error_response(404, "Not Found", target);
  std::ifstream in(real, std::ios::binary);
  if (!in) return error_response(403, "Forbidden", cat(target, " (unreadable)"));
  Response r;
  r.type = mime_type(real);
  r.body.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  r.head = method == "HEAD";
  return r;
}

struct Connection {
  int fd = -1;
  std::string in, out;
  std::size_t sent = 0;
  bool responding = false;
  std::chrono::steady_clock::time_point last;
};

void set_nonblocking(int fd) {
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL, 0) | O_NONBLOCK);
}

/// Parses the request head once it is complete and queues the response.
void respond(const Site& site, Connection& c, bool quiet) {
  const std::size_t line_end = c.in.find("\r\n");
  std::istringstream line(c.in.substr(0, line_end));
  std::string method, target, version;
  line >> method >> target >> version;
  Response r;
  if (method.empty() || target.empty() || version.rfind("HTTP/1.", 0) != 0)
    r = error_response(400, "Bad Request", "malformed request line");
  else
    r = serve(site, method, target);
  if (!quiet) std::fprintf(stderr, "%s %s %d %zu\n", method.c_str(), target.c_str(), r.status, r.body.size());
  c.out = serialize(r);
  c.responding = true;
}

}  // namespace

int cmd_view(const Args& args) {
  args.require_known({"port", "models", "web", "exit-after", "quiet"});
  const long port = args.integer("port", 8080);
  if (port < 0 || port > 65535) throw InvalidInput(cat("--port: ", port, " out of range [0, 65535]"));
  const double exit_after = args.number("exit-after", 0.0);
  require_nonnegative(exit_after, "--exit-after", "seconds");
  const bool quiet = args.flag("quiet");

  Site site;
  site.web =
      fs::canonical(find_folder(args.get("web"), MEDSPRING_SOURCE_WEB_DIR, "web", "web page", "index.html"));
  std::error_code ec;
  if (const auto m = args.get("models")) {
    if (!fs::is_directory(*m, ec)) throw IoError(cat("--models ", *m, ": not a folder"));
    site.models = fs::canonical(*m);
  } else if (fs::is_directory(site.web / "models", ec)) {
    site.models = fs::canonical(site.web / "models");
  }
  if (!fs::exists(site.web / "dist" / "medspring.mjs", ec))
    std::fprintf(stderr,
                 "medspring view: warning: %s missing (build the engine: bash web/build.sh); the page "
                 "will show an error\n",
                 (site.web / "dist" / "medspring.mjs").c_str());
  if (!fs::exists(site.web / "node_modules" / "three" / "build" / "three.module.js", ec))
    std::fprintf(stderr, "medspring view: warning: three.js missing in %s (run npm ci in web/)\n",
                 (site.web / "node_modules").c_str());

  const int lfd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (lfd < 0) throw IoError(cat("socket: ", std::strerror(errno)));
  const int one = 1;
  ::setsockopt(lfd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(lfd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || ::listen(lfd, 64) != 0) {
    const std::string why = std::strerror(errno);
    ::close(lfd);
    throw IoError(cat("cannot listen on 127.0.0.1:", port, ": ", why, port ? " (try --port 0)" : ""));
  }
  socklen_t len = sizeof addr;
  ::getsockname(lfd, reinterpret_cast<sockaddr*>(&addr), &len);
  set_nonblocking(lfd);

  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  ::sigaction(SIGINT, &sa, nullptr);
  ::sigaction(SIGTERM, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);

  std::printf("MedSpring viewer: http://127.0.0.1:%d/\n", ntohs(addr.sin_port));
  std::printf("  page   %s\n  models %s\n  (Ctrl-C to stop)\n", site.web.c_str(),
              site.models.empty() ? "(none: built-in models only; --models DIR)" : site.models.c_str());
  std::fflush(stdout);

  using clock = std::chrono::steady_clock;
  const auto started = clock::now();
  std::vector<Connection> conns;
  std::vector<pollfd> fds;
  while (!g_stop) {
    if (exit_after > 0 && std::chrono::duration<double>(clock::now() - started).count() > exit_after) break;
    fds.assign(1, pollfd{lfd, POLLIN, 0});
    for (const Connection& c : conns)
      fds.push_back(pollfd{c.fd, static_cast<short>(c.responding ? POLLOUT : POLLIN), 0});
    if (::poll(fds.data(), fds.size(), 200) < 0) {
      if (errno == EINTR) continue;
      throw IoError(cat("poll: ", std::strerror(errno)));
    }
    const auto now = clock::now();
    for (std::size_t k = 0; k < conns.size(); ++k) {
      Connection& c = conns[k];
      const short ev = fds[k + 1].revents;
      bool done = false;
      if (!c.responding && (ev & (POLLIN | POLLHUP | POLLERR))) {
        char buf[4096];
        const ssize_t n = ::recv(c.fd, buf, sizeof buf, 0);
        if (n > 0) {
          c.in.append(buf, static_cast<std::size_t>(n));
          c.last = now;
          if (c.in.find("\r\n\r\n") != std::string::npos) {
            respond(site, c, quiet);
          } else if (c.in.size() > kMaxRequestHead) {
            c.out =
                serialize(error_response(431, "Request Header Fields Too Large", "request head over 16 KiB"));
            c.responding = true;
          }
        } else if (n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
          done = true;
        }
      } else if (c.responding && (ev & (POLLOUT | POLLHUP | POLLERR))) {
        const ssize_t n = ::send(c.fd, c.out.data() + c.sent, c.out.size() - c.sent, MSG_NOSIGNAL);
        if (n > 0) {
          c.sent += static_cast<std::size_t>(n);
          c.last = now;
          done = c.sent == c.out.size();
        } else if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
          done = true;
        }
      }
      if (!done && std::chrono::duration<double>(now - c.last).count() > kConnectionTimeout) done = true;
      if (done) {
        ::close(c.fd);
        c.fd = -1;
      }
    }
    std::erase_if(conns, [](const Connection& c) { return c.fd < 0; });
    if (fds[0].revents & POLLIN) {
      for (;;) {
        const int fd = ::accept(lfd, nullptr, nullptr);
        if (fd < 0) break;
        set_nonblocking(fd);
        conns.push_back(Connection{fd, {}, {}, 0, false, now});
      }
    }
  }
  for (const Connection& c : conns) ::close(c.fd);
  ::close(lfd);
  std::printf("MedSpring viewer: stopped\n");
  std::fflush(stdout);
  return 0;
}

}  // namespace medspring::cli
