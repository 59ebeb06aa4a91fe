// Fuzzing the parsers of outside input with the deterministic mutation driver of mutator.h (GCC has no
// libFuzzer). One test per parser: it replays the committed seed corpus (tests/fuzz/corpus/<harness>/,
// which also holds every input that once crashed a parser) and then runs a bounded number of mutated
// inputs. The rule for every input: the parser returns or throws rsvio::Error (a one-line message); any
// other exception, a crash, or a sanitizer report (in the sanitizer build, scripts/sanitize.sh) fails.
//
// Executions per harness: $RSVIO_FUZZ_EXECS (default 1500; 400 in the sanitizer build), seed
// $RSVIO_FUZZ_SEED (default 1). A failing input is written to <tmp>/rsvio_fuzz_<harness>_failure.bin
// and the input being run to <tmp>/rsvio_fuzz_<harness>_current.bin (what a crash leaves behind); copy
// it into the harness's corpus folder once fixed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fuzz/mutator.h"
#include "plugins/source/source_fixture.h"
#include "rsvio/config/config.h"
#include "rsvio/config/validate.h"
#include "rsvio/core/error.h"
#include "rsvio/eval/evaluate_files.h"
#include "rsvio/io/calibration.h"
#include "rsvio/io/csv.h"
#include "rsvio/io/diagnostics_log.h"
#include "rsvio/io/image_file.h"
#include "rsvio/io/ply.h"
#include "rsvio/io/snapshot.h"
#include "rsvio/io/states.h"
#include "rsvio/io/trajectory.h"
#include "rsvio/plugin/host.h"

namespace fs = std::filesystem;
using namespace rsvio;

namespace {

long envLong(const char* name, long fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::strtol(v, nullptr, 10) : fallback;
}

#ifdef RSVIO_SANITIZE
constexpr long kDefaultExecs = 400;
#else
constexpr long kDefaultExecs = 1500;
#endif

std::string readBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void writeBytes(const fs::path& p, const std::string& s) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(s.data(), static_cast<std::streamsize>(s.size()));
}

std::string printable(const std::string& s, size_t max = 400) {
  std::string o;
  for (size_t i = 0; i < s.size() && i < max; ++i) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (c == '\n') o += "\\n";
    else if (c >= 32 && c < 127) o += static_cast<char>(c);
    else {
      char b[8];
      std::snprintf(b, sizeof(b), "\\x%02x", c);
      o += b;
    }
  }
  if (s.size() > max) o += "...";
  return o;
}

std::vector<std::string> loadCorpus(const std::string& harness) {
  const fs::path dir = fs::path(RSVIO_SOURCE_DIR) / "tests" / "fuzz" / "corpus" / harness;
  std::vector<fs::path> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::vector<std::string> out;
  for (const auto& f : files) out.push_back(readBytes(f));
  return out;
}

class FuzzTest : public ::testing::Test {
 protected:
  void SetUp() override {
    work_ = fs::temp_directory_path() /
            ("rsvio_fuzz_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(work_);
    fs::create_directories(work_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(work_, ec);
  }

  // Replays the corpus, then `execs` mutated inputs. `run` parses one input (it may throw rsvio::Error).
  // multi_line: the parser may report several problems at once, one per line (config validation).
  void fuzz(const std::string& harness, const std::vector<std::string>& tokens,
            const std::function<void(const std::string&)>& run, bool multi_line = false) {
    const auto corpus = loadCorpus(harness);
    ASSERT_FALSE(corpus.empty()) << "no seed corpus in tests/fuzz/corpus/" << harness;
    const long execs = envLong("RSVIO_FUZZ_EXECS", kDefaultExecs);
    const uint64_t seed = static_cast<uint64_t>(envLong("RSVIO_FUZZ_SEED", 1)) * 1000003u +
                          std::hash<std::string>()(harness) % 1000003u;
    fuzz::Mutator m(seed, corpus, tokens);
    const fs::path current = fs::temp_directory_path() / ("rsvio_fuzz_" + harness + "_current.bin");
    const fs::path failure = fs::temp_directory_path() / ("rsvio_fuzz_" + harness + "_failure.bin");
    long rejected = 0, accepted = 0, failures = 0;
    const long total = static_cast<long>(corpus.size()) + execs;
    for (long i = 0; i < total; ++i) {
      const std::string input = i < static_cast<long>(corpus.size()) ? corpus[i] : m.next();
      writeBytes(current, input);
      std::string problem;
      try {
        run(input);
        ++accepted;
      } catch (const Error& e) {
        ++rejected;
        const std::string msg = e.what();
        if (msg.empty() || (!multi_line && msg.find('\n') != std::string::npos))
          problem = "rsvio::Error message is not one line: " + msg;
      } catch (const std::exception& e) {
        problem = std::string("exception that is not an rsvio::Error: ") + e.what();
      } catch (...) {
        problem = "unknown exception";
      }
      if (!problem.empty()) {
        ++failures;
        if (failures == 1) writeBytes(failure, input);
        if (failures <= 3)
          ADD_FAILURE() << harness << " input " << i << (i < static_cast<long>(corpus.size()) ? " (corpus)" : "")
                        << ": " << problem << "\n  input: " << printable(input) << "\n  saved: " << failure;
      }
    }
    std::remove(current.c_str());
    std::printf("[fuzz] %s: %ld executions (%zu corpus + %ld mutated), %ld accepted, %ld rejected with a message, "
                "%ld failures\n",
                harness.c_str(), total, corpus.size(), execs, accepted, rejected, failures);
    RecordProperty("executions", static_cast<int>(total));
    EXPECT_EQ(failures, 0);
  }

  fs::path work_;
};

}  // namespace

TEST_F(FuzzTest, Csv) {
  const fs::path f = work_ / "data.csv";
  fuzz("csv", {"#timestamp [ns],a,b", "1e3", "+5", "0x10", ",,", "  "}, [&](const std::string& in) {
    writeBytes(f, in);
    const unsigned char sel = in.empty() ? 0 : static_cast<unsigned char>(in.back());
    io::CsvFormat fmt;
    fmt.delimiter = sel & 1 ? io::CsvFormat::Delimiter::kWhitespace : io::CsvFormat::Delimiter::kComma;
    fmt.skip_text_header = sel & 2;
    io::CsvReader r(f.string(), {"t", "x", "y"}, fmt);
    while (r.next()) {
      for (size_t i = 0; i < r.size() + 1; ++i) {
        (void)r.raw(i);
        (void)r.column(i);
        (void)r.fieldName(i);
        try { (void)r.getInt64(i); } catch (const DataError&) {}
        try { (void)r.getDouble(i); } catch (const DataError&) {}
        try { (void)r.getFiniteDouble(i); } catch (const DataError&) {}
        try { (void)r.getString(i); } catch (const DataError&) {}
      }
      try { r.expectFieldCount(); } catch (const DataError&) {}
      r.expectFieldCount(1, 3);
    }
    (void)io::parseInt64(in);
    (void)io::parseDouble(in);
  });
}

// source.euroc opening a tiny dataset (64x48, 5 frames) whose mav0/cam0/sensor.yaml is the input.
TEST_F(FuzzTest, EurocSensorYaml) {
  test::DatasetSpec spec;
  test::writeDataset(work_, spec);
  auto src = test::makeSource();
  const fs::path yaml = work_ / "mav0" / "cam0" / "sensor.yaml";
  fuzz("euroc_yaml", {"intrinsics:", "resolution:", "T_BS:", "data: [", "]", "{", "}", "- ", ": ", "~", "&a", "*a",
                      "!!binary", "rows: 4", "cols: 4", "distortion_model: equidistant", "camera_model: omni"},
       [&](const std::string& in) {
         writeBytes(yaml, in);
         src->open(work_.string());
       });
}

// source.euroc with a Kalibr camchain (camchain-imucam.yaml in the dataset folder) as the input.
TEST_F(FuzzTest, KalibrCamchainYaml) {
  test::DatasetSpec spec;
  test::writeDataset(work_, spec);
  auto src = test::makeSource();
  const fs::path yaml = work_ / "camchain-imucam-fuzz.yaml";
  fuzz("kalibr_yaml", {"cam0:", "cam1:", "T_cam_imu:", "- [", "]", "intrinsics:", "resolution:", "timeshift_cam_imu:",
                       "line_delay:", "distortion_model: equidistant", "camera_model: pinhole", "~", "{", "}"},
       [&](const std::string& in) {
         writeBytes(yaml, in);
         src->open(work_.string());
       });
}

// DSO photometric calibration: pcalib.txt (inverse response), times.txt, vignette.png.
TEST_F(FuzzTest, PhotometricCalibration) {
  const fs::path f = work_ / "calib";
  fuzz("photometric", {"\x89PNG\r\n\x1a\n", " 255", " 65535", "00042 "}, [&](const std::string& in) {
    writeBytes(f, in);
    std::string first;
    try {
      (void)io::readInverseResponse(f.string());
    } catch (const Error& e) {
      first = e.what();
    }
    try {
      (void)io::readExposureTimes(f.string());
    } catch (const Error& e) {
      if (first.empty()) first = e.what();
    }
    (void)io::hasPngSignature(f.string());
    (void)io::readVignette(f.string(), in.size() % 2 ? 8 : 0, 6);
  });
}

// JSON configs: the input is a config file that may "extends" base.json (and itself, for cycles);
// trailing lines "--set a.b=v" are applied as --set; the result is validated against the run schema.
// Validation lists every problem at once, one per line (README, Configs), so messages may be multi-line.
TEST_F(FuzzTest, JsonConfig) {
  PluginHost host({RSVIO_PLUGIN_DIR});
  writeBytes(work_ / "base.json", R"({"threads": 1, "frontend": {"points": 300}, "camera": {"plugin": "camera.pinhole"}})");
  const fs::path f = work_ / "config.json";
  fuzz("config", {"\"extends\": ", "\"base.json\"", "\"config.json\"", "null", "true", "{", "}", "[", "]", ":",
                  "\"plugin\": ", "\"params\": ", "--set ", "=", ".", "\\u0000", "\"photometric\"", "1e400"},
       [&](const std::string& in) {
         std::string text = in;
         std::vector<std::string> sets;
         for (size_t at; (at = text.rfind("\n--set ")) != std::string::npos;) {
           sets.insert(sets.begin(), text.substr(at + 7));
           text.resize(at);
         }
         writeBytes(f, text);
         nlohmann::json raw = loadConfigWithSets(f.string(), sets);
         (void)validateConfig(raw, runConfigSchema(), host, f.string());
       },
       /*multi_line=*/true);
}

// Trajectories as eval reads them: TUM or EuRoC ground truth (readGroundTruth), estimates (readTum),
// and the evaluation of the input as an estimate against a valid ground truth.
TEST_F(FuzzTest, Trajectory) {
  const fs::path f = work_ / "traj.txt", gt = work_ / "gt.tum";
  std::string g = "# frame: camera\n";
  for (int i = 0; i < 20; ++i) {
    char b[160];
    std::snprintf(b, sizeof(b), "%d.%09d %.3f %.3f 0.5 0 0 %.6f %.6f\n", 100 + i / 10, (i % 10) * 100000000, 0.1 * i,
                  0.02 * i * i, std::sin(0.05 * i), std::cos(0.05 * i));
    g += b;
  }
  writeBytes(gt, g);
  fuzz("trajectory", {"# frame: body", "# frame: camera", "# frame: ", "1311868164.363181", "1e2"},
       [&](const std::string& in) {
         writeBytes(f, in);
         std::string first;
         try {
           (void)io::readGroundTruth(f.string());
         } catch (const Error& e) {
           first = e.what();
         }
         try {
           (void)io::readEurocMocap(f.string());
         } catch (const Error&) {
         }
         try {
           (void)io::readEurocStateGroundTruth(f.string());
         } catch (const Error&) {
         }
         (void)io::readTum(f.string());
         eval::FileEvalRequest req;
         req.gt_path = gt.string();
         req.est_path = f.string();
         (void)eval::evaluateFiles(req);
       });
}

TEST_F(FuzzTest, DiagnosticsLog) {
  const fs::path f = work_ / "diagnostics.bin";
  fuzz("diagnostics", {std::string("RSVIODG1\x01\0\0\0", 12), std::string(8, '\xff'), std::string(8, '\0')},
       [&](const std::string& in) {
         writeBytes(f, in);
         (void)DiagnosticsLog::read(f.string());
       });
}

TEST_F(FuzzTest, Ply) {
  const fs::path f = work_ / "points.ply";
  fuzz("ply", {"element vertex ", "property float x", "property double ", "property uchar ", "property list uchar int ",
               "format binary_little_endian 1.0", "format binary_big_endian 1.0", "format ascii 1.0", "end_header\n",
               "element face 1", "4294967295"},
       [&](const std::string& in) {
         writeBytes(f, in);
         (void)io::readPly(f.string());
       });
}

// A run folder as viz reads it (io::readSnapshot): the input's first line names the file it replaces
// ("@report.json"), the rest is that file; the other files come from a valid tiny run.
TEST_F(FuzzTest, Snapshot) {
  const fs::path run = work_ / "run";
  const auto corpus = loadCorpus("snapshot");
  std::map<std::string, std::string> base;  // the valid run: every corpus entry's file, first seen
  for (const auto& c : corpus) {
    const size_t nl = c.find('\n');
    if (c.rfind("@", 0) == 0 && nl != std::string::npos) base.emplace(c.substr(1, nl - 1), c.substr(nl + 1));
  }
  ASSERT_GE(base.size(), 5u);
  fuzz("snapshot", {"@report.json\n", "@trajectory.tum\n", "@keyframes.tum\n", "@states.csv\n", "@points.ply\n",
                    "\"status\": ", "\"failed\"", "\"eval\": ", "\"align\": \"sim3\"", "\"stage_ms\": ", "null"},
       [&](const std::string& in) {
         fs::remove_all(run);
         fs::create_directories(run);
         for (const auto& [name, text] : base) writeBytes(run / name, text);
         const size_t nl = in.find('\n');
         if (in.rfind("@", 0) == 0 && nl != std::string::npos) {
           const std::string name = in.substr(1, nl - 1);
           if (base.count(name)) writeBytes(run / name, in.substr(nl + 1));
         }
         io::SnapshotOptions opt;
         opt.ground_truth_path = (run / "trajectory.tum").string();
         (void)io::readSnapshot(run.string(), opt);
       });
}
