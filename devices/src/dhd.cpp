// Force Dimension devices through the DHD API (compiled only with the SDK: HL_HAVE_DHD).
// Units: the DHD API works in metres, metres per second and newtons, as HapticLab does.
// No vendor scheduler runs here: the engine's force loop calls dhdSetForce itself, so there
// is no force slot to go stale (a stopped engine's last command is zero, RtEngine::Stop).
#include <dhdc.h>

#include <chrono>
#include <stdexcept>
#include <string>

#include "hapticlab/devices/vendor.hpp"

namespace hapticlab::devices {
namespace {

class DhdDevice final : public HapticDevice {
 public:
  DhdDevice() {
    id_ = dhdOpen();
    if (id_ < 0)
      throw std::runtime_error(std::string("dhd: cannot open a device: ") + dhdErrorGetLastStr());
    name_ = std::string("dhd ") + dhdGetSystemName();
    if (dhdEnableForce(DHD_ON, static_cast<char>(id_)) < 0) {
      dhdClose(static_cast<char>(id_));
      throw std::runtime_error(std::string("dhd: cannot enable forces: ") + dhdErrorGetLastStr());
    }
  }
  ~DhdDevice() override {
    dhdSetForce(0, 0, 0, static_cast<char>(id_));
    dhdClose(static_cast<char>(id_));
  }
  DeviceCapabilities Capabilities() const override {
    DeviceCapabilities c;
    c.name = name_;
    c.max_force_N = 12;  // conservative for the omega.3 (vendor: 12 N continuous)
    c.max_stiffness_N_per_m = 14500;
    c.max_rate_hz = 4000;
    c.workspace_m = {0.16, 0.16, 0.12};
    return c;
  }
  void SetTimeBase(std::chrono::steady_clock::time_point t0) noexcept override { t0_ = t0; }
  ReadResult Read(DeviceSample* out) noexcept override {
    double x, y, z, vx, vy, vz;
    const char id = static_cast<char>(id_);
    if (dhdGetPosition(&x, &y, &z, id) < DHD_NO_ERROR) return ReadResult::kLost;
    if (dhdGetLinearVelocity(&vx, &vy, &vz, id) < DHD_NO_ERROR) return ReadResult::kLost;
    out->state.p_m = {x, y, z};
    out->state.v_mps = {vx, vy, vz};
    out->t_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    return ReadResult::kOk;
  }
  void WriteForce(const Eigen::Vector3d& f) noexcept override {
    dhdSetForce(f.x(), f.y(), f.z(), static_cast<char>(id_));
  }

 private:
  int id_ = -1;
  std::string name_;
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

}  // namespace

bool HaveDhd() { return true; }
std::unique_ptr<HapticDevice> OpenDhd() { return std::make_unique<DhdDevice>(); }

}  // namespace hapticlab::devices
