// ConeLOD CLI — `conelod serve FILE.clod [--port P]`: the web viewer (web/) and one .clod file on
// localhost, with HTTP Range requests, so that a browser reads only the byte ranges it needs.
//
// A small HTTP/1.1 server on plain POSIX sockets, one thread per connection. It serves a fixed
// table of files and nothing else: the page's own files and its libraries (three.js, the meshopt
// decoder), read into memory at start, and the .clod file, opened once and read with pread. A
// request path is looked up in that table as it is (after percent-decoding): there is no path
// to resolve, so "..", encoded or not, can only miss (404). GET and HEAD; `Range: bytes=a-b`,
// `bytes=a-` and `bytes=-n` (206 with Content-Range), 416 for a range that is malformed or starts
// past the end, 200 with the whole file for several ranges (RFC 9110 lets a server ignore Range).
// Binds to 127.0.0.1 unless --host says otherwise. Ctrl-C (SIGINT) stops it.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "cli_common.h"
#include "commands.h"
#include "conelod/lod/lod_read.h"
#include "conelod/mesh/safe_file.h"

#ifndef CONELOD_WEB_SOURCE_DIR
#define CONELOD_WEB_SOURCE_DIR ""
#endif
#ifndef CONELOD_WEB_INSTALL_DIR
#define CONELOD_WEB_INSTALL_DIR "share/conelod/web"
#endif

namespace conelod {
namespace cli {

const char* kServeUsage =
    "  serve FILE.clod [--port P] [--host ADDR] [--web DIR]\n"
    "      serves the web viewer and FILE.clod on http://127.0.0.1:P/ (HTTP Range requests) and\n"
    "      prints the viewer's URL; Ctrl-C stops it. --port 0 (default 8080): a free port.\n"
    "      Each request is logged on stdout: METHOD PATH STATUS RANGE BYTES.\n";

namespace {

// The page's files, relative to the web folder: the page, its modules, and the libraries from
// npm (web/node_modules, installed by scripts/setup.sh with `npm ci`) at the same relative paths.
const char* const kWebFiles[] = {
    "index.html",
    "clod.js",
    "refine.js",
    "viewer.js",
    "node_modules/three/build/three.module.js",
    "node_modules/three/build/three.core.js",
    "node_modules/three/examples/jsm/controls/OrbitControls.js",
    "node_modules/meshoptimizer/meshopt_decoder.mjs",
};

struct Resource {
  std::string type;
  std::string body;  // the page's files
  int fd = -1;       // the .clod file
  uint64_t size = 0;
};

std::string ContentType(const std::string& path) {
  auto ends = [&](const char* s) {
    const size_t n = std::strlen(s);
    return path.size() >= n && path.compare(path.size() - n, n, s) == 0;
  };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".js") || ends(".mjs")) return "text/javascript; charset=utf-8";
  return "application/octet-stream";
}

bool ReadWhole(const std::string& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  out = s.str();
  return bool(in) || in.eof();
}

bool IsFile(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// Where the page is: --web DIR, else $CONELOD_WEB_DIR, else installed beside the executable
// (PREFIX/bin/conelod -> PREFIX/share/conelod/web), else the source tree this was built from.
std::string FindWebDir(const std::string& given, std::string& tried) {
  std::vector<std::string> dirs;
  if (!given.empty()) {
    dirs.push_back(given);
  } else {
    if (const char* env = std::getenv("CONELOD_WEB_DIR")) dirs.push_back(env);
    char exe[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n > 0) {
      std::string bin(exe, size_t(n));
      bin = bin.substr(0, bin.rfind('/'));
      dirs.push_back(bin.substr(0, bin.rfind('/')) + "/" + CONELOD_WEB_INSTALL_DIR);
    }
    if (*CONELOD_WEB_SOURCE_DIR) dirs.push_back(CONELOD_WEB_SOURCE_DIR);
  }
  for (const auto& d : dirs) {
    tried += (tried.empty() ? "" : ", ") + d;
    if (IsFile(d + "/index.html")) return d;
  }
  return "";
}

std::string PercentDecode(const std::string& s, bool& ok) {
  std::string out;
  ok = true;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '%') {
      out += s[i];
      continue;
    }
    if (i + 2 >= s.size() || !isxdigit(uint8_t(s[i + 1])) || !isxdigit(uint8_t(s[i + 2]))) {
      ok = false;
      return "";
    }
    out += char(std::strtol(s.substr(i + 1, 2).c_str(), nullptr, 16));
    i += 2;
  }
  return out;
}

std::string PercentEncode(const std::string& s) {
  std::string out;
  for (unsigned char c : s) {
    if (isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += char(c);
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      out += hex;
    }
  }
  return out;
}

bool SendAll(int fd, const char* p, size_t n) {
  while (n > 0) {
    const ssize_t w = ::send(fd, p, n, MSG_NOSIGNAL);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= size_t(w);
  }
  return true;
}

// Parses a Range header's value against a resource of `size` bytes. Returns 0: no range (serve
// it whole), 1: one range [first, last], -1: unsatisfiable or malformed (416).
int ParseRange(const std::string& value, uint64_t size, uint64_t& first, uint64_t& last) {
  std::string v;
  for (char c : value)
    if (c != ' ' && c != '\t') v += c;
  if (v.compare(0, 6, "bytes=") != 0) return -1;
  v = v.substr(6);
  if (v.find(',') != std::string::npos) return 0;  // several ranges: the whole file (RFC 9110 §14.2)
  const size_t dash = v.find('-');
  if (dash == std::string::npos) return -1;
  const std::string a = v.substr(0, dash), b = v.substr(dash + 1);
  auto number = [](const std::string& s, uint64_t& out) {
    if (s.empty() || s.size() > 19) return false;
    for (char c : s)
      if (c < '0' || c > '9') return false;
    out = std::strtoull(s.c_str(), nullptr, 10);
    return true;
  };
  if (a.empty()) {  // the last n bytes
    uint64_t n = 0;
    if (!number(b, n) || n == 0 || size == 0) return -1;
    first = n >= size ? 0 : size - n;
    last = size - 1;
    return 1;
  }
  if (!number(a, first) || first >= size) return -1;
  if (b.empty()) {
    last = size - 1;
  } else {
    if (!number(b, last) || last < first) return -1;
    if (last >= size) last = size - 1;
  }
  return 1;
}

class Server {
 public:
  std::map<std::string, Resource> files;  // request path -> what it serves
  std::mutex logMutex;

  void Log(const std::string& line) {
    std::lock_guard<std::mutex> lock(logMutex);
    std::fprintf(stdout, "%s\n", line.c_str());
    std::fflush(stdout);
  }

  // Serves one connection: requests until the client closes it or is idle for 30 s.
  void Connection(int fd) {
    timeval tv{30, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    const int one = 1;  // no Nagle delay between a reply's header and its body
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    std::string pending;
    char buf[8192];
    for (;;) {
      size_t end;
      while ((end = pending.find("\r\n\r\n")) == std::string::npos) {
        if (pending.size() > 64 * 1024) {
          Reply(fd, 431, "request header too large", "", "");
          ::close(fd);
          return;
        }
        const ssize_t r = ::recv(fd, buf, sizeof buf, 0);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) {
          ::close(fd);
          return;
        }
        pending.append(buf, size_t(r));
      }
      const std::string head = pending.substr(0, end);
      pending.erase(0, end + 4);
      if (!Handle(fd, head)) break;
    }
    ::close(fd);
  }

 private:
  bool Reply(int fd, int status, const std::string& reason, const std::string& headers, const std::string& body,
             bool withBody = true) {
    std::string r = "HTTP/1.1 " + std::to_string(status) + " " + reason + "\r\n" + headers +
                    "Content-Length: " + std::to_string(body.size()) +
                    "\r\nContent-Type: text/plain; charset=utf-8\r\nConnection: close\r\n\r\n";
    if (withBody) r += body;
    SendAll(fd, r.data(), r.size());
    return false;  // the connection closes after an error
  }

  // Handles one request (its header block); false: close the connection.
  bool Handle(int fd, const std::string& head) {
    std::istringstream lines(head);
    std::string requestLine;
    std::getline(lines, requestLine);
    if (!requestLine.empty() && requestLine.back() == '\r') requestLine.pop_back();
    std::istringstream rl(requestLine);
    std::string method, target, version;
    rl >> method >> target >> version;
    std::map<std::string, std::string> h;
    for (std::string line; std::getline(lines, line);) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      const size_t colon = line.find(':');
      if (colon == std::string::npos) continue;
      std::string name = line.substr(0, colon), value = line.substr(colon + 1);
      for (char& c : name) c = char(tolower(uint8_t(c)));
      const size_t s = value.find_first_not_of(" \t");
      h[name] = s == std::string::npos ? "" : value.substr(s);
    }
    if (version.compare(0, 5, "HTTP/") != 0 || target.empty() || target[0] != '/') {
      Log(method + " " + target + " 400");
      return Reply(fd, 400, "Bad Request", "", "bad request\n");
    }
    const bool isHead = method == "HEAD";
    if (method != "GET" && !isHead) {
      Log(method + " " + target + " 405");
      return Reply(fd, 405, "Method Not Allowed", "Allow: GET, HEAD\r\n", "only GET and HEAD\n");
    }
    std::string path = target.substr(0, target.find_first_of("?#"));
    bool ok = true;
    path = PercentDecode(path, ok);
    if (path == "/") path = "/index.html";
    const auto it = ok ? files.find(path) : files.end();
    if (it == files.end()) {
      Log(method + " " + target + " 404");
      return Reply(fd, 404, "Not Found", "", "not found\n", !isHead);
    }
    const Resource& res = it->second;
    const uint64_t size = res.fd >= 0 ? res.size : res.body.size();
    uint64_t first = 0, last = size ? size - 1 : 0;
    int status = 200;
    const auto range = h.find("range");
    if (range != h.end()) {
      const int kind = ParseRange(range->second, size, first, last);
      if (kind < 0) {
        Log(method + " " + path + " 416 " + range->second);
        return Reply(fd, 416, "Range Not Satisfiable", "Content-Range: bytes */" + std::to_string(size) + "\r\n",
                     "range not satisfiable\n", !isHead);
      }
      if (kind == 1) status = 206;
    }
    const uint64_t length = size ? last - first + 1 : 0;
    std::string r = "HTTP/1.1 " + std::to_string(status) + (status == 206 ? " Partial Content" : " OK") +
                    "\r\nContent-Type: " + res.type + "\r\nContent-Length: " + std::to_string(length) +
                    "\r\nAccept-Ranges: bytes\r\nCache-Control: no-cache\r\n";
    if (status == 206)
      r += "Content-Range: bytes " + std::to_string(first) + "-" + std::to_string(last) + "/" + std::to_string(size) +
           "\r\n";
    std::string connection = h.count("connection") ? h["connection"] : "";
    for (char& ch : connection) ch = char(tolower(uint8_t(ch)));
    const bool keepAlive = version == "HTTP/1.0" ? connection == "keep-alive" : connection != "close";
    r += keepAlive ? "Connection: keep-alive\r\n\r\n" : "Connection: close\r\n\r\n";
    if (!SendAll(fd, r.data(), r.size())) return false;
    uint64_t sent = 0;
    if (!isHead) {
      if (res.fd < 0) {
        if (!SendAll(fd, res.body.data() + first, size_t(length))) return false;
      } else {
        std::vector<char> chunk(1 << 20);
        for (uint64_t at = first; at <= last && length;) {
          const size_t n = size_t(std::min<uint64_t>(chunk.size(), last + 1 - at));
          const ssize_t got = ::pread(res.fd, chunk.data(), n, off_t(at));
          if (got < 0 && errno == EINTR) continue;
          if (got <= 0 || !SendAll(fd, chunk.data(), size_t(got))) return false;
          at += uint64_t(got);
        }
      }
      sent = length;
    }
    Log(method + " " + path + " " + std::to_string(status) + " " +
        (status == 206 ? std::to_string(first) + "-" + std::to_string(last) : std::string("-")) + " " +
        std::to_string(sent));
    return keepAlive;
  }
};

}  // namespace

int CmdServe(int argc, char** argv) {
  Args a(argc, argv, {"--port", "--host", "--web"}, {});
  if (!a.ok()) return Fail(kUsage, a.error() + "\n" + kServeUsage);
  if (a.positional().size() != 1) return Fail(kUsage, std::string("expected one FILE.clod\n") + kServeUsage);
  const std::string path = a.positional()[0];
  const int port = a.integer("--port", 8080);
  if (!a.ok()) return Fail(kUsage, a.error());
  if (port < 0 || port > 65535) return Fail(kUsage, "--port must be in 0..65535");
  const std::string host = a.str("--host", "127.0.0.1");

  // The file: a readable, regular .clod file whose header and roots read (LodReader::Open), named
  // *.clod (so that its name never shadows one of the page's).
  const std::string inputError = CheckInputPath(path);
  if (!inputError.empty()) return Fail(kBadInput, inputError);
  if (path.size() < 6 || path.compare(path.size() - 5, 5, ".clod") != 0 || path[path.size() - 6] == '/')
    return Fail(kBadInput, "'" + path + "' is not named NAME.clod (conelod serve serves a .clod file)");
  {
    std::unique_ptr<LodReader> reader;
    const Status s = LodReader::Open(path, reader);
    if (!s.ok()) return Fail(kBadInput, s.message);
  }
  Server server;
  std::string tried;
  const std::string web = FindWebDir(a.str("--web"), tried);
  if (web.empty()) return Fail(kIoError, "the web viewer's page (index.html) is not in " + tried);
  for (const char* f : kWebFiles) {
    Resource r;
    r.type = ContentType(f);
    if (!ReadWhole(web + "/" + f, r.body))
      return Fail(kIoError, "cannot read the web viewer's file " + web + "/" + f +
                                (std::strncmp(f, "node_modules/", 13) == 0
                                     ? " (its libraries come from npm: run scripts/setup.sh, or `npm ci` in web/)"
                                     : ""));
    server.files["/" + std::string(f)] = std::move(r);
  }
  Resource clod;
  clod.type = "application/octet-stream";
  clod.fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st;
  if (clod.fd < 0 || fstat(clod.fd, &st) != 0)
    return Fail(kIoError, "cannot read '" + path + "': " + std::strerror(errno));
  clod.size = uint64_t(st.st_size);
  std::string name = path.substr(path.rfind('/') == std::string::npos ? 0 : path.rfind('/') + 1);
  server.files["/" + name] = std::move(clod);

  const int sock = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (sock < 0) return Fail(kIoError, std::string("cannot open a socket: ") + std::strerror(errno));
  const int one = 1;
  setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(uint16_t(port));
  if (inet_pton(AF_INET, host.c_str(), &addr.sin_addr) != 1)
    return Fail(kUsage, "--host must be an IPv4 address such as 127.0.0.1");
  if (::bind(sock, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0)
    return Fail(kIoError, "cannot listen on " + host + ":" + std::to_string(port) + ": " + std::strerror(errno));
  socklen_t len = sizeof addr;
  if (::listen(sock, 64) != 0 || getsockname(sock, reinterpret_cast<sockaddr*>(&addr), &len) != 0)
    return Fail(kIoError, std::string("cannot listen: ") + std::strerror(errno));
  std::printf("serving %s (%llu bytes) and the web viewer from %s\nopen http://%s:%d/?file=%s\n(Ctrl-C stops)\n",
              path.c_str(), (unsigned long long)st.st_size, web.c_str(), host.c_str(), ntohs(addr.sin_port),
              PercentEncode(name).c_str());
  std::fflush(stdout);
  for (;;) {
    const int fd = ::accept4(sock, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED || errno == EMFILE || errno == ENFILE) continue;
      return Fail(kIoError, std::string("accept failed: ") + std::strerror(errno));
    }
    try {
      std::thread([&server, fd] { server.Connection(fd); }).detach();
    } catch (const std::system_error&) {  // no thread to be had now: drop this connection
      ::close(fd);
    }
  }
}

}  // namespace cli
}  // namespace conelod
