// Small helpers of the study: subprocesses, files, the machine's name and the clock.
#include <sys/wait.h>

#include <cstdlib>
#include <ctime>
#include <fstream>
#include <vector>

#include "internal.hpp"
#include "medspring/core/check.hpp"

namespace medspring::paper {

namespace {

// The last `count` non-blank lines of a log, joined by " | " (the log itself goes with the staging folder
// when the run fails, so the error message carries what it said: which job, and the traceback that
// render.py's faulthandler prints on an abort).
std::string last_lines(const std::filesystem::path& file, std::size_t count) {
  std::ifstream in(file);
  std::string line;
  std::vector<std::string> last;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    last.push_back(line);
    if (last.size() > count) last.erase(last.begin());
  }
  std::string out;
  for (const std::string& l : last) out += (out.empty() ? "" : " | ") + l;
  return out;
}

}  // namespace

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

void run_logged(const std::string& what, const std::string& command, const std::filesystem::path& log) {
  const int rc = std::system((command + " > " + shell_quote(log.string()) + " 2>&1").c_str());
  const int status = rc == -1 ? -1 : (WIFEXITED(rc) ? WEXITSTATUS(rc) : 128);
  if (status != 0)
    throw Error(cat(what, " failed (exit ", status, status == 134 ? ", an abort" : "",
                    "): ", last_lines(log, 12), " [log: ", log.string(), "]"));
}

void render_report(const std::filesystem::path& results_json, const std::filesystem::path& report_md,
                   const StudyOptions& o) {
  const std::filesystem::path log = report_md.parent_path() / "logs" / "report.log";
  std::filesystem::create_directories(log.parent_path());
  run_logged("report (python3 with Jinja2: Debian python3-jinja2)",
             shell_quote(o.python) + " " + shell_quote((o.scripts_dir / "report.py").string()) + " " +
                 shell_quote(results_json.string()) + " " + shell_quote(report_md.string()),
             log);
}

namespace detail {

void write_text(const fs::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
  if (!out) throw IoError(cat(file.string(), ": cannot write"));
}

json vec(const Vec3& v) {
  return json::array({v.x(), v.y(), v.z()});
}

std::string cpu_name() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const auto p = line.find(':');
      return p == std::string::npos ? line : line.substr(p + 2);
    }
  return "unknown CPU";
}

std::string now_utc() {
  const std::time_t t = std::time(nullptr);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M UTC", std::gmtime(&t));
  return buf;
}

}  // namespace detail
}  // namespace medspring::paper
