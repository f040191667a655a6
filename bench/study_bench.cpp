// How many times faster than real time a simulated session runs: one participant through the
// dissertation's ch. V.3 protocol (training + 90 rated trials, 1.5 s per stimulus, both
// stimuli of every trial rendered at 1 kHz force / 10 kHz vibration) into a fresh database.
// The counter `realtime_x` is simulated stimulus time / wall time.
//
//   build/bench/study_bench

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>

#include "hapticlab/runner/study_runner.hpp"

namespace {

using namespace hapticlab;

void Session(benchmark::State& state, runner::RecordMode mode) {
  const auto p = protocols::LoadProtocol(std::string(HL_SOURCE_DIR) +
                                         "/studies/shin2019/ch5-hybrid-realism.toml");
  const auto db = (std::filesystem::temp_directory_path() /
                   ("hl_study_bench_" + std::to_string(getpid()) + ".db"))
                      .string();
  double simulated = 0, wall = 0;
  int i = 0;
  for (auto _ : state) {
    runner::RunOptions o;
    o.db_path = db;
    o.participant = "B" + std::to_string(++i);
    o.record = mode;
    const auto t0 = std::chrono::steady_clock::now();
    const auto s = runner::RunStudy(p, o);
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    simulated += s.simulated_s;
  }
  state.counters["realtime_x"] = simulated / wall;
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(db + suffix);
}

void SimulatedSessionNoRecording(benchmark::State& state) {
  Session(state, runner::RecordMode::kNone);
}
void SimulatedSessionRecordingAll(benchmark::State& state) {
  Session(state, runner::RecordMode::kAll);
}
BENCHMARK(SimulatedSessionNoRecording)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK(SimulatedSessionRecordingAll)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
