// The exports of a demo-sized study database (issue #32: "BIDS of 3 participants takes 41 s"):
// 3 simulated participants of the dissertation's ch. V.3 protocol (training + 90 rated trials
// each) recorded as `hapticlab demo --participants 3 --record R` records them, then timed:
//  - BM_ExportCsv/0: ratings, trials and events (the CSV default);
//  - BM_ExportCsv/1: the same with the trajectory tables (--trajectories);
//  - BM_ExportBids: the BIDS dataset (beh tables, gzipped physio recordings, sidecars);
//  - BM_ExportXdf: one XDF file per session.
// The database is built once per process (tens of seconds); each export writes into a fresh
// directory. HL_EXPORT_BENCH_RECORD=all records every participant's trajectories (default:
// the demo's default, 'first').
//
//   build/bench/export_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "hapticlab/db/database.hpp"
#include "hapticlab/db/export.hpp"
#include "hapticlab/db/interchange.hpp"
#include "hapticlab/runner/study_runner.hpp"

namespace {

using namespace hapticlab;
namespace fs = std::filesystem;

const fs::path& Dir() {
  static const fs::path kDir =
      fs::temp_directory_path() / ("hl_export_bench_" + std::to_string(getpid()));
  return kDir;
}

// The demo's database, made on first use.
const std::string& DemoDb() {
  static const std::string kPath = [] {
    fs::create_directories(Dir());
    std::string db = (Dir() / "study.db").string();
    const char* env = std::getenv("HL_EXPORT_BENCH_RECORD");
    const bool all = env && std::string(env) == "all";
    const auto p = protocols::LoadProtocol(std::string(HL_SOURCE_DIR) +
                                           "/studies/shin2019/ch5-hybrid-realism.toml");
    for (int i = 0; i < 3; ++i) {
      runner::RunOptions o;
      o.db_path = db;
      o.participant = "SIM0" + std::to_string(i + 1);
      o.record = all || i == 0 ? runner::RecordMode::kAll : runner::RecordMode::kNone;
      runner::RunStudy(p, o);
    }
    return db;
  }();
  return kPath;
}

void Export(benchmark::State& state, const char* format) {
  const db::Database d = db::OpenForReading(DemoDb());
  int run = 0;
  std::size_t files = 0;
  for (auto _ : state) {
    const fs::path out = Dir() / (std::string(format) + std::to_string(++run));
    const std::string f = format;
    if (f == "csv")
      files = db::ExportCsv(d, out.string(), state.range(0) != 0).size();
    else if (f == "bids")
      files = db::ExportBids(d, out.string()).size();
    else
      files = db::ExportXdf(d, out.string()).size();
    state.PauseTiming();
    fs::remove_all(out);
    state.ResumeTiming();
  }
  state.counters["files"] = static_cast<double>(files);
}

void BM_ExportCsv(benchmark::State& state) { Export(state, "csv"); }
void BM_ExportBids(benchmark::State& state) { Export(state, "bids"); }
void BM_ExportXdf(benchmark::State& state) { Export(state, "xdf"); }
BENCHMARK(BM_ExportCsv)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_ExportBids)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_ExportXdf)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  fs::remove_all(Dir());
  return 0;
}
