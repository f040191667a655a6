// The Falcon's firmware load (falcon.hpp): the FTDI line set-up, the bootloader handshake, the
// upload with its echo check, normal mode and the first valid status packet, with retries.

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>

#include "hapticlab/core/diagnostics.hpp"
#include "hapticlab/devices/falcon.hpp"

namespace hapticlab::devices::falcon {

const char* LoadStateName(LoadState s) {
  switch (s) {
    case LoadState::kIdle:
      return "idle";
    case LoadState::kPurge:
      return "purge";
    case LoadState::kLineSetup:
      return "line set-up";
    case LoadState::kHandshake:
      return "bootloader handshake";
    case LoadState::kBootloader:
      return "bootloader baud switch";
    case LoadState::kUpload:
      return "upload";
    case LoadState::kNormalMode:
      return "normal mode";
    case LoadState::kVerify:
      return "verify";
    case LoadState::kDone:
      return "done";
    case LoadState::kFailed:
      return "failed";
  }
  return "?";
}

namespace {

struct Attempt {
  UsbTransport& usb;
  const LoadOptions& o;
  LoadResult& r;
  LoadState state = LoadState::kIdle;

  bool Fail(const std::string& what) {
    r.failed_in = state;
    r.error = fmt::format("{} (state: {})", what, LoadStateName(state));
    return false;
  }
  void Enter(LoadState s) {
    state = s;
    r.trace.push_back(s);
  }
  bool Ctl(std::uint8_t req, std::uint16_t value, const char* what) {
    const int rc = usb.Control(ftdi::kRequestType, req, value, 0, o.timeout_ms);
    return rc >= 0 || Fail(fmt::format("{}: USB error {}", what, rc));
  }
  bool Write(const std::uint8_t* d, int n, const char* what) {
    const int rc = usb.BulkWrite(d, n, o.timeout_ms);
    return rc == n || Fail(fmt::format("{}: wrote {} of {} bytes", what, rc, n));
  }
  // Reads and strips the two FTDI status bytes; returns payload bytes or -1.
  int Read(std::uint8_t* d, int n) {
    std::uint8_t raw[64 + 2];
    const int rc = usb.BulkRead(raw, std::min(n + 2, 64), o.timeout_ms);
    if (rc < 2) return rc < 0 ? -1 : 0;
    std::memcpy(d, raw + 2, static_cast<std::size_t>(rc - 2));
    return rc - 2;
  }

  bool Run(const std::vector<std::uint8_t>& fw) {
    Enter(LoadState::kPurge);
    if (!Ctl(ftdi::kReset, ftdi::kPurgeRx, "purge rx") ||
        !Ctl(ftdi::kReset, ftdi::kPurgeTx, "purge tx"))
      return false;
    Enter(LoadState::kLineSetup);
    if (!Ctl(ftdi::kLatency, 16, "latency 16 ms") ||
        !Ctl(ftdi::kBaudRate, ftdi::kBaud9600, "9600 baud") || !Ctl(ftdi::kData, 8, "8N1") ||
        !Ctl(ftdi::kFlowCtrl, 0, "no flow control") ||
        !Ctl(ftdi::kModemCtrl, ftdi::kRtsLow, "RTS low") ||
        !Ctl(ftdi::kModemCtrl, ftdi::kDtrLow, "DTR low") ||
        !Ctl(ftdi::kModemCtrl, ftdi::kDtrHigh, "DTR high"))
      return false;
    Enter(LoadState::kHandshake);
    const std::uint8_t hello[3] = {0x0a, 0x43, 0x0d}, answer[4] = {0x0a, 0x44, 0x2c, 0x0d};
    bool greeted = false;
    for (int i = 0; i < o.handshake_tries && !greeted; ++i) {
      if (!Write(hello, 3, "handshake")) return false;
      std::uint8_t in[64];
      const int n = Read(in, 62);
      // Some hosts see a leading 0x00 before the answer.
      if (n == 4 && std::memcmp(in, answer, 4) == 0) greeted = true;
      if (n == 5 && in[0] == 0 && std::memcmp(in + 1, answer, 4) == 0) greeted = true;
    }
    if (!greeted)
      return Fail(fmt::format(
          "no bootloader answer to 0x0a 'C' 0x0d after {} tries (is the Falcon powered?)",
          o.handshake_tries));
    Enter(LoadState::kBootloader);
    if (!Ctl(ftdi::kModemCtrl, ftdi::kDtrLow, "DTR low") ||
        !Ctl(ftdi::kBaudRate, ftdi::kBaud140000, "140000 baud"))
      return false;
    const std::uint8_t a = 'A';
    if (!Write(&a, 1, "bootloader 'A'")) return false;
    std::uint8_t echo[64];
    if (Read(echo, 1) != 1 || echo[0] != 'A') return Fail("bootloader did not echo 'A'");
    Enter(LoadState::kUpload);
    for (std::size_t at = 0; at < fw.size();) {
      const int n = static_cast<int>(std::min<std::size_t>(62, fw.size() - at));
      if (!Write(fw.data() + at, n, "firmware block")) return false;
      int got = 0;
      while (got < n) {
        std::uint8_t in[64];
        const int k = Read(in, n - got);
        if (k <= 0)
          return Fail(fmt::format("no echo for firmware bytes {}-{} (time-out {} ms)",
                                  at + static_cast<std::size_t>(got),
                                  at + static_cast<std::size_t>(n), o.timeout_ms));
        if (std::memcmp(in, fw.data() + at + got, static_cast<std::size_t>(k)) != 0)
          return Fail(fmt::format("echo of firmware bytes from {} differs (line noise?)",
                                  at + static_cast<std::size_t>(got)));
        got += k;
      }
      at += static_cast<std::size_t>(n);
    }
    Enter(LoadState::kNormalMode);
    if (!Ctl(ftdi::kLatency, 1, "latency 1 ms") ||
        !Ctl(ftdi::kBaudRate, ftdi::kBaudNormal, "normal baud") ||
        !Ctl(ftdi::kReset, ftdi::kPurgeRx, "purge rx") ||
        !Ctl(ftdi::kReset, ftdi::kPurgeTx, "purge tx"))
      return false;
    Enter(LoadState::kVerify);
    const auto packet = EncodeCommand({});
    std::uint8_t in[64];
    std::vector<std::uint8_t> stream;
    for (int i = 0; i < o.verify_tries; ++i) {
      if (!Write(packet.data(), 16, "status request")) return false;
      const int k = Read(in, 62);
      if (k > 0) stream.insert(stream.end(), in, in + k);
      Status st;
      if (DecodeStatus(stream.data(), stream.size(), &st)) {
        Enter(LoadState::kDone);
        return true;
      }
    }
    return Fail(
        fmt::format("firmware loaded but no valid status packet in {} exchanges", o.verify_tries));
  }
};

}  // namespace

LoadResult LoadFirmware(UsbTransport& usb, const std::vector<std::uint8_t>& fw,
                        const LoadOptions& o) {
  LoadResult r;
  if (fw.empty()) {
    r.error = "empty firmware";
    r.failed_in = LoadState::kIdle;
    return r;
  }
  for (int a = 1; a <= o.attempts; ++a) {
    r.attempts = a;
    r.trace.clear();
    Attempt at{usb, o, r};
    if (at.Run(fw)) {
      r.ok = true;
      r.error.clear();
      return r;
    }
    r.trace.push_back(LoadState::kFailed);
  }
  r.error = fmt::format("firmware load failed after {} attempts: {}", o.attempts, r.error);
  return r;
}

std::vector<std::uint8_t> ReadFirmwareFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f)
    throw InputError(
        path, 0, "firmware",
        "cannot open the firmware file (supply the Falcon firmware yourself; docs/hardware.md)");
  std::vector<std::uint8_t> d((std::istreambuf_iterator<char>(f)), {});
  if (d.empty()) throw InputError(path, 0, "firmware", "empty firmware file");
  return d;
}

}  // namespace hapticlab::devices::falcon
