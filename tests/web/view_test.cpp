// `medspring view` end to end: the URL it prints, the files it serves with their MIME types, what it
// refuses (path traversal, other node_modules, methods), and a clean stop on SIGTERM.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <thread>

namespace {

namespace fs = std::filesystem;

struct Reply {
  int status = 0;
  std::string head, body;
};

Reply http(int port, const std::string& request) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  Reply r;
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return r;
  }
  ::send(fd, request.data(), request.size(), 0);
  std::string all;
  char buf[65536];
  for (ssize_t n; (n = ::recv(fd, buf, sizeof buf, 0)) > 0;) all.append(buf, static_cast<std::size_t>(n));
  ::close(fd);
  const std::size_t sep = all.find("\r\n\r\n");
  if (sep == std::string::npos) return r;
  r.head = all.substr(0, sep);
  r.body = all.substr(sep + 4);
  std::sscanf(r.head.c_str(), "HTTP/1.1 %d", &r.status);
  return r;
}
Reply get(int port, const std::string& path) { return http(port, "GET " + path + " HTTP/1.1\r\nHost: x\r\n\r\n"); }
std::string header(const Reply& r, const std::string& name) {
  std::smatch m;
  if (std::regex_search(r.head, m, std::regex("\r\n" + name + ": ([^\r]*)", std::regex::icase))) return m[1];
  return "";
}

class ViewServer : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("medspring_view_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_ / "web" / "dist");
    fs::create_directories(dir_ / "web" / "node_modules" / "three" / "build");
    fs::create_directories(dir_ / "web" / "node_modules" / "other");
    fs::create_directories(dir_ / "models");
    std::ofstream(dir_ / "web" / "index.html") << "<!doctype html><title>t</title>";
    std::ofstream(dir_ / "web" / "app.js") << "export {};";
    std::ofstream(dir_ / "web" / "dist" / "medspring.mjs") << "export default 1;";
    std::ofstream(dir_ / "web" / "dist" / "engine.wasm") << "\0asm";
    std::ofstream(dir_ / "web" / "node_modules" / "three" / "build" / "three.module.js") << "export {};";
    std::ofstream(dir_ / "web" / "node_modules" / "other" / "x.js") << "secret";
    std::ofstream(dir_ / "models" / "models.json") << "[]";
    std::ofstream(dir_ / "models" / "kidney.msm", std::ios::binary) << "MSPRMODL";
    std::ofstream(dir_ / "secret.txt") << "outside";

    int pipefd[2];
    ASSERT_EQ(::pipe(pipefd), 0);
    pid_ = ::fork();
    ASSERT_GE(pid_, 0);
    if (pid_ == 0) {
      ::dup2(pipefd[1], 1);
      ::close(pipefd[0]);
      const std::string web = (dir_ / "web").string(), models = (dir_ / "models").string();
      ::execl(MEDSPRING_EXE, MEDSPRING_EXE, "view", "--port", "0", "--web", web.c_str(), "--models", models.c_str(),
              "--quiet", "--exit-after", "120", static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::close(pipefd[1]);
    out_ = ::fdopen(pipefd[0], "r");
    char line[512];
    ASSERT_NE(std::fgets(line, sizeof line, out_), nullptr) << "medspring view printed nothing";
    std::cmatch m;
    ASSERT_TRUE(std::regex_search(line, m, std::regex("http://127\\.0\\.0\\.1:(\\d+)/"))) << line;
    port_ = std::stoi(m[1]);
  }
  void TearDown() override {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      ::waitpid(pid_, nullptr, 0);
    }
    if (out_) std::fclose(out_);
    fs::remove_all(dir_);
  }
  fs::path dir_;
  pid_t pid_ = -1;
  FILE* out_ = nullptr;
  int port_ = 0;
};

TEST_F(ViewServer, ServesThePageWithMimeTypes) {
  Reply r = get(port_, "/");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(header(r, "Content-Type"), "text/html; charset=utf-8");
  EXPECT_EQ(r.body, "<!doctype html><title>t</title>");
  EXPECT_EQ(header(r, "Content-Length"), std::to_string(r.body.size()));
  EXPECT_EQ(header(r, "Cross-Origin-Embedder-Policy"), "require-corp");
  EXPECT_EQ(header(get(port_, "/app.js"), "Content-Type"), "text/javascript; charset=utf-8");
  EXPECT_EQ(header(get(port_, "/dist/medspring.mjs"), "Content-Type"), "text/javascript; charset=utf-8");
  EXPECT_EQ(header(get(port_, "/dist/engine.wasm"), "Content-Type"), "application/wasm");
  EXPECT_EQ(get(port_, "/node_modules/three/build/three.module.js").status, 200);
  r = get(port_, "/models/models.json?x=1");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(header(r, "Content-Type"), "application/json");
  r = get(port_, "/models/kidney.msm");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, "MSPRMODL");
  EXPECT_EQ(header(r, "Content-Type"), "application/octet-stream");
  EXPECT_EQ(get(port_, "/index%2Ehtml").status, 200);  // percent-decoded
}

TEST_F(ViewServer, RefusesWhatItMustNotServe) {
  EXPECT_EQ(get(port_, "/nope.js").status, 404);
  EXPECT_EQ(get(port_, "/dist").status, 404);  // a folder
  EXPECT_EQ(get(port_, "/../secret.txt").status, 403);
  EXPECT_EQ(get(port_, "/%2e%2e/secret.txt").status, 403);
  EXPECT_EQ(get(port_, "/models/..%2f..%2fsecret.txt").status, 403);
  EXPECT_EQ(get(port_, "/dist/..\\..\\secret.txt").status, 403);
  EXPECT_EQ(get(port_, "/node_modules/other/x.js").status, 403);
  EXPECT_EQ(get(port_, "/%zz").status, 400);
  EXPECT_EQ(get(port_, "/a%00b").status, 400);
  EXPECT_EQ(get(port_, "relative").status, 400);
  Reply r = http(port_, "POST / HTTP/1.1\r\nContent-Length: 0\r\n\r\n");
  EXPECT_EQ(r.status, 405);
  EXPECT_EQ(header(r, "Allow"), "GET, HEAD");
  r = http(port_, "HEAD /app.js HTTP/1.1\r\n\r\n");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(header(r, "Content-Length"), "10");
  EXPECT_EQ(r.body, "");
  EXPECT_EQ(http(port_, "garbage\r\n\r\n").status, 400);
}

TEST_F(ViewServer, SurvivesAnIdleConnectionAndStopsOnSigterm) {
  // A client that connects and sends nothing must not block the others (single thread, poll).
  const int idle = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port_));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::connect(idle, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  EXPECT_EQ(get(port_, "/app.js").status, 200);
  ::close(idle);
  ASSERT_EQ(::kill(pid_, SIGTERM), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(pid_, &status, 0), pid_);
  pid_ = -1;
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  char line[512];
  std::string rest;
  while (std::fgets(line, sizeof line, out_)) rest += line;
  EXPECT_NE(rest.find("stopped"), std::string::npos) << rest;
}

TEST(ViewCommand, RefusesBadOptions) {
  const std::string exe = MEDSPRING_EXE;
  EXPECT_NE(std::system((exe + " view --port 70000 2>/dev/null").c_str()), 0);
  EXPECT_NE(std::system((exe + " view --models /nonexistent/folder 2>/dev/null").c_str()), 0);
  EXPECT_NE(std::system((exe + " view --bogus 1 2>/dev/null").c_str()), 0);
}

}  // namespace
