// The medspring command end to end: `run` writes a ParaView series, bad scenes fail with one line naming
// the JSON path and write nothing, output folders are written safely, `paper --quick` makes the report.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;

struct Result {
  int rc = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string quote(const std::string& s) {
  return "'" + s + "'";
}

/// Runs `medspring ARGS` with stdout and stderr captured (stderr is not a terminal: plain progress lines).
Result medspring(const std::string& args) {
  static int n = 0;
  const fs::path dir = testing::temp_dir("cli-io-" + std::to_string(n++));
  const std::string cmd = quote(MEDSPRING_EXE) + " " + args + " > " + quote((dir / "out").string()) + " 2> " +
                          quote((dir / "err").string());
  const int status = std::system(cmd.c_str());
  Result r;
  r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(dir / "out");
  r.err = slurp(dir / "err");
  return r;
}

void write(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

int count_lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

/// A short phantom scene: the kidney pressed for 30 ms, released, run to 50 ms.
const char* kSmallScene = R"({
  "model": {"kind": "hybrid", "source": {"phantom": "kidney"}},
  "loads": [{"node": 223, "direction": "towards_atom", "atom": 21, "magnitude": 0.5, "t_ramp": 10, "t_release": 30}],
  "duration": 50,
  "record": {"every": 10, "atoms": [21]}
})";

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto p = text.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  return text.replace(p, from.size(), to);
}

TEST(CliRun, SmallPhantomSceneWritesAParaViewSeriesTracesAndSummary) {
  const fs::path dir = testing::temp_dir("cli-run");
  write(dir / "small.json", kSmallScene);
  const fs::path out = dir / "result";
  const Result r =
      medspring("run " + quote((dir / "small.json").string()) + " --out " + quote(out.string()) + " --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const nlohmann::json s = nlohmann::json::parse(r.out);
  EXPECT_EQ(s["updates"], 100);
  EXPECT_EQ(s["frames"], 11);  // rest + every 10 updates
  EXPECT_TRUE(fs::exists(out / "small.pvd"));
  EXPECT_TRUE(fs::exists(out / "small_atoms.pvd"));
  int vtp = 0;
  for (const auto& e : fs::directory_iterator(out / "frames")) vtp += e.path().extension() == ".vtp";
  EXPECT_EQ(vtp, 22);  // surface + atoms per frame
  const std::string pvd = slurp(out / "small.pvd");
  EXPECT_NE(pvd.find("frames/small_00010.vtp"), std::string::npos);
  const std::string vtp0 = slurp(out / "frames" / "small_00005.vtp");
  for (const char* array : {"displacement", "displacement_magnitude", "local_displacement", "Normals"})
    EXPECT_NE(vtp0.find(std::string("Name=\"") + array + "\""), std::string::npos) << array;
  EXPECT_EQ(count_lines(slurp(out / "trace.csv")), 102);  // header + rest + 100 updates
  EXPECT_TRUE(fs::exists(out / "scene.json"));
  EXPECT_GT(s["contact_peak_mm"].get<double>(), 0.5);
  // no temporary folder is left beside the output
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".result.tmp"), std::string::npos);
}

TEST(CliParams, InfoParamsIsTheCommittedTableAndRunSetChangesTheScene) {  // docs/parameters.md
  const Result info = medspring("info --params");
  ASSERT_EQ(info.rc, 0) << info.err;
  EXPECT_EQ(info.out, slurp(fs::path(MEDSPRING_SOURCE_DIR) / "docs" / "parameters.md"));
  const fs::path dir = testing::temp_dir("cli-set");
  write(dir / "s.json", kSmallScene);
  const Result ok =
      medspring("run " + quote((dir / "s.json").string()) + " --out " + quote((dir / "out").string()) +
                " --quiet --set integrator.dt=0.25,model.parameters.k_spoke=0.08");
  ASSERT_EQ(ok.rc, 0) << ok.err;
  const std::string scene = slurp(dir / "out" / "scene.json");  // the scene as run, defaults filled in
  EXPECT_NE(scene.find("\"dt\": 0.25"), std::string::npos) << scene;
  EXPECT_NE(scene.find("\"k_spoke\": 0.08"), std::string::npos) << scene;
  const Result bad = medspring("run " + quote((dir / "s.json").string()) + " --out " +
                               quote((dir / "bad").string()) + " --set integrator.safety=2");
  EXPECT_EQ(bad.rc, 1);
  EXPECT_NE(bad.err.find("--set integrator.safety: must be in (0, 1] (got 2)"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

TEST(CliRun, StoppedAndResumedRunGivesTheUninterruptedTraceBitForBit) {
  const fs::path dir = testing::temp_dir("cli-resume");
  write(dir / "small.json", kSmallScene);
  const std::string scene = quote((dir / "small.json").string());
  const Result whole = medspring("run " + scene + " --out " + quote((dir / "whole").string()) + " --quiet");
  ASSERT_EQ(whole.rc, 0) << whole.err;
  // the first part stops at 22 ms (during the press), checkpointing every 10 updates and at the stop
  const fs::path ck = dir / "part.mscp";
  const Result part =
      medspring("run " + scene + " --out " + quote((dir / "part1").string()) +
                " --checkpoint-every 10 --stop-at 22 --checkpoint " + quote(ck.string()) + " --json");
  ASSERT_EQ(part.rc, 0) << part.err;
  const nlohmann::json s1 = nlohmann::json::parse(part.out);
  EXPECT_TRUE(s1["stopped"].get<bool>());
  EXPECT_EQ(s1["updates"], 44);
  ASSERT_TRUE(fs::exists(ck));
  const Result rest = medspring("run " + scene + " --out " + quote((dir / "part2").string()) + " --resume " +
                                quote(ck.string()) + " --json");
  ASSERT_EQ(rest.rc, 0) << rest.err;
  const nlohmann::json s2 = nlohmann::json::parse(rest.out);
  EXPECT_EQ(s2["first_update"], 45);
  EXPECT_EQ(s2["resumed_from_ms"], 22.0);
  EXPECT_FALSE(s2["stopped"].get<bool>());
  EXPECT_EQ(slurp(dir / "part2" / "trace.csv"), slurp(dir / "whole" / "trace.csv"));
  // the last frame of the resumed run is the uninterrupted run's, byte for byte
  EXPECT_EQ(slurp(dir / "part2" / "frames" / "small_00010.vtp"),
            slurp(dir / "whole" / "frames" / "small_00010.vtp"));
  const nlohmann::json w = nlohmann::json::parse(slurp(dir / "whole" / "summary.json"));
  const nlohmann::json r2 = nlohmann::json::parse(slurp(dir / "part2" / "summary.json"));
  for (const char* key :
       {"contact_peak_mm", "contact_hold_mm", "max_disp_peak_mm", "return_ms", "final_max_disp_mm"})
    EXPECT_EQ(r2[key], w[key]) << key;

  // a corrupted checkpoint and one of another scene are refused, naming the file, writing nothing
  std::string bytes = slurp(ck);
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x55);
  std::ofstream(dir / "bad.mscp", std::ios::binary) << bytes;
  const Result bad = medspring("run " + scene + " --out " + quote((dir / "bad").string()) + " --resume " +
                               quote((dir / "bad.mscp").string()));
  EXPECT_NE(bad.rc, 0);
  EXPECT_NE(bad.err.find("corrupted checkpoint"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "bad"));
  write(dir / "other.json",
        R"({"model": {"kind": "surface", "source": {"phantom": "tube"}}, "duration": 50})");
  const Result other = medspring("run " + quote((dir / "other.json").string()) + " --out " +
                                 quote((dir / "other").string()) + " --resume " + quote(ck.string()));
  EXPECT_NE(other.rc, 0);
  EXPECT_NE(other.err.find("another model"), std::string::npos) << other.err;
  EXPECT_FALSE(fs::exists(dir / "other"));
  // the same model under another scene: its traces would not fit, refused by name
  write(dir / "copy.json", kSmallScene);
  const Result copy = medspring("run " + quote((dir / "copy.json").string()) + " --out " +
                                quote((dir / "copy").string()) + " --resume " + quote(ck.string()));
  EXPECT_NE(copy.rc, 0);
  EXPECT_NE(copy.err.find("saved from scene 'small', this is scene 'copy'"), std::string::npos) << copy.err;
  EXPECT_FALSE(fs::exists(dir / "copy"));
}

#if MEDSPRING_TEST_WITH_CGAL  // the web set's organ scenes remesh their surface (balloon): CGAL
TEST(CliExport, WebSetIsWrittenAndEveryPackageRebuilds) {
  const fs::path dir = testing::temp_dir("cli-export");
  const Result r = medspring("export --web --out " + quote((dir / "models").string()) + " --json");
  ASSERT_EQ(r.rc, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  std::set<std::string> files;
  for (const auto& m : j["models"]) {
    files.insert(m["file"].get<std::string>());
    EXPECT_TRUE(fs::exists(dir / "models" / m["file"].get<std::string>()));
    EXPECT_GT(m["masses"].get<long>(), 0);
  }
  EXPECT_TRUE(fs::exists(dir / "models" / "models.json"));
  for (const char* f : {"kidney.msm", "aorta.msm", "kidney_phantom.msm", "vessel_phantom.msm", "tube.msm"})
    EXPECT_EQ(files.count(f), 1u) << f;
  for (const auto& m : j["models"])
    if (m["file"] == "kidney.msm") {
      EXPECT_EQ(m["surface_nodes"], 458);
      EXPECT_EQ(m["masses"], 500);
    } else if (m["file"] == "aorta.msm") {
      EXPECT_EQ(m["surface_nodes"], 1200);
      EXPECT_EQ(m["masses"], 40);
    }
  // With the builders layer (CGAL), the whole tree also comes with its one watertight surface.
  if (files.count("aorta_tree_blended.msm") > 0)
    for (const auto& m : j["models"])
      if (m["file"] == "aorta_tree_blended.msm") {
        EXPECT_EQ(m["kind"], "smrm_tree");
        EXPECT_EQ(m["surface_nodes"], 2083);
        EXPECT_EQ(m["masses"], 60);
      }
  // without --web or a scene: a usage error
  const Result usage = medspring("export --out " + quote((dir / "x").string()));
  EXPECT_NE(usage.rc, 0);
  EXPECT_NE(usage.err.find("--web"), std::string::npos) << usage.err;
}
#endif

struct BadScene {
  std::string name, text, expected;
};

TEST(CliRun, BadScenesFailWithOneLineNamingTheJsonPathAndWriteNothing) {
  const fs::path dir = testing::temp_dir("cli-bad");
  // a 20 mm object whose coordinates are in metres (0.02), declared as millimetres
  write(dir / "tiny.obj",
        "v 0 0 0\nv 0.02 0 0\nv 0 0.02 0\nv 0 0 0.02\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  const std::vector<BadScene> cases = {
      {"missing_file",
       replaced(kSmallScene, "\"phantom\": \"kidney\"", R"("mesh": {"file": "nope.obj", "unit": "mm"})"),
       "model.source.mesh.file: file not found"},
      {"wrong_unit",
       replaced(kSmallScene, "\"phantom\": \"kidney\"", R"("mesh": {"file": "tiny.obj", "unit": "mm"})"),
       "model.source.mesh.unit: the mesh tiny.obj is 0.0"},
      {"unknown_key", replaced(kSmallScene, "\"every\"", "\"evry\""), "record.evry: unknown key"},
      {"node_out_of_range", replaced(kSmallScene, "\"node\": 223", "\"node\": 458"),
       "loads[0].node: index 458 out of range [0, 458)"},
      {"negative_duration", replaced(kSmallScene, "\"duration\": 50", "\"duration\": -50"),
       "duration: must be > 0 ms (got -50)"},
      {"dt_above_stable_bound",
       replaced(kSmallScene, "\"duration\": 50",
                R"("duration": 50, "integrator": {"dt": 1.5, "substep": false})"),
       "integrator.dt: 1.5 ms is above the stable step"},
  };
  for (const auto& c : cases) {
    const fs::path scene = dir / (c.name + ".json");
    write(scene, c.text);
    const fs::path out = dir / ("out_" + c.name);
    const Result r = medspring("run " + quote(scene.string()) + " --out " + quote(out.string()));
    EXPECT_NE(r.rc, 0) << c.name;
    EXPECT_EQ(count_lines(r.err), 1) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(scene.string() + ": " + c.expected), std::string::npos) << c.name << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
  }
  int left = 0;  // nothing but the inputs: no output or temporary folders
  for (const auto& e : fs::directory_iterator(dir)) left += e.is_directory();
  EXPECT_EQ(left, 0);
  const Result missing =
      medspring("run " + quote((dir / "absent.json").string()) + " --out " + quote((dir / "o").string()));
  EXPECT_NE(missing.rc, 0);
  EXPECT_NE(missing.err.find("absent.json: cannot read the scene file"), std::string::npos) << missing.err;
  EXPECT_NE(medspring("run --out x").rc, 0);
  EXPECT_NE(medspring("run a.json b.json --out x").rc, 0);
}

TEST(CliRun, NonEmptyOutputFolderIsRefusedWithoutForceAndReplacedWithIt) {
  const fs::path dir = testing::temp_dir("cli-force");
  write(dir / "small.json", kSmallScene);
  const fs::path out = dir / "result";
  fs::create_directories(out);
  write(out / "keep.txt", "old\n");
  const std::string args = "run " + quote((dir / "small.json").string()) + " --out " + quote(out.string());
  const Result refused = medspring(args);
  EXPECT_NE(refused.rc, 0);
  EXPECT_NE(refused.err.find("not empty (use --force"), std::string::npos) << refused.err;
  EXPECT_TRUE(fs::exists(out / "keep.txt"));
  EXPECT_FALSE(fs::exists(out / "small.pvd"));
  const Result forced = medspring(args + " --force --quiet");
  ASSERT_EQ(forced.rc, 0) << forced.err;
  EXPECT_EQ(forced.err, "");  // --quiet: no progress
  EXPECT_FALSE(fs::exists(out / "keep.txt"));
  EXPECT_TRUE(fs::exists(out / "small.pvd"));
  // an empty folder is not refused
  fs::create_directories(dir / "empty");
  EXPECT_EQ(medspring("run " + quote((dir / "small.json").string()) + " --quiet --out " +
                      quote((dir / "empty").string()))
                .rc,
            0);
}

TEST(CliHelp, RunAndPaperAreListedAndHaveHelp) {
  const Result top = medspring("--help");
  EXPECT_EQ(top.rc, 0);
  EXPECT_NE(top.out.find("\n  paper "), std::string::npos);  // scripts/main.sh switches on this line
  EXPECT_NE(top.out.find("\n  run "), std::string::npos);
  for (const char* cmd : {"run", "paper"}) {
    const Result r = medspring(std::string(cmd) + " --help");
    EXPECT_EQ(r.rc, 0) << cmd;
    EXPECT_NE(r.out.find(std::string("usage: medspring ") + cmd), std::string::npos) << cmd;
  }
  EXPECT_NE(medspring("paper --out x --bogus").rc, 0);
  EXPECT_NE(medspring("paper").rc, 0);
  // an --accuracy file that is not there is refused before anything runs, and nothing is written
  const fs::path dir = testing::temp_dir("cli-paper-accuracy");
  const Result bad = medspring("paper --quick --out " + quote((dir / "p").string()) + " --accuracy " +
                               quote((dir / "missing.json").string()));
  EXPECT_NE(bad.rc, 0);
  EXPECT_NE(bad.err.find("--accuracy"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "p" / "report.md"));
}

// Issue 22: the command line on CLI11. Every command and kind has --help listing its options with units
// and defaults; mistakes on the command line are one line naming the option, exit status 2.
TEST(CliHelp, EveryCommandAndKindListsItsOptionsWithUnitsAndDefaults) {
  const Result top = medspring("--help");
  ASSERT_EQ(top.rc, 0);
  for (const char* cmd : {"demo", "bench", "info", "haptics", "export", "view", "build", "study", "run",
                          "accuracy", "calibrate", "paper"}) {
    EXPECT_NE(top.out.find(std::string("\n  ") + cmd + " "), std::string::npos) << cmd;
    const Result r = medspring(std::string(cmd) + " --help");
    EXPECT_EQ(r.rc, 0) << cmd;
    EXPECT_NE(r.out.find(std::string("usage: medspring ") + cmd), std::string::npos) << cmd;
    EXPECT_NE(r.out.find("\noptions:\n"), std::string::npos) << cmd << ": " << r.out;
    EXPECT_EQ(medspring(std::string("help ") + cmd).out, r.out) << cmd;
  }
  EXPECT_EQ(top.out.find("completion"), std::string::npos);  // hidden
  for (const char* kind : {"kidney", "centerline", "vessel"}) {
    const Result r = medspring(std::string("build ") + kind + " --help");
    EXPECT_EQ(r.rc, 0) << kind;
    EXPECT_NE(r.out.find(std::string("usage: medspring build ") + kind), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("  --out DIR"), std::string::npos) << r.out;
  }
  // units and defaults beside the options
  const Result accuracy = medspring("accuracy --help");
  EXPECT_NE(accuracy.out.find("  --radius A              contact disk radius a; > 0 [mm, default 8]"),
            std::string::npos)
      << accuracy.out;
  EXPECT_NE(medspring("view --help").out.find("[default 8080]"), std::string::npos);
  EXPECT_NE(medspring("build kidney -h").out.find("surface nodes [default 458]"), std::string::npos);
  EXPECT_NE(medspring("build --help").out.find("  vessel "), std::string::npos);
}

TEST(CliUsage, UnknownOptionsMissingValuesAndBadNumbersExitTwoWithOneLineNamingTheOption) {
  const fs::path dir = testing::temp_dir("cli-usage");
  write(dir / "small.json", kSmallScene);
  const std::string scene = quote((dir / "small.json").string());
  struct Case {
    std::string args, expected;
  };
  const std::vector<Case> cases = {
      {"run --no-such-option", "medspring run: error: unknown option --no-such-option"},
      {"run " + scene + " --out " + quote((dir / "o").string()) + " --no-such-option=3",
       "unknown option --no-such-option"},
      {"run " + scene + " --out", "medspring run: error: option --out needs a value (DIR)"},
      {"build kidney --mesh", "medspring build kidney: error: option --mesh needs a value (FILE)"},
      {"build vessel --close-holes 3", "medspring build vessel: error: unknown option --close-holes"},
      {"view --port eighty", "option --port: 'eighty' is not an integer"},
      {"demo extra", "unexpected argument 'extra'"},
      {"bench --quick --compare --filter x", "option --filter does not apply here"},
      {"nosuch", "medspring: error: unknown command 'nosuch'"},
      {"--bogus", "medspring: error: unknown option --bogus"},
      // the hand-written parser took options before build's kind: the error says what to write
      {"build --mesh x.obj kidney", "the kind comes first: write medspring build kidney|centerline|vessel"},
  };
  for (const auto& c : cases) {
    const Result r = medspring(c.args);
    EXPECT_EQ(r.rc, 2) << c.args << ": " << r.err;
    EXPECT_EQ(count_lines(r.err), 1) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << ": " << r.err;
    EXPECT_EQ(r.out, "") << c.args;
  }
  EXPECT_FALSE(fs::exists(dir / "o"));
  // the same option given twice: the last one counts (as before); a negative number is a value
  EXPECT_EQ(medspring("demo --force 2 --force 0.5 --json").rc, 0);
  const Result negative =
      medspring("run " + scene + " --out " + quote((dir / "n").string()) + " --threads -3");
  EXPECT_EQ(negative.rc, 1);
  EXPECT_NE(negative.err.find("--threads: must be an integer in 1..256 (got -3)"), std::string::npos);
}

TEST(CliBench, TableCasesAreReportedByBench) {
  const Result r = medspring("bench --quick --json --samples 20 --filter table_smrm_1200_nonlinear");
  ASSERT_EQ(r.rc, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  std::vector<std::string> names;
  for (const auto& c : j["results"]) names.push_back(c["name"]);
  EXPECT_EQ(names,
            (std::vector<std::string>{"table_smrm_1200_nonlinear", "table_smrm_1200_nonlinear_local_no_cache",
                                      "table_smrm_1200_nonlinear_local_cache"}));
}

// bench --gpu never falls back to the CPU: without a GPU (or without the CUDA backend) it exits non-zero
// naming why (docs/gpu.md). On a GPU machine the smallest run succeeds instead.
TEST(CliBench, GpuWithoutADeviceFailsClearly) {
  const Result r = medspring("bench --gpu --sizes 1200 --batch 0 --cpu-max 0 --no-torch");
  if (r.rc == 0) {
    EXPECT_NE(r.out.find("GPU:"), std::string::npos) << r.out;  // the card is named
    return;
  }
  EXPECT_NE(r.err.find("GPU"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("CPU engine"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("tube_1.2k"), std::string::npos) << r.out;  // nothing was timed
  EXPECT_NE(medspring("bench --gpu --sizes 5").rc, 0);
  EXPECT_NE(medspring("bench --gpu --bogus 1").rc, 0);
  const Result m = medspring("bench --gpu --models-per-thread 3");  // 1, 2 or 4
  EXPECT_NE(m.rc, 0);
  EXPECT_NE(m.err.find("--models-per-thread"), std::string::npos) << m.err;
}

TEST(CliThreads, BadThreadCountsFailWithOneLine) {
  const fs::path dir = testing::temp_dir("cli-threads");
  write(dir / "small.json", kSmallScene);
  for (const std::string bad : {"0", "-2", "257", "99999999"}) {
    for (const std::string& cmd :
         {"bench --compare --threads " + bad, "run " + quote((dir / "small.json").string()) + " --out " +
                                                  quote((dir / "out").string()) + " --threads " + bad}) {
      const Result r = medspring(cmd);
      EXPECT_EQ(r.rc, 1) << cmd;
      EXPECT_EQ(count_lines(r.err), 1) << r.err;
      EXPECT_NE(r.err.find("--threads: must be an integer in 1..256 (got " + bad + ")"), std::string::npos)
          << r.err;
      EXPECT_FALSE(fs::exists(dir / "out"));
    }
  }
  // a good count runs (the kidney phantom is small: it runs on one thread)
  const Result ok = medspring("run " + quote((dir / "small.json").string()) + " --out " +
                              quote((dir / "ok").string()) + " --threads 2 --json");
  ASSERT_EQ(ok.rc, 0) << ok.err;
  EXPECT_EQ(nlohmann::json::parse(ok.out)["updates"], 100);
}

// Issue 15, bad input: a model too large for memory (or for 32-bit indices) is refused before anything
// is built or written, with one line naming the model, its size and the memory.
TEST(CliTooLarge, ModelsBeyondMemoryFailWithOneLine) {
  const fs::path dir = testing::temp_dir("cli-too-large");
  const std::string scene =
      R"({"model": {"kind": "surface", "source": {"phantom": {"name": "tube", "rings": 1000,
    "spokes": 1000}}}, "loads": [{"node": 5, "direction": [0, 0, -1], "magnitude": 0.5}], "duration": 5})";
  write(dir / "big.json", scene);
  write(dir / "huge.json", replaced(replaced(scene, "\"rings\": 1000", "\"rings\": 100000"),
                                    "\"spokes\": 1000", "\"spokes\": 50000"));
  ::setenv("MEDSPRING_MEMORY_LIMIT_MB", "100", 1);  // the 1M-node tube then needs more than the machine has
  const Result run =
      medspring("run " + quote((dir / "big.json").string()) + " --out " + quote((dir / "out").string()));
  const Result bench = medspring("bench --compare --sizes 1M --no-bullet");
  ::unsetenv("MEDSPRING_MEMORY_LIMIT_MB");
  for (const Result& r : {run, bench}) {
    EXPECT_EQ(r.rc, 1) << r.err;
    EXPECT_EQ(count_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("a model of 1000000 nodes: needs about 0.9 GB of memory, more than the 0.1 GB"),
              std::string::npos)
        << r.err;
  }
  const Result huge =
      medspring("run " + quote((dir / "huge.json").string()) + " --out " + quote((dir / "out").string()));
  EXPECT_EQ(huge.rc, 1) << huge.err;
  EXPECT_EQ(count_lines(huge.err), 1) << huge.err;
  EXPECT_NE(huge.err.find("too large (indices are 32-bit"), std::string::npos) << huge.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(CliPaper, QuickRunMakesTheReportFiguresAndTablesOnThePhantoms) {
  const fs::path dir = testing::temp_dir("cli-paper");
  const fs::path out = dir / "paper";
  // A previous accuracy run (two held-out cases of one model kind) is summarised, not re-run.
  using nlohmann::json;
  const auto held_out = [](double contact, double rms, bool train) {
    return json{
        {"site", 1}, {"force_N", 0.2}, {"train", train}, {"contact_error_pct", contact}, {"rms_pct", rms}};
  };
  const json model = {{"kind", "hybrid (Duffing)"},
                      {"calibrated", true},
                      {"update_us", 12.5},
                      {"cases", json::array({held_out(1.0, 1.0, true), held_out(6.0, 9.0, false),
                                             held_out(10.0, 11.0, false)})}};
  const json organ = {
      {"organ", "kidney phantom"}, {"fem", {{"median_solve_s", 4.2}}}, {"models", json::array({model})}};
  const json accuracy = {{"material", {{"E_kPa", 10}, {"nu", 0.45}}},
                         {"contact_radius_mm", 8},
                         {"organs", json::array({organ})}};
  const fs::path acc = dir / "accuracy.json";
  std::ofstream(acc) << accuracy.dump();
  const Result r =
      medspring("paper --quick --out " + quote(out.string()) + " --accuracy " + quote(acc.string()));
  ASSERT_EQ(r.rc, 0) << r.err;
  const std::string report = slurp(out / "report.md");
  for (const char* part : {"## Fig. 9", "## Fig. 10", "**Table I**", "**Table II**", "## Parameters used",
                           "## Accuracy against the FEM reference (CalculiX)",
                           "| kidney phantom | hybrid (Duffing) | — | 8.0 % | — | 10.0 % | 12.5 |", "4.2 s"})
    EXPECT_NE(report.find(part), std::string::npos) << part;
  for (const char* png : {"fig9_A", "fig9_B", "fig9_C", "fig9_D", "fig10_A", "fig10_B", "fig10_C", "fig10_D",
                          "fig10_E", "fig10_F", "fig9_displacement", "fig10_displacement",
                          "force_displacement", "vessel_profile", "timing"}) {
    const fs::path p = out / "figures" / (std::string(png) + ".png");
    ASSERT_TRUE(fs::exists(p)) << p;
    EXPECT_GT(fs::file_size(p), 10000u) << p;
    EXPECT_NE(report.find(std::string("figures/") + png + ".png"), std::string::npos) << png;
  }
  const nlohmann::json t = nlohmann::json::parse(slurp(out / "tables.json"));
  EXPECT_GT(t["table1"]["smrm"]["nonlinear"]["measured_median_ms"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(t["table1"]["mass_spring"]["linear"]["paper_ms"].get<double>(), 18.0);
  EXPECT_DOUBLE_EQ(t["table2"]["smrm"]["with_local"]["paper_ms"].get<double>(), 27.0);
  EXPECT_EQ(t["scenes"].size(), 12u);
  // The whole vessel tree (issue 17): the phantom tree, light and strong force on the arch and a branch.
  EXPECT_NE(report.find("## The whole vessel tree"), std::string::npos);
  for (const char* png : {"tree_arch", "tree_branch"}) {
    const fs::path p = out / "figures" / (std::string(png) + ".png");
    ASSERT_TRUE(fs::exists(p)) << p;
    EXPECT_GT(fs::file_size(p), 10000u) << p;
  }
  const nlohmann::json& tree = t["tree"];
  EXPECT_EQ(tree["branches"].get<int>(), 3);
  EXPECT_EQ(tree["junctions"].get<int>(), 1);
  ASSERT_EQ(tree["runs"].size(), 4u);
  for (std::size_t k = 0; k < 4; k += 2) {  // light then strong at each site
    const nlohmann::json &light = tree["runs"][k], &strong = tree["runs"][k + 1];
    EXPECT_EQ(light["site"], strong["site"]);
    EXPECT_EQ(light["model"]["kind"], "smrm_tree");
    // 10x the force moves the loaded atom more (the chain stiffens: less than 10x), and both return.
    EXPECT_GT(strong["atom_hold_mm"].get<double>(), 2.0 * light["atom_hold_mm"].get<double>());
    EXPECT_GT(light["atom_hold_mm"].get<double>(), 0.0);
    EXPECT_LT(strong["return_ms"].get<double>(), 200.0);
    EXPECT_LT(strong["hold_turning_change_deg"].get<double>(), 25.0);  // a smooth bend, no kink
    EXPECT_EQ(strong["warnings"].get<int>(), 0);
  }
  EXPECT_TRUE(
      fs::exists(out / "scenes" / "phantom" / "kidney_1.0N_nonlinear" / "phantom_kidney_1.0N_nonlinear.pvd"));
  // Issue 22: the report is rendered from results.json; the paper-literal set (Duffing `Absolute`) runs
  // beside the default and the report compares them; the D-9 visibility filter is reported.
  const nlohmann::json res = nlohmann::json::parse(slurp(out / "results.json"));
  EXPECT_EQ(res["runs"].size(), 14u);
  int literal = 0;
  for (const auto& x : res["runs"]) literal += x["literal"].get<bool>() ? 1 : 0;
  EXPECT_EQ(literal, 2);
  EXPECT_TRUE(fs::exists(out / "scenes" / "phantom" / "kidney_1.0N_nonlinear_literal" / "summary.json"));
  for (const char* part : {"## The paper's literal constants next to the unit-consistent default",
                           "On the kidney (1.0 N nonlinear) ",
                           "**Spokes and the visibility filter (ALGORITHMS.md D-9, §4.2).**"})
    EXPECT_NE(report.find(part), std::string::npos) << part;
  // a second run into the same folder is refused without --force and leaves the report as it was
  const Result again = medspring("paper --quick --out " + quote(out.string()));
  EXPECT_NE(again.rc, 0);
  EXPECT_NE(again.err.find("not empty (use --force"), std::string::npos) << again.err;
  EXPECT_EQ(slurp(out / "report.md"), report);
}

// Issue 21: `medspring haptics --device cuda` runs the loop on gpu::HapticLoop. Without a GPU (or a CUDA
// build) it fails in one line naming the cause and the CPU alternative, writing nothing (no fallback);
// with one, its force trace is the CPU loop's (the contact read is the same position when not stale).
TEST(CliHaptics, DeviceCudaRunsTheGpuLoopOrFailsInOneLine) {
  const fs::path dir = testing::temp_dir("cli-haptics-cuda");
  write(dir / "press.csv", "time_ms,x,y,z\n0,0,0,31\n20,0,0,26\n40,0,0,26\n");
  const std::string base =
      "haptics kidney_phantom --trajectory " + quote((dir / "press.csv").string()) + " --duration 40 --json";
  const Result bad = medspring(base + " --device tpu");
  EXPECT_EQ(bad.rc, 2);
  EXPECT_NE(bad.err.find("--device"), std::string::npos) << bad.err;
  EXPECT_EQ(medspring(base + " --device cuda --tool sphere:5").rc, 2);

  const Result cpu = medspring(base + " --device cpu");
  ASSERT_EQ(cpu.rc, 0) << cpu.err;
  const Result gpu = medspring(base + " --device cuda --out " + quote((dir / "gpu").string()));
  if (gpu.rc != 0) {  // no GPU here: one line, the cause, the CPU alternative, nothing written
    EXPECT_EQ(count_lines(gpu.err), 1) << gpu.err;
    const bool names_cause =
        gpu.err.find("no CUDA backend") != std::string::npos || gpu.err.find("GPU") != std::string::npos;
    EXPECT_TRUE(names_cause) << gpu.err;
    EXPECT_NE(gpu.err.find("CPU engine"), std::string::npos) << gpu.err;
    EXPECT_FALSE(fs::exists(dir / "gpu"));
    GTEST_SKIP() << "no GPU: " << gpu.err;
  }
  const auto a = nlohmann::json::parse(cpu.out), b = nlohmann::json::parse(gpu.out);
  EXPECT_EQ(b["device"], "cuda");
  EXPECT_EQ(a["ticks"], b["ticks"]);
  ASSERT_EQ(b["stale_ticks"].get<long>(), 0) << "reads arrived late: the loops saw different contacts";
  EXPECT_NEAR(b["peak_force_n"].get<double>(), a["peak_force_n"].get<double>(), 1e-9);
  for (int d = 0; d < 3; ++d)
    EXPECT_NEAR(b["final_reaction_n"][d].get<double>(), a["final_reaction_n"][d].get<double>(), 1e-9);
  EXPECT_GT(a["peak_force_n"].get<double>(), 0.1);
}

}  // namespace
}  // namespace medspring
