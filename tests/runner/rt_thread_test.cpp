// The loop threads set themselves up before their first tick (rt_thread.hpp): timer slack
// 1 ns read back on each loop thread; a refused SCHED_FIFO or memory-lock request is
// reported and the loops run anyway. Real clock, no timing assertions.

#include "hapticlab/runner/rt_thread.hpp"

#include <gtest/gtest.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>

#include "../renderer/test_materials.hpp"
#include "hapticlab/runner/rt_engine.hpp"
#include "hapticlab/test/test_util.hpp"

namespace hapticlab::runner::rt_thread_test {
namespace {

// A stylus held still 0.2 mm into the surface, stamped with the engine's clock.
class StillDevice : public devices::HapticDevice {
 public:
  explicit StillDevice(const RtEngine*& engine) : engine_(engine) {}
  devices::DeviceCapabilities Capabilities() const override { return {}; }
  devices::ReadResult Read(renderer::DeviceSample* out) noexcept override {
    out->state.p_m = {0, 0, -0.2e-3};
    out->state.v_mps = {0.02, 0, 0};
    out->t_s = engine_->Now();
    return devices::ReadResult::kOk;
  }
  void WriteForce(const Eigen::Vector3d&) noexcept override {}

 private:
  const RtEngine*& engine_;
};

struct EngineRun {
  EngineStats stats;
  long slack_seen_ns[2] = {-1, -1};  // read back on each loop thread by the enter hook
  int threads = 0;
};

EngineRun RunEngine(const RtThreadOptions& rt, double seconds = 0.1) {
  const auto m = test::TexturedMaterial();
  renderer::RenderOptions ro;
  ro.force_rate_hz = 1000;
  ro.vibration_rate_hz = 10000;
  renderer::HybridRenderer r(m, ro);
  const RtEngine* eng = nullptr;
  StillDevice dev(eng);
  EngineRun out;
  std::atomic<int> n{0};
  EngineOptions eo;
  eo.rt = rt;
  eo.on_thread_enter = [&] {
    const int i = n.fetch_add(1);
    if (i < 2) out.slack_seen_ns[i] = CurrentTimerSlackNs();
  };
  RtEngine engine(r, dev, nullptr, eo);
  eng = &engine;
  engine.RunFor(std::chrono::duration<double>(seconds));
  out.stats = engine.Stats();
  out.threads = n.load();
  return out;
}

TEST(RtThread, LoopThreadsRunWithOneNanosecondTimerSlack) {
  // The test's own thread keeps the default (50 us for an ordinary thread): the loops set theirs.
  const long own = CurrentTimerSlackNs();
  const EngineRun r = RunEngine({});
  ASSERT_EQ(r.threads, 2);
  EXPECT_EQ(r.slack_seen_ns[0], 1);
  EXPECT_EQ(r.slack_seen_ns[1], 1);
  EXPECT_EQ(r.stats.force_thread.timer_slack_ns, 1);
  EXPECT_EQ(r.stats.vibration_thread.timer_slack_ns, 1);
  EXPECT_EQ(CurrentTimerSlackNs(), own) << "the caller's thread is left alone";
  EXPECT_TRUE(r.stats.force_thread.stack_prefaulted);
  EXPECT_GT(r.stats.force_ticks, 10u);
  // Every tick is in the histograms.
  EXPECT_EQ(r.stats.force_timing.ticks, r.stats.force_ticks);
  EXPECT_LE(r.stats.force_timing.late_p50_s, r.stats.force_timing.late_p99_s);
  EXPECT_LE(r.stats.force_timing.late_p99_s, r.stats.force_timing.late_max_s);
}

TEST(RtThread, APriorityAboveTheMaximumIsReportedNotFatal) {
  RtThreadOptions rt;
  rt.priority = sched_get_priority_max(SCHED_FIFO) + 1;
  const EngineRun r = RunEngine(rt);
  EXPECT_FALSE(r.stats.force_thread.fifo);
  EXPECT_EQ(r.stats.force_thread.priority, 0);
  EXPECT_NE(r.stats.force_thread.priority_status.find("refused"), std::string::npos)
      << r.stats.force_thread.priority_status;
  EXPECT_NE(r.stats.priority_status.find("outside"), std::string::npos) << r.stats.priority_status;
  EXPECT_GT(r.stats.force_ticks, 10u) << "the loops ran anyway";
  EXPECT_EQ(sched_getscheduler(0), SCHED_OTHER);
}

TEST(RtThread, AnUnprivilegedProcessIsRefusedFifoAndMemoryLockAndRunsAnyway) {
  // A child without the privileges: RLIMIT_RTPRIO and RLIMIT_MEMLOCK 0 and, when the test
  // runs as root, the uid of nobody (which drops every capability).
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const rlimit zero{0, 0};
    if (setrlimit(RLIMIT_RTPRIO, &zero) != 0 || setrlimit(RLIMIT_MEMLOCK, &zero) != 0) _exit(10);
    if (geteuid() == 0 && setresuid(65534, 65534, 65534) != 0) _exit(11);
    RtThreadOptions rt;
    rt.priority = 50;
    rt.lock_memory = true;
    const EngineRun r = RunEngine(rt, 0.05);
    if (r.stats.force_thread.fifo || r.stats.vibration_thread.fifo) _exit(12);
    if (r.stats.force_thread.priority_status.rfind("refused", 0) != 0) _exit(13);
    // The sanitizers intercept mlockall and return success without locking (they cannot lock
    // their shadow memory), so a refusal can only be seen in an uninstrumented build.
    if (!test::kSanitizerBuild &&
        (r.stats.memory.locked || r.stats.memory.status.rfind("refused", 0) != 0))
      _exit(14);
    if (r.stats.force_ticks < 10) _exit(15);
    if (r.stats.force_thread.timer_slack_ns != 1) _exit(16);
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0)
      << "10/11: could not drop privileges; 12: FIFO granted; 13: no refusal reported; "
         "14: memory lock not refused; 15: loops did not run; 16: slack";
}

TEST(RtThread, AnOutOfRangeCpuIsReported) {
  RtThreadOptions rt;
  rt.cpu = CPU_SETSIZE + 5;
  const EngineRun r = RunEngine(rt, 0.05);
  EXPECT_EQ(r.stats.force_thread.cpu, -1);
  EXPECT_NE(r.stats.force_thread.affinity_status.find("refused"), std::string::npos);
  EXPECT_GT(r.stats.force_ticks, 10u);
}

}  // namespace
}  // namespace hapticlab::runner::rt_thread_test
