#pragma once
// A scripted stand-in for the Force Dimension DHD SDK header (not a Debian package; the SDK's
// dhdc.h declares these calls with these signatures, units m, m/s, N). Only the calls
// devices/src/dhd.cpp makes; each one reads or records the state in `fake_dhd::state`, so
// tests/devices/dhd_test.cpp can script the device and check what the back-end did.

#include <string>

using uchar = unsigned char;
// Constants as the SDK defines them: macros.
#define DHD_ON 1
#define DHD_NO_ERROR 0

namespace fake_dhd {
struct State {
  int open_result = 0;              // dhdOpen's answer (< 0: no device)
  int enable_result = 0;            // dhdEnableForce's answer
  int read_result = DHD_NO_ERROR;   // dhdGetPosition's and dhdGetLinearVelocity's answer
  std::string last_error = "none";  // dhdErrorGetLastStr
  std::string system_name = "omega.3";
  double p_m[3] = {0, 0, 0}, v_mps[3] = {0, 0, 0};
  double force_N[3] = {0, 0, 0};  // the last dhdSetForce
  int set_force_calls = 0, close_calls = 0, enable_calls = 0;
  char last_id = -2;  // the device id of the last call
};
inline State state;
}  // namespace fake_dhd

inline int dhdOpen() { return fake_dhd::state.open_result; }
inline const char* dhdErrorGetLastStr() { return fake_dhd::state.last_error.c_str(); }
inline const char* dhdGetSystemName(char id = -1) {
  fake_dhd::state.last_id = id;
  return fake_dhd::state.system_name.c_str();
}
inline int dhdEnableForce(uchar on, char id = -1) {
  fake_dhd::state.last_id = id;
  fake_dhd::state.enable_calls += on == DHD_ON ? 1 : 0;
  return fake_dhd::state.enable_result;
}
inline int dhdClose(char id = -1) {
  fake_dhd::state.last_id = id;
  ++fake_dhd::state.close_calls;
  return 0;
}
inline int dhdSetForce(double fx, double fy, double fz, char id = -1) {
  auto& s = fake_dhd::state;
  s.last_id = id;
  s.force_N[0] = fx, s.force_N[1] = fy, s.force_N[2] = fz;
  ++s.set_force_calls;
  return 0;
}
inline int dhdGetPosition(double* px, double* py, double* pz, char id = -1) {
  auto& s = fake_dhd::state;
  s.last_id = id;
  *px = s.p_m[0], *py = s.p_m[1], *pz = s.p_m[2];
  return s.read_result;
}
inline int dhdGetLinearVelocity(double* vx, double* vy, double* vz, char id = -1) {
  auto& s = fake_dhd::state;
  s.last_id = id;
  *vx = s.v_mps[0], *vy = s.v_mps[1], *vz = s.v_mps[2];
  return s.read_result;
}
