#include "hapticlab/sim/falcon_twin.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace hapticlab::sim {
namespace {
namespace fal = devices::falcon;
constexpr int kUsbErrorIo = -1;  // LIBUSB_ERROR_IO

// d(theta)/d(p) by central differences of the inverse kinematics.
bool Jacobian(const Eigen::Vector3d& p, Eigen::Matrix3d* J) {
  const double h = 1e-7;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d a = p, b = p, ta, tb;
    a[k] += h;
    b[k] -= h;
    if (!fal::InverseKinematics(a, &ta) || !fal::InverseKinematics(b, &tb)) return false;
    J->col(k) = (ta - tb) / (2 * h);
  }
  return J->allFinite();
}
}  // namespace

Eigen::Vector3d FalconHomePosition() { return {0, 0, 0.125}; }

std::vector<std::uint8_t> FalconTwinFirmware() {
  std::vector<std::uint8_t> fw(1024);
  for (std::size_t i = 0; i < fw.size(); ++i)
    fw[i] = static_cast<std::uint8_t>((i * 131 + 7) & 0xff);
  return fw;
}

FalconTwinTransport::FalconTwinTransport(Hand& hand, const devices::Clock& clock,
                                         const FalconTwinOptions& o)
    : hand_(hand), clock_(clock), o_(o), rng_(o.seed), grip_m_(FalconHomePosition()) {}

bool FalconTwinTransport::DroppedOut() const {
  const double t = clock_.Now();
  return dropout_start_s_ >= 0 && t >= dropout_start_s_ && t < dropout_start_s_ + dropout_s_;
}

void FalconTwinTransport::Reply(const std::uint8_t* d, std::size_t n) {
  if (out_n_ + n > out_.size()) {  // the FTDI buffer keeps the newest bytes
    const std::size_t drop = out_n_ + n - out_.size();
    std::memmove(out_.data(), out_.data() + drop, out_n_ - drop);
    out_n_ -= drop;
  }
  std::memcpy(out_.data() + out_n_, d, n);
  out_n_ += n;
}

int FalconTwinTransport::Control(std::uint8_t, std::uint8_t req, std::uint16_t value, std::uint16_t,
                                 unsigned) {
  if (DroppedOut()) return kUsbErrorIo;
  if (req == fal::ftdi::kBaudRate) baud_ = value;
  if (req == fal::ftdi::kModemCtrl && value == fal::ftdi::kDtrHigh) dtr_ = true;
  if (req == fal::ftdi::kModemCtrl && value == fal::ftdi::kDtrLow) dtr_ = false;
  if (req == fal::ftdi::kReset && value == fal::ftdi::kPurgeRx) out_n_ = split_hold_ = 0;
  return 0;
}

int FalconTwinTransport::BulkWrite(const std::uint8_t* d, int n, unsigned) {
  if (DroppedOut()) return kUsbErrorIo;
  const auto un = static_cast<std::size_t>(n);
  if (baud_ == fal::ftdi::kBaud9600 && dtr_ && n == 3 && d[0] == 0x0a && d[1] == 0x43 &&
      d[2] == 0x0d) {
    const std::uint8_t answer[4] = {0x0a, 0x44, 0x2c, 0x0d};  // the bootloader's greeting
    Reply(answer, 4);
  } else if (baud_ == fal::ftdi::kBaud140000 && !loading_ && n == 1 && d[0] == 'A') {
    loading_ = true;
    Reply(d, 1);
  } else if (baud_ == fal::ftdi::kBaud140000 && loading_) {
    Reply(d, un);  // the bootloader echoes every firmware byte
  } else if (baud_ == fal::ftdi::kBaudNormal && n == 16 && d[0] == '<' && d[15] == '>') {
    normal_ = true;
    loading_ = false;
    // The motor efforts become torques and the force on the grip, felt by the hand.
    Eigen::Vector3d tau;
    for (int k = 0; k < 3; ++k) {
      std::uint16_t v = 0;
      for (int j = 0; j < 4; ++j)
        v = static_cast<std::uint16_t>(v | ((d[1 + 4 * k + j] - 0x41) & 0xf) << (4 * j));
      tau[k] = -static_cast<double>(static_cast<std::int16_t>(v)) / o_.motor_units_per_Nm;
    }
    if (holding_) {
      Eigen::Matrix3d J;
      hand_.Push(Jacobian(grip_m_, &J) ? Eigen::Vector3d(J.transpose() * tau)
                                       : Eigen::Vector3d::Zero());
      grip_m_ = hand_.Step(clock_.Now()).p_m;
    }
    // The encoders of the grip's position (unchanged where the arms cannot reach).
    Eigen::Vector3d th;
    if (fal::InverseKinematics(grip_m_, &th)) {
      const double per_count = fal::EncoderToAngle(1) - fal::EncoderToAngle(0);
      for (int k = 0; k < 3; ++k)
        encoders_[static_cast<std::size_t>(k)] = static_cast<std::int16_t>(
            std::clamp(std::lround((th[k] - fal::EncoderToAngle(0)) / per_count), -32768L, 32767L));
    }
    fal::Command c;
    c.motor = encoders_;  // the status packet has the command's wire format
    const auto p = fal::EncodeCommand(c);
    Reply(p.data(), p.size());
    ++status_packets_;
    if (o_.split_probability > 0 && rng_.Uniform() < o_.split_probability) {
      split_hold_ = 9;  // the last 9 bytes of this packet arrive with the next read
      ++split_packets_;
    }
  }
  return n;
}

int FalconTwinTransport::BulkRead(std::uint8_t* d, int n, unsigned) {
  if (DroppedOut()) return kUsbErrorIo;
  d[0] = 0x31;  // FTDI modem status bytes lead every read
  d[1] = 0x60;
  if (normal_ && o_.empty_read_probability > 0 && rng_.Uniform() < o_.empty_read_probability) {
    ++empty_reads_;
    return 2;
  }
  const std::size_t avail = out_n_ > split_hold_ ? out_n_ - split_hold_ : 0;
  const std::size_t k = std::min(avail, static_cast<std::size_t>(std::max(n - 2, 0)));
  std::memcpy(d + 2, out_.data(), k);
  std::memmove(out_.data(), out_.data() + k, out_n_ - k);
  out_n_ -= k;
  split_hold_ = 0;
  return static_cast<int>(k) + 2;
}

}  // namespace hapticlab::sim
