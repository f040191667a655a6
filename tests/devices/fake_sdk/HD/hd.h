#pragma once
// A scripted stand-in for the OpenHaptics HD API header (3D Systems; not a Debian package).
// The declarations follow the SDK's hd.h (handles, HDErrorInfo, the scheduler callback, the
// HD_* parameters; lengths in millimetres, forces in newtons); only the calls
// devices/src/openhaptics.cpp makes. The scheduler runs no thread here: a test calls
// fake_hd::Tick() to run the scheduled servo callback once, as the HD servo loop would.

#include <cstdint>
#include <string>

using HHD = unsigned int;
using HDerror = unsigned int;
using HDenum = unsigned int;
using HDdouble = double;
using HDushort = std::uint16_t;
using HDCallbackCode = unsigned int;
using HDSchedulerHandle = unsigned long;
#define HDCALLBACK
using HDSchedulerCallback = HDCallbackCode (*)(void*);

// Constants as the SDK defines them: macros.
#define HD_INVALID_HANDLE 0xFFFFFFFFu
#define HD_SUCCESS 0x0000u
#define HD_CALLBACK_DONE 0u
#define HD_CALLBACK_CONTINUE 1u
#define HD_MAX_SCHEDULER_PRIORITY static_cast<HDushort>(0xFFFF)
#define HD_DEFAULT_DEVICE nullptr
#define HD_CURRENT_POSITION 0x2050u
#define HD_CURRENT_VELOCITY 0x2051u
#define HD_CURRENT_FORCE 0x2700u
#define HD_NOMINAL_MAX_STIFFNESS 0x2602u
#define HD_NOMINAL_MAX_FORCE 0x2603u
#define HD_FORCE_OUTPUT 0x4000u

struct HDErrorInfo {
  HDerror errorCode;
  int internalErrorCode;
  HHD hHD;
};
#define HD_DEVICE_ERROR(X) (((X).errorCode) != HD_SUCCESS)

namespace fake_hd {
struct State {
  HDerror init_error = HD_SUCCESS;   // hdGetError after hdInitDevice
  HDerror frame_error = HD_SUCCESS;  // hdGetError after a servo frame
  HDerror pending = HD_SUCCESS;      // what the next hdGetError returns
  double max_force_N = 3.3, max_stiffness_N_per_mm = 0.8;
  double p_mm[3] = {0, 0, 0}, v_mmps[3] = {0, 0, 0};
  double force_N[3] = {0, 0, 0};  // the last HD_CURRENT_FORCE
  bool force_output = false, scheduler_running = false, disabled = false;
  std::string init_name = "unset";  // the device name hdInitDevice was given
  HDSchedulerCallback callback = nullptr;
  void* user = nullptr;
  int frames = 0;
};
inline State state;
// Runs the scheduled callback once (one servo tick).
inline HDCallbackCode Tick() {
  state.pending = state.frame_error;
  return state.callback(state.user);
}
}  // namespace fake_hd

inline HHD hdInitDevice(const char* name) {
  fake_hd::state.init_name = name ? name : "(default)";
  fake_hd::state.pending = fake_hd::state.init_error;
  return 1;
}
inline HDErrorInfo hdGetError() {
  const HDErrorInfo e{fake_hd::state.pending, 0, 1};
  fake_hd::state.pending = HD_SUCCESS;
  return e;
}
inline void hdGetDoublev(HDenum what, HDdouble* out) {
  const auto& s = fake_hd::state;
  if (what == HD_NOMINAL_MAX_FORCE) out[0] = s.max_force_N;
  if (what == HD_NOMINAL_MAX_STIFFNESS) out[0] = s.max_stiffness_N_per_mm;
  for (int i = 0; i < 3; ++i) {
    if (what == HD_CURRENT_POSITION) out[i] = s.p_mm[i];
    if (what == HD_CURRENT_VELOCITY) out[i] = s.v_mmps[i];
  }
}
inline void hdSetDoublev(HDenum what, const HDdouble* in) {
  if (what == HD_CURRENT_FORCE)
    for (int i = 0; i < 3; ++i) fake_hd::state.force_N[i] = in[i];
}
inline void hdEnable(HDenum what) { fake_hd::state.force_output |= what == HD_FORCE_OUTPUT; }
inline HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback cb, void* user, HDushort) {
  fake_hd::state.callback = cb;
  fake_hd::state.user = user;
  return 7;
}
inline void hdStartScheduler() { fake_hd::state.scheduler_running = true; }
inline void hdStopScheduler() { fake_hd::state.scheduler_running = false; }
inline void hdUnschedule(HDSchedulerHandle) { fake_hd::state.callback = nullptr; }
inline void hdDisableDevice(HHD) { fake_hd::state.disabled = true; }
inline void hdBeginFrame(HHD) { ++fake_hd::state.frames; }
inline void hdEndFrame(HHD) {}
