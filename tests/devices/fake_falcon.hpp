#pragma once
// Shared by the Falcon tests (tests/devices/falcon_test.cpp, falcon_firmware_test.cpp): a
// scripted fake of the FTDI link, the bootloader and the SDK firmware's packet loop, and a
// firmware image.

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <deque>
#include <utility>
#include <vector>

#include "hapticlab/devices/falcon.hpp"

namespace hapticlab::devices::falcon {
namespace {

// A scripted Falcon: the FTDI link plus the bootloader and the SDK firmware's packet loop.
class FakeFalcon : public UsbTransport {
 public:
  std::vector<std::pair<int, int>> controls;  // (request, value)
  std::vector<std::uint8_t> uploaded;
  int drop_handshakes = 0;    // ignore this many handshake messages
  int corrupt_echo_at = -1;   // corrupt the echo of this upload byte (once)
  bool dead = false;          // never answers
  bool firmware_runs = true;  // answers status packets after loading
  bool unplugged = false;     // reads fail with a USB error
  int split_replies_at = 0;   // > 0: the next read returns only this many payload bytes
  std::array<std::int16_t, 3> encoders{0, 0, 0};
  std::vector<std::array<std::int16_t, 3>> motors;  // commands seen in normal mode

  int Control(std::uint8_t type, std::uint8_t req, std::uint16_t value, std::uint16_t,
              unsigned) override {
    EXPECT_EQ(type, 0x40);
    controls.emplace_back(req, value);
    if (req == ftdi::kBaudRate) baud_ = value;
    if (req == ftdi::kModemCtrl && value == ftdi::kDtrHigh) dtr_ = true;
    if (req == ftdi::kModemCtrl && value == ftdi::kDtrLow) dtr_ = false;
    return 0;
  }
  int BulkWrite(const std::uint8_t* d, int n, unsigned) override {
    if (dead) return n;
    if (baud_ == ftdi::kBaud9600 && dtr_ && n == 3 && d[0] == 0x0a && d[1] == 0x43 &&
        d[2] == 0x0d) {
      if (drop_handshakes > 0) {
        --drop_handshakes;
        return n;
      }
      Reply({0x0a, 0x44, 0x2c, 0x0d});
    } else if (baud_ == ftdi::kBaud140000 && !loading_ && n == 1 && d[0] == 'A') {
      loading_ = true;
      Reply({'A'});
    } else if (baud_ == ftdi::kBaud140000 && loading_) {
      std::vector<std::uint8_t> echo(d, d + n);
      for (int i = 0; i < n; ++i) {
        if (static_cast<int>(uploaded.size()) == corrupt_echo_at) {
          echo[static_cast<std::size_t>(i)] ^= 0xff;
          corrupt_echo_at = -1;
        }
        uploaded.push_back(d[i]);
      }
      Reply(echo);
    } else if (baud_ == ftdi::kBaudNormal && n == 16 && firmware_runs) {
      Status st;
      // Record the motor command, answer with the encoders.
      std::array<std::int16_t, 3> m{};
      for (int k = 0; k < 3; ++k) {
        std::uint16_t v = 0;
        for (int j = 0; j < 4; ++j)
          v = static_cast<std::uint16_t>(v | (d[1 + 4 * k + j] - 0x41) << (4 * j));
        m[static_cast<std::size_t>(k)] = static_cast<std::int16_t>(v);
      }
      motors.push_back(m);
      Command c;
      c.motor = encoders;  // same wire format both ways
      const auto p = EncodeCommand(c);
      Reply(std::vector<std::uint8_t>(p.begin(), p.end()));
    }
    return n;
  }
  int BulkRead(std::uint8_t* d, int n, unsigned) override {
    if (unplugged) return -4;  // LIBUSB_ERROR_NO_DEVICE
    d[0] = 0x31;               // FTDI modem status bytes
    d[1] = 0x60;
    if (replies_.empty()) return 2;
    auto r = replies_.front();
    int k = std::min(static_cast<int>(r.size()), n - 2);
    if (split_replies_at > 0)
      k = std::min(k, std::exchange(split_replies_at, 0));  // one split read
    std::memcpy(d + 2, r.data(), static_cast<std::size_t>(k));
    if (k < static_cast<int>(r.size()))
      replies_.front().erase(replies_.front().begin(), replies_.front().begin() + k);
    else
      replies_.pop_front();
    return k + 2;
  }

 private:
  void Reply(std::vector<std::uint8_t> r) { replies_.push_back(std::move(r)); }
  std::deque<std::vector<std::uint8_t>> replies_;
  std::uint16_t baud_ = 0;
  bool dtr_ = false, loading_ = false;
};

inline std::vector<std::uint8_t> Firmware(std::size_t n) {
  std::vector<std::uint8_t> fw(n);
  for (std::size_t i = 0; i < n; ++i) fw[i] = static_cast<std::uint8_t>((i * 37 + 11) & 0xff);
  return fw;
}

}  // namespace
}  // namespace hapticlab::devices::falcon
