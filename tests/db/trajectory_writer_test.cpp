#include "hapticlab/db/trajectory_writer.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "hapticlab/db/database.hpp"
#include "hapticlab/test/study_rows.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::db::trajectory_writer_test {
namespace {

struct Fixture {
  test::TempDir dir;
  std::string path = dir.File("w.db");
  std::int64_t trial = 0;
  Fixture() {
    Database db(path);
    const auto se =
        test::AddStudySession(db, {.name = "w", .protocol_toml = "x", .seed = 1}).session;
    trial = db.AddTrial({.session_id = se, .phase = PhaseKind::kMain, .material = "m"});
  }
};

std::vector<std::string> Channels(int n) {
  std::vector<std::string> c;
  for (int i = 0; i < n; ++i) c.push_back("ch" + std::to_string(i));
  return c;
}

// The live display's copy (TrajectoryStream::Latest): nothing before the writer took a
// sample; after a flush, the newest sample pushed, values and time as recorded.
TEST(TrajectoryWriter, LatestIsTheNewestSampleTheWriterTook) {
  Fixture f;
  TrajectoryWriter w(f.path);
  auto* s = w.OpenStream(f.trial, "force", 1000, Channels(3));
  TrajectorySample got{};
  EXPECT_FALSE(s->Latest(&got)) << "nothing recorded yet";
  for (int i = 0; i < 50; ++i) {
    const float v[3] = {static_cast<float>(i), 2.f * static_cast<float>(i), -1.f};
    s->Push(i / 1000.0, v);
  }
  w.Flush();
  ASSERT_TRUE(s->Latest(&got));
  EXPECT_EQ(got.t_s, 49 / 1000.0);
  EXPECT_EQ(got.values[0], 49.f);
  EXPECT_EQ(got.values[1], 98.f);
  EXPECT_EQ(got.values[2], -1.f);
  w.CloseStream(s);
}

TEST(TrajectoryWriter, KeepsUpWith4kHzTimes16ChannelsWithoutProducerBlocking) {
  Fixture f;
  constexpr double kRate = 4000;
  constexpr int kSamples = 8000;  // 2 s paced at the real rate
  TrajectoryWriter w(f.path);
  auto* s = w.OpenStream(f.trial, "force", kRate, Channels(16));
  float v[16];
  const auto t0 = std::chrono::steady_clock::now();
  int pushed = 0;
  for (int i = 0; i < kSamples; ++i) {
    for (int c = 0; c < 16; ++c) v[c] = static_cast<float>(i * 16 + c);
    {
      test::NoAllocGuard guard;  // the producer's call allocates nothing
      if (s->Push(i / kRate, v)) ++pushed;
      ASSERT_EQ(guard.count(), 0u);
    }
    std::this_thread::sleep_until(t0 + std::chrono::microseconds(250 * (i + 1)));
  }
  w.CloseStream(s);
  EXPECT_EQ(pushed, kSamples);
  EXPECT_TRUE(w.error().empty()) << w.error();
  Database db(f.path);
  const auto chunks = db.TrajectoryChunks(f.trial);
  std::size_t total = 0;
  for (const auto& c : chunks) {
    ASSERT_EQ(c.channels.size(), 16u);
    // Each chunk's samples are consecutive and their times follow from start and rate.
    const auto first = static_cast<std::size_t>(std::lround(c.start_time_s * kRate));
    for (std::size_t i = 0; i < c.sample_count(); ++i)
      for (std::size_t ch = 0; ch < 16; ++ch)
        ASSERT_EQ(c.samples[i * 16 + ch], static_cast<float>((first + i) * 16 + ch));
    total += c.sample_count();
  }
  EXPECT_EQ(total, static_cast<std::size_t>(kSamples));
}

TEST(TrajectoryWriter, OverflowIsCountedNotWaitedOnAndGapsCutChunks) {
  Fixture f;
  WriterOptions o;
  o.queue_capacity = 64;
  o.start_thread = false;  // nobody drains: the queue fills
  TrajectoryWriter w(f.path, o);
  auto* s = w.OpenStream(f.trial, "vib", 1000, {"acc_mps2"});
  int accepted = 0;
  for (int i = 0; i < 100; ++i) {
    const float x = static_cast<float>(i);
    if (s->Push(i / 1000.0, &x)) ++accepted;
  }
  EXPECT_EQ(accepted, 64);
  EXPECT_EQ(s->overflow_count(), 36u);
  w.CloseStream(s);
  Database db(f.path);
  const auto chunks = db.TrajectoryChunks(f.trial);
  ASSERT_EQ(chunks.size(), 1u);
  EXPECT_EQ(chunks[0].sample_count(), 64u);
  EXPECT_EQ(chunks[0].samples.back(), 63.f);  // the rejected samples never appear
}

TEST(TrajectoryWriter, ATimeGapStartsANewChunk) {
  Fixture f;
  WriterOptions o;
  o.start_thread = false;
  TrajectoryWriter w(f.path, o);
  auto* s = w.OpenStream(f.trial, "vib", 1000, {"acc_mps2"});
  for (int i : {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 20, 21, 22}) {
    const float x = static_cast<float>(i);
    ASSERT_TRUE(s->Push(i / 1000.0, &x));
  }
  w.CloseStream(s);
  Database db(f.path);
  const auto chunks = db.TrajectoryChunks(f.trial);
  ASSERT_EQ(chunks.size(), 2u);
  EXPECT_EQ(chunks[0].sample_count(), 10u);
  EXPECT_NEAR(chunks[1].start_time_s, 0.020, 1e-12);
  EXPECT_EQ(chunks[1].samples, (std::vector<float>{20.f, 21.f, 22.f}));
}

TEST(TrajectoryWriter, DestructorWritesEverythingQueued) {
  Fixture f;
  {
    WriterOptions o;
    o.chunk_samples = 7;
    TrajectoryWriter w(f.path, o);
    auto* s = w.OpenStream(f.trial, "force", 1000, {"a", "b"});
    for (int i = 0; i < 50; ++i) {
      const float x[2] = {static_cast<float>(i), -static_cast<float>(i)};
      s->Push(i / 1000.0, x);
    }
  }
  Database db(f.path);
  std::size_t total = 0;
  for (const auto& c : db.TrajectoryChunks(f.trial)) {
    EXPECT_LE(c.sample_count(), 7u);
    total += c.sample_count();
  }
  EXPECT_EQ(total, 50u);
}

TEST(TrajectoryWriter, AFailedCommitIsRetriedSoNothingIsLost) {
  // A lock released before the stream closes: the failed chunks are committed on a retry.
  Fixture f;
  const std::string& path = f.path;
  const std::vector<std::int64_t> ids = {f.trial};
  Database db(path);
  TrajectoryWriter w(path, {.chunk_samples = 10, .busy_timeout_ms = 20});
  db.StartTrial(ids[0]);
  auto* s = w.OpenStream(ids[0], "left_force", 1000.0, {"a"});
  Database locker(path);
  locker.Exec("BEGIN EXCLUSIVE");
  const float v = 1;
  for (int i = 0; i < 50; ++i) ASSERT_TRUE(s->Push(i / 1000.0, &v));
  // Wait (no time limit asserted) until the writer has met the lock at least once.
  while (w.error().empty()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  locker.Exec("COMMIT");
  const auto rep = w.CloseStream(s);
  EXPECT_EQ(rep.samples_written, 50u);
  EXPECT_NO_THROW(db.CompleteTrial(ids[0], {{"roughness", 50, 1}}, w.TakeReports(ids[0])));
  std::uint64_t n = 0;
  for (const auto& c : db.TrajectoryChunks(ids[0])) n += c.sample_count();
  EXPECT_EQ(n, 50u);
}

}  // namespace
}  // namespace hapticlab::db::trajectory_writer_test
