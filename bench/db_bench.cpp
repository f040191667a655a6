// Trajectory samples per second into SQLite: the writer (SPSC queue -> packed float32
// chunks) against two baselines of one INSERT per sample (a row of 16 REAL columns through a
// prepared statement):
//  - BM_InsertPerSample: each INSERT its own transaction, as a naive logger that writes every
//    sample when it arrives would do (the study database's synchronous=FULL setting);
//  - BM_InsertPerSampleBatched: the same INSERTs grouped in transactions of the writer's
//    chunk size, the strongest row-per-sample design.
// Prints both ratios at the end.
//
//   build/bench/db_bench [--benchmark_min_time=2]

#include <benchmark/benchmark.h>
#include <sqlite3.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

#include "hapticlab/db/database.hpp"
#include "hapticlab/db/trajectory_writer.hpp"

namespace {

using namespace hapticlab;

constexpr int kChannels = 16;
constexpr int kBatch = 2048;  // samples per writer chunk and per baseline transaction

std::string TempDb(const char* tag) {
  return (std::filesystem::temp_directory_path() /
          ("hl_db_bench_" + std::string(tag) + "_" + std::to_string(getpid()) + ".db"))
      .string();
}

void RemoveDb(const std::string& p) {
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(p + suffix);
}

std::int64_t MakeTrial(db::Database& d) {
  const auto st = d.CreateStudy({.name = "bench", .protocol_toml = "x", .seed = 1});
  const auto p = d.AddParticipant({.study_id = st, .code = "P01"});
  const auto se = d.StartSession({.participant_id = p});
  return d.AddTrial({.session_id = se, .phase = PhaseKind::kMain, .material = "m"});
}

void BM_WriterSamples(benchmark::State& state) {
  const std::string path = TempDb("writer");
  RemoveDb(path);
  std::int64_t trial;
  {
    db::Database d(path);
    trial = MakeTrial(d);
  }
  std::int64_t total = 0;
  std::uint64_t overflow = 0;
  {
    db::TrajectoryWriter w(path);
    std::vector<std::string> ch;
    for (int c = 0; c < kChannels; ++c) ch.push_back("ch" + std::to_string(c));
    auto* s = w.OpenStream(trial, "force", 4000, ch);
    float v[kChannels] = {};
    double t = 0;
    for (auto _ : state) {
      // 20 000 samples (5 s at 4 kHz), pushed as fast as the queue accepts them.
      for (int i = 0; i < 20000; ++i) {
        v[0] = static_cast<float>(i);
        while (!s->Push(t, v)) {
        }  // benchmark only: measure the writer's sustained rate, not the queue size
        t += 1.0 / 4000;
      }
      w.Flush();
      total += 20000;
    }
    overflow = s->overflow_count();
  }
  state.SetItemsProcessed(total);
  state.counters["queue_full_retries"] = static_cast<double>(overflow);
  RemoveDb(path);
}
BENCHMARK(BM_WriterSamples)->Unit(benchmark::kMillisecond)->UseRealTime();

// Runs `per_txn` INSERTs per transaction, `samples` per iteration.
void InsertRows(benchmark::State& state, int samples, int per_txn) {
  const std::string path = TempDb("insert");
  RemoveDb(path);
  db::Database d(path);
  const auto trial = MakeTrial(d);
  std::string cols = "trial_id, t_s", qs = "?, ?";
  for (int c = 0; c < kChannels; ++c) {
    cols += ", ch" + std::to_string(c);
    qs += ", ?";
  }
  d.Exec("CREATE TABLE sample (" + cols + ")");
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(d.handle(), ("INSERT INTO sample VALUES (" + qs + ")").c_str(), -1, &st,
                     nullptr);
  std::int64_t total = 0;
  double t = 0;
  for (auto _ : state) {
    for (int b = 0; b < samples / per_txn; ++b) {
      db::WriteTransaction tx(d);
      for (int i = 0; i < per_txn; ++i) {
        sqlite3_bind_int64(st, 1, trial);
        sqlite3_bind_double(st, 2, t);
        for (int c = 0; c < kChannels; ++c) sqlite3_bind_double(st, 3 + c, i + c);
        sqlite3_step(st);
        sqlite3_reset(st);
        t += 1.0 / 4000;
      }
      tx.Commit();
      total += per_txn;
    }
  }
  sqlite3_finalize(st);
  state.SetItemsProcessed(total);
  RemoveDb(path);
}

void BM_InsertPerSample(benchmark::State& state) { InsertRows(state, 1000, 1); }
BENCHMARK(BM_InsertPerSample)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_InsertPerSampleBatched(benchmark::State& state) { InsertRows(state, 10 * kBatch, kBatch); }
BENCHMARK(BM_InsertPerSampleBatched)->Unit(benchmark::kMillisecond)->UseRealTime();

// Console output plus a record of each benchmark's items per second.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const auto& r : runs) {
      auto it = r.counters.find("items_per_second");
      if (it != r.counters.end()) rate[r.benchmark_name()] = it->second.value;
    }
  }
  std::map<std::string, double> rate;
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  double w = 0, b = 0, bb = 0;
  for (const auto& [name, v] : reporter.rate) {
    if (name.rfind("BM_WriterSamples", 0) == 0) w = v;
    if (name.rfind("BM_InsertPerSample/", 0) == 0) b = v;
    if (name.rfind("BM_InsertPerSampleBatched", 0) == 0) bb = v;
  }
  if (w > 0 && b > 0 && bb > 0)
    std::printf(
        "\nwriter: %.0f samples/s (16 ch)\n"
        "one INSERT per sample, own transaction: %.0f samples/s, writer is %.1fx faster\n"
        "one INSERT per sample, batched %d per transaction: %.0f samples/s, writer is "
        "%.1fx faster\n",
        w, b, w / b, kBatch, bb, w / bb);
  benchmark::Shutdown();
  return 0;
}
