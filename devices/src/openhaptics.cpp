// 3D Systems (SensAble) devices through the OpenHaptics HD API (compiled only with the SDK:
// HL_HAVE_OPENHAPTICS). The HD scheduler owns the servo loop (1 kHz); its callback copies the
// device state out and the engine's last force in through lock-free triple buffers, so the
// engine's loop and the scheduler never wait on each other (one extra servo tick of latency).
// The force slot carries the time the engine wrote it: when it is older than
// kForceStaleNs (the engine stalled or stopped), the servo commands zero force.
// Units: the HD API works in millimetres; HapticLab in metres.
#include <HD/hd.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>

#include "hapticlab/core/triple_buffer.hpp"
#include "hapticlab/devices/vendor.hpp"

namespace hapticlab::devices {
namespace {

struct State {
  double p[3], v[3];
  double t;
  bool ok;
};
struct Force {
  double f[3];
  long long t_ns;  // steady-clock time the engine wrote it
};
constexpr long long kForceStaleNs = 5'000'000;  // 5 ms: five servo ticks

long long SteadyNs() noexcept {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

class OpenHapticsDevice final : public HapticDevice {
 public:
  explicit OpenHapticsDevice(const std::string& name) {
    hhd_ = hdInitDevice(name.empty() ? HD_DEFAULT_DEVICE : name.c_str());
    HDErrorInfo e = hdGetError();
    if (HD_DEVICE_ERROR(e))
      throw std::runtime_error("openhaptics: cannot initialise the device (error " +
                               std::to_string(e.errorCode) + ")");
    hdGetDoublev(HD_NOMINAL_MAX_FORCE, &max_force_N_);
    double k_hd = 0;  // N/mm, the HD API's unit
    hdGetDoublev(HD_NOMINAL_MAX_STIFFNESS, &k_hd);
    max_k_N_per_m_ = k_hd * 1000;
    hdEnable(HD_FORCE_OUTPUT);
    handle_ = hdScheduleAsynchronous(&Servo, this, HD_MAX_SCHEDULER_PRIORITY);
    hdStartScheduler();
    e = hdGetError();
    if (HD_DEVICE_ERROR(e)) {
      hdDisableDevice(hhd_);
      throw std::runtime_error("openhaptics: cannot start the scheduler (error " +
                               std::to_string(e.errorCode) + ")");
    }
  }
  ~OpenHapticsDevice() override {
    hdStopScheduler();
    hdUnschedule(handle_);
    hdDisableDevice(hhd_);
  }
  DeviceCapabilities Capabilities() const override {
    DeviceCapabilities c;
    c.name = "openhaptics";
    c.max_force_N = max_force_N_;
    c.max_stiffness_N_per_m = max_k_N_per_m_;
    c.max_rate_hz = 1000;
    return c;
  }
  void SetTimeBase(std::chrono::steady_clock::time_point t0) noexcept override {
    t0_ns_.store(
        std::chrono::duration_cast<std::chrono::nanoseconds>(t0.time_since_epoch()).count());
  }
  ReadResult Read(DeviceSample* out) noexcept override {
    const State& s = state_.Read();
    if (!s.ok) return ReadResult::kLost;
    if (s.t == last_t_) return ReadResult::kNoNewData;  // the servo has not run since
    last_t_ = s.t;
    out->state.p_m = {s.p[0], s.p[1], s.p[2]};
    out->state.v_mps = {s.v[0], s.v[1], s.v[2]};
    out->t_s = s.t;
    return ReadResult::kOk;
  }
  void WriteForce(const Eigen::Vector3d& f) noexcept override {
    Force& slot = force_.WriteSlot();
    slot.f[0] = f.x(), slot.f[1] = f.y(), slot.f[2] = f.z();
    slot.t_ns = SteadyNs();
    force_.Publish();
  }

 private:
  static HDCallbackCode HDCALLBACK Servo(void* self_ptr) {
    auto* self = static_cast<OpenHapticsDevice*>(self_ptr);
    hdBeginFrame(self->hhd_);
    double p[3], v[3];
    hdGetDoublev(HD_CURRENT_POSITION, p);  // mm
    hdGetDoublev(HD_CURRENT_VELOCITY, v);  // mm/s
    const Force& f = self->force_.Read();
    // A stale slot (the engine stalled or stopped writing) gives zero force.
    const bool fresh = SteadyNs() - f.t_ns <= kForceStaleNs;
    double cmd[3] = {fresh ? f.f[0] : 0.0, fresh ? f.f[1] : 0.0, fresh ? f.f[2] : 0.0};
    hdSetDoublev(HD_CURRENT_FORCE, cmd);
    hdEndFrame(self->hhd_);
    const HDErrorInfo e = hdGetError();
    State& s = self->state_.WriteSlot();
    for (int i = 0; i < 3; ++i) s.p[i] = p[i] * 1e-3, s.v[i] = v[i] * 1e-3;
    const auto now = std::chrono::steady_clock::now().time_since_epoch();
    s.t = static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(now).count() -
                              self->t0_ns_.load()) *
          1e-9;
    s.ok = !HD_DEVICE_ERROR(e);
    self->state_.Publish();
    return HD_CALLBACK_CONTINUE;
  }

  HHD hhd_ = HD_INVALID_HANDLE;
  HDSchedulerHandle handle_ = 0;
  double max_force_N_ = 3.3, max_k_N_per_m_ = 1000;
  TripleBuffer<State> state_{State{{0, 0, 0}, {0, 0, 0}, 0, false}};
  TripleBuffer<Force> force_{Force{{0, 0, 0}, 0}};
  double last_t_ = -1;  // engine thread only
  std::atomic<long long> t0_ns_{0};
};

}  // namespace

bool HaveOpenHaptics() { return true; }
std::unique_ptr<HapticDevice> OpenOpenHaptics(const std::string& name) {
  return std::make_unique<OpenHapticsDevice>(name);
}

}  // namespace hapticlab::devices
