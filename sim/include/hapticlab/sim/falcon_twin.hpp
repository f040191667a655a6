#pragma once
/// @file The Falcon twin: an emulated FTDI transport that answers like a Novint Falcon, so
/// the real Falcon back-end (devices::falcon: firmware loader, 16-byte packets, kinematics,
/// force-to-torque) runs end to end without the device. The simulated hand holds the twin's
/// grip: a status read steps the hand to the clock's time and answers with the encoder
/// counts of the grip's position (inverse kinematics, quantized like the real encoders); a
/// motor command is turned back into the force on the grip (f = J^T tau, tau = -effort /
/// motor_units_per_Nm) and pushed onto the hand. The link can return empty reads, split
/// packets across reads and drop out, as a USB link does.

#include <array>
#include <cstdint>
#include <deque>
#include <vector>

#include "hapticlab/core/rng.hpp"
#include "hapticlab/devices/clock.hpp"
#include "hapticlab/devices/falcon.hpp"
#include "hapticlab/sim/sim_device.hpp"

namespace hapticlab::sim {

struct FalconTwinOptions {
  double motor_units_per_Nm = 10000;  ///< the twin's true force scale (a rig file may differ)
  double empty_read_probability = 0;  ///< a read that carries no packet
  double split_probability = 0;       ///< a status packet split across two reads
  std::uint64_t seed = 1;
};

/// The twin's grip at rest (the Falcon's home pose) [m, device frame].
Eigen::Vector3d FalconHomePosition();

class FalconTwinTransport final : public devices::falcon::UsbTransport {
 public:
  /// Borrowed: the hand on the grip and the clock (the engine's virtual clock).
  FalconTwinTransport(Hand& hand, const devices::Clock& clock, const FalconTwinOptions& o = {});
  int Control(std::uint8_t request_type, std::uint8_t request, std::uint16_t value,
              std::uint16_t index, unsigned timeout_ms) override;
  int BulkWrite(const std::uint8_t* data, int n, unsigned timeout_ms) override;
  int BulkRead(std::uint8_t* data, int n, unsigned timeout_ms) override;

  /// The link drops out (every exchange fails) from `start_s` for `duration_s` (clock time).
  void InjectDropout(double start_s, double duration_s) {
    dropout_start_s_ = start_s;
    dropout_s_ = duration_s;
  }
  /// Before a run: the grip is wherever the hand puts it from now on.
  void BeginRun() { holding_ = true; }
  bool firmware_loaded() const { return normal_; }
  std::uint64_t status_packets() const { return status_packets_; }
  std::uint64_t empty_reads() const { return empty_reads_; }
  std::uint64_t split_packets() const { return split_packets_; }

 private:
  void Reply(const std::uint8_t* d, std::size_t n);
  bool DroppedOut() const;
  Hand& hand_;
  const devices::Clock& clock_;
  FalconTwinOptions o_;
  Rng rng_;
  std::uint16_t baud_ = 0;
  bool dtr_ = false, loading_ = false, normal_ = false, holding_ = false;
  std::array<std::uint8_t, 256> out_{};  // bytes waiting for the host's reads
  std::size_t out_n_ = 0;
  std::size_t split_hold_ = 0;  // > 0: bytes of the pending packet held for the next read
  Eigen::Vector3d grip_m_;
  std::array<std::int16_t, 3> encoders_{};
  double dropout_start_s_ = -1, dropout_s_ = 0;
  std::uint64_t status_packets_ = 0, empty_reads_ = 0, split_packets_ = 0;
};

/// A stand-in for the Falcon firmware file (the twin takes any bytes; the loader uploads
/// and verifies them block by block).
std::vector<std::uint8_t> FalconTwinFirmware();

}  // namespace hapticlab::sim
