#pragma once
/// @file The Novint Falcon over libusb: its FTDI serial link, the firmware-load state machine
/// (with retries and time-outs), the 16-byte packet protocol of the Novint SDK firmware, and
/// the encoder kinematics (R. E. Stamper's delta-robot kinematics with the Falcon geometry
/// published by the libnifalcon project). The firmware binary is supplied by the user.
///
/// Everything below the USB transport is testable without a device: tests drive the state
/// machine and the device through a scripted FakeUsbTransport with recorded packet fixtures.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hapticlab/devices/device.hpp"
#include "hapticlab/devices/velocity_filter.hpp"

namespace hapticlab::devices::falcon {

inline constexpr std::uint16_t kVendorId = 0x0403;   ///< FTDI
inline constexpr std::uint16_t kProductId = 0xcb48;  ///< Falcon
inline constexpr unsigned char kEndpointOut = 0x02, kEndpointIn = 0x81;

// ---------------------------------------------------------------------------------------------
// Packets (Novint SDK firmware). 16 bytes: '<', 12 data nibbles, an info nibble pair, a spare
// nibble, '>'. Every nibble travels as 0x41 + value ('A'..'P'); three signed 16-bit values
// go as four nibbles each, least significant first.

/// Host to device: motor commands and LEDs.
struct Command {
  std::array<std::int16_t, 3> motor{};  ///< motor effort (signed, device units)
  std::uint8_t leds = 0;                ///< bit 1 green, bit 2 blue, bit 3 red
  bool homing = false;                  ///< request homing mode
};
/// Device to host: encoders, homing state and grip buttons.
struct Status {
  std::array<std::int16_t, 3> encoder{};
  std::uint8_t homing = 0;   ///< three bits, one per arm: homed
  std::uint8_t buttons = 0;  ///< four grip buttons
};
std::array<std::uint8_t, 16> EncodeCommand(const Command& c);
/// Scans a byte stream for the newest complete packet ('<' ... '>' 16 bytes apart); malformed
/// fragments are skipped and counted. Returns false when none.
bool DecodeStatus(const std::uint8_t* data, std::size_t n, Status* out, int* malformed = nullptr);

// ---------------------------------------------------------------------------------------------
// Kinematics (SI units; the Falcon's frame: z away from the base, y up).

/// Motor angle [rad] from an encoder count: the encoder wheel (320 slots, quadrature) on a
/// 14.25 mm shaft drives the 110 mm arm drum; 35 deg at count zero.
double EncoderToAngle(std::int16_t count);
/// Inverse kinematics: the three motor angles [rad] at a tool position [m]; false outside the
/// reachable workspace.
bool InverseKinematics(const Eigen::Vector3d& p_m, Eigen::Vector3d* theta_rad);
/// Forward kinematics by Newton's method on the inverse (from `guess`, the last position);
/// false when it does not converge to 1e-9 rad in 20 iterations.
bool ForwardKinematics(const Eigen::Vector3d& theta_rad, const Eigen::Vector3d& guess_m,
                       Eigen::Vector3d* p_m);
/// Motor torques [N m] that produce the force `f_N` at position `p_m`: tau = J^-T f with J the
/// Jacobian d(theta)/d(p).
bool ForceToTorque(const Eigen::Vector3d& p_m, const Eigen::Vector3d& f_N, Eigen::Vector3d* tau_Nm);

// ---------------------------------------------------------------------------------------------
// USB transport.

/// The calls the Falcon needs from libusb (so tests can script them). Return values follow
/// libusb: >= 0 success (bytes transferred for bulk), < 0 an error code.
class UsbTransport {
 public:
  virtual ~UsbTransport() = default;
  virtual int Control(std::uint8_t request_type, std::uint8_t request, std::uint16_t value,
                      std::uint16_t index, unsigned timeout_ms) = 0;
  virtual int BulkWrite(const std::uint8_t* data, int n, unsigned timeout_ms) = 0;
  /// Reads up to n bytes; FTDI prefixes every read with two modem-status bytes.
  virtual int BulkRead(std::uint8_t* data, int n, unsigned timeout_ms) = 0;
};

/// libusb-1.0 transport: opens the index-th device with the Falcon's vendor/product id and
/// claims interface 0. @throws std::runtime_error naming what failed.
std::unique_ptr<UsbTransport> OpenLibusb(int index = 0);
/// Number of Falcons on the bus (0 when libusb cannot start).
int CountDevices();

// FTDI vendor requests used on the link.
namespace ftdi {
inline constexpr std::uint8_t kRequestType = 0x40;
inline constexpr std::uint8_t kReset = 0, kModemCtrl = 1, kFlowCtrl = 2, kBaudRate = 3, kData = 4,
                              kLatency = 9;
inline constexpr std::uint16_t kPurgeRx = 1, kPurgeTx = 2;
inline constexpr std::uint16_t kDtrHigh = 0x0101, kDtrLow = 0x0100, kRtsLow = 0x0200;
inline constexpr std::uint16_t kBaud9600 = 0x4138, kBaud140000 = 0x0015,
                               kBaudNormal = 0x0002;  // divisors
}  // namespace ftdi

// ---------------------------------------------------------------------------------------------
// Firmware loading.

enum class LoadState {
  kIdle,
  kPurge,
  kLineSetup,
  kHandshake,
  kBootloader,
  kUpload,
  kNormalMode,
  kVerify,
  kDone,
  kFailed
};
const char* LoadStateName(LoadState s);

struct LoadOptions {
  int attempts = 3;            ///< whole-load retries
  int handshake_tries = 100;   ///< handshake messages before giving up
  unsigned timeout_ms = 1000;  ///< per USB transfer
  int verify_tries = 50;       ///< packets sent after loading before declaring the firmware dead
};
/// How a firmware load went. A failing load is the environment failing (the device, its
/// cable, its USB link), not bad user data, so under the error policy (docs/architecture.md,
/// "Errors") it is reported like a solver's SolverSummary: a retrying procedure returns its
/// outcome with the trace the tests and the operator need, and the caller decides (the
/// factory throws std::runtime_error with `error`). A bad firmware file is an InputError
/// from ReadFirmwareFile before any load starts.
struct LoadResult {
  bool ok = false;
  int attempts = 0;
  LoadState failed_in = LoadState::kIdle;
  std::string error;             ///< what failed, in words, with the state
  std::vector<LoadState> trace;  ///< states visited (last attempt)
};
/// Loads `firmware` (the user's file, e.g. the Novint SDK's test firmware): purge, line set-up
/// at 9600 baud, the bootloader handshake (0x0a 'C' 0x0d answered by 0x0a 'D' ',' 0x0d), 140000
/// baud and 'A' answered by 'A', upload in 62-byte blocks each echoed back and compared,
/// normal mode (1 ms latency timer, the fast baud divisor), then packets until a valid status
/// comes back. Each attempt starts over; errors name the state.
LoadResult LoadFirmware(UsbTransport& usb, const std::vector<std::uint8_t>& firmware,
                        const LoadOptions& o = {});
/// Reads a firmware file. @throws InputError naming the file.
std::vector<std::uint8_t> ReadFirmwareFile(const std::string& path);

// ---------------------------------------------------------------------------------------------
// The device.

/// The driver's name for itself (Capabilities().name, its messages).
inline constexpr const char* kDeviceName = "falcon";

struct FalconOptions {
  double motor_units_per_Nm =
      10000;                   ///< command scale (calibrate with a force gauge; docs/hardware.md)
  double max_force_N = 8.0;    ///< the Falcon's rated peak force
  unsigned io_timeout_ms = 2;  ///< a read that takes longer counts as no data
  double velocity_cutoff_hz = 100;  ///< low-pass of the differentiated position
};

/// HapticDevice on a Falcon whose firmware is loaded. Read() does one exchange: sends the last
/// force command, reads what the link has, runs the kinematics on the newest complete status
/// packet. A packet split across two reads is reassembled (the incomplete tail is kept for
/// the next read). Results: kOk with a new packet; kNoNewData when the read carried no
/// complete packet (an empty USB frame, a packet still in flight); kLost when the USB
/// exchange failed or the encoders gave no position. Whether a loss is sustained is the
/// engine's watchdog's decision.
class FalconDevice final : public HapticDevice {
 public:
  /// @param usb the link to a Falcon whose firmware runs (non-null: PreconditionError)
  /// @param clock seconds on the loops' time base; empty: seconds since SetTimeBase (the engine's)
  FalconDevice(std::unique_ptr<UsbTransport> usb, std::function<double()> clock = {},
               const FalconOptions& o = {});
  void SetTimeBase(std::chrono::steady_clock::time_point t0) noexcept override { t0_ = t0; }
  DeviceCapabilities Capabilities() const override;
  ReadResult Read(DeviceSample* out) noexcept override;
  void WriteForce(const Eigen::Vector3d& force_N) noexcept override;
  const Status& last_status() const { return status_; }
  int malformed_packets() const { return malformed_; }
  /// Packet counters: complete status packets decoded, reads without one, failed exchanges.
  std::uint64_t packets() const { return packets_; }
  std::uint64_t empty_reads() const { return empty_reads_; }
  std::uint64_t lost_reads() const { return lost_reads_; }

 private:
  std::unique_ptr<UsbTransport> usb_;
  std::function<double()> clock_;
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
  FalconOptions o_;
  Command cmd_;
  Status status_;
  Eigen::Vector3d p_m_{0, 0, 0.12};  // the last position: forward kinematics' next guess
  bool have_p_ = false;
  VelocityFilter velocity_;
  int malformed_ = 0;
  std::uint64_t packets_ = 0, empty_reads_ = 0, lost_reads_ = 0;
  std::array<std::uint8_t, 64> buf_{};
  std::array<std::uint8_t, 128> pending_{};  // link bytes not yet consumed (a partial packet)
  std::size_t pending_n_ = 0;
};

}  // namespace hapticlab::devices::falcon
